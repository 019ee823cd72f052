"""The result cache: finished cases on disk, safe for concurrent processes and checked on read.

Layout: ``FOLDER/<key>/`` holds ``<engine>.csv``, ``<engine>.json`` and ``manifest.json``,
the SHA-256 and size of both files. An entry is built in a temporary folder beside it and
renamed into place in one step, so a reader sees a whole entry or none. Every read verifies
the checksums: a damaged or truncated entry (a crash of an older version, a full disk, a
hand edit) is reported in a warning and recomputed, never used silently.

Concurrency: several processes (two ``paper`` runs on one folder, the workers of a study) may
``put`` and ``get`` the same keys at once. A reader opens the entry folder once and reads its
files through that handle, so a concurrent replacement cannot mix two versions; a writer that
finds a valid entry already in place discards its own copy (same key, same physics), and one
that finds a damaged entry moves it aside first. No ``get`` or ``put`` raises for any of these
races; a ``put`` that cannot write (full or read-only disk) warns and leaves the cache as it
was: the computed result is still returned to the caller.

Files: the result's own format (:meth:`Result.csv_bytes`, units in the header) with the time
column written exactly, so a cached result is bit-identical to the fresh one; entries written by
earlier versions (a ``# units:`` comment line above a plain header) are read as they are.
"""

from __future__ import annotations

import contextlib
import errno
import hashlib
import json
import os
import secrets
import shutil
import warnings
from pathlib import Path

from deckpound.models.errors import SceneError
from deckpound.models.file_io import atomic_write_bytes, ensure_folder, is_temporary
from deckpound.models.result import Result

MANIFEST = "manifest.json"
FORMAT = 1
_TMP = ".deckpound-tmp"


def _sha256(data: bytes) -> str:
    return hashlib.sha256(data).hexdigest()


class CorruptEntry(Exception):
    """A cache entry whose files do not match its manifest (internal)."""


class ResultCache:
    """A folder of finished results, one sub-folder per case key.

    ``get(key, engine)`` returns the cached :class:`Result` or None (and counts ``hits`` and
    ``misses``, in total and per engine in ``by_engine[engine] = [hits, misses]``: the report
    shows that changing one engine's settings re-runs that engine only); ``put(key, result)``
    stores one. See the module docstring for the guarantees.
    """

    def __init__(self, folder: str | Path):
        self.folder = ensure_folder(folder, "--cache")
        self.hits = 0
        self.misses = 0
        self.corrupt = 0
        self.by_engine: dict[str, list[int]] = {}

    def path(self, key: str) -> Path:
        if not key or "/" in key or key.startswith(".") or is_temporary(key):
            raise ValueError(f"not a cache key: {key!r}")
        return self.folder / key

    # -- reading -------------------------------------------------------------------------
    def get(self, key: str, engine: str) -> Result | None:
        """The cached result of ``key`` or None; a damaged entry warns and counts as a miss."""
        try:
            result = self._load(self.path(key), engine)
        except CorruptEntry as err:
            self.corrupt += 1
            warnings.warn(
                f"result cache entry {key[:16]} in {str(self.folder)!r} is damaged "
                f"({err}); recomputing it",
                stacklevel=2,
            )
            result = None
        counts = self.by_engine.setdefault(engine, [0, 0])
        if result is None:
            self.misses += 1
            counts[1] += 1
        else:
            self.hits += 1
            counts[0] += 1
        return result

    def _load(self, entry: Path, engine: str) -> Result | None:
        """Read an entry through one folder handle; None if absent (or from an old version)."""
        try:
            dfd = os.open(entry, os.O_RDONLY | getattr(os, "O_DIRECTORY", 0))
        except (FileNotFoundError, NotADirectoryError):
            return None
        except OSError as err:
            raise CorruptEntry(f"cannot open it: {err.strerror or err}") from None
        try:
            names = os.listdir(dfd)
            if MANIFEST not in names:
                # an older cache without checksums, or a folder being removed: recompute
                return None
            files = {}
            for name in (MANIFEST, f"{engine}.csv", f"{engine}.json"):
                try:
                    files[name] = _read_at(dfd, name)
                except FileNotFoundError:
                    if name == MANIFEST:
                        return None  # moved aside by a concurrent writer
                    raise CorruptEntry(f"{name} is missing") from None
        finally:
            os.close(dfd)
        _verify(files, engine)
        try:
            return Result.from_bytes(
                engine, files[f"{engine}.csv"], files[f"{engine}.json"], source=str(entry)
            )
        except (SceneError, ValueError) as err:
            raise CorruptEntry(str(err)) from None

    # -- writing -------------------------------------------------------------------------
    def put(self, key: str, result: Result) -> None:
        """Store ``result`` under ``key`` (whole entry or nothing; never raises for races or a
        full disk: it warns and the cache stays as it was)."""
        final = self.path(key)
        tmp = self.folder / f".{key[:16]}.{os.getpid()}-{secrets.token_hex(4)}{_TMP}"
        try:
            _write_entry(tmp, result)
            self._install(tmp, final, result.engine)
        except OSError as err:
            warnings.warn(
                f"could not store a result in the cache {str(self.folder)!r} "
                f"({err.strerror or err}); it will be recomputed next time",
                stacklevel=2,
            )
        finally:
            if tmp.exists():
                shutil.rmtree(tmp, ignore_errors=True)

    def _install(self, tmp: Path, final: Path, engine: str) -> None:
        for _ in range(8):
            try:
                os.rename(tmp, final)  # atomic; fails if a non-empty entry is in place
                return
            except FileNotFoundError:
                raise
            except OSError as err:
                if err.errno not in (errno.ENOTEMPTY, errno.EEXIST, errno.ENOTDIR):
                    raise
            try:
                if self._load(final, engine) is not None:
                    return  # a valid entry is already there (the same case): keep it
            except CorruptEntry:
                pass
            # damaged, or from an older version: move it aside, then retry the rename
            aside = self.folder / f".{final.name[:16]}.old-{secrets.token_hex(4)}{_TMP}"
            with contextlib.suppress(FileNotFoundError):
                os.rename(final, aside)
                if aside.is_dir():
                    shutil.rmtree(aside, ignore_errors=True)
                else:
                    aside.unlink()
        # lost every race against other writers: their entries are as good as ours


def _read_at(dfd: int, name: str) -> bytes:
    fd = os.open(name, os.O_RDONLY, dir_fd=dfd)
    try:
        chunks = []
        while True:
            chunk = os.read(fd, 1 << 20)
            if not chunk:
                return b"".join(chunks)
            chunks.append(chunk)
    finally:
        os.close(fd)


def _verify(files: dict[str, bytes], engine: str) -> None:
    try:
        manifest = json.loads(files[MANIFEST].decode("utf-8"))
        listed = manifest["files"]
    except (UnicodeDecodeError, ValueError, KeyError, TypeError):
        raise CorruptEntry(f"{MANIFEST} is unreadable") from None
    for name in (f"{engine}.csv", f"{engine}.json"):
        want = listed.get(name) if isinstance(listed, dict) else None
        if not isinstance(want, dict):
            raise CorruptEntry(f"{MANIFEST} does not list {name}")
        data = files[name]
        if want.get("size") != len(data):
            raise CorruptEntry(
                f"{name} holds {len(data)} bytes, the manifest says {want.get('size')}"
            )
        if want.get("sha256") != _sha256(data):
            raise CorruptEntry(f"{name} does not match its SHA-256 checksum")


def _write_entry(folder: Path, result: Result) -> None:
    """A complete entry in a new folder: both files, then the manifest (mode per umask)."""

    os.mkdir(folder)
    data = {
        # the time column as computed, so that a cached result is bit-identical to a fresh one
        f"{result.engine}.csv": result.csv_bytes(exact_time=True),
        f"{result.engine}.json": result.json_bytes(),
    }
    for name, content in data.items():
        atomic_write_bytes(folder / name, content, field="cache")
    manifest = {
        "format": FORMAT,
        "engine": result.engine,
        "files": {n: {"sha256": _sha256(c), "size": len(c)} for n, c in data.items()},
    }
    atomic_write_bytes(folder / MANIFEST, json.dumps(manifest, indent=1).encode(), field="cache")
