"""A checkpoint's zip archive checked with the standard library before torch reads it.

``torch.load(weights_only=True)`` runs no code, but it believes sizes: a deflated record of zeros
(a 1.5 MB file) is inflated in full, and each tensor's storage is as big as the pickle says.
torch writes its archives with every record stored (uncompressed), so here only that is
accepted: each record's bytes must be present in the file, all of them together under a
ceiling, and every storage the pickle names must be a record of exactly the bytes it claims.
Memory is then bounded by the file's size, as for NPZ files (:mod:`choreo.formats.safe_arrays`).
"""

from __future__ import annotations

import pickletools
import zipfile
from pathlib import Path

from ..errors import InputError
from ..formats.safe_arrays import ZIP_ERRORS, printable

MAX_CHECKPOINT_BYTES = 1 << 31  # three times the paper model's training state (weights, EMA, AdamW)
MAX_PICKLE_BYTES = 1 << 22  # configs, weight names, the loss history: tens of kB (3 s to read 4 MiB of opcodes)
ITEM_BYTES = {"Double": 8, "Float": 4, "Half": 2, "BFloat16": 2, "Long": 8, "Int": 4, "Short": 2, "Char": 1,
              "Byte": 1, "Bool": 1, "ComplexDouble": 16, "ComplexFloat": 8, "Untyped": 1}
PICKLE_ERRORS = (ValueError, IndexError, KeyError, TypeError, EOFError)  # pickletools on damaged bytes


def check_checkpoint_archive(path: Path) -> None:
    """Refuse, in one line, a checkpoint whose reading would allocate more than its file holds."""
    try:
        with zipfile.ZipFile(path) as archive:
            records = _stored_records(archive, path.stat().st_size, str(path))
            pickle_name = next((name for name in records if name.endswith("/data.pkl")), None)
            if pickle_name is None:
                raise InputError(f"{path} is not a checkpoint torch writes (no data.pkl in its archive)")
            if records[pickle_name] > MAX_PICKLE_BYTES:
                raise InputError(f"{path}: a {records[pickle_name]:,}-byte pickle (more than a checkpoint holds)")
            claims = _storage_claims(archive.read(pickle_name), str(path))
    except ZIP_ERRORS as error:
        raise InputError(f"{path} is not a readable checkpoint ({type(error).__name__})") from None
    folder = pickle_name.removesuffix("data.pkl")
    for key, claimed in claims.items():
        held = records.get(f"{folder}data/{key}")
        if held != claimed:
            raise InputError(f"{path}: storage {printable(key)} claims {claimed:,} bytes but its record holds "
                             f"{'none' if held is None else f'{held:,}'} (damaged or forged)")


def _stored_records(archive: zipfile.ZipFile, file_bytes: int, where: str) -> dict[str, int]:
    """{record name: bytes} of an archive whose records are all stored and present in the file."""
    records, total = {}, 0
    for info in archive.infolist():
        name = printable(info.filename)
        if info.compress_type != zipfile.ZIP_STORED:
            raise InputError(f"{where}: record {name} is compressed (torch stores its records; a zip bomb?)")
        if info.file_size != info.compress_size or info.header_offset + info.compress_size > file_bytes:
            raise InputError(f"{where}: record {name} declares {info.file_size:,} bytes that the file does not hold")
        total += info.file_size
        if total > MAX_CHECKPOINT_BYTES:
            raise InputError(f"{where}: its records hold more than the {MAX_CHECKPOINT_BYTES:,} bytes choreo reads")
        records[info.filename] = info.file_size
    return records


def _storage_claims(data: bytes, where: str) -> dict[str, int]:
    """{storage key: bytes} that the pickle's persistent ids claim, read by following its opcodes
    on a stack of plain values (strings, numbers, globals, tuples), never by unpickling."""
    stack: list = []
    marks: list[int] = []
    memo: dict = {}
    claims: dict[str, int] = {}
    try:
        for opcode, argument, _ in pickletools.genops(data):
            _step(opcode, argument, stack, marks, memo, claims, where)
    except PICKLE_ERRORS as error:
        raise InputError(f"{where}: a damaged checkpoint pickle ({type(error).__name__})") from None
    return claims


class _Opaque:
    """Any value the claim reading does not need (dicts, lists, rebuilt tensors)."""


def _step(opcode, argument, stack: list, marks: list[int], memo: dict, claims: dict, where: str) -> None:
    """One opcode's effect on the stack, as pickletools documents it (stack_before / stack_after)."""
    name = opcode.name
    if name == "BINPERSID":
        claims.update([_claim(stack.pop(), where)])
        stack.append(_Opaque())
    elif name in ("PUT", "BINPUT", "LONG_BINPUT"):
        memo[argument] = stack[-1]
    elif name == "MEMOIZE":
        memo[len(memo)] = stack[-1]
    elif name in ("GET", "BINGET", "LONG_BINGET"):
        stack.append(memo[argument])
    elif name == "MARK":
        marks.append(len(stack))
    elif pickletools.markobject in opcode.stack_before:  # takes everything above the last mark
        start = marks.pop()
        items = stack[start:]
        del stack[start:]
        if name == "TUPLE":
            stack.append(tuple(items))
        elif name != "POP_MARK" and opcode.stack_before.index(pickletools.markobject) == 0:
            stack.append(_Opaque())  # LIST, DICT, FROZENSET, INST, OBJ; APPENDS and SETITEMS keep theirs
    else:
        taken = len(opcode.stack_before)
        items = stack[len(stack) - taken:] if taken else []
        if len(items) != taken:
            raise IndexError("stack underflow")
        del stack[len(stack) - taken:]
        stack.extend(_results(name, argument, items, len(opcode.stack_after)))


def _results(name: str, argument, items: list, count: int) -> list:
    """What an opcode without a mark pushes: its argument, a global's name, a small tuple, or opaque."""
    if name in ("GLOBAL", "STACK_GLOBAL"):
        return [("global", argument if name == "GLOBAL" else " ".join(map(str, items)))]
    if name in ("TUPLE1", "TUPLE2", "TUPLE3"):
        return [tuple(items)]
    if name == "EMPTY_TUPLE":
        return [()]
    if name == "DUP":
        return items * 2
    if count and argument is not None and not name.endswith(("PUT", "GET")):
        return [argument]
    return [_Opaque() for _ in range(count)]


def _claim(saved_id, where: str) -> tuple[str, int]:
    """(key, bytes) of torch's persistent id ('storage', torch.<Type>Storage, key, location, count)."""
    if not (isinstance(saved_id, tuple) and len(saved_id) == 5 and saved_id[0] == "storage"):
        raise InputError(f"{where}: a checkpoint pickle naming something other than a tensor's storage")
    _, kind, key, _, count = saved_id
    kind = kind[1] if isinstance(kind, tuple) and len(kind) == 2 and kind[0] == "global" else None
    item = ITEM_BYTES.get(kind.removeprefix("torch ").removesuffix("Storage")) if isinstance(kind, str) else None
    if item is None or not isinstance(key, str) or not isinstance(count, int) or isinstance(count, bool) or count < 0:
        raise InputError(f"{where}: a checkpoint pickle with a malformed storage ({printable(str(kind))})")
    return key, count * item
