"""The docs point at what exists: every internal link of the READMEs and docs/ resolves (file and
anchor), every docs/<page>.md a help text, docstring or comment names exists, and every reference of the
form `docs/<page>.md, "Section"` names a heading of that file (its text equal to the name or starting
with it). The journal in docs/history/ is checked for its links only: its prose names sections as
they were on its day."""

import re
from functools import cache
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]
PAGES = sorted([REPO / "README.md", REPO / "experiments" / "README.md", *(REPO / "docs").rglob("*.md")])
CURRENT_PAGES = [page for page in PAGES if "history" not in page.relative_to(REPO).parts]
CODE = sorted(path for folder in ("src", "generators", "scripts", "benchmarks", "experiments", "tests")
               for path in (REPO / folder).rglob("*.py"))

FENCE = re.compile(r"^ *```.*?^ *```", re.S | re.M)
LINK = re.compile(r"\[[^\]\n]*\]\(([^)\s]+)\)")  # [text](target) and ![alt](target)
HEADING = re.compile(r"^#{1,6} +(.+?) *#* *$", re.M)
DOC_PATH = re.compile(r"docs/[A-Za-z0-9_/.-]+\.md")
# docs/<page>.md, "Section" (also `docs/<page>.md ("Section"`); and [text](<page>.md), "Section" in the docs themselves
SECTION_BY_PATH = re.compile(r"(docs/[A-Za-z0-9_/.-]+\.md),? \(?\"([^\"]+)\"")
SECTION_BY_LINK = re.compile(r"\]\(([^)\s#]+\.md)\),? \(?\"([^\"]+)\"")


def rel(path: Path) -> str:
    return str(path.relative_to(REPO))


def prose(path: Path) -> str:
    """The file's text as one line of words: Markdown without its code blocks; Python with its comment
    markers and escaped quotes undone, so a reference wrapped over two lines reads whole."""
    text = path.read_text(encoding="utf-8")
    if path.suffix == ".md":
        text = FENCE.sub("", text)
    else:
        text = re.sub(r"\n[ \t]*#[ \t]*", " ", text).replace('\\"', '"')
    return re.sub(r"\s+", " ", text)


def slug(heading: str) -> str:
    """GitHub's anchor for a heading: lower case, punctuation dropped, spaces as hyphens."""
    return re.sub(r"[^\w\- ]", "", heading.strip().lower()).replace(" ", "-")


@cache
def headings(path: Path) -> tuple[str, ...]:
    text = FENCE.sub("", path.read_text(encoding="utf-8"))
    return tuple(re.sub(r"`", "", match.group(1)) for match in HEADING.finditer(text))


@cache
def anchors(path: Path) -> frozenset[str]:
    seen: dict[str, int] = {}
    found = set()
    for heading in headings(path):
        base = slug(heading)
        found.add(base if base not in seen else f"{base}-{seen[base]}")
        seen[base] = seen.get(base, 0) + 1
    return frozenset(found)


def has_section(path: Path, name: str) -> bool:
    return any(heading == name or heading.startswith(name) for heading in headings(path))


def links(page: Path) -> list[str]:
    return LINK.findall(FENCE.sub("", page.read_text(encoding="utf-8")))


@pytest.mark.parametrize("page", PAGES, ids=rel)
def test_every_internal_link_resolves(page):
    broken = []
    for target in links(page):
        if re.match(r"[a-z]+:", target):  # https:, mailto:
            continue
        path, _, anchor = target.partition("#")
        file = (page.parent / path).resolve() if path else page
        if not file.exists():
            broken.append(f"{target}: no such file")
        elif anchor and file.suffix == ".md" and anchor not in anchors(file):
            broken.append(f"{target}: no heading with that anchor in {rel(file)}")
    assert not broken, f"{rel(page)}: " + "; ".join(broken)


@pytest.mark.parametrize("path", [*CODE, REPO / "README.md"], ids=rel)
def test_every_docs_path_named_in_code_exists(path):
    missing = sorted({name for name in DOC_PATH.findall(path.read_text(encoding="utf-8"))
                      if not (REPO / name).exists()})
    assert not missing, f"{rel(path)} names {missing}"


@pytest.mark.parametrize("path", [*CODE, *CURRENT_PAGES], ids=rel)
def test_every_named_section_exists(path):
    text = prose(path)
    wrong = [f'{name}, "{section}"' for name, section in SECTION_BY_PATH.findall(text)
             if (REPO / name).exists() and not has_section(REPO / name, section)]
    if path.suffix == ".md":
        wrong += [f'{target}, "{section}"' for target, section in SECTION_BY_LINK.findall(text)
                  if (path.parent / target).exists() and not has_section((path.parent / target).resolve(), section)]
    assert not wrong, f"{rel(path)}: no such heading: " + "; ".join(wrong)


def test_the_checks_see_what_they_check():
    """The patterns find what they are meant to (a check that finds nothing passes for nothing)."""
    assert slug("Frame rate and travel (`--fps`, `--in-place`)") == "frame-rate-and-travel---fps---in-place"
    assert slug("The travel's guidance") == "the-travels-guidance"
    assert "whole-songs-the-primary-evaluation" in anchors(REPO / "docs" / "results.md")
    assert has_section(REPO / "docs" / "results.md", "Whole songs")
    assert not has_section(REPO / "docs" / "results.md", "No such section")
    wrapped = prose(REPO / "generators" / "choreo_sgmd" / "options.py")
    assert SECTION_BY_PATH.search(wrapped)
    assert sum(len(links(page)) for page in PAGES) > 100
