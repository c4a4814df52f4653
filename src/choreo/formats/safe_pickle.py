"""Unpickling numpy arrays from untrusted files without ever calling into numpy's pickle support.

AIST++ ships motions as pickles. A whitelist of numpy globals is not enough: numpy's own
``dtype.__setstate__`` can be crashed by a crafted state, ``_reconstruct`` allocates whatever
shape it is told, and a single memo opcode can make the C unpickler grow its memo to gigabytes.
So (1) the opcode stream is checked first with pure-Python ``pickletools`` (allowed opcodes only,
small memo indices), (2) the numpy globals are replaced by inert stand-ins that just record what
the pickle asked for, and (3) arrays are built from those records with ``np.frombuffer`` after
checking that the bytes present match the declared shape and a plain numeric dtype; (4) shared
containers are rebuilt once each, under a count and a depth limit. Memory is then bounded by the
file's size.
"""

from __future__ import annotations

import io
import pickle
import pickletools
from pathlib import Path

import numpy as np

MAX_FILE_BYTES = 1 << 30
MAX_MEMO_INDEX = 1 << 16
NUMERIC_DTYPES = {f"{kind}{size}" for kind in "fiu" for size in (1, 2, 4, 8)} - {"f1"} | {"b1"}
ALLOWED_OPCODES = {
    "PROTO", "FRAME", "STOP", "MARK", "POP", "POP_MARK", "DUP",
    "EMPTY_DICT", "DICT", "SETITEM", "SETITEMS", "EMPTY_LIST", "LIST", "APPEND", "APPENDS",
    "EMPTY_TUPLE", "TUPLE", "TUPLE1", "TUPLE2", "TUPLE3",
    "NONE", "NEWTRUE", "NEWFALSE", "INT", "BININT", "BININT1", "BININT2", "LONG", "LONG1", "FLOAT", "BINFLOAT",
    "STRING", "BINSTRING", "SHORT_BINSTRING", "UNICODE", "BINUNICODE", "SHORT_BINUNICODE", "BINUNICODE8",
    "BINBYTES", "SHORT_BINBYTES", "BINBYTES8", "BYTEARRAY8",
    "GLOBAL", "STACK_GLOBAL", "REDUCE", "BUILD",
    "PUT", "BINPUT", "LONG_BINPUT", "GET", "BINGET", "LONG_BINGET", "MEMOIZE",
}  # fmt: skip
MEMO_OPCODES = {"PUT", "BINPUT", "LONG_BINPUT", "GET", "BINGET", "LONG_BINGET"}


class UnsafePickle(ValueError):
    """The file is not a plain pickle of numpy arrays, dicts, lists and numbers."""


class _NdarrayMarker:
    """Stands in for ``numpy.ndarray`` (only ever passed to _reconstruct)."""


class _DTypeRecord:
    def __init__(self, code, align=False, copy=False):
        if not isinstance(code, str) or code not in NUMERIC_DTYPES:
            raise UnsafePickle(f"dtype {code!r} is not a plain numeric type")
        self.code, self.byteorder = code, "="

    def __setstate__(self, state):
        if not isinstance(state, tuple) or len(state) < 8 or any(part is not None for part in state[2:5]):
            raise UnsafePickle("structured or sub-array dtypes are not allowed")
        if state[1] not in ("<", ">", "|", "="):
            raise UnsafePickle(f"bad byte order {state[1]!r}")
        self.byteorder = state[1]

    def resolve(self) -> np.dtype:
        dtype = np.dtype(self.code)
        return dtype if self.byteorder in ("|", "=") else dtype.newbyteorder(self.byteorder)


class _ArrayRecord:
    array: np.ndarray | None = None

    @classmethod
    def of(cls, array: np.ndarray) -> "_ArrayRecord":
        record = cls()
        record.array = array
        return record

    def __setstate__(self, state):
        if not isinstance(state, tuple) or len(state) != 5:
            raise UnsafePickle("unexpected array state")
        _, shape, dtype, fortran, raw = state
        if not isinstance(dtype, _DTypeRecord):
            raise UnsafePickle("array without a plain dtype")
        self.array = _array_from_bytes(_as_bytes(raw), dtype, shape, "F" if fortran else "C")


def _array_from_bytes(raw: bytes, dtype: _DTypeRecord, shape: tuple, order: str) -> np.ndarray:
    if not isinstance(shape, tuple) or not all(isinstance(n, int) and 0 <= n for n in shape):
        raise UnsafePickle(f"bad array shape {shape!r}")
    resolved = dtype.resolve()
    count = 1
    for n in shape:
        count *= n
    if count * resolved.itemsize != len(raw):  # the bytes must be in the file: no allocation on trust
        raise UnsafePickle(f"array of shape {shape} does not match its {len(raw)} bytes")
    return np.frombuffer(raw, resolved).reshape(shape, order=order).copy()


def _frombuffer(buffer, dtype, shape, order):
    """Protocol 5's array constructor (numpy._core.numeric._frombuffer), in-band buffers only."""
    if not isinstance(dtype, _DTypeRecord) or order not in ("C", "F"):
        raise UnsafePickle("array without a plain dtype")
    return _ArrayRecord.of(_array_from_bytes(_as_bytes(buffer), dtype, shape, order))


def _as_bytes(raw) -> bytes:
    if isinstance(raw, str):  # Python 2 pickles read with encoding="latin1"
        return raw.encode("latin1")
    if not isinstance(raw, (bytes, bytearray)):
        raise UnsafePickle("array data is not raw bytes")
    return bytes(raw)


def _reconstruct(cls, shape, typecode):
    if cls is not _NdarrayMarker:
        raise UnsafePickle("only numpy arrays may be reconstructed")
    return _ArrayRecord()


def _scalar(dtype, raw):
    if not isinstance(dtype, _DTypeRecord):
        raise UnsafePickle("scalar without a plain dtype")
    raw = _as_bytes(raw)
    resolved = dtype.resolve()
    if len(raw) != resolved.itemsize:
        raise UnsafePickle("scalar of the wrong size")
    return np.frombuffer(raw, resolved)[0]


def _encode(text, encoding="utf-8"):
    if not isinstance(text, str) or encoding not in ("latin1", "latin-1"):
        raise UnsafePickle("unexpected codec call")
    return text.encode("latin1")


def _empty_bytes(*args):
    """Protocol 2 writes ``b""`` (an empty array's data) as a call of ``bytes()``: allowed with no
    argument only, since ``bytes(n)`` would allocate what the file says."""
    if args:
        raise UnsafePickle("unexpected bytes() call")
    return b""


_STAND_INS = {
    ("numpy.core.multiarray", "_reconstruct"): _reconstruct, ("numpy._core.multiarray", "_reconstruct"): _reconstruct,
    ("numpy.core.multiarray", "scalar"): _scalar, ("numpy._core.multiarray", "scalar"): _scalar,
    ("numpy.core.numeric", "_frombuffer"): _frombuffer, ("numpy._core.numeric", "_frombuffer"): _frombuffer,
    ("numpy", "ndarray"): _NdarrayMarker, ("numpy", "dtype"): _DTypeRecord, ("_codecs", "encode"): _encode,
    ("__builtin__", "bytes"): _empty_bytes, ("builtins", "bytes"): _empty_bytes,
}  # fmt: skip


class _StandInUnpickler(pickle.Unpickler):
    def find_class(self, module, name):
        if (module, name) in _STAND_INS:
            return _STAND_INS[(module, name)]
        wanted = f"{module}.{name}"  # the pickle's own words, which may hold newlines
        raise UnsafePickle(f"refusing to load {wanted if wanted.isprintable() else ascii(wanted)}")


def check_opcodes(data: bytes) -> None:
    """Walk the opcode stream in pure Python: allowed opcodes only, memo indices kept small."""
    try:
        for opcode, argument, _ in pickletools.genops(data):
            if opcode.name not in ALLOWED_OPCODES:
                raise UnsafePickle(f"pickle opcode {opcode.name} is not allowed")
            if opcode.name in MEMO_OPCODES and not (isinstance(argument, int) and 0 <= argument <= MAX_MEMO_INDEX):
                raise UnsafePickle("pickle memo index out of range")
    except UnsafePickle:
        raise
    except Exception as error:  # pickletools raises ValueError and friends on malformed streams
        raise UnsafePickle(f"malformed pickle ({type(error).__name__})") from None


MAX_DEPTH = 64  # containers inside containers: AIST++ files nest 2 deep
MAX_OBJECTS = 1_000_000  # containers and items built: a 367-byte file of shared lists must not ask for 2^40


class _Materialiser:
    """Stand-ins to real values. A pickle may share one list many times over (its memo): each shared
    object is built once, and the size of the tree the sharing unfolds into is counted, so neither
    this nor anything that later walks the result (np.asarray on nested lists) can be asked for
    2^40 items by a file of a few hundred bytes."""

    def __init__(self):
        self.built: dict[int, tuple[object, int]] = {}  # id -> (value, items in its unfolded tree)
        self.total = 0

    def __call__(self, value, depth: int = 0):
        return self._build(value, depth)[0]

    def _build(self, value, depth: int) -> tuple[object, int]:
        if depth > MAX_DEPTH:
            raise UnsafePickle(f"pickle nests containers more than {MAX_DEPTH} deep")
        if isinstance(value, _ArrayRecord):
            if value.array is None:
                raise UnsafePickle("array without data")
            return value.array, 1
        if isinstance(value, (_DTypeRecord, _NdarrayMarker)) or value is _NdarrayMarker:
            raise UnsafePickle("stray numpy object")
        if not isinstance(value, (dict, list, tuple)):
            return value, 1
        if id(value) not in self.built:
            items = value.items() if isinstance(value, dict) else enumerate(value)
            parts = {key: self._build(item, depth + 1) for key, item in items}
            size = 1 + sum(n for _, n in parts.values())
            if isinstance(value, dict):
                result = {key: part for key, (part, _) in parts.items()}
            else:
                result = [part for part, _ in parts.values()]
                result = result if isinstance(value, list) else tuple(result)
            self.built[id(value)] = (result, size)
        result, size = self.built[id(value)]
        self.total += size
        if size > MAX_OBJECTS or self.total > MAX_OBJECTS * 4:
            raise UnsafePickle(f"pickle unfolds into more than {MAX_OBJECTS:,} values")
        return result, size


def load_numpy_pickle(path: str | Path):
    """The object in a pickle of numpy arrays and plain containers; ``UnsafePickle`` otherwise."""
    path = Path(path)
    if path.stat().st_size > MAX_FILE_BYTES:
        raise UnsafePickle(f"file is larger than {MAX_FILE_BYTES >> 20} MiB")
    data = path.read_bytes()
    check_opcodes(data)
    try:
        value = _StandInUnpickler(io.BytesIO(data), encoding="latin1").load()
    except UnsafePickle:
        raise
    except RecursionError:
        raise UnsafePickle("pickle nests too deeply") from None
    except Exception as error:  # malformed streams raise many kinds; none of them may escape
        raise UnsafePickle(f"unreadable pickle ({type(error).__name__})") from None
    return _Materialiser()(value)
