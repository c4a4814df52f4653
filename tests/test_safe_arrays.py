"""NumPy files whose headers lie about their size are refused before anything is allocated."""

import io
import zipfile

import numpy as np
import pytest

from choreo.errors import MotionFormatError
from choreo.formats.safe_arrays import load_npy, load_npz


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
