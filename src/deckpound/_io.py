"""Safe output files and folders: atomic, never through a symbolic link, with the user's umask.

Every file a deckpound command writes goes through this module, for three promises:

* **Atomic.** A file is written to a temporary file in the target folder, flushed to disk and
  renamed over the target (:func:`atomic_write_bytes`, :func:`atomic_write_text`, and
  :func:`atomic_path` for libraries that want a file name, e.g. matplotlib, pandas, meshio).
  A reader sees the old file or the new one, never half of one; an error, a full disk or
  Ctrl-C removes the temporary file. :func:`atomic_write_files` writes a *set* of files all
  or nothing (every temporary file first, then the renames, which need no space).
* **Never through a link.** A target file or an output folder that is a symbolic link is
  refused (:class:`~deckpound.models.errors.SceneError`, exit status 2): writing through it
  would overwrite whatever the link points to. Folders *above* the named output are the
  user's business (system layouts link ``/tmp`` and home folders).
* **Devices stay devices.** An existing character device or pipe (``/dev/null``, ``/dev/full``,
  a named pipe) is written in place: renaming over it would replace the device node.
* **The user's umask.** Files are created with mode ``0o666`` and folders with ``0o777``,
  both reduced by the umask, like any other program's (``tempfile.mkstemp`` would make them
  readable by their owner only).

:func:`output_folder` wraps a whole command whose output is a folder: while it runs, the
folder holds a marker file ``INCOMPLETE`` naming the command; on success the marker is
removed, on failure it stays (with the reason), so a half-finished folder is never mistaken
for a result, and re-running the command resumes (finished cases come from the cache) and
removes it. A folder the command created and left empty is removed instead. The marker is
shared safely by concurrent commands on one folder (``flock`` on the folder).
"""

from __future__ import annotations

import contextlib
import errno
import fcntl
import os
import secrets
import shutil
import socket
import stat
import time
from collections.abc import Iterator
from pathlib import Path

from deckpound.models.errors import SceneError

#: name of the marker file of an unfinished output folder
INCOMPLETE = "INCOMPLETE"
_TMP_TAG = ".deckpound-tmp"


def is_temporary(name: str) -> bool:
    """True for the names of this module's temporary files and folders."""
    return _TMP_TAG in name


def _tmp_name(path: Path) -> Path:
    """A fresh temporary name beside ``path`` that keeps its suffix (matplotlib and pandas
    choose the format from it)."""
    token = f"{os.getpid()}-{secrets.token_hex(4)}"
    return path.with_name(f".{path.name}.{token}{_TMP_TAG}{path.suffix}")


def check_target(path: str | Path, field: str = "--output") -> Path:
    """Refuse a target file that is a symbolic link, a folder, a block device or a socket;
    return it as a Path. (A character device or a pipe, e.g. /dev/null, is written directly.)"""
    _kind(Path(path), field)
    return Path(path)


def _kind(path: Path, field: str) -> str:
    """``"absent"``, ``"file"`` (regular) or ``"stream"`` (character device or pipe: written
    in place, since renaming over it would replace the device); anything else is refused."""
    try:
        st = os.lstat(path)
    except FileNotFoundError:
        return "absent"
    except NotADirectoryError:
        return "absent"  # below a file: check_parent names the problem
    if stat.S_ISLNK(st.st_mode):
        raise SceneError(
            field,
            f"{str(path)!r} is a symbolic link (to {os.readlink(path)!r}); "
            "deckpound never writes through links: remove it or give another name",
        )
    if stat.S_ISDIR(st.st_mode):
        raise SceneError(field, f"{str(path)!r} is a folder; give a file name")
    if stat.S_ISREG(st.st_mode):
        return "file"
    if stat.S_ISCHR(st.st_mode) or stat.S_ISFIFO(st.st_mode):
        return "stream"
    raise SceneError(field, f"{str(path)!r} is a block device or a socket, not a file")


def _write_stream(path: Path, data: bytes) -> None:
    """Write into an existing character device or pipe (no temporary file, no rename)."""
    fd = os.open(path, os.O_WRONLY | getattr(os, "O_CLOEXEC", 0))
    try:
        view = memoryview(data)
        while view:
            view = view[os.write(fd, view) :]
    except OSError as err:
        raise OSError(err.errno, err.strerror, str(path)) from None
    finally:
        os.close(fd)


def check_parent(path: str | Path, field: str = "--output") -> None:
    """Refuse a path below a regular file (it can never be created)."""
    path = Path(path)
    for parent in path.parents:
        if parent.exists() or parent.is_symlink():
            if not parent.is_dir():
                raise SceneError(
                    field, f"cannot write {str(path)!r}: {str(parent)!r} is a file, not a folder"
                )
            return


def ensure_folder(path: str | Path, field: str = "--output") -> Path:
    """Create folder ``path`` (and its parents) unless it exists; refuse a symbolic link, a
    file in its place, or a file among its parents."""
    path = Path(path)
    if path.is_symlink():
        raise SceneError(
            field,
            f"{str(path)!r} is a symbolic link (to {os.readlink(path)!r}); "
            "deckpound never writes through links: give the real folder",
        )
    if path.exists() and not path.is_dir():
        raise SceneError(field, f"{str(path)!r} exists and is not a folder")
    check_parent(path, field)
    path.mkdir(parents=True, exist_ok=True)
    return path


def _write_fd(fd: int, data: bytes) -> None:
    view = memoryview(data)
    while view:
        n = os.write(fd, view)
        view = view[n:]
    os.fsync(fd)


def _write_temporary(path: Path, data: bytes) -> Path:
    """``data`` in a new temporary file beside ``path`` (mode 0o666 less the umask)."""
    tmp = _tmp_name(path)
    try:
        fd = os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL | getattr(os, "O_CLOEXEC", 0), 0o666)
    except OSError as err:  # name the file the user asked for, not the temporary one
        raise OSError(err.errno, err.strerror, str(path)) from None
    try:
        _write_fd(fd, data)
    except BaseException as err:
        os.close(fd)
        _unlink_quietly(tmp)
        if isinstance(err, OSError) and err.filename is None:  # name the file, not the fd
            raise OSError(err.errno, err.strerror, str(path)) from None
        raise
    os.close(fd)
    return tmp


def _unlink_quietly(path: Path) -> None:
    with contextlib.suppress(OSError):
        os.unlink(path)


def atomic_write_bytes(path: str | Path, data: bytes, *, field: str = "--output") -> Path:
    """Write ``data`` to ``path`` atomically (temporary file, fsync, rename)."""
    path = Path(path)
    if _kind(path, field) == "stream":
        _write_stream(path, data)
        return path
    check_parent(path, field)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = _write_temporary(path, data)
    try:
        os.replace(tmp, path)
    except BaseException:
        _unlink_quietly(tmp)
        raise
    return path


def atomic_write_text(path: str | Path, text: str, *, field: str = "--output") -> Path:
    """Write ``text`` (UTF-8) to ``path`` atomically."""
    return atomic_write_bytes(path, text.encode("utf-8"), field=field)


def atomic_write_files(files: dict[Path, str | bytes], *, field: str = "--output") -> list[Path]:
    """Write several files all or nothing: every temporary file is written first (a full disk
    leaves no file changed), then each is renamed into place."""
    targets = [Path(p) for p in files]
    kinds = [_kind(p, field) for p in targets]
    for p in targets:
        check_parent(p, field)
        p.parent.mkdir(parents=True, exist_ok=True)
    datas = [c.encode("utf-8") if isinstance(c, str) else c for c in files.values()]
    temps: list[Path] = []
    renames: list[tuple[Path, Path]] = []
    try:
        for p, kind, data in zip(targets, kinds, datas):
            if kind != "stream":
                tmp = _write_temporary(p, data)
                temps.append(tmp)
                renames.append((tmp, p))
        for p, kind, data in zip(targets, kinds, datas):
            if kind == "stream":
                _write_stream(p, data)
        for tmp, p in renames:
            os.replace(tmp, p)
    finally:
        for tmp in temps:
            if tmp.exists():
                _unlink_quietly(tmp)
    return targets


@contextlib.contextmanager
def atomic_path(path: str | Path, *, field: str = "--output") -> Iterator[Path]:
    """A temporary file name beside ``path`` for a library to write; renamed to ``path`` when
    the block ends without error, removed otherwise.

    >>> with atomic_path("fig.png") as tmp:   # doctest: +SKIP
    ...     fig.savefig(tmp)
    """
    path = Path(path)
    if _kind(path, field) == "stream":
        yield path  # a device or pipe: the library writes into it directly
        return
    check_parent(path, field)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = _tmp_name(path)
    try:
        try:
            yield tmp
        except OSError as err:
            if err.filename is not None and os.fspath(err.filename) == str(tmp):
                raise OSError(err.errno, err.strerror, str(path)) from None
            raise
        if not tmp.is_file():
            raise OSError(errno.ENOENT, "the writer produced no file", str(path))
        with open(tmp, "rb+") as fh:  # flush to disk before the rename makes it visible
            os.fsync(fh.fileno())
        os.replace(tmp, path)
    finally:
        if tmp.exists() or tmp.is_symlink():
            _unlink_quietly(tmp)


def write_csv(frame, path: str | Path, **kwargs) -> Path:
    """``frame.to_csv(path, index=False, **kwargs)`` atomically."""
    kwargs.setdefault("index", False)
    with atomic_path(path) as tmp:
        frame.to_csv(tmp, **kwargs)
    return Path(path)


# -- the INCOMPLETE marker of an output folder ----------------------------------------------


@contextlib.contextmanager
def _folder_lock(folder: Path) -> Iterator[None]:
    """An exclusive ``flock`` on the folder itself (no lock file left behind)."""
    fd = os.open(folder, os.O_RDONLY | getattr(os, "O_DIRECTORY", 0))
    try:
        fcntl.flock(fd, fcntl.LOCK_EX)
        yield
    finally:
        os.close(fd)  # releases the lock


def _pid_alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True


def _entries(marker: Path) -> list[str]:
    try:
        text = marker.read_text(encoding="utf-8", errors="replace")
    except FileNotFoundError:
        return []
    return [line for line in text.splitlines() if line.strip()]


def _still_running(line: str, host: str) -> bool:
    """A marker line of a command that is still running (same host, process alive)."""
    parts = line.split()
    if len(parts) < 4 or parts[0] != "running":
        return False
    fields = dict(p.split("=", 1) for p in parts[2:4] if "=" in p)
    if fields.get("host") != host:
        return True  # another machine (shared folder): cannot tell, keep it
    try:
        return _pid_alive(int(fields.get("pid", "0")))
    except ValueError:
        return False


class _Marker:
    """The ``INCOMPLETE`` file of one output folder, shared by concurrent commands.

    One line per command: ``running TOKEN pid=P host=H COMMAND started TIME``, turned into
    ``failed TOKEN ... REASON`` when it fails. A command that finishes removes its own line and
    every line of commands that failed or died; the file goes when no line is left.
    """

    HEADER = (
        "# deckpound: this folder is incomplete: a command writing it has not finished "
        "(or failed). Re-run it to resume; finished cases come from the cache."
    )

    def __init__(self, folder: Path, command: str):
        self.path = folder / INCOMPLETE
        self.folder = folder
        self.token = secrets.token_hex(6)
        self.host = socket.gethostname().split()[0] if socket.gethostname() else "localhost"
        self.command = " ".join(command.split()) or "deckpound"

    def _write(self, lines: list[str]) -> None:
        body = [ln for ln in lines if not ln.startswith("#")]
        if body:
            atomic_write_text(self.path, "\n".join([self.HEADER] + body) + "\n")
        elif self.path.exists() and not self.path.is_symlink():
            _unlink_quietly(self.path)

    def start(self) -> None:
        stamp = time.strftime("%Y-%m-%dT%H:%M:%S")
        with _folder_lock(self.folder):
            lines = _entries(self.path)
            lines.append(
                f"running {self.token} pid={os.getpid()} host={self.host} "
                f"{self.command} started {stamp}"
            )
            self._write(lines)

    def fail(self, reason: str) -> None:
        reason = " ".join(reason.split())[:300]
        with _folder_lock(self.folder):
            lines = [
                f"failed {self.token} {self.command}: {reason}" if f" {self.token} " in ln else ln
                for ln in _entries(self.path)
            ]
            self._write(lines)

    def finish(self) -> None:
        with _folder_lock(self.folder):
            keep = [
                ln
                for ln in _entries(self.path)
                if f" {self.token} " not in ln and _still_running(ln, self.host)
            ]
            self._write(keep)


def _holds_only_marker(folder: Path) -> bool:
    for root, _dirs, files in os.walk(folder):
        if any(not (Path(root) == folder and f == INCOMPLETE) for f in files):
            return False
    return True


@contextlib.contextmanager
def output_folder(path: str | Path, command: str, *, field: str = "--output") -> Iterator[Path]:
    """The output folder of one command (see the module docstring): created if needed (a
    symbolic link or a file in its place refused), marked ``INCOMPLETE`` while the block
    runs, unmarked on success; on failure marked with the reason, or removed if this command
    created it and wrote nothing into it."""
    path = Path(path)
    existed = path.exists() or path.is_symlink()
    folder = ensure_folder(path, field)
    marker = _Marker(folder, command)
    try:
        marker.start()
    except BaseException:
        if not existed:
            shutil.rmtree(folder, ignore_errors=True)
        raise
    try:
        yield folder
    except BaseException as err:
        reason = f"{type(err).__name__}: {err}" if str(err) else type(err).__name__
        with contextlib.suppress(OSError):
            marker.fail(reason)
        if not existed:
            with contextlib.suppress(OSError):
                _remove_if_unused(folder, marker)
        raise
    marker.finish()


def _remove_if_unused(folder: Path, marker: _Marker) -> None:
    """Remove a folder this command created if it holds nothing but the marker and no other
    command is writing into it."""
    with _folder_lock(folder):
        others = [ln for ln in _entries(marker.path) if ln.startswith("running")]
        if _holds_only_marker(folder) and not any(_still_running(ln, marker.host) for ln in others):
            shutil.rmtree(folder)
