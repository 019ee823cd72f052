"""Run one fuzz case of :mod:`tests._fuzz_corpus` through ``deckpound.cli.main`` and classify it.

Outcomes: ``refused`` (exit 2), ``engine failure`` (1), ``I/O error`` (3), ``interrupted``
(130), ``success`` (0) — and the four that must never happen:

* ``TRACEBACK``: an exception escaped ``main``, exit status 4 (internal error), or
  "Traceback" on stderr;
* ``UNCLEAN``: more than one error line, a line that is not ``deckpound: ...``, or an exit
  status the case does not allow (e.g. success through a symbolic link);
* ``PARTIAL OUTPUT``: a temporary file left anywhere, a new output folder of a failed command
  without its ``INCOMPLETE`` marker, a new output file of a failed command, a pre-existing
  file changed or lost, an output of a success still marked incomplete, or a result file that
  does not parse;
* ``SILENT NONSENSE``: success where the case says it would be nonsense, or a result CSV with
  non-finite values or fewer than 2 rows.

Faults are injected by patching (``os.fsync``, ``os.replace``, the write loop of
:mod:`deckpound.models.file_io`, ``os.mkdir``/``os.open``/``open`` for a read-only folder, matplotlib's
``savefig``, the engine entry point, stdout; stdout or stderr closed: None in ``sys``, as
Python sets them when the shell closed them) only for the duration of one case.
"""

from __future__ import annotations

import builtins
import contextlib
import errno
import hashlib
import io
import json
import os
import shutil
import stat
import sys
import warnings
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from deckpound.cli import main
from deckpound.models.file_io import INCOMPLETE, is_temporary
from deckpound.models.result import read_table

OK_OUTCOMES = ("refused", "engine failure", "I/O error", "interrupted", "success")
BAD_OUTCOMES = ("TRACEBACK", "UNCLEAN", "PARTIAL OUTPUT", "SILENT NONSENSE")
_STATUS = {0: "success", 1: "engine failure", 2: "refused", 3: "I/O error", 130: "interrupted"}
ENGINES = ("opensees", "compliance", "nonsmooth")


@dataclass
class Outcome:
    case_id: str
    outcome: str
    code: int | None
    detail: str = ""


# -- faults ---------------------------------------------------------------------------------


class _Counter:
    def __init__(self, k: int):
        self.k, self.n = k, 0

    def hit(self) -> bool:
        self.n += 1
        return self.n == self.k


@contextlib.contextmanager
def _patched(obj, name, value):
    old = getattr(obj, name)
    setattr(obj, name, value)
    try:
        yield
    finally:
        setattr(obj, name, old)


class _FullStdout(io.StringIO):
    def write(self, text):
        raise OSError(errno.ENOSPC, "No space left on device")

    def flush(self):
        raise OSError(errno.ENOSPC, "No space left on device")


def _inject(fault: str, root: Path, stack: contextlib.ExitStack) -> None:
    """Install ``fault`` (see tests._fuzz_outputs.FAULTS) until ``stack`` closes."""
    import deckpound.models.file_io as dio
    from deckpound.compare import engines

    kind, _, arg = fault.partition(":")
    if kind in ("enospc-write", "interrupt-write", "memory-write"):
        counter, real = _Counter(int(arg)), dio._write_fd

        def write_fd(fd, data, **kw):
            if counter.hit():
                if kind == "interrupt-write":
                    raise KeyboardInterrupt
                if kind == "memory-write":
                    raise MemoryError
                os.write(fd, bytes(data[: len(data) // 2]))  # half written, then the disk is full
                raise OSError(errno.ENOSPC, "No space left on device")
            return real(fd, data, **kw)

        stack.enter_context(_patched(dio, "_write_fd", write_fd))
    elif kind == "enospc-fsync":
        counter, real_fsync = _Counter(int(arg)), os.fsync

        def fsync(fd):
            if counter.hit():
                raise OSError(errno.ENOSPC, "No space left on device")
            return real_fsync(fd)

        stack.enter_context(_patched(os, "fsync", fsync))
    elif kind == "eio-replace":
        counter, real_replace = _Counter(int(arg)), os.replace

        def replace(src, dst, **kw):
            if counter.hit():
                raise OSError(errno.EIO, "Input/output error", str(dst))
            return real_replace(src, dst, **kw)

        stack.enter_context(_patched(os, "replace", replace))
    elif kind == "readonly":
        _readonly(getattr(errno, arg), root, stack)
    elif kind == "savefig-enospc":
        from matplotlib.figure import Figure

        def savefig(self, fname, *a, **kw):
            Path(fname).write_bytes(b"\x89PNG\r\n\x1a\n partial")
            raise OSError(errno.ENOSPC, "No space left on device", str(fname))

        stack.enter_context(_patched(Figure, "savefig", savefig))
    elif kind in ("memory-engine", "interrupt-engine", "recursion-engine"):
        exc = {
            "memory-engine": MemoryError,
            "interrupt-engine": KeyboardInterrupt,
            "recursion-engine": RecursionError,
        }[kind]

        def run_engine(*a, **kw):
            raise exc()

        stack.enter_context(_patched(engines, "run_engine", run_engine))
    elif kind in ("stdout-full", "stdout-closed", "stderr-closed", "streams-closed"):
        pass  # handled by the runner (stdout and stderr replaced)
    elif kind == "connect-timeout":
        from deckpound.compare import cases

        stack.enter_context(_patched(cases, "CONNECT_TIMEOUT", 1.0))
    else:
        raise ValueError(f"unknown fault {fault!r}")


def _readonly(code: int, root: Path, stack: contextlib.ExitStack) -> None:
    """The case's folder behaves like a read-only folder: nothing can be created in it."""
    real_mkdir, real_open, real_bopen = os.mkdir, os.open, builtins.open
    real_replace, real_rename = os.replace, os.rename
    top = str(root)

    def inside(p) -> bool:
        try:
            return os.path.abspath(os.fsdecode(p)).startswith(top)
        except TypeError:
            return False

    def fail(p):
        raise OSError(code, os.strerror(code), os.fsdecode(p))

    def mkdir(p, mode=0o777, *a, **kw):
        if inside(p):
            if os.path.lexists(p):
                raise FileExistsError(errno.EEXIST, "File exists", os.fsdecode(p))
            fail(p)
        return real_mkdir(p, mode, *a, **kw)

    def osopen(p, flags, mode=0o777, *a, **kw):
        if inside(p) and flags & (os.O_WRONLY | os.O_RDWR | os.O_CREAT):
            fail(p)
        return real_open(p, flags, mode, *a, **kw)

    def bopen(p, mode="r", *a, **kw):
        if (
            isinstance(p, (str, bytes, os.PathLike))
            and inside(p)
            and any(m in mode for m in "wax+")
        ):
            fail(p)
        return real_bopen(p, mode, *a, **kw)

    def replace(src, dst, *a, **kw):
        if inside(dst):
            fail(dst)
        return real_replace(src, dst, *a, **kw)

    def rename(src, dst, *a, **kw):
        if inside(dst):
            fail(dst)
        return real_rename(src, dst, *a, **kw)

    for obj, name, value in (
        (os, "mkdir", mkdir),
        (os, "open", osopen),
        (builtins, "open", bopen),
        (os, "replace", replace),
        (os, "rename", rename),
    ):
        stack.enter_context(_patched(obj, name, value))


# -- materialising and snapshots ------------------------------------------------------------


def _fmt(text: str, root: Path) -> str:
    return text.replace("{tmp}", str(root))


def materialise(case, root: Path, result_dir: Path | None) -> list[str]:
    """Create the case's files, folders and links under ``root``; return its argv."""
    root.mkdir(parents=True, exist_ok=True)
    for step in case.setup:
        if step == "result":
            shutil.copytree(result_dir, root / "res")
        elif step.startswith("damage:"):
            _damage(root / "res" / "opensees.csv", step.split(":", 1)[1])
    for d in case.dirs:
        (root / d).mkdir(parents=True, exist_ok=True)
    for rel, data in case.files:
        p = root / rel
        p.parent.mkdir(parents=True, exist_ok=True)
        p.write_bytes(data)
    for rel, target in case.links:
        os.symlink(_fmt(target, root), root / rel)
    return [_fmt(a, root) for a in case.argv]


def _damage(csv: Path, how: str) -> None:
    frame = read_table(csv)
    if how == "csv-nan":
        frame.loc[3, "deck_theta"] = np.nan
    elif how == "csv-decreasing":
        frame.loc[2, "t"], frame.loc[3, "t"] = frame.loc[3, "t"], frame.loc[2, "t"]
    elif how == "csv-missing-col":
        frame = frame.drop(columns=["seat2_theta"])
    frame.to_csv(csv, index=False)


def _digest(p: Path) -> str:
    st = os.lstat(p)
    if stat.S_ISLNK(st.st_mode):
        return "link:" + os.readlink(p)
    if stat.S_ISREG(st.st_mode):
        return hashlib.sha256(p.read_bytes()).hexdigest()
    return f"mode:{stat.S_IFMT(st.st_mode)}"


def snapshot(root: Path) -> dict[str, str]:
    """Every path under ``root`` with a digest of its content (links not followed)."""
    out = {}
    if not root.exists():
        return out
    for dirpath, dirnames, filenames in os.walk(root):
        for name in dirnames + filenames:
            p = Path(dirpath) / name
            out[str(p.relative_to(root))] = (
                "dir" if p.is_dir() and not p.is_symlink() else _digest(p)
            )
    return out


# -- running and classifying ----------------------------------------------------------------


def _show_on_stderr(message, category, filename, lineno, file=None, line=None):
    sys.stderr.write(warnings.formatwarning(message, category, filename, lineno, line))


def run_case(case, root: Path, result_dir: Path | None = None) -> Outcome:
    """Materialise, run in-process, classify; ``root`` is removed afterwards."""
    try:
        return _run(case, root, result_dir)
    finally:
        shutil.rmtree(root, ignore_errors=True)


def _target_state(path: str) -> str:
    if not path:
        return ""
    try:
        st = os.lstat(path)
    except OSError:
        return "absent"
    if stat.S_ISCHR(st.st_mode):
        return "device"
    return "dir" if stat.S_ISDIR(st.st_mode) else "other"


def _run(case, root: Path, result_dir: Path | None) -> Outcome:
    argv = materialise(case, root, result_dir)
    target = _fmt(case.target, root)
    before = snapshot(root)
    target_before = _target_state(target)
    out, err = (_FullStdout() if case.fault == "stdout-full" else io.StringIO()), io.StringIO()
    # a stream closed by the shell (`>&-`, `2>&-`) is None in sys for Python
    closed_out = case.fault in ("stdout-closed", "streams-closed")
    closed_err = case.fault in ("stderr-closed", "streams-closed")
    escaped = None
    with contextlib.ExitStack() as stack:
        stack.enter_context(warnings.catch_warnings())
        warnings.showwarning = _show_on_stderr
        if case.fault:
            _inject(case.fault, root, stack)
        stack.enter_context(contextlib.redirect_stdout(None if closed_out else out))
        stack.enter_context(contextlib.redirect_stderr(None if closed_err else err))
        try:
            code = main(argv)
        except BaseException as exc:
            code, escaped = None, exc
    stderr = err.getvalue()
    if escaped is not None:
        return Outcome(case.id, "TRACEBACK", None, f"{type(escaped).__name__}: {escaped}"[:300])
    if code == 4 or "Traceback" in stderr:
        return Outcome(case.id, "TRACEBACK", code, stderr[-300:])
    lines = [ln for ln in stderr.splitlines() if not ln.startswith("deckpound: warning:")]
    if closed_err:
        lines = ["deckpound: (stderr closed: its line is lost)"] if code != 0 else []
    if code != 0 and (len(lines) != 1 or not lines[0].startswith("deckpound: ")):
        return Outcome(case.id, "UNCLEAN", code, f"stderr {stderr[-300:]!r}")
    if code == 0 and lines:
        return Outcome(case.id, "UNCLEAN", code, f"success with stderr {stderr[-300:]!r}")
    if case.expect and code not in case.expect:
        return Outcome(
            case.id,
            "UNCLEAN",
            code,
            f"exit {code}, expected {case.expect}: {stderr.strip()[-250:]}",
        )
    partial = _partial(case, root, target, target_before, before, code)
    if partial:
        return Outcome(case.id, "PARTIAL OUTPUT", code, partial)
    if code == 0:
        shown = out.getvalue() if case.fault != "stdout-full" and not closed_out else ""
        nonsense = _nonsense(case, target, shown)
        if nonsense:
            return Outcome(case.id, "SILENT NONSENSE", code, nonsense)
    return Outcome(case.id, _STATUS.get(code, "UNCLEAN"), code, lines[0][:200] if lines else "")


def _partial(case, root: Path, target: str, target_before: str, before: dict, code: int) -> str:
    after = snapshot(root)
    temps = [p for p in after if is_temporary(Path(p).name)]
    if temps:
        return f"temporary files left: {temps[:3]}"
    for rel, digest in before.items():  # nothing the user had may change, except the target
        full = str(root / rel)
        if full == target or full.startswith(target + os.sep):
            if "keep.txt" in rel and after.get(rel) != digest:
                return f"user file {rel} changed or lost"
            continue
        if after.get(rel) != digest:
            return f"{rel} changed or lost"
    if target and not target.startswith(str(root)):
        state = _target_state(target)
        if state != target_before and state != "absent":
            return f"system path {target} changed ({target_before} -> {state})"
        return ""
    if not target:
        return ""
    tpath = Path(target)
    if case.target_kind == "dir" and tpath.is_dir() and not tpath.is_symlink():
        marked = (tpath / INCOMPLETE).exists()
        if code == 0 and marked:
            return "successful output folder still marked INCOMPLETE"
        if code != 0 and not marked and not (code == 1 and _failed_result(tpath)):
            new = {
                p
                for p in after
                if p not in before and (str(root / p) + os.sep).startswith(target + os.sep)
            }
            if new:
                return f"failed command left {sorted(new)[:3]} without an INCOMPLETE marker"
        bad = _damaged_results(tpath)
        if bad:
            return bad
    if case.target_kind == "file" and code != 0 and target_before == "absent" and tpath.exists():
        return f"failed command left the file {target}"
    return ""


def _failed_result(folder: Path) -> bool:
    """An engine failure's folder holds the complete result of the failed run (the history up
    to the failure, status "failed" in its metadata: the engine contract), not partial output."""
    for e in ENGINES:
        try:
            meta = json.loads((folder / f"{e}.json").read_text())
        except (OSError, ValueError):
            continue
        if meta.get("status") == "failed" and (folder / f"{e}.csv").is_file():
            return True
    return False


def _damaged_results(folder: Path) -> str:
    for e in ENGINES:
        csv, js = folder / f"{e}.csv", folder / f"{e}.json"
        if csv.exists() != js.exists():
            return f"{e}: one of csv/json missing"
        if csv.exists():
            try:
                read_table(csv)
                json.loads(js.read_text())
            except Exception as err:
                return f"{e} result does not parse: {err}"[:200]
    return ""


def _nonsense(case, target: str, stdout: str) -> str:
    if case.nonsense:
        return "accepted input that must be refused"
    if (
        case.argv[:2] == ("scene", "validate")
        and case.fault != "stdout-full"
        and ": valid;" not in stdout
    ):
        return "validate succeeded without saying valid"
    if case.target_kind == "dir" and target and Path(target).is_dir():
        for e in ENGINES:
            csv = Path(target) / f"{e}.csv"
            if csv.exists():
                frame = read_table(csv)
                if len(frame) < 2:
                    return f"{e}.csv holds {len(frame)} row(s)"
                values = frame.to_numpy(dtype=float)
                if not np.all(np.isfinite(values)):
                    return f"{e}.csv holds non-finite values"
    return ""
