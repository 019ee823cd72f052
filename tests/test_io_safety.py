"""Safe outputs (issue 16): atomic files, no writing through links, umask modes, devices kept,
and the INCOMPLETE marker of output folders (deckpound.models.file_io); temporaries of killed writes
removed and one command per output folder (issue 28)."""

from __future__ import annotations

import errno
import os
import signal
import socket
import stat
import subprocess
import sys

import numpy as np
import pytest

import deckpound.models.file_io as dio
from deckpound.cli import main as cli_main
from deckpound.models.errors import SceneError
from deckpound.models.file_io import (
    INCOMPLETE,
    LOCK_FILE,
    atomic_path,
    atomic_write_files,
    atomic_write_text,
    claim_folder,
    command_scope,
    ensure_folder,
    is_temporary,
    output_folder,
)
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

    def full_disk(fd, data, **_):
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

    def third_fails(fd, data, **kw):
        calls.append(len(data))
        if len(calls) == 3:
            raise OSError(errno.ENOSPC, "No space left on device")
        real(fd, data, **kw)

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


# -- temporaries of killed writes, one command per folder (issue 28) ------------------------

# a child process that writes a file through deckpound.models.file_io and stops inside the write:
# "kill" dies there (SIGKILL to itself: the child, never the test runner), "wait" waits for a
# line on stdin and then finishes the write
WRITER = r"""
import os, signal, sys
from deckpound.models.file_io import atomic_path
with atomic_path(sys.argv[1]) as tmp:
    tmp.write_bytes(b"t,x\n" * 1000)
    print(tmp.name, flush=True)
    if sys.argv[2] == "kill":
        os.kill(os.getpid(), signal.SIGKILL)
    sys.stdin.readline()
"""


def _writer(target, how):
    proc = subprocess.Popen(
        [sys.executable, "-c", WRITER, str(target), how],
        stdin=subprocess.PIPE,
        stdout=subprocess.PIPE,
        text=True,
    )
    return proc, proc.stdout.readline().strip()


def test_temporaries_of_killed_writes_are_removed_by_the_next_write(tmp_path):
    """A SIGKILL during a write left a 30 MB '.…deckpound-tmp.csv' that no later command
    removed; the next write into the folder removes it, never a live writer's temporary."""
    out = ensure_folder(tmp_path / "out")
    killed, dead_name = _writer(out / "opensees.csv", "kill")
    assert killed.wait(timeout=120) == -signal.SIGKILL and (out / dead_name).is_file()
    killed.communicate(timeout=60)  # closes its pipes
    live, live_name = _writer(out / "other.csv", "wait")
    dead_pid = dead_name.split(".")[-3].split("-")[0]
    # the same dead writer: a name from before the host tag, and one from another host
    old_style = f".a.csv.{dead_pid}-0123abcd.deckpound-tmp.csv"
    tag = dead_name.split(".")[-3].split("-")[1]
    foreign = f".b.csv.{dead_pid}-{'0' if tag[0] != '0' else '1'}{tag[1:]}-0123abcd.deckpound-tmp"
    user_file = "notes.deckpound-tmp.txt"  # not deckpound's pattern: the user's own file
    for name in (old_style, foreign, user_file):
        (out / name).write_text("x")
    try:
        code = cli_main(
            ["run", "saiidi-4span", "--set", "excitation.duration=0.3", "--engine", "nonsmooth"]
            + ["-o", str(out)]
        )
        assert code == 0
        left = {p.name for p in out.iterdir()}
        assert dead_name not in left and old_style not in left
        assert {live_name, foreign, user_file} <= left and "nonsmooth.csv" in left
    finally:
        live.communicate("\n", timeout=120)
        live.stdout.close()
    assert live.returncode == 0 and (out / "other.csv").is_file()  # its write finished
    assert live_name not in {p.name for p in out.iterdir()}


HOLDER = r"""
import sys
from deckpound.models.file_io import claim_folder, command_scope
with command_scope("deckpound run saiidi-4span --set deck.mass=99 -o " + sys.argv[1]):
    claim_folder(sys.argv[1])
    print("held", flush=True)
    sys.stdin.readline()
"""
TINY = ("--set", "excitation.duration=0.3")
FOLDER_COMMANDS = {  # every command that writes an output folder ({out}; {tmp}: the test's)
    "run": ("run", "saiidi-4span", *TINY, "--engine", "nonsmooth", "-o", "{out}"),
    "compare": ("compare", "saiidi-4span", *TINY, "--engines", "nonsmooth", "-o", "{out}"),
    "study": ("study", "friction", "saiidi-4span", "--quick", "-o", "{out}"),
    "variability": ("study", "variability", "saiidi-4span", "--quick", "-o", "{out}"),
    "paper": ("paper", "--quick", *TINY, "-o", "{out}"),
    "export": ("export", "saiidi-4span", *TINY, "--format", "tcl", "-o", "{out}/m.tcl"),
    "export-vtk": ("export-vtk", "{tmp}/res", "-o", "{out}"),
    "bench": ("bench", "--quick", "-o", "{out}"),
    "stress": ("stress", "--quick", "-o", "{out}"),
}


@pytest.mark.parametrize("command", list(FOLDER_COMMANDS))
def test_a_folder_in_use_is_refused_naming_its_holder(tmp_path, command, capsys):
    """Two commands on one output folder both exited 0 and the last writer won silently: a
    second command is refused (exit 2) naming the first's command line and PID, and writes
    nothing; once the holder has ended, the same command runs."""
    out = tmp_path / "out"
    holder = subprocess.Popen(
        [sys.executable, "-c", HOLDER, str(out)],
        stdin=subprocess.PIPE,
        stdout=subprocess.PIPE,
        text=True,
    )
    try:
        assert holder.stdout.readline().strip() == "held"
        argv = [a.format(out=out, tmp=tmp_path) for a in FOLDER_COMMANDS[command]]
        capsys.readouterr()
        code = cli_main(argv)
        err = capsys.readouterr().err
        left = sorted(p.name for p in out.iterdir())
    finally:
        holder.communicate("\n", timeout=60)
    assert code == 2, err
    lines = err.splitlines()
    assert len(lines) == 1 and lines[0].startswith("deckpound: error: --output: "), err
    assert f"is in use by 'deckpound run saiidi-4span --set deck.mass=99 -o {out}'" in err
    assert f"(PID {holder.pid}, started " in err
    assert left == [LOCK_FILE]  # the holder's, untouched
    assert holder.returncode == 0 and not out.exists()  # the holder created it, then removed it


def test_a_lock_held_by_the_test_process_stops_a_real_command(tmp_path):
    """The lock holds between processes (the CLI in a subprocess, this process holding the
    folder with the same function); released, the folder is free again and no lock file is
    left."""
    out = tmp_path / "out"
    argv = [sys.executable, "-m", "deckpound", *FOLDER_COMMANDS["run"]]
    argv = [a.format(out=out) for a in argv]
    with command_scope("deckpound paper --quick -o out"):
        claim_folder(out)
        p = subprocess.run(argv, capture_output=True, text=True, timeout=300, check=False)
        assert p.returncode == 2, p.stderr
        assert f"in use by 'deckpound paper --quick -o out' (PID {os.getpid()}," in p.stderr
        assert sorted(x.name for x in out.iterdir()) == [LOCK_FILE]
    assert not out.exists()  # created for the claim, empty, removed with it
    p = subprocess.run(argv, capture_output=True, text=True, timeout=300, check=False)
    assert p.returncode == 0 and p.stderr == "", p.stderr
    assert sorted(x.name for x in out.iterdir()) == ["nonsmooth.csv", "nonsmooth.json"]


def test_a_lock_left_by_a_killed_command_is_taken_over_with_a_warning(tmp_path):
    out = ensure_folder(tmp_path / "out")
    killed = subprocess.Popen([sys.executable, "-c", "pass"])
    killed.wait()
    host = socket.gethostname().split()[0]
    (out / LOCK_FILE).write_text(
        f"pid={killed.pid} host={host} started=2020-01-01T00:00:00 command=deckpound compare x\n"
    )
    took_over = rf"'deckpound compare x' \(PID {killed.pid}, .*ended without releasing it"
    with pytest.warns(UserWarning, match=took_over), output_folder(out, "run"):
        assert (out / LOCK_FILE).read_text().startswith(f"pid={os.getpid()} ")
    assert sorted(p.name for p in out.iterdir()) == []


KILLED_WITH_A_WORKER = r"""
import multiprocessing, os, signal, sys, time
from deckpound.models.file_io import claim_folder, command_scope


def work(started):
    started.set()
    time.sleep(120)


with command_scope("deckpound compare x -o out"):
    claim_folder(sys.argv[1])
    started = multiprocessing.get_context("fork").Event()
    worker = multiprocessing.get_context("fork").Process(target=work, args=(started,))
    worker.start()
    started.wait()  # the fork's hooks have run in the worker (a busy machine may lag)
    print(worker.pid, flush=True)
    os.kill(os.getpid(), signal.SIGKILL)  # this child process dies; its worker runs on
"""


def test_a_worker_left_by_a_killed_command_does_not_hold_its_folder(tmp_path):
    """A forked worker shares its parent's lock descriptor; it closes its copy, so a command
    killed while its workers run frees the folder at once (taken over with a warning)."""
    out = tmp_path / "out"
    parent = subprocess.Popen(
        [sys.executable, "-c", KILLED_WITH_A_WORKER, str(out)], stdout=subprocess.PIPE, text=True
    )
    worker = int(parent.stdout.readline())
    parent.stdout.close()  # the worker holds the pipe's other end: no waiting for its end
    assert parent.wait(timeout=120) == -signal.SIGKILL
    try:
        os.kill(worker, 0)  # still running
        with command_scope("deckpound run y"), pytest.warns(UserWarning, match="taking it over"):
            claim_folder(out)
    finally:
        os.kill(worker, signal.SIGKILL)
    assert list(out.iterdir()) == []  # the killed command's lock file went with the new claim


def test_a_held_folder_whose_lock_file_went_is_locked_afresh(tmp_path):
    """A claim is known by the folder's (device, inode); a removed folder's inode can be given
    to a new folder. The claim must then not be taken for the new folder's lock: a claim whose
    lock file is no longer in the folder is dropped and the folder locked again (the removed
    lock file stands for the removed folder, which no file system reuses on demand)."""
    with command_scope("deckpound run x"):
        out = claim_folder(ensure_folder(tmp_path / "out"))
        (out / LOCK_FILE).unlink()
        claim_folder(out)
        assert (out / LOCK_FILE).read_text().startswith(f"pid={os.getpid()} ")
    assert list(out.iterdir()) == []  # released: the new lock file is removed


def test_an_export_to_a_device_or_pipe_is_refused(tmp_path, capsys):
    """An export writes its data folder beside the script: to /dev/null that folder would be
    /dev/null_data. A pipe is refused the same way (the export is one file plus a folder)."""
    fifo = tmp_path / "pipe.py"
    os.mkfifo(fifo)
    for target in ("/dev/null", str(fifo)):
        assert cli_main(["export", "saiidi-4span", "--format", "py", "-o", target]) == 2
        assert "device or a pipe" in capsys.readouterr().err
    assert not os.path.exists("/dev/null_data") and not (tmp_path / "pipe_data").exists()


def test_an_atomic_write_is_flushed_to_the_disk(tmp_path, monkeypatch):
    """A result file is flushed (fsync) before its rename; only a sweep's row log, read back
    line by line, is appended without a flush (deckpound.compare.row_log)."""
    flushed = []
    real_fsync = os.fsync
    monkeypatch.setattr(os, "fsync", lambda fd: flushed.append(fd) or real_fsync(fd))
    result = atomic_write_text(tmp_path / "result.json", "{}")
    assert result.read_text() == "{}" and len(flushed) == 1 and not _temps(tmp_path)
