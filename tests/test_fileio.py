"""Tests of choreo.fileio: issue 38, items 3, 4, 5 and a full disk from 8: where an output goes, with what permissions,
and what ffmpeg is handed to read.

3. A symlink at an output is followed only as the kernel's ``fs.protected_symlinks`` would: in a
   sticky world-writable folder, only a link owned by us or by the folder's owner.
4. A new output gets the umask's permissions, a replaced one keeps those of the file it replaces.
5. The music reaches ffmpeg as ``file:`` and an absolute path, and only if it is a regular file.
8. No room to write (here a real ``ulimit -f``) is exit 3 with one line.


Markers say where a test came from: hardening (pyproject.toml, tests/README.md)."""

import os
import resource
import stat
import subprocess
import sys
from pathlib import Path

import pytest

from choreo.fileio import atomic_output, atomic_path
from tests.outputs import run

OTHER_USER = 54321


as_root = pytest.mark.skipif(os.geteuid() != 0, reason="planting a link owned by another user needs root")


def shared_folder(parent: Path, owner: int | None = None) -> Path:
    """A folder like /tmp: sticky and writable by everyone."""
    folder = parent / "shared"
    folder.mkdir()
    folder.chmod(0o1777)
    if owner is not None:
        os.chown(folder, owner, owner)
    return folder


def plant_link(folder: Path, target: Path, owner: int | None) -> Path:
    link = folder / "dance.bvh"
    link.symlink_to(target)
    if owner is not None:
        os.lchown(link, owner, owner)
    return link


@pytest.mark.hardening
@as_root
@pytest.mark.parametrize("chain", [False, True])
def test_a_link_planted_by_another_user_in_a_shared_folder_is_not_followed(tmp_path, source, capsys, chain):
    victim = tmp_path / "victim.bvh"
    victim.write_bytes(b"the other user's file")
    folder = shared_folder(tmp_path)
    link = plant_link(folder, victim, OTHER_USER)
    if chain:  # our own link to theirs: every link on the way is checked, as the kernel does
        (folder / "mine.bvh").symlink_to(link)
        link = folder / "mine.bvh"
    code, lines = run(capsys, "convert", source, link)
    assert code == 3 and len(lines) == 1 and "protected_symlinks" in lines[0], lines
    assert victim.read_bytes() == b"the other user's file" and link.is_symlink()
    assert sorted(p.name for p in folder.iterdir()) == sorted({link.name, "dance.bvh"})


@pytest.mark.hardening
@as_root
@pytest.mark.parametrize("link_owner, folder_owner", [(None, None), (OTHER_USER, OTHER_USER)])
def test_a_link_of_ours_or_of_the_folders_owner_is_written_through(tmp_path, source, capsys, link_owner, folder_owner):
    target = tmp_path / "target.bvh"
    target.write_bytes(b"old")
    link = plant_link(shared_folder(tmp_path, folder_owner), target, link_owner)
    code, lines = run(capsys, "convert", source, link)
    assert code == 0, lines
    assert link.is_symlink() and target.read_bytes().startswith(b"HIERARCHY")


@pytest.mark.hardening
def test_links_outside_shared_folders_are_followed_relative_to_their_folder(tmp_path, source, capsys):
    (tmp_path / "real").mkdir()
    (tmp_path / "real" / "dance.bvh").write_bytes(b"old")
    (tmp_path / "links").mkdir()
    (tmp_path / "links" / "dance.bvh").symlink_to(Path("..") / "real" / "dance.bvh")
    code, lines = run(capsys, "convert", source, tmp_path / "links" / "dance.bvh")
    assert code == 0, lines
    assert (tmp_path / "real" / "dance.bvh").read_bytes().startswith(b"HIERARCHY")


@pytest.mark.hardening
def test_a_loop_of_links_is_one_output_error(tmp_path, source, capsys):
    (tmp_path / "a.bvh").symlink_to("b.bvh")
    (tmp_path / "b.bvh").symlink_to("a.bvh")
    code, lines = run(capsys, "convert", source, tmp_path / "a.bvh")
    assert code == 3 and len(lines) == 1 and "links" in lines[0], lines


@pytest.fixture
def umask():
    """Set the umask for one test and put the old one back."""
    before = os.umask(0o022)
    yield os.umask
    os.umask(before)


@pytest.mark.hardening
@pytest.mark.parametrize("mask, mode", [(0o077, 0o600), (0o002, 0o664), (0o022, 0o644)])
def test_a_new_output_gets_the_umasks_permissions(tmp_path, source, capsys, umask, mask, mode):
    umask(mask)
    assert run(capsys, "convert", source, tmp_path / "new.npz")[0] == 0
    assert stat.S_IMODE(os.stat(tmp_path / "new.npz").st_mode) == mode


@pytest.mark.hardening
@pytest.mark.parametrize("mode", [0o600, 0o640, 0o664])
def test_a_replaced_output_keeps_its_permissions(tmp_path, source, capsys, umask, mode):
    umask(0o022)
    old = tmp_path / "old.bvh"
    old.write_bytes(b"private")
    old.chmod(mode)
    assert run(capsys, "convert", source, old)[0] == 0
    assert old.read_bytes().startswith(b"HIERARCHY") and stat.S_IMODE(os.stat(old).st_mode) == mode


@pytest.mark.hardening
def test_every_atomic_writer_applies_the_same_permissions(tmp_path, umask):
    """Writers that hand the temporary path to another program (ffmpeg, Blender, matplotlib) too."""
    umask(0o027)
    with atomic_output(tmp_path / "a.bin") as handle:
        handle.write(b"x")
    with atomic_path(tmp_path / "b.bin") as temporary:
        temporary.write_bytes(b"x")
        temporary.chmod(0o755)  # what the other program left does not count
    assert [stat.S_IMODE(os.stat(tmp_path / name).st_mode) for name in ("a.bin", "b.bin")] == [0o640, 0o640]


@pytest.mark.hardening
@pytest.mark.parametrize("make", [os.mkfifo, os.mkdir])
def test_music_that_is_not_a_regular_file_is_refused_before_any_work(tmp_path, source, capsys, make):
    make(tmp_path / "song.wav")
    code, lines = run(capsys, "render", source, "--music", tmp_path / "song.wav", "-o", tmp_path / "out.mp4")
    assert code == 2 and len(lines) == 1 and "not a regular file" in lines[0], lines
    assert not (tmp_path / "out.mp4").exists()


@pytest.mark.hardening
def test_a_full_disk_is_an_output_error_with_one_line(tmp_path, source):
    """``ulimit -f`` makes the kernel refuse the write (EFBIG) as a full disk would (ENOSPC)."""
    def small_files():
        resource.setrlimit(resource.RLIMIT_FSIZE, (20_000, 20_000))

    done = subprocess.run([sys.executable, "-m", "choreo", "convert", str(source), "big.bvh", "--fps", "120"],
                          cwd=tmp_path, capture_output=True, text=True, preexec_fn=small_files,
                          env={**os.environ, "PYTHONDONTWRITEBYTECODE": "1"})
    lines = [line for line in done.stderr.splitlines() if line.strip()]
    assert done.returncode == 3 and len(lines) == 1 and lines[0].startswith("choreo: error: cannot write"), lines
    assert sorted(p.name for p in tmp_path.iterdir()) == ["source.bvh"]


@pytest.mark.hardening
@pytest.mark.parametrize("command", ["generate", "render"])
def test_a_preview_past_the_disk_names_the_users_file_and_the_reason(tmp_path, source, command):
    """ffmpeg writes the video: past ``ulimit -f`` it is killed (SIGXFSZ), on a full disk it says
    so in its own words; either way one line naming the user's file, as choreo's own writers give."""
    limit = 400_000 if command == "generate" else 20_000  # the dance (100 KB) fits, its video (1 MB) does not

    def small_files():
        resource.setrlimit(resource.RLIMIT_FSIZE, (limit, limit))

    song = Path(__file__).parents[1] / "examples" / "drum_and_bass_174bpm.wav"
    args = (["generate", str(song), "-o", "dance.npy", "--steps", "2", "--threads", "1", "--preview"]
            if command == "generate" else ["render", str(source), "-o", "dance.mp4"])
    done = subprocess.run([sys.executable, "-m", "choreo", *args], cwd=tmp_path, capture_output=True, text=True,
                          preexec_fn=small_files, env={**os.environ, "CHOREO_CACHE_DIR": str(tmp_path / "cache")})
    lines = [line for line in done.stderr.splitlines() if line.strip()]
    assert done.returncode == 3 and lines[-1] == "choreo: error: cannot write dance.mp4: File too large", lines
    assert not [p.name for p in tmp_path.iterdir() if p.name != "cache" and p.name != "source.bvh"]


@pytest.mark.hardening
@pytest.mark.parametrize("follow_links", [True, False])
def test_a_link_is_written_through_only_when_links_are_followed(tmp_path, follow_links):
    victim, link = tmp_path / "victim.txt", tmp_path / "entry.npz"
    victim.write_bytes(b"precious")
    victim.chmod(0o600)
    link.symlink_to(victim)
    with atomic_output(link, follow_links=follow_links) as handle:
        handle.write(b"new")
    if follow_links:  # an output the user named: written through, the link kept
        assert link.is_symlink() and victim.read_bytes() == b"new"
    else:  # the link is replaced by a new file with the default mode; the victim is untouched
        assert not link.is_symlink() and link.read_bytes() == b"new" and victim.read_bytes() == b"precious"
        assert stat.S_IMODE(link.stat().st_mode) == 0o666 & ~os.umask(os.umask(0o022))
