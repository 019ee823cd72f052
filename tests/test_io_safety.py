"""Safe outputs (issue 16): atomic files, no writing through links, umask modes, devices kept,
and the INCOMPLETE marker of output folders (deckpound._io)."""

from __future__ import annotations

import errno
import os
import socket
import stat

import numpy as np
import pytest

import deckpound._io as dio
from deckpound._io import (
    INCOMPLETE,
    atomic_path,
    atomic_write_files,
    atomic_write_text,
    ensure_folder,
    is_temporary,
    output_folder,
)
from deckpound.models.errors import SceneError
from deckpound.models.result import Result


def _temps(folder):
    return [p for p in folder.rglob("*") if is_temporary(p.name)]


@pytest.fixture
def umask():
    """Set a umask for one test and restore the previous one."""
    old = os.umask(0o022)
    os.umask(old)

    def set_(mask):
        os.umask(mask)

    yield set_
    os.umask(old)


@pytest.mark.parametrize("mask,mode", [(0o022, 0o644), (0o027, 0o640), (0o002, 0o664)])
def test_files_follow_the_umask(tmp_path, umask, mask, mode):
    """tempfile.mkstemp made every output 0600; outputs now get 0666 less the umask."""
    umask(mask)
    p = atomic_write_text(tmp_path / "a.txt", "x")
    assert stat.S_IMODE(p.stat().st_mode) == mode
    with atomic_path(tmp_path / "b.csv") as tmp:
        tmp.write_text("t\n0\n")
    assert stat.S_IMODE((tmp_path / "b.csv").stat().st_mode) == mode
    r = Result(engine="x", columns={"t": np.arange(3.0)})
    csv, js = r.write(tmp_path / "res")
    assert stat.S_IMODE(csv.stat().st_mode) == mode and stat.S_IMODE(js.stat().st_mode) == mode


def test_a_failed_write_keeps_the_old_file_and_leaves_no_temporary(tmp_path, monkeypatch):
    target = atomic_write_text(tmp_path / "t.csv", "old content\n")
    real = dio._write_fd

    def full_disk(fd, data):
        os.write(fd, bytes(data[:5]))
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(dio, "_write_fd", full_disk)
    with pytest.raises(OSError) as err:
        atomic_write_text(target, "new content that does not fit\n")
    assert err.value.errno == errno.ENOSPC and err.value.filename == str(target)
    assert target.read_text() == "old content\n" and not _temps(tmp_path)
    monkeypatch.setattr(dio, "_write_fd", real)
    atomic_write_text(target, "new\n")
    assert target.read_text() == "new\n"


def test_a_set_of_files_is_written_all_or_nothing(tmp_path, monkeypatch):
    """export on a nearly full disk left a record cut at 32,768 bytes: now no file changes."""
    files = {tmp_path / f"f{i}.txt": f"content {i}\n" * 1000 for i in range(4)}
    (tmp_path / "f0.txt").write_text("before\n")
    calls = []
    real = dio._write_fd

    def third_fails(fd, data):
        calls.append(len(data))
        if len(calls) == 3:
            raise OSError(errno.ENOSPC, "No space left on device")
        real(fd, data)

    monkeypatch.setattr(dio, "_write_fd", third_fails)
    with pytest.raises(OSError):
        atomic_write_files(files)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["f0.txt"]
    assert (tmp_path / "f0.txt").read_text() == "before\n"
    monkeypatch.setattr(dio, "_write_fd", real)
    atomic_write_files(files)
    assert all(p.read_text() == text for p, text in files.items())


def test_atomic_path_removes_a_half_written_library_file(tmp_path):
    target = atomic_write_text(tmp_path / "fig.png", "old")
    with pytest.raises(RuntimeError), atomic_path(target) as tmp:
        assert tmp.suffix == ".png" and tmp.parent == tmp_path  # format inferred from suffix
        tmp.write_bytes(b"half a png")
        raise RuntimeError("the renderer failed")
    assert target.read_text() == "old" and not _temps(tmp_path)


def test_symbolic_links_are_refused_and_their_targets_untouched(tmp_path):
    victim = tmp_path / "victim.txt"
    victim.write_text("precious\n")
    (tmp_path / "link.txt").symlink_to(victim)
    (tmp_path / "realdir").mkdir()
    (tmp_path / "linkdir").symlink_to(tmp_path / "realdir")
    for write in (
        lambda: atomic_write_text(tmp_path / "link.txt", "evil"),
        lambda: atomic_write_files({tmp_path / "link.txt": "evil"}),
        lambda: atomic_path(tmp_path / "link.txt").__enter__(),
        lambda: Result(engine="link", columns={"t": np.zeros(2)}).write(tmp_path / "linkdir"),
        lambda: ensure_folder(tmp_path / "linkdir"),
    ):
        with pytest.raises(SceneError, match="symbolic link"):
            write()
    assert victim.read_text() == "precious\n" and not list((tmp_path / "realdir").iterdir())


def test_folder_checks(tmp_path):
    (tmp_path / "afile").write_text("x")
    with pytest.raises(SceneError, match="is not a folder"):
        ensure_folder(tmp_path / "afile")
    with pytest.raises(SceneError, match="'.*afile' is a file, not a folder"):
        ensure_folder(tmp_path / "afile" / "below")
    with pytest.raises(SceneError, match="is a folder; give a file name"):
        atomic_write_text(tmp_path, "x")
    assert ensure_folder(tmp_path / "a" / "b").is_dir()


def test_devices_are_written_in_place_never_replaced():
    """Renaming over /dev/full would replace the device node with a regular file."""
    atomic_write_text("/dev/null", "discarded\n")
    with pytest.raises(OSError) as err:
        atomic_write_text("/dev/full", "no room\n")
    assert err.value.errno == errno.ENOSPC and err.value.filename == "/dev/full"
    for dev in ("/dev/null", "/dev/full"):
        assert stat.S_ISCHR(os.lstat(dev).st_mode)
    with atomic_path("/dev/null") as tmp:
        assert str(tmp) == "/dev/null"


# -- output folders ---------------------------------------------------------------------------


def test_output_folder_success_leaves_no_marker(tmp_path):
    with output_folder(tmp_path / "out", "test") as out:
        assert (out / INCOMPLETE).is_file()  # marked while the command runs
        assert "running" in (out / INCOMPLETE).read_text()
        atomic_write_text(out / "a.txt", "done")
    assert sorted(p.name for p in (tmp_path / "out").iterdir()) == ["a.txt"]


def test_output_folder_failure_before_any_output_leaves_no_folder(tmp_path):
    with pytest.raises(OSError), output_folder(tmp_path / "out", "test"):
        raise OSError(errno.EIO, "Input/output error")
    assert not (tmp_path / "out").exists()


def test_output_folder_failure_after_output_is_marked_then_resumed(tmp_path):
    out = tmp_path / "out"
    with pytest.raises(KeyboardInterrupt), output_folder(out, "paper"):
        atomic_write_text(out / "tables.csv", "t\n")
        raise KeyboardInterrupt
    marker = (out / INCOMPLETE).read_text()
    assert "failed" in marker and "paper: KeyboardInterrupt" in marker and "Re-run" in marker
    with output_folder(out, "paper"):  # the re-run finishes: the folder is complete
        pass
    assert not (out / INCOMPLETE).exists() and (out / "tables.csv").is_file()


def test_output_folder_keeps_the_entry_of_a_concurrent_live_command(tmp_path):
    out = ensure_folder(tmp_path / "out")
    other = (
        f"running abc123 pid={os.getpid()} host={socket.gethostname().split()[0]} paper started now"
    )
    atomic_write_text(out / INCOMPLETE, other + "\n")
    with output_folder(out, "paper"):
        pass
    assert (out / INCOMPLETE).read_text().strip().endswith(other)
    dead = other.replace(f"pid={os.getpid()}", "pid=999999999")
    atomic_write_text(out / INCOMPLETE, dead + "\n")
    with output_folder(out, "paper"):
        pass
    assert not (out / INCOMPLETE).exists()  # a dead command's entry is cleared


def test_output_folder_of_an_existing_user_folder_is_never_removed(tmp_path):
    out = ensure_folder(tmp_path / "mine")
    (out / "keep.txt").write_text("user data")
    with pytest.raises(OSError), output_folder(out, "run"):
        raise OSError(errno.ENOSPC, "No space left on device")
    assert (out / "keep.txt").read_text() == "user data"


def test_result_read_refuses_damaged_files(tmp_path):
    Result(engine="e", columns={"t": np.arange(3.0)}).write(tmp_path)
    (tmp_path / "e.json").write_text('{"engine": ')
    with pytest.raises(SceneError, match="e.json is not valid JSON"):
        Result.read(tmp_path, "e")
    (tmp_path / "e.json").write_text("[]")
    with pytest.raises(SceneError, match="must hold an object"):
        Result.read(tmp_path, "e")
    (tmp_path / "e.json").write_text("{}")
    (tmp_path / "e.csv").write_bytes(b"")
    with pytest.raises(SceneError, match="e.csv is not a table of numbers"):
        Result.read(tmp_path, "e")
