"""Safe output files and folders: atomic, never through a symbolic link, with the user's umask.

Every file a deckpound command writes goes through this module, for three promises:

* **Atomic.** A file is written to a temporary file in the target folder, flushed to disk and
  renamed over the target (:func:`atomic_write_bytes`, :func:`atomic_write_text`, and
  :func:`atomic_path` for libraries that want a file name, e.g. matplotlib, pandas, meshio).
  A reader sees the old file or the new one, never half of one; an error, a full disk or
  Ctrl-C removes the temporary file. :func:`atomic_write_files` writes a *set* of files all
  or nothing (every temporary file first, then the renames, which need no space). The one
  exception is a log read back line by line (:func:`open_append`): whole lines appended.
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
removes it. A folder the command created and left empty is removed instead.

**One command per folder.** A command holds an exclusive ``flock`` on a lock file
``.deckpound-lock`` in each output folder while it runs (:func:`claim_folder`,
:func:`folder_lock`; the CLI releases them when the command ends), with its PID, host, start
time and command line written into it. A second command on the same folder is refused (exit
status 2) naming that holder; the kernel drops the lock when the holder dies, so a lock file
left by a killed command is taken over with a warning. **Temporaries of killed writers** (a
SIGKILL between the temporary file and its rename) are removed by the next write into their
folder (:func:`remove_stale_temporaries`): a temporary's name carries its writer's PID and host,
and only those whose writer is no longer alive on this host are removed.
"""

from __future__ import annotations

import contextlib
import errno
import fcntl
import hashlib
import os
import re
import secrets
import shutil
import socket
import stat
import time
import warnings
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path

from deckpound.models.errors import SceneError

#: name of the marker file of an unfinished output folder
INCOMPLETE = "INCOMPLETE"
#: name of the lock file of an output folder in use (removed when its command ends)
LOCK_FILE = ".deckpound-lock"
_TMP_TAG = ".deckpound-tmp"
_HOST = (socket.gethostname().split() or ["localhost"])[0]
#: six hex digits naming this host in temporary names (a shared folder's other hosts' PIDs
#: cannot be checked from here)
_HOST_TAG = hashlib.sha256(_HOST.encode("utf-8", "replace")).hexdigest()[:6]
#: ``.NAME.PID-HOST-RANDOM.deckpound-tmp[SUFFIX]``; names written before the host tag have none
_TMP_NAME = re.compile(
    r"^\..+\.(?P<pid>\d{1,10})-(?:(?P<host>[0-9a-f]{6})-)?[0-9a-f]{8}"
    + re.escape(_TMP_TAG)
    + r"(?:\.[^.]*)?$",
    re.DOTALL,
)


def is_temporary(name: str) -> bool:
    """True for the names of this module's temporary files and folders."""
    return _TMP_TAG in name


def _tmp_name(path: Path) -> Path:
    """A fresh temporary name beside ``path`` that keeps its suffix (matplotlib and pandas
    choose the format from it) and names its writer (PID and host) for
    :func:`remove_stale_temporaries`."""
    _sweep_once(path.parent)
    token = f"{os.getpid()}-{_HOST_TAG}-{secrets.token_hex(4)}"
    return path.with_name(f".{path.name}.{token}{_TMP_TAG}{path.suffix}")


def remove_stale_temporaries(folder: str | Path) -> list[Path]:
    """Remove from ``folder`` (not below it) the temporary files and folders of this module's
    naming pattern whose writer died before its rename (a SIGKILL, a power cut); return them.

    A temporary is removed only if its name carries a PID that is not alive on this host (and
    this host's tag, for the names that have one): a live writer's file, another program's
    file or another host's file is never touched."""
    removed: list[Path] = []
    try:
        entries = list(os.scandir(folder))
    except OSError:
        return removed  # not there yet, or not readable: the write itself says what is wrong
    for entry in entries:
        match = _TMP_NAME.match(entry.name)
        if match is None or match["host"] not in (None, _HOST_TAG):
            continue
        if _pid_alive(int(match["pid"])):
            continue
        try:
            if entry.is_dir(follow_symlinks=False):
                shutil.rmtree(entry.path)
            else:
                os.unlink(entry.path)
        except OSError:
            continue  # removed by another command meanwhile, or not ours to remove
        removed.append(Path(entry.path))
    return removed


#: folders already cleared of stale temporaries by this process (until the command ends)
_SWEPT: set[str] = set()


def _sweep_once(folder: Path) -> None:
    key = os.path.abspath(folder)
    if key not in _SWEPT:
        _SWEPT.add(key)
        remove_stale_temporaries(folder)


def check_target(path: str | Path, field: str = "--output", *, stream: bool = True) -> Path:
    """Refuse a target file that is a symbolic link, a folder, a block device or a socket;
    return it as a Path. A character device or a pipe, e.g. /dev/null, is written directly,
    unless ``stream`` is False (an output that brings files beside it, such as an export's
    data folder, which would land among the devices)."""
    if _kind(Path(path), field) == "stream" and not stream:
        raise SceneError(
            field,
            f"{str(path)!r} is a device or a pipe, and this output writes a folder beside "
            "its file: give a file name in a folder",
        )
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
        write_all(fd, data)
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


def file_digest(path: str | Path) -> str:
    """SHA-256 of a file's bytes (hex); OSError when it cannot be read."""
    with open(path, "rb") as f:
        return hashlib.file_digest(f, "sha256").hexdigest()


def write_all(fd: int, data: bytes) -> None:
    """Write all of ``data`` to the open file ``fd`` (a short write is continued)."""
    view = memoryview(data)
    while view:
        view = view[os.write(fd, view) :]


def open_append(path: str | Path, field: str = "--output") -> int:
    """``path`` opened for appending, its folder made: each ``write`` lands whole at the end of
    the file (``O_APPEND``), also with several writers. Created with mode 0o666 less the umask;
    a link (also one made after the check: ``O_NOFOLLOW``), a folder, a device or a pipe in its
    place is refused (SceneError naming ``field``). For logs read back line by line (a sweep's
    rows, :mod:`deckpound.compare.row_log`); every other file is written atomically."""
    path = Path(path)
    if _kind(path, field) == "stream":
        raise SceneError(field, f"{str(path)!r} is a device or a pipe, not a file to append to")
    ensure_folder(path.parent, field)
    flags = os.O_WRONLY | os.O_APPEND | os.O_CREAT | os.O_NOFOLLOW | getattr(os, "O_CLOEXEC", 0)
    try:
        return os.open(path, flags, 0o666)
    except OSError as err:
        if err.errno == errno.ELOOP:
            _kind(path, field)  # a link made since the check: refused as such
        raise OSError(err.errno, err.strerror, str(path)) from None


def _write_fd(fd: int, data: bytes) -> None:
    write_all(fd, data)
    os.fsync(fd)


def _write_temporary(path: Path, data: bytes) -> Path:
    """``data`` in a new temporary file beside ``path`` (mode 0o666 less the umask), flushed
    to the disk."""
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
    """Write ``text`` (UTF-8) to ``path`` atomically (:func:`atomic_write_bytes`)."""
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


#: a CSV header cell that states its column's unit: ``deck_theta [rad]``, ``gap_closures [-]``
UNIT_HEADER = re.compile(r"^(?P<name>.*?) \[(?P<unit>[^\[\]]*)\]$")


def unit_label(name: str, unit: str | None) -> str:
    """The header cell of column ``name`` in ``unit``: ``"deck_theta [rad]"``; a column without
    a unit (text, flags: ``engine``, ``status``) keeps its plain name. Dimensionless is ``-``."""
    return f"{name} [{unit}]" if unit else name


def csv_cell(text: str) -> str:
    """``text`` as one CSV cell: quoted when it holds a comma, a quote or a line break
    (RFC 4180); the contact-state columns' unit reads ``0 open, 1 stick, 2 slip``."""
    if any(ch in text for ch in ',"\n\r'):
        return '"' + text.replace('"', '""') + '"'
    return text


def split_unit_label(header: str) -> tuple[str, str | None]:
    """(name, unit) of a header cell written by :func:`unit_label` (unit None without one)."""
    m = UNIT_HEADER.match(header)
    return (m.group("name"), m.group("unit")) if m else (header, None)


def write_csv(frame, path: str | Path, units: dict[str, str] | None = None, **kwargs) -> Path:
    """``frame.to_csv(path, index=False, **kwargs)`` atomically, each column named
    ``name [unit]`` for the numeric columns ``units`` gives a unit (:func:`unit_label`), so that a plain
    ``pandas.read_csv(path)`` reads the numbers as numbers and the header says their units."""
    kwargs.setdefault("index", False)
    if units:
        # a unit names a number: a column of text (a study's "initial" stiffness choice) or of
        # flags keeps its plain name
        numeric = {c for c in frame.columns if frame[c].dtype.kind in "iufc"}
        frame = frame.rename(
            columns={
                c: unit_label(c, units.get(c) if c in numeric else None) for c in frame.columns
            }
        )
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
    if pid <= 0:
        return True  # never a writer's PID (and os.kill(0, 0) would ask the process group)
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    except (OverflowError, ValueError):
        return False  # beyond any PID the kernel hands out
    return True


# -- one command per output folder ----------------------------------------------------------


@dataclass
class _Claim:
    """This process's lock on one output folder."""

    folder: Path
    fd: int | None  # the locked lock file (None: the file system cannot lock; warned)
    created: list[Path]  # folders the claim created, innermost first (removed if left empty)
    for_command: bool = False  # held until the command ends (:func:`release_folders`)
    scopes: int = 0  # open :func:`folder_lock` blocks
    key: tuple[int, int] = field(default=(0, 0))


#: this process's claims by the folder's (device, inode)
_CLAIMS: dict[tuple[int, int], _Claim] = {}
#: the command line written into lock files (the CLI sets it, :func:`command_scope`)
_COMMAND = ["deckpound (Python API)"]


def _printable(text: str) -> str:
    """``text`` on one line with control characters escaped (it is quoted in messages)."""
    return "".join(c if c.isprintable() else repr(c)[1:-1] for c in text)


def _holder_line() -> str:
    stamp = time.strftime("%Y-%m-%dT%H:%M:%S")
    return f"pid={os.getpid()} host={_HOST} started={stamp} command={_printable(_COMMAND[0])}\n"


def _holder(text: str) -> dict[str, str]:
    """The fields of a lock file's line (empty if the holder has not written it yet)."""
    match = re.match(r"pid=(\d+) host=(\S*) started=(\S*) command=(.*)", text.strip())
    if match is None:
        return {}
    return dict(zip(("pid", "host", "started", "command"), match.groups()))


def _describe(holder: dict[str, str]) -> str:
    if not holder:
        return "another deckpound command (it has not written its name yet)"
    where = f" on host {holder['host']}" if holder["host"] != _HOST else ""
    return (
        f"{holder['command']!r} (PID {holder['pid']}{where}, started "
        f"{holder['started'].replace('T', ' ')})"
    )


def _read_fd(fd: int) -> str:
    try:
        return os.pread(fd, 4096, 0).decode("utf-8", "replace")
    except OSError:
        return ""


def _open_lock_file(lock: Path) -> int:
    flags = os.O_CREAT | getattr(os, "O_NOFOLLOW", 0) | getattr(os, "O_CLOEXEC", 0)
    try:
        return os.open(lock, os.O_RDWR | flags, 0o666)
    except PermissionError:  # another user's lock file: a read-only descriptor locks as well
        return os.open(lock, os.O_RDONLY | flags)


def _lock(folder: Path, field: str) -> int | None:
    """Take the lock file of ``folder``; refuse (:class:`SceneError`) if a live command holds
    it. Returns the locked descriptor (None where the file system has no locks)."""
    lock = folder / LOCK_FILE
    while True:
        fd = _open_lock_file(lock)
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            holder = _holder(_read_fd(fd))
            for _ in range(50):  # the holder writes its line just after it took the lock
                if holder:
                    break
                time.sleep(0.02)
                holder = _holder(_read_fd(fd))
            os.close(fd)
            ended = ""
            if holder and holder["host"] == _HOST and not _pid_alive(int(holder["pid"])):
                ended = " (that process has ended; a process it started still holds the lock)"
            raise SceneError(
                field,
                f"the folder {str(folder)!r} is in use by {_describe(holder)}{ended}; wait "
                "until it ends or give another output folder",
            ) from None
        except OSError as err:
            os.close(fd)
            if err.errno not in (errno.ENOLCK, errno.EOPNOTSUPP, errno.ENOTSUP, errno.EINVAL):
                raise
            warnings.warn(
                f"the file system of {str(folder)!r} cannot lock files ({err.strerror}): a "
                "second command writing into this folder at the same time would not be "
                "stopped",
                stacklevel=3,
            )
            return None
        try:  # the holder before us may have removed the file between our open and lock
            same = os.path.samestat(os.fstat(fd), os.stat(lock, follow_symlinks=False))
        except FileNotFoundError:
            same = False
        if same:
            break
        os.close(fd)
    previous = _holder(_read_fd(fd))
    if previous and previous["pid"] != str(os.getpid()):
        warnings.warn(
            f"the folder {str(folder)!r} was locked by {_describe(previous)}, which ended "
            "without releasing it (killed?); taking it over",
            stacklevel=3,
        )
    with contextlib.suppress(OSError):  # a read-only descriptor: the lock holds, unnamed
        os.ftruncate(fd, 0)
        os.pwrite(fd, _holder_line().encode("utf-8"), 0)
    return fd


def _acquire(path: str | Path, field: str, *, through_links: bool) -> _Claim:
    """This process's claim on folder ``path`` (created if needed), new or existing."""
    path = Path(path)
    missing = []
    for folder in (path, *path.parents):
        if os.path.lexists(folder):
            break
        missing.append(folder)
    if through_links:
        if path.exists() and not path.is_dir():
            raise SceneError(field, f"{str(path)!r} exists and is not a folder")
        check_parent(path, field)
        path.mkdir(parents=True, exist_ok=True)
    else:
        ensure_folder(path, field)
    st = os.stat(path)
    key = (st.st_dev, st.st_ino)
    claim = _CLAIMS.get(key)
    if claim is not None and not _still_holds(claim, path):
        _forget(claim)  # its folder was removed and the inode reused by this one
        claim = None
    if claim is None:
        try:
            fd = _lock(path, field)
        except BaseException:
            _remove_created(missing)
            raise
        claim = _CLAIMS[key] = _Claim(path, fd, missing, key=key)
        _SWEPT.discard(os.path.abspath(path))
        _sweep_once(path)
    return claim


def _still_holds(claim: _Claim, path: Path) -> bool:
    """Whether ``claim`` is on the folder now at ``path``: a removed folder's (device, inode)
    can be given to a new folder, which must then be locked afresh."""
    if claim.fd is None:
        return os.path.abspath(claim.folder) == os.path.abspath(path)
    try:
        return os.path.samestat(
            os.fstat(claim.fd), os.stat(path / LOCK_FILE, follow_symlinks=False)
        )
    except OSError:
        return False


def _forget(claim: _Claim) -> None:
    """Drop a claim whose folder is gone (its lock file went with it)."""
    _CLAIMS.pop(claim.key, None)
    if claim.fd is not None:
        with contextlib.suppress(OSError):
            os.close(claim.fd)


def _remove_created(folders: list[Path]) -> None:
    for folder in folders:  # innermost first; stops at the first that is not empty
        try:
            os.rmdir(folder)
        except FileNotFoundError:
            continue  # removed already (a failed command's empty output folder)
        except OSError:
            return


def _release(claim: _Claim) -> None:
    _CLAIMS.pop(claim.key, None)
    if claim.fd is not None:
        lock = claim.folder / LOCK_FILE
        with contextlib.suppress(OSError):  # ours only: the folder may be gone or re-made
            if os.path.samestat(os.fstat(claim.fd), os.stat(lock, follow_symlinks=False)):
                os.unlink(lock)  # while still locked, so no one locks the removed file
        os.close(claim.fd)  # releases the lock
    _remove_created(claim.created)


def claim_folder(path: str | Path, field: str = "--output", *, through_links: bool = False):
    """Lock output folder ``path`` (created if needed) until the command ends
    (:func:`release_folders`): a second command on it is refused with a :class:`SceneError`
    naming this one. A symbolic link in place of ``path`` is refused unless ``through_links``
    (the folder of an output *file*, which may be a link). Returns the folder."""
    claim = _acquire(path, field, through_links=through_links)
    claim.for_command = True
    return claim.folder


def claim_folder_of(path: str | Path, field: str = "--output") -> None:
    """Lock the folder that output file ``path`` goes into (not for a device or pipe, which
    is written in place)."""
    if _kind(Path(path), field) != "stream":
        claim_folder(Path(path).parent, field, through_links=True)


@contextlib.contextmanager
def folder_lock(path: str | Path, field: str = "--output") -> Iterator[_Claim]:
    """Lock output folder ``path`` (created if needed) for the block, unless this process
    holds it already (then it stays held as before)."""
    claim = _acquire(path, field, through_links=False)
    claim.scopes += 1
    try:
        yield claim
    finally:
        claim.scopes -= 1
        if not claim.scopes and not claim.for_command and _CLAIMS.get(claim.key) is claim:
            _release(claim)


def _forget_claims_in_child() -> None:
    """A forked child (a sweep's worker, a guarded stress-test child) does not hold its
    parent's folders: its copies of the lock descriptors are closed (the lock stays with the
    parent's), so that workers left running after the parent was killed do not keep the folder
    locked in a dead command's name, and the child never removes the parent's lock file."""
    for claim in _CLAIMS.values():
        if claim.fd is not None:
            with contextlib.suppress(OSError):
                os.close(claim.fd)
    _CLAIMS.clear()


os.register_at_fork(after_in_child=_forget_claims_in_child)


def release_folders() -> None:
    """Release every folder this process holds (the end of a command) and forget which
    folders were cleared of stale temporaries."""
    for claim in list(_CLAIMS.values()):
        _release(claim)
    _SWEPT.clear()


@contextlib.contextmanager
def command_scope(command: str) -> Iterator[None]:
    """One command: ``command`` (its command line) is what lock files name; every folder it
    claimed is released when the block ends."""
    before = _COMMAND[0]
    _COMMAND[0] = command
    try:
        yield
    finally:
        _COMMAND[0] = before
        release_folders()


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
        if any(not (Path(root) == folder and f in (INCOMPLETE, LOCK_FILE)) for f in files):
            return False
    return True


@contextlib.contextmanager
def output_folder(path: str | Path, command: str, *, field: str = "--output") -> Iterator[Path]:
    """The output folder of one command (see the module docstring): created if needed (a
    symbolic link or a file in its place refused), locked against other commands
    (:func:`folder_lock`), marked ``INCOMPLETE`` while the block runs, unmarked on success; on
    failure marked with the reason, or removed if this command created it and wrote nothing
    into it."""
    with folder_lock(path, field) as claim:
        folder = Path(path)
        existed = not claim.created
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
