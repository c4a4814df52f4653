"""NumPy files whose headers lie about their size are refused before anything is allocated."""

import io
import zipfile

import numpy as np
import pytest

from choreo.errors import MotionFormatError
from choreo.formats import (
    read_joint_positions,
    safe_arrays,
)
from choreo.formats.safe_arrays import load_npy, load_npz
from tests.formats.helpers import npy_with_header


def forged_npy(shape, dtype="<f8") -> bytes:
    """A valid .npy header declaring ``shape`` followed by 16 bytes of data."""
    buffer = io.BytesIO()
    np.lib.format.write_array_header_1_0(buffer, {"descr": dtype, "fortran_order": False, "shape": shape})
    return buffer.getvalue() + b"\0" * 16


def test_a_header_declaring_a_trillion_rows_is_refused(tmp_path):
    path = tmp_path / "huge.npy"
    path.write_bytes(forged_npy((10**12, 72)))
    with pytest.raises(MotionFormatError, match="declares"):
        load_npy(path)
    npz = tmp_path / "huge.npz"
    with zipfile.ZipFile(npz, "w") as archive:
        archive.writestr("smpl_poses.npy", forged_npy((10**12, 72)))
    with pytest.raises(MotionFormatError, match="declares"):
        load_npz(npz)


def test_a_zip_bomb_is_refused_from_its_directory(tmp_path):
    path = tmp_path / "bomb.npz"
    with zipfile.ZipFile(path, "w", zipfile.ZIP_DEFLATED) as archive:
        header = forged_npy((300_000, 1024))[:-16]
        with archive.open("smpl_poses.npy", "w", force_zip64=True) as member:
            member.write(header)
            zeros = bytes(1 << 20)
            for _ in range(2400):  # 2.4 GB of zeros: a few MB once compressed
                member.write(zeros)
    assert path.stat().st_size < 20_000_000
    with pytest.raises(MotionFormatError, match="uncompressed"):
        load_npz(path)


def test_declared_data_missing_from_the_file_is_refused(tmp_path):
    path = tmp_path / "short.npy"
    path.write_bytes(forged_npy((1000, 3)))  # 24 kB declared, 16 bytes present
    with pytest.raises(MotionFormatError, match="holds 16"):
        load_npy(path)


def test_object_arrays_and_honest_files(tmp_path):
    path = tmp_path / "objects.npy"
    path.write_bytes(forged_npy((2,), dtype="|O"))
    with pytest.raises(MotionFormatError, match="objects"):
        load_npy(path)
    good = tmp_path / "good.npz"
    np.savez_compressed(good, a=np.arange(12.0).reshape(3, 4), b=np.array("text"))
    arrays = load_npz(good)
    np.testing.assert_array_equal(arrays["a"], np.arange(12.0).reshape(3, 4))
    assert str(arrays["b"]) == "text"


# -- safe .npy / .npz loading: hand-made headers ----------------------------------------------------------------
def npy_bytes(descr: str, shape, data: bytes = b"", version=(1, 0)) -> bytes:
    """An .npy file written byte by byte: magic, version, header length, the header dict, data."""
    header = f"{{'descr': '{descr}', 'fortran_order': False, 'shape': {tuple(shape)!r}, }}".encode()
    length_bytes = 2 if version == (1, 0) else 4
    total = 6 + 2 + length_bytes + len(header) + 1
    header += b" " * ((-total) % 64) + b"\n"
    return (b"\x93NUMPY" + bytes(version) + len(header).to_bytes(length_bytes, "little") + header + data)


def declared(raw: bytes) -> int:
    return safe_arrays._declared_bytes(io.BytesIO(raw), "w")


@pytest.mark.survivor
def test_declared_bytes_from_hand_made_headers():
    assert declared(npy_bytes("<f4", (3, 4))) == 48
    assert declared(npy_bytes("<f8", (2, 5), version=(2, 0))) == 80
    assert declared(npy_bytes("<f8", (0, 3))) == 0
    assert declared(npy_bytes("|V0", (0,))) == 0
    assert declared(npy_bytes("<f8", (2**40, 2**40))) == 8 * 2**80  # no int64 wrap-around
    for raw, message in (
        (npy_bytes("<f8", (-1, 3)), "w: a negative dimension in its header"),
        (npy_bytes("|V0", (1,)), "w: items of zero bytes (|V0)"),
        (npy_bytes("|V0", (3,)), "w: items of zero bytes (|V0)"),
        (b"\x93NUMPY\x09\x07" + b"\0" * 64, "w: unknown .npy format version 9.7"),
        (b"\x93NUMPY\x02\x00" + (65537).to_bytes(4, "little") + b" " * 64, "w: a 65,537-byte .npy header (damaged or forged)"),
    ):
        with pytest.raises(MotionFormatError) as error:
            declared(raw)
        assert str(error.value) == message
    for raw in (b"\x93NUMPY\x02\x00" + (65536).to_bytes(4, "little") + b" " * 64,
                b"\x93NUMPY\x02\x00" + b"\xff\xff\x00\x00" + b" " * 64,  # 65,535 read little-endian
                b"\x93NUMPY\x01\x00" + b"\x10\x00" + b"{'descr': 1}    "):
        with pytest.raises(MotionFormatError, match=r"^w: not a readable NumPy array \((ValueError|EOFError|OSError)\)$"):
            declared(raw)


@pytest.mark.survivor
def test_text_arrays_are_checked_in_any_byte_order(tmp_path):
    path = tmp_path / "t.npy"
    np.save(path, np.array(["ab", "\U0010ffff"], dtype=">U2"))
    assert list(safe_arrays.load_npy(path)) == ["ab", "\U0010ffff"]
    path.write_bytes(npy_bytes("<U1", (2,), (0x61).to_bytes(4, "little") + (0x110000).to_bytes(4, "little")))
    with pytest.raises(MotionFormatError) as error:
        safe_arrays.load_npy(path)
    assert str(error.value) == f"{path}: text with characters beyond Unicode (damaged file)"


@pytest.mark.survivor
def test_npy_size_checks_name_the_file(tmp_path):
    path = tmp_path / "a.npy"
    np.save(path, np.zeros(10))
    assert safe_arrays.load_npy(path, limit=80).shape == (10,)  # exactly at the limit
    with pytest.raises(MotionFormatError) as error:
        safe_arrays.load_npy(path, limit=79)
    assert str(error.value) == f"{path}: declares 80 bytes of data (more than the 79 choreo reads)"
    path.write_bytes(npy_bytes("<f8", (100,), b"\0" * 80))
    with pytest.raises(MotionFormatError) as error:
        safe_arrays.load_npy(path)
    assert str(error.value) == f"{path}: declares 800 bytes of data but holds 80 (damaged or forged)"
    path.write_bytes(b"\x93NUMPY\x01\x00\x10\x00{'descr': 1}    ")
    with pytest.raises(MotionFormatError, match=rf"^{path}: not a readable NumPy array \(\w+\)$"):
        safe_arrays.load_npy(path)


def npz_of(path, members: dict, compression=zipfile.ZIP_STORED):
    with zipfile.ZipFile(path, "w", compression) as archive:
        for name, raw in members.items():
            archive.writestr(name, raw)
    return path


@pytest.mark.survivor
def test_npz_member_sizes_against_the_limit(tmp_path):
    member = io.BytesIO()
    np.save(member, np.zeros(1000))
    raw = member.getvalue()
    path = npz_of(tmp_path / "z.npz", {"a.npy": raw})
    size = len(raw)  # the zip directory's uncompressed size of the member
    data = size - 128
    assert data == 8000
    np.testing.assert_array_equal(safe_arrays.load_npz(path, limit=10_000)["a"], np.zeros(1000))
    with pytest.raises(MotionFormatError) as error:
        safe_arrays.load_npz(path, limit=size - 4096)
    assert str(error.value) == f"{path}: a.npy: declares 8,000 bytes of data (more than the {size - 4096:,} choreo reads)"
    with pytest.raises(MotionFormatError) as error:
        safe_arrays.load_npz(path, limit=size - 4097)
    assert str(error.value) == f"{path}: a.npy: {size:,} bytes uncompressed (more than choreo reads)"


@pytest.mark.survivor
def test_npz_damaged_members_are_named(tmp_path):
    forged = npz_of(tmp_path / "f.npz", {"b\nc.npy": npy_bytes("<f8", (100,), b"\0" * 80)})
    with pytest.raises(MotionFormatError) as error:
        safe_arrays.load_npz(forged)
    assert str(error.value) == f"{forged}: 'b\\nc.npy': declares 800 bytes of data but holds 80 (damaged or forged)"
    broken = npz_of(tmp_path / "h.npz", {"h.npy": b"\x93NUMPY\x01\x00\x10\x00{'descr': 1}    "})
    with pytest.raises(MotionFormatError, match=rf"^{broken}: h.npy: not a readable NumPy array \(\w+\)$"):
        safe_arrays.load_npz(broken)
    text = npz_of(tmp_path / "t.npz", {"t.npy": npy_bytes("<U1", (1,), (0x110000).to_bytes(4, "little"))})
    with pytest.raises(MotionFormatError) as error:
        safe_arrays.load_npz(text)
    assert str(error.value) == f"{text}: t.npy: text with characters beyond Unicode (damaged file)"
    member = io.BytesIO()
    np.save(member, np.arange(50.0))
    raw = member.getvalue()
    crc = npz_of(tmp_path / "c.npz", {"c.npy": raw})
    archive = bytearray(crc.read_bytes())
    archive[archive.index(raw[-16:]) + 8] ^= 0xFF  # stored data that no longer matches the zip's CRC
    crc.write_bytes(bytes(archive))
    with pytest.raises(MotionFormatError) as error:
        safe_arrays.load_npz(crc)
    assert str(error.value) == f"{crc}: c.npy: not a readable array (BadZipFile)"
    (tmp_path / "n.npz").write_bytes(b"not a zip")
    with pytest.raises(MotionFormatError) as error:
        safe_arrays.load_npz(tmp_path / "n.npz")
    assert str(error.value) == f"{tmp_path / 'n.npz'}: not a readable NPZ file (BadZipFile)"
    assert safe_arrays.printable("a b") == "a b" and safe_arrays.printable("a\tb") == "'a\\tb'"


# -- .npy headers numpy's tokenizer chokes on (TokenError, not ValueError) ------------------------
@pytest.mark.fuzz_finding
@pytest.mark.parametrize("header", ["{'descr': '<f8', 'fortran_order': False, 'shape': (2, 3",
                                    "{'descr': '<f8', 'fortran_order': False, 'shape': (2, 3))}"])
def test_an_unbalanced_npy_header_is_refused(tmp_path, header):
    path = tmp_path / "bad.npy"
    path.write_bytes(npy_with_header(header))
    with pytest.raises(MotionFormatError, match="not a readable NumPy array"):
        load_npy(path)
    with pytest.raises(MotionFormatError):
        read_joint_positions(path)
    npz = tmp_path / "bad.npz"
    with zipfile.ZipFile(npz, "w") as archive:
        archive.writestr("smpl_poses.npy", npy_with_header(header))
    with pytest.raises(MotionFormatError, match="not a readable NumPy array"):
        load_npz(npz)


@pytest.mark.fuzz_finding
def test_a_damaged_npy_version_does_not_make_numpy_read_gigabytes(tmp_path):
    """Version 1.255: numpy would read a 4-byte header length (2 GB here) and ask for that much."""
    data = bytearray(npy_with_header("{'descr': '<f8', 'fortran_order': False, 'shape': (2, 3), }"))
    data[7] = 0xFF
    data[10:12] = b"\x00\x7b"
    path = tmp_path / "v1_255.npy"
    path.write_bytes(bytes(data))
    with pytest.raises(MotionFormatError, match="version 1.255"):
        load_npy(path)
    data[6:8] = b"\x02\x00"  # a real version 2.0, whose 4-byte length field now says 2 GB
    path.write_bytes(bytes(data))
    with pytest.raises(MotionFormatError, match="header"):
        load_npy(path)


@pytest.mark.fuzz_finding
def test_npz_member_named_with_a_newline_gives_one_line(tmp_path):
    path = tmp_path / "n.npz"
    with zipfile.ZipFile(path, "w") as archive:
        archive.writestr("format\nversion.npy", b"\x93NUMPY damaged")
    with pytest.raises(MotionFormatError) as caught:
        load_npz(path)
    assert "\n" not in str(caught.value) and "format\\nversion" in str(caught.value)
