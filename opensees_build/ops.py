"""The one module that imports openseespy: a logging proxy with a tag registry.

:class:`OpsSession` executes OpenSees commands and logs the model-defining ones, so that the
same model can be written out as a Tcl or Python script (:mod:`.export`) or compared with a
golden command log. Integer tags are handed out by name from a per-kind registry
(``session.tag("node", "deck")``), so the model code never invents numbers.

Usage::

    with OpsSession() as ops:          # wipes the OpenSees domain on entry and on exit
        ops.model("basic", "-ndm", 2, "-ndf", 3)
        n = ops.tag("node", "deck")
        ops.node(n, 0.0, 0.0)
        ...
        ops.analyze(1, dt)             # queries and stepping are executed, not logged

Only one session may be open at a time (openseespy holds one global domain).

Long value lists (support records) are passed as :class:`ArrayArg`; in process they expand to
``-values v0 v1 ...``, in the log they are abbreviated to their length and SHA-256, and the
exported scripts read them from files in the script's data folder (``-filePath``).
"""

from __future__ import annotations

import hashlib
import resource
from dataclasses import dataclass, field
from importlib.metadata import version
from typing import Any

import numpy as np

from .quoting import comment_text, py_str, tcl_word

#: address space [MiB] that loading openseespy and running it need beyond what the process
#: has mapped already: under a tighter ``ulimit -v`` its C libraries fail where Python cannot
#: see it (MPI_Init ends the process with status 15, OpenBLAS prints an error and fails the
#: run), so such a limit is refused before the import
OPENSEES_ADDRESS_SPACE_MIB = 256


def address_space_left_mib() -> float | None:
    """Address space [MiB] this process may still map under its ``RLIMIT_AS`` (``ulimit -v``):
    the soft limit less the mapped size (``VmSize`` of ``/proc/self/status``); None when
    unlimited or not readable."""
    soft, _ = resource.getrlimit(resource.RLIMIT_AS)
    if soft == resource.RLIM_INFINITY:
        return None
    try:
        with open("/proc/self/status", encoding="ascii") as status:
            mapped_kib = next(int(line.split()[1]) for line in status if line.startswith("VmSize:"))
    except (OSError, StopIteration, ValueError, IndexError):
        return None
    return (soft - 1024 * mapped_kib) / 2**20


def _load_openseespy():
    """openseespy's ``opensees`` module, or an ImportError named ``openseespy`` that says why
    it cannot be loaded.

    openseespy's package turns every failure of its binary module into
    ``RuntimeError("Failed to import openseespy on Linux.")`` (a bare ``except``), so a
    missing shared library or too little memory to map it (``ulimit -v``) looked like a bug in
    deckpound. The innermost cause is named instead; the CLI reports an ImportError of a
    library as a resource or environment failure (exit status 3). An address-space limit that
    leaves less than :data:`OPENSEES_ADDRESS_SPACE_MIB` is refused the same way before the
    import: below it the C libraries end or fail the process themselves."""
    left = address_space_left_mib()
    if left is not None and left < OPENSEES_ADDRESS_SPACE_MIB:
        raise ImportError(
            f"the memory limit (ulimit -v) leaves this process {max(left, 0.0):.0f} MiB of "
            f"address space and OpenSees needs about {OPENSEES_ADDRESS_SPACE_MIB} MiB more (its "
            "MPI and BLAS libraries end the process when they run out)",
            name="openseespy",
        )
    try:
        import openseespy.opensees as module
    except Exception as err:  # MemoryError included: it is an Exception
        cause, seen = err, 0
        while (cause.__cause__ or cause.__context__) is not None and seen < 16:
            cause, seen = cause.__cause__ or cause.__context__, seen + 1
        why = f"{type(cause).__name__}: {cause}" if str(cause) else type(cause).__name__
        raise ImportError(f"openseespy cannot be loaded ({why})", name="openseespy") from err
    return module


_ops = _load_openseespy()

__all__ = [
    "OPENSEES_ADDRESS_SPACE_MIB",
    "ArrayArg",
    "Command",
    "OpsSession",
    "address_space_left_mib",
    "openseespy_version",
    "render_value",
]

#: commands executed but never logged: state queries, stepping and analysis bookkeeping
QUERIES = frozenset(
    {
        "analyze",
        "nodeDisp",
        "nodeVel",
        "nodeAccel",
        "eleResponse",
        "testIter",
        "testNorm",
        "getTime",
        "nodeEigenvector",
        "nodeReaction",
        "reactions",
        "getNodeTags",
        "getEleTags",
        "revertToLastCommit",
        "printModel",
        "setNodeDisp",
        "version",
        "nodeCoord",
    }
)


def openseespy_version() -> str:
    try:
        return version("openseespy")
    except Exception:  # pragma: no cover - metadata missing
        return "unknown"


@dataclass(frozen=True, eq=False)
class ArrayArg:
    """A long list of floats passed as ``-values ...`` (in process) or read from a file.

    ``name`` is a short label used for the file written beside an exported script.
    """

    name: str
    values: np.ndarray

    def digest(self, sig: int = 10) -> str:
        """SHA-256 of the values formatted with ``sig`` significant digits, entries below
        1e-9 of the largest set to 0 (robust to last-bit differences between platforms)."""
        v = np.asarray(self.values, dtype=float)
        scale = float(np.abs(v).max()) if v.size else 0.0
        v = np.where(np.abs(v) < 1e-9 * scale, 0.0, v)
        text = "\n".join(f"{x:.{sig - 1}e}" for x in v)
        return hashlib.sha256(text.encode()).hexdigest()

    def file_text(self) -> str:
        """One value per line, 17 significant digits: reading it back gives the same doubles."""
        return "".join(f"{float(v)!r}\n" for v in self.values)


@dataclass(frozen=True)
class Command:
    """One logged OpenSees command: name and positional arguments."""

    name: str
    args: tuple[Any, ...] = field(default_factory=tuple)


def render_value(v: Any, style: str, *, golden: bool = False) -> str:
    """One argument as Tcl or Python source text (``golden``: floats to 12 digits)."""
    if isinstance(v, ArrayArg):
        raise TypeError("ArrayArg is rendered by the caller")
    if isinstance(v, bool):
        v = int(v)
    if isinstance(v, (int, np.integer)):
        return str(int(v))
    if isinstance(v, (float, np.floating)):
        v = float(v)
        if golden:
            return f"{v:.12g}"
        return repr(v)
    if isinstance(v, str):
        # quoted so that no string can start a substitution or a new command (issue 16)
        return py_str(v) if style == "py" else tcl_word(v)
    raise TypeError(f"cannot render argument {v!r}")


class OpsSession:
    """Execute OpenSees commands and log the model-defining ones.

    Attribute access returns a callable: ``session.node(1, 0.0, 0.0)`` runs
    ``openseespy.opensees.node`` and appends ``Command("node", (1, 0.0, 0.0))`` to
    :attr:`log` (unless the command is a query in :data:`QUERIES` or logging is paused).
    """

    _active = False

    def __init__(self) -> None:
        self.log: list[Command] = []
        self._tags: dict[str, dict[str, int]] = {}
        self._logging = True
        self._open = False

    # -- context ------------------------------------------------------------------------
    def __enter__(self) -> OpsSession:
        if OpsSession._active:
            raise RuntimeError("an OpsSession is already open (openseespy has one global domain)")
        OpsSession._active = True
        self._open = True
        _ops.wipe()
        self.log.append(Command("wipe"))
        return self

    def __exit__(self, *exc) -> None:
        try:
            _ops.wipe()
        finally:
            OpsSession._active = False
            self._open = False

    @property
    def raw(self):
        """The openseespy module itself, for hot loops (nothing is logged through it)."""
        if not self._open:
            raise RuntimeError("OpsSession is not open")
        return _ops

    # -- tags ---------------------------------------------------------------------------
    def tag(self, kind: str, name: str) -> int:
        """Integer tag of ``name`` among objects of ``kind`` (allocated 1, 2, ... on first use)."""
        reg = self._tags.setdefault(kind, {})
        if name not in reg:
            reg[name] = len(reg) + 1
        return reg[name]

    def tags(self, kind: str) -> dict[str, int]:
        """Name → tag of every object of ``kind`` allocated so far."""
        return dict(self._tags.get(kind, {}))

    def kinds(self) -> list[str]:
        """The kinds that have tags, in order of first use (for the export's tag legend)."""
        return list(self._tags)

    def comment(self, text: str) -> None:
        """A comment line in the log and the exported scripts (not executed)."""
        if self._logging:
            self.log.append(Command("#", (text,)))

    # -- execution ----------------------------------------------------------------------
    def call(self, name: str, *args: Any) -> Any:
        if not self._open:
            raise RuntimeError(f"OpenSees command {name!r} outside an OpsSession")
        flat: list[Any] = []
        for a in args:
            if isinstance(a, ArrayArg):
                flat.append("-values")
                flat.extend(float(v) for v in a.values)
            elif isinstance(a, (np.floating,)):
                flat.append(float(a))
            elif isinstance(a, (np.integer,)):
                flat.append(int(a))
            else:
                flat.append(a)
        out = getattr(_ops, name)(*flat)
        if self._logging and name not in QUERIES:
            self.log.append(Command(name, tuple(args)))
        return out

    def __getattr__(self, name: str):
        if name.startswith("_"):
            raise AttributeError(name)
        if not hasattr(_ops, name):
            raise AttributeError(f"openseespy has no command {name!r}")
        return lambda *args: self.call(name, *args)

    # -- rendering ----------------------------------------------------------------------
    def render(self, style: str = "log", **kw) -> str:
        """The log as text; see :func:`render_commands`."""
        return render_commands(self.log, style, **kw)


def render_command(
    cmd: Command,
    style: str,
    *,
    golden: bool = False,
    file_of: dict[str, str] | None = None,
    module: str = "ops",
) -> str:
    """One command as a line of ``style``: ``log`` (Tcl-like, arrays abbreviated), ``tcl`` or
    ``py`` (arrays read with ``-filePath`` from files named by ``file_of[name]`` in the script's
    data folder: ``$dataDir`` in Tcl, ``_data(name)`` in Python — the scripts define both).
    Strings are quoted for the language and comments escaped (:mod:`.quoting`)."""
    if cmd.name == "#":
        return f"# {comment_text(cmd.args[0], 'py' if style == 'py' else 'tcl')}"
    parts: list[str] = []
    py_parts: list[str] = []
    for a in cmd.args:
        if isinstance(a, ArrayArg):
            if style == "log":
                parts.append(f"-values <{a.name}: {len(a.values)} values sha256 {a.digest()}>")
            else:
                fname = (file_of or {}).get(a.name, f"{a.name}.txt")
                parts.append(f"-filePath [file join $dataDir {tcl_word(fname)}]")
                py_parts += ["'-filePath'", f"_data({py_str(fname)})"]
            continue
        parts.append(render_value(a, "tcl" if style != "py" else "py", golden=golden))
        py_parts.append(render_value(a, "py"))
    if style == "py":
        return f"{module}.{cmd.name}({', '.join(py_parts)})"
    return " ".join([cmd.name] + parts)


def render_commands(
    log: list[Command],
    style: str = "log",
    *,
    golden: bool = False,
    file_of: dict[str, str] | None = None,
    module: str = "ops",
) -> str:
    """The whole log, one command a line."""
    return (
        "\n".join(
            render_command(c, style, golden=golden, file_of=file_of, module=module) for c in log
        )
        + "\n"
    )
