"""The ``deckpound`` command line, and its one error boundary.

Every command ends in exactly one of these exit statuses, with at most one line on stderr
(``deckpound: error: ...``) after any warnings, and never a traceback:

===  ==========================================================================================
0    success
1    engine failure: an engine could not finish (its status message names step and time)
2    bad input: scene, record, override or option refused (the line names the field, the
     value and what is allowed), including output paths that can never be written (below a
     file, a symbolic link, a folder where a file is expected) and an output folder in use by
     another running command (the line names its command line and PID) — refused before any
     work
3    I/O or resource failure: the system refused (read-only or full disk, no permission,
     ``/proc``, stdout closed or full, out of memory, stack exhausted, an unreachable Dask
     scheduler), or a library an engine or a command needs cannot be loaded (missing, broken,
     or no memory to load it: openseespy, matplotlib, dask)
4    internal error: a bug in deckpound (please report it with ``DECKPOUND_DEBUG=1``, which
     prints the traceback)
130  interrupted (Ctrl-C)
143  terminated (SIGTERM: ``kill``, ``timeout``, a batch scheduler): the same clean stop as
     Ctrl-C — workers killed, one line saying what is cached, resumable; a second SIGTERM
     ends the process at once
===  ==========================================================================================

An output folder of a command that failed or was interrupted is either removed (if the command
created it and wrote nothing) or holds a file ``INCOMPLETE`` naming the command; re-running
the command resumes and removes it (:mod:`deckpound.models.file_io`, which also locks output folders and
removes temporary files left by killed writes). A closed stdout or stderr (``>&-``) changes no
exit status except that output which cannot be written to stdout is an I/O failure (3); the
closed descriptor is pointed at ``/dev/null`` first, so no output file can take its number and
receive the libraries' messages. What the engines' libraries print on
stderr (OpenSees's solver chatter) is held back so that a failure stays one line;
``DECKPOUND_DEBUG=1`` shows it. Subcommands live in small modules
(``_cli_*``) that each register themselves on the parser.
"""

from __future__ import annotations

import argparse
import errno
import io
import os
import shlex
import sys
import warnings

from deckpound import __version__
from deckpound._terminal import terminal_text
from deckpound.models.errors import DoubtfulResult, EngineFailure, SceneError
from deckpound.models.file_io import command_scope

EXIT_OK, EXIT_ENGINE, EXIT_INPUT, EXIT_IO, EXIT_BUG, EXIT_INTERRUPTED = 0, 1, 2, 3, 4, 130
EXIT_TERMINATED = 143  # 128 + SIGTERM, what a shell reports for a process ended by SIGTERM
EXIT_CODES_HELP = """exit status:
  0    success
  1    engine failure (the message names the step and time), or a doubtful result: the
       run finished but created energy at its contacts (run.accept_doubtful accepts it)
  2    bad input: scene, record, override or option refused (one line names the field),
       or the output folder is in use by another command (named with its PID)
  3    I/O or resource failure: read-only or full disk, no permission, stdout closed or
       full, out of memory, unreachable Dask scheduler, a library that cannot be loaded
  4    internal error (a bug: re-run with DECKPOUND_DEBUG=1 for the traceback and report it)
  130  interrupted
  143  terminated (SIGTERM), stopped as cleanly as by Ctrl-C
A failed command leaves no new output folder, or one marked by a file INCOMPLETE
(re-run the command to resume). Messages of the engines' libraries (OpenSees) are
shown only with DECKPOUND_DEBUG=1."""


class UsageError(Exception):
    """Bad command-line usage (argparse's own errors are routed here)."""


class _Parser(argparse.ArgumentParser):
    """ArgumentParser whose errors are one line and exit status 2, never a usage dump."""

    def error(self, message: str):
        raise UsageError(f"{self.prog}: {message}")

    def _print_message(self, message, file=None):
        # argparse's own version swallows OSError: --help into a closed or full stdout would
        # end in success with nothing written; here it is an I/O failure like any output
        if message:
            (file or sys.stderr).write(message)


def build_parser() -> argparse.ArgumentParser:
    from . import _cli_bench, _cli_compile, _cli_engines, _cli_fragility, _cli_scene, _cli_study

    parser = _Parser(
        prog="deckpound",
        description="Deck-abutment pounding of bridges, three "
        "ways from one scene: OpenSees, compliance and nonsmooth engines.",
        epilog=EXIT_CODES_HELP,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser.add_argument("--version", action="version", version=f"deckpound {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", parser_class=_Parser)
    sub.required = True
    for module in (_cli_scene, _cli_engines, _cli_study, _cli_bench, _cli_compile):
        module.register(sub)
    _cli_fragility.register(sub)
    return parser


def _one_line(text: str, limit: int = 600) -> str:
    # line breaks and other white space become one space; ESC, BEL, bidi controls... in a
    # name or path quoted by the message are shown escaped, never sent to the terminal
    line = terminal_text(" ".join(str(text).split()))
    return line if len(line) <= limit else line[: limit - 3] + "..."


def _os_error_text(err: OSError) -> str:
    """'cannot write 'x': No space left on device' style text of an OSError."""
    what = err.strerror or (str(err) if str(err) else type(err).__name__)
    if err.errno == errno.ENOSPC:
        what = "no space left on the device"
    names = [n for n in (err.filename, err.filename2) if n is not None]
    return f"I/O error on {str(names[0])!r}: {what}" if names else what


def _report(kind: str, message: str) -> None:
    text = (
        f"deckpound: {kind}: {_one_line(message)}"
        if kind
        else f"deckpound: {terminal_text(message)}"
    )
    try:
        print(text, file=sys.stderr, flush=True)
    except Exception:
        pass  # stderr itself is gone: the exit status is all that is left, and stays the same


class StdoutError(OSError):
    """Writing the command's output to stdout failed (full device, closed, I/O error)."""


class _GuardedStdout:
    """Stdout during a command: an OSError of write/flush becomes :class:`StdoutError`, so the
    boundary can tell "stdout is full" from a failing output file."""

    def __init__(self, stream):
        self._stream = stream

    def write(self, text):
        try:
            return self._stream.write(text)
        except BrokenPipeError:
            raise
        except OSError as err:
            raise StdoutError(err.errno, err.strerror or str(err)) from None

    def flush(self):
        try:
            return self._stream.flush()
        except BrokenPipeError:
            raise
        except OSError as err:
            raise StdoutError(err.errno, err.strerror or str(err)) from None

    def __getattr__(self, name):
        return getattr(self._stream, name)


class _ClosedStdout(io.TextIOBase):
    """Stands for a stdout that was closed when the program started (``>&-``: Python sets
    ``sys.stdout`` to None): writing the command's output to it fails as writing to a closed
    descriptor does, an I/O failure (exit status 3); a command that prints nothing succeeds."""

    def write(self, text):
        if text:
            raise OSError(errno.EBADF, "it is closed (give a file or /dev/null instead)")
        return 0


class _ClosedStderr(io.TextIOBase):
    """Stands for a stderr that was closed when the program started: messages are lost, the
    exit status is what it would have been."""

    def write(self, text):
        return len(text)


class _QuietStderr:
    """Stderr during a command: deckpound's own lines (``deckpound: ...`` warnings and errors,
    ``\r`` progress bars) pass; other text — the engines' libraries write theirs here (OpenSees:
    "WARNING ZeroLengthContact2D ...", "analyze failed ...") — is held back, so a failure is still
    one line. ``DECKPOUND_DEBUG=1`` lets everything through."""

    def __init__(self, stream, show_all: bool):
        self._stream, self._show_all = stream, show_all
        self._passing = True  # the decision for the line being written
        self._at_start = True  # the next write starts a new line
        self.held = 0  # lines held back

    def write(self, text):
        if self._show_all or not text:
            return self._stream.write(text)
        if self._at_start:
            self._passing = text.startswith(("deckpound", "\r", "\n"))
            self.held += not self._passing
        self._at_start = text.endswith("\n")
        if "\n" in text[:-1] and not self._passing:  # several lines in one write
            rest = text[text.index("\n") + 1 :]
            self._at_start = True
            return self.write(rest) if rest else len(text)
        return self._stream.write(text) if self._passing else len(text)

    def __getattr__(self, name):
        return getattr(self._stream, name)


def _flush_stdout() -> None:
    """Flush stdout inside the boundary (a full or closed stdout is an I/O failure)."""
    sys.stdout.flush()


def _silence_stdout() -> None:
    """After a failed write to stdout, point it at /dev/null so the interpreter's own flush
    at exit cannot print a second error."""
    try:
        fd = sys.stdout.fileno()
    except (AttributeError, OSError, ValueError):
        return  # not a real file (tests capture it)
    try:
        null = os.open(os.devnull, os.O_WRONLY)
        os.dup2(null, fd)
        os.close(null)
    except OSError:
        pass


def _quiet_exit() -> None:
    """In the real process, after the last word: stdout flushed, stderr to /dev/null, so that
    libraries cannot add lines at interpreter exit (OpenSees prints 'Process 0 Terminating')."""
    try:
        if sys.stdout is not None:  # None: closed when the program started
            sys.stdout.flush()
    except (OSError, ValueError):
        _silence_stdout()
    try:
        sys.stderr.flush()
        null = os.open(os.devnull, os.O_WRONLY)
        os.dup2(null, sys.stderr.fileno())
        os.close(null)
    except (AttributeError, OSError, ValueError):
        pass


def main(argv: list[str] | None = None) -> int:
    """Entry point; returns the exit status (see the module docstring).

    The program itself (``argv`` None: the console script, ``python -m deckpound``) ends
    through :func:`_fast_exit` once everything is written and flushed.
    """
    if argv is None:
        _fill_closed_descriptors()
        _stop_on_sigterm()
    code = _main(argv)
    if argv is None:  # the program itself (console script, python -m deckpound)
        _quiet_exit()
        _fast_exit(code)
    return code


def _fill_closed_descriptors() -> None:
    """Point a standard descriptor (0, 1, 2) that was closed when the program started
    (``>&-``) at ``/dev/null``. Left free, its number would go to the next file opened — an
    output file or a lock file — and whatever the engines' libraries write to fd 1 or 2 would
    land in it. ``sys.stdout``/``sys.stderr`` stay None, so :func:`_main` still treats them as
    closed."""
    for fd in (0, 1, 2):
        try:
            os.fstat(fd)
            continue
        except OSError:
            pass
        try:
            null = os.open(os.devnull, os.O_RDWR)
        except OSError:
            return
        if null != fd:
            os.dup2(null, fd)
            os.close(null)


#: set by the SIGTERM handler: the KeyboardInterrupt it raised is a termination
_TERMINATED = [False]


def _stop_on_sigterm() -> None:
    """Make SIGTERM stop the program as Ctrl-C does (exit 143 instead of 130).

    Python's default for SIGTERM ends the process on the spot: no line saying what is cached,
    and a sweep's output marked INCOMPLETE with nothing said. The handler raises
    KeyboardInterrupt in the main thread, so every clean-up a Ctrl-C runs (a compiled loop
    halted, workers killed, the resume line) runs; a second SIGTERM while that clean-up runs
    ends the process at once (workers die with it, :mod:`deckpound.compare._workers`). Installed
    only over the default action, by the program itself (not when :func:`main` is called from
    Python); sweep workers put the default back (:func:`deckpound.compare.pool.worker_init`).
    """
    import signal

    if signal.getsignal(signal.SIGTERM) is not signal.SIG_DFL:
        return

    def on_sigterm(signum, frame):
        if _TERMINATED[0]:
            os._exit(EXIT_TERMINATED)
        _TERMINATED[0] = True
        raise KeyboardInterrupt

    signal.signal(signal.SIGTERM, on_sigterm)


def _fast_exit(code: int) -> None:
    """End the process now: run the ``atexit`` handlers, then ``os._exit``. Skips the
    interpreter's module teardown — 0.2–0.3 s of freeing numba's and LLVM's objects after a
    compiled run, a quarter of a warm ``deckpound run`` — which has nothing left to do: every
    output is written atomically and flushed, worker pools are shut down by the command.
    ``DECKPOUND_DEBUG=1`` keeps the normal interpreter exit."""
    if os.environ.get("DECKPOUND_DEBUG", "").strip() not in ("", "0"):
        return
    import atexit

    try:
        atexit._run_exitfuncs()
    except BaseException:
        pass
    os._exit(code)


def _main(argv: list[str] | None) -> int:
    stdout, stderr = sys.stdout, sys.stderr
    debug = os.environ.get("DECKPOUND_DEBUG", "").strip() not in ("", "0")
    # None: closed when the program started (`>&-`); the exit status must not depend on it
    sys.stdout = _GuardedStdout(stdout if stdout is not None else _ClosedStdout())
    sys.stderr = _QuietStderr(stderr if stderr is not None else _ClosedStderr(), show_all=debug)
    words = sys.argv[1:] if argv is None else argv
    try:
        with command_scope(shlex.join(["deckpound", *map(str, words)])):
            return _guarded_main(argv)
    finally:
        if isinstance(sys.stdout, _GuardedStdout):
            sys.stdout = stdout
        if isinstance(sys.stderr, _QuietStderr):
            sys.stderr = stderr


def _guarded_main(argv: list[str] | None) -> int:
    debug = os.environ.get("DECKPOUND_DEBUG", "").strip() not in ("", "0")
    warnings.simplefilter("default")
    warnings.formatwarning = lambda msg, cat, *a, **k: f"deckpound: warning: {_one_line(msg)}\n"
    try:
        try:
            parser = build_parser()
            try:
                args = parser.parse_args(argv)
            except SystemExit as done:  # --help / --version have printed their text
                _flush_stdout()
                return done.code if isinstance(done.code, int) else 0
            from deckpound.compare.pool import pool_scope

            with pool_scope():  # sweeps of this command share one set of worker processes
                code = int(args.func(args) or 0)
            _flush_stdout()
            return code
        except (SceneError, UsageError) as err:
            _report("error", str(err))
            return EXIT_INPUT
        except DoubtfulResult as err:  # finished, but a quality check failed (energy created)
            _report("doubtful result", str(err))
            return EXIT_ENGINE
        except EngineFailure as err:
            _report("engine failure", str(err))
            return EXIT_ENGINE
        except KeyboardInterrupt as err:  # a sweep says what is cached and how to resume
            how, code = "interrupted", EXIT_INTERRUPTED
            if _TERMINATED[0]:
                how, code = "terminated (SIGTERM)", EXIT_TERMINATED
            _report("", f"{how}: {err}" if str(err) else how)
            return code
        except BrokenPipeError:
            _silence_stdout()  # `deckpound ... | head`: the reader has all it wanted
            return EXIT_OK
        except OSError as err:
            if debug:
                raise
            if isinstance(err, StdoutError):
                _silence_stdout()
                _report("error", f"cannot write the output to stdout: {_os_error_text(err)}")
            else:
                _report("error", _os_error_text(err))
            return EXIT_IO
        except MemoryError:
            _report(
                "error",
                "out of memory; reduce the record length, the output rate "
                "(run.output_dt) or the number of workers",
            )
            return EXIT_IO
        except RecursionError:
            if debug:
                raise
            _report("error", "input nested too deeply (Python's recursion limit was reached)")
            return EXIT_IO
        except ImportError as err:
            library = _library_of(err)
            if debug or library is None:
                raise  # deckpound's own module: a bug (below)
            _report("error", _library_failure(library, err))
            return EXIT_IO
    except Exception as err:  # a bug: one line, the traceback only on request
        if debug:
            raise
        _report(
            "internal error",
            f"{type(err).__name__}: {err} (this is a bug in deckpound "
            f"{__version__}; re-run with DECKPOUND_DEBUG=1 for the traceback and report it)",
        )
        return EXIT_BUG


#: what each optional library is needed for, for the message when it cannot be loaded
_LIBRARY_USE = {
    "openseespy": "the OpenSees engine",
    "matplotlib": "figures",
    "dask": "--scheduler",
    "distributed": "--scheduler",
}
#: the pip requirement that installs each library, where it is not the library's own name
_LIBRARY_PIP = {"dask": "'dask[distributed]'", "distributed": "'dask[distributed]'"}


def _library_of(err: ImportError) -> str | None:
    """The top-level name of the library whose import failed, or None if it is one of
    deckpound's own modules (a bug, exit status 4). Without a module name, the module whose
    code raised the error decides."""
    name = err.name
    if not name:
        tb = err.__traceback__
        while tb is not None and tb.tb_next is not None:
            tb = tb.tb_next
        name = tb.tb_frame.f_globals.get("__name__", "") if tb is not None else ""
    top = str(name or "").split(".")[0]
    return None if top in ("", "deckpound", "__main__") else top


def _library_failure(library: str, err: ImportError) -> str:
    """One line: which library, why (memory or a missing/broken install), what to do."""
    use = f" (needed for {_LIBRARY_USE[library]})" if library in _LIBRARY_USE else ""
    chain, cause = [], err
    while cause is not None and len(chain) < 16:
        chain.append(cause)
        cause = cause.__cause__ or cause.__context__
    text = " ".join(str(c) for c in chain).lower()
    short_of_memory = any(isinstance(c, MemoryError) for c in chain) or any(
        w in text for w in ("memory", "failed to map segment")
    )
    if short_of_memory:
        return (
            f"not enough memory to load the library {library!r}{use}: {err}; free memory "
            "or raise the process's memory limit (ulimit -v)"
        )
    return (
        f"the library {library!r}{use} cannot be loaded: {err}; it is missing or broken in "
        "this Python environment: reinstall it (pip install --force-reinstall "
        f"{_LIBRARY_PIP.get(library, library)})"
    )


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
