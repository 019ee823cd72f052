"""Reading earthquake records: PEER AT2 and plain two-column text (CSV: :mod:`.record_csv`).

The readers only read: they return the values as written (acceleration in the file's unit,
time in the record's seconds) with what they tolerated, and the processing, time scaling and
scaling to a target PGA happen in :mod:`deckpound.models.record_motion`.

Rules every reader follows (issue 16):

* sizes are checked before anything big is allocated: the file is read in chunks, at most
  ``MAX_RECORD_BYTES`` bytes and ``MAX_SAMPLES`` lines, and an AT2 header's NPTS is checked
  before the values are converted;
* a message quotes a file's content only once the file was recognised as a record (AT2 header
  line with NPTS and DT, CSV header with the time column, a text file's first data line), and
  then only the excerpt needed (one token, at most ``EXCERPT`` characters) — naming a system
  file as a record never prints its lines;
* paths are shown resolved (absolute, symbolic links followed);
* every tolerance (a value more than NPTS, a time base not starting at 0, ...) is a sentence in
  ``notes``; :func:`deckpound.models.excitation.support_motion` turns the notes into warnings
  and into the motion's provenance once the whole motion is accepted.
"""

from __future__ import annotations

import dataclasses
import hashlib
import io
import re
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .errors import SceneError
from .kept import Kept

MIN_SAMPLES = 16  # shortest record the processing (zero-phase filter, taper) can handle
MAX_SAMPLES = 2_000_000  # longest record held in memory (600 s at 0.3 ms)
MAX_RECORD_BYTES = 256 * 2**20  # 2e6 rows of a 23-column CSV hold about 250 MB
EXCERPT = 24  # longest excerpt of a record quoted in a message [characters]
_CHUNK = 2**20
#: samples of parsed record files kept per process, at most [bytes] (a sweep applies one record
#: pair at many levels: IDA, stripes; each file is parsed once, not once per case), keyed by
#: field, path and the SHA-256 of the bytes just read: an edited file is parsed again; the
#: least recently read go first, and a record larger than this is not kept
PARSED_BYTES = 64 * 2**20
PARSED = Kept(PARSED_BYTES, lambda rec: rec.values.nbytes)

# a number ends where no digit, point, exponent or sign follows ("1.2.3", "1e" are no numbers)
_NUMBER = r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[EeDd][-+]?\d+)?(?![\d.EeDd+-])"
_NPTS = re.compile(rf"NPTS\s*[=:]?\s*({_NUMBER})", re.IGNORECASE)
_DT = re.compile(rf"\bDT\s*[=:]?\s*({_NUMBER})", re.IGNORECASE)
_OLD = re.compile(rf"^\s*({_NUMBER})[\s,;]+({_NUMBER})[\s,;]+NPTS\s*[,;]?\s*DT\b", re.IGNORECASE)
_NAMES = re.compile(r"\bNPTS\b.*\bDT\b|\bDT\b.*\bNPTS\b", re.IGNORECASE)
_KIND = re.compile(r"\b(VELOCITY|DISPLACEMENT)\b", re.IGNORECASE)
_UNIT = re.compile(r"UNITS?\s+OF\s+([A-Za-z/*^0-9.']+)", re.IGNORECASE)
_SEP = re.compile(r"[\s,;]+")


@dataclass
class RecordFile:
    """One record file as read.

    Attributes
    ----------
    path : resolved absolute path; sha256 : hex digest of the file's bytes; size : bytes.
    header : the station/event line (AT2 line 2, a text file's first comment), one line.
    npts : value count the file declares (AT2 NPTS) or holds (text), before tolerances.
    dt : sampling step as written [s]; t0 : first time stamp as written [s] (AT2: 0).
    values : (n,) samples as written (AT2: g; text: ``acc_unit``).
    notes : what was tolerated, one sentence each, prefixed with the field and the path.
    """

    field: str
    path: str
    sha256: str
    size: int
    header: str | None = None
    npts: int = 0
    dt: float = 0.0
    t0: float = 0.0
    values: np.ndarray = field(default_factory=lambda: np.zeros(0))
    notes: list[str] = field(default_factory=list)

    @property
    def label(self) -> str:
        """``excitation.file_x (/abs/path/x.at2)``: the prefix of every message about it."""
        return f"{self.field} ({self.path})"

    def note(self, text: str) -> None:
        self.notes.append(f"{self.label}: {text}")

    def info(self) -> dict:
        """JSON-able identity of the file for the provenance."""
        return {"path": self.path, "sha256": self.sha256, "bytes": self.size}


def excerpt(text: str) -> str:
    """``repr`` of at most EXCERPT characters of a user's record (control characters escaped)."""
    return repr(text[:EXCERPT] + ("…" if len(text) > EXCERPT else ""))


def one_line(text: str, limit: int = 120) -> str:
    """A header line made safe for a report: printable characters, single spaces, ≤ limit."""
    clean = "".join(c if c.isprintable() else " " for c in text)
    clean = " ".join(clean.split())
    return clean[:limit]


def resolve_path(path: str | Path, field_name: str, base: Path | None = None) -> Path:
    """``path`` (relative to ``base`` if given and not absolute) made absolute, ``~`` expanded,
    symbolic links followed; a path the system cannot use is refused, not a traceback."""
    try:
        p = Path(path).expanduser()
        return ((base / p) if base is not None and not p.is_absolute() else p).resolve()
    except (ValueError, RuntimeError, OSError) as err:  # NUL byte, unknown ~user, link loop
        reason = str(err).splitlines()[0][:60] if str(err) else type(err).__name__
        raise SceneError(field_name, f"is not a usable file path ({reason})") from None


def read_capped(
    path: str | Path | None, field_name: str, what: str, max_lines: int
) -> tuple[bytes, RecordFile]:
    """The bytes of a record file with its SHA-256, refused when too big before it is all read.

    Reads in 1 MiB chunks and stops as soon as the file exceeds ``MAX_RECORD_BYTES`` or holds
    more than ``max_lines`` lines, so a 10-million-row file costs a few megabytes to refuse.
    """
    if not path:
        raise SceneError(field_name, f"names no {what} file")
    resolved = resolve_path(path, field_name)
    if not resolved.is_file():
        raise SceneError(field_name, f"{what} {str(resolved)!r} does not exist or is not a file")
    digest, chunks, size, lines = hashlib.sha256(), [], 0, 0
    try:
        with open(resolved, "rb") as fh:
            while chunk := fh.read(_CHUNK):
                size += len(chunk)
                lines += chunk.count(b"\n")
                if size > MAX_RECORD_BYTES:
                    raise SceneError(
                        field_name,
                        f"{what} {str(resolved)!r} is larger than "
                        f"{MAX_RECORD_BYTES // 2**20} MiB, the largest record read",
                    )
                if lines > max_lines:
                    raise SceneError(
                        field_name,
                        f"{what} {str(resolved)!r} holds more than "
                        f"{max_lines:,} lines; records of at most {MAX_SAMPLES:,} "
                        "samples are read",
                    )
                digest.update(chunk)
                chunks.append(chunk)
    except OSError as err:
        raise SceneError(
            field_name, f"cannot read {str(resolved)!r}: {err.strerror or type(err).__name__}"
        ) from None
    raw = b"".join(chunks)
    if b"\x00" in raw[:65536]:
        raise SceneError(
            field_name,
            f"{str(resolved)!r} is not a text file (it holds NUL bytes); a {what} is text",
        )
    return raw, RecordFile(field_name, str(resolved), digest.hexdigest(), size)


def _to_floats(tokens: list[str], rec: RecordFile, where) -> np.ndarray:
    """Tokens to floats; a bad token is quoted (excerpt) with its place from ``where(i)``."""
    try:
        values = np.array(tokens, dtype=float)
    except ValueError:
        values = None
    if values is None or not np.all(np.isfinite(values)):
        for i, tok in enumerate(tokens):
            try:
                ok = np.isfinite(float(tok.replace("D", "E").replace("d", "e")))
            except ValueError:
                ok = False
            if not ok:
                raise SceneError(
                    rec.field,
                    f"{rec.path!r}: {where(i)} holds {excerpt(tok)}: not finite or not a number",
                ) from None
    return values


def check_count(n: int, rec: RecordFile, what: str) -> None:
    """Refuse a sample count the processing cannot handle or memory cannot hold."""
    if n < MIN_SAMPLES:
        raise SceneError(
            rec.field, f"{rec.path!r}: {what} {n} samples; at least {MIN_SAMPLES} are needed"
        )
    if n > MAX_SAMPLES:
        raise SceneError(
            rec.field, f"{rec.path!r}: {what} {n:,} samples; at most {MAX_SAMPLES:,} are read"
        )


def _check_dt(dt: float, rec: RecordFile, what: str) -> None:
    if not (np.isfinite(dt) and 1e-5 <= dt <= 0.5):
        raise SceneError(
            rec.field, f"{rec.path!r}: {what} must be between 1e-05 s and 0.5 s, got {dt:g} s"
        )


# -- PEER AT2 ------------------------------------------------------------------------------


def _at2_header(lines: list[str]) -> tuple[int, int, float] | None:
    """(line index, NPTS, DT) of the first header line (of the first 6) giving both."""
    for i, line in enumerate(lines[:6]):
        old = _OLD.search(line)
        if old:
            return i, *_npts_dt(old.group(1), old.group(2))
        n, d = _NPTS.search(line), _DT.search(line)
        if n and d:
            return i, *_npts_dt(n.group(1), d.group(1))
    return None


def _npts_dt(n: str, d: str) -> tuple[int, float]:
    npts = float(n.replace("D", "E").replace("d", "e"))
    dt = float(d.replace("D", "E").replace("d", "e"))
    return (int(npts) if np.isfinite(npts) and npts == int(npts) else -1), dt


def _parsed(kind: str, raw: bytes, rec: RecordFile, parse: Callable) -> RecordFile:
    """``parse(raw, rec)`` (it fills ``rec``) once per file content: a file read again with the
    same bytes gets a copy of the first parse (its own notes list; the values array shared,
    read-only). A refused file is parsed (and refused) every time."""
    key = (kind, rec.field, rec.path, rec.sha256)
    done = PARSED.get(key)
    if done is None:
        parse(raw, rec)
        rec.values.flags.writeable = False
        done = dataclasses.replace(rec, notes=list(rec.notes))
        PARSED.put(key, done)
    return dataclasses.replace(done, notes=list(done.notes))


def read_at2(path: str | Path | None, field_name: str = "excitation.file_x") -> RecordFile:
    """Read a PEER AT2 acceleration record [g].

    Header (liberal with spacing, commas, case, ``=`` or ``:``): text lines, then one line
    giving NPTS and DT, either ``NPTS= 7999, DT= .0050 SEC`` (NGA-West2) or
    ``7999 0.0050 NPTS, DT`` (older PEER files), among the first 6 lines; the values follow,
    any number per line. The station/event line is line 2.

    Tolerated, with a note: more values than NPTS (downloads can hold one more: the first
    NPTS are used). Refused: fewer values than NPTS (a cut file: the strong motion may be what
    is missing; if the file is complete, correct NPTS), a velocity or displacement series
    (VT2, DT2), a unit other than g, NPTS outside [MIN_SAMPLES, MAX_SAMPLES] (checked before
    the values are converted), DT outside [1e-5, 0.5] s.
    """
    raw, rec = read_capped(path, field_name, "AT2 record", MAX_SAMPLES + 10)
    return _parsed("at2", raw, rec, _parse_at2)


def _parse_at2(raw: bytes, rec: RecordFile) -> None:
    """The AT2 parse of :func:`read_at2` into ``rec``."""
    field_name = rec.field
    text = raw.decode("utf-8", errors="replace")
    lines = text.splitlines()
    head = _at2_header(lines)
    named = [i for i, line in enumerate(lines[:6]) if _NAMES.search(line)]
    if head is None and named:
        raise SceneError(
            field_name,
            f"{rec.path!r}: header line {named[0] + 1} must give NPTS "
            "and DT as numbers (as 'NPTS= 7999, DT= .0050 SEC' or "
            "'7999 .0050 NPTS, DT')",
        )
    if head is None:  # not recognised as a record: quote nothing of it
        raise SceneError(
            field_name,
            f"{rec.path!r} is not a PEER AT2 file: none of its first 6 "
            "lines gives NPTS and DT (as 'NPTS= 7999, DT= .0050 SEC' or "
            "'7999 .0050 NPTS, DT')",
        )
    k, npts, dt = head
    for line in lines[:k]:
        kind, unit = _KIND.search(line), _UNIT.search(line)
        if kind:
            raise SceneError(
                field_name,
                f"{rec.path!r} is a {kind.group(1).lower()} time series "
                "(header line), not an acceleration record",
            )
        if unit and not unit.group(1).upper().startswith("G"):
            raise SceneError(
                field_name,
                f"{rec.path!r}: the header gives the unit "
                f"{excerpt(unit.group(1))}; AT2 records are read in g",
            )
    rec.header = one_line(lines[1]) if k >= 2 else None
    if npts < 0:
        raise SceneError(
            field_name, f"{rec.path!r}: NPTS in header line {k + 1} must be a whole number"
        )
    check_count(npts, rec, "NPTS gives")
    _check_dt(dt, rec, f"DT in header line {k + 1}")
    rec.npts, rec.dt = npts, dt
    body = lines[k + 1 :]
    counts = np.cumsum([0] + [len(line.split()) for line in body])
    joined = " ".join(body)
    tokens = joined.split()
    if len(tokens) < npts:
        raise SceneError(
            field_name,
            f"{rec.path!r}: header says NPTS={npts} but the file holds "
            f"{len(tokens)} values (a cut download?); if the file is complete, "
            f"correct NPTS in header line {k + 1}",
        )
    if len(tokens) > npts:
        extra = len(tokens) - npts
        if extra > max(10, npts // 100):  # more than a stray value: not the record described
            raise SceneError(
                field_name,
                f"{rec.path!r}: header says NPTS={npts} but the file "
                f"holds {len(tokens)} values ({extra} more); at most "
                f"{max(10, npts // 100)} extra values are tolerated",
            )
        rec.note(
            f"holds {len(tokens)} values but NPTS = {npts}: the first {npts} are used, the "
            f"last {extra} ignored"
        )
        tokens = tokens[:npts]

    def where(i: int) -> str:
        return f"line {k + 2 + int(np.searchsorted(counts, i, side='right')) - 1}"

    if "D" in joined or "d" in joined:  # Fortran exponents (1.0D-03) somewhere: Python's form
        tokens = [t.replace("D", "E").replace("d", "e") for t in tokens]
    rec.values = _to_floats(tokens, rec, where)


# -- two-column text -----------------------------------------------------------------------


def read_text(path: str | Path | None, field_name: str = "excitation.file_x") -> RecordFile:
    """Read a plain two-column record: time [s], acceleration [``acc_unit``], one pair a line.

    Separators: spaces, tabs, commas or semicolons. Blank lines and lines starting with ``#``,
    ``%`` or ``!`` are skipped (the first such line is kept as the header); one leading line
    of words (e.g. ``time acc``) is taken as column titles. The time stamps must be evenly
    spaced (within 1 % of the step: printed values are rounded) and increasing; a record not
    starting at 0 is shifted to 0, with a note.
    """
    raw, rec = read_capped(path, field_name, "text record", MAX_SAMPLES + 1000)
    return _parsed("text", raw, rec, _parse_text)


def _parse_text(raw: bytes, rec: RecordFile) -> None:
    """The two-column parse of :func:`read_text` into ``rec``."""
    field_name = rec.field
    decoded = raw.decode("utf-8", errors="replace")
    text = decoded.translate(_TO_SPACE)
    lines = text.splitlines()
    skip, first = 0, None
    for no, line in enumerate(lines, start=1):  # up to the first data line only
        s = line.strip()
        if s and s[0] in _COMMENT:
            if rec.header is None:  # the untranslated line: keep its commas
                original = decoded.splitlines()[no - 1].strip()
                rec.header = one_line(original.lstrip("".join(_COMMENT) + " "))
        elif s and not any(_is_number(tok) for tok in s.split()) and first is None:
            first, skip = "titles", no  # column titles
        elif s:
            first = s.split()
            break
    if not isinstance(first, list) or len(first) != 2 or not all(map(_is_number, first)):
        raise SceneError(
            field_name,
            f"{rec.path!r} is not a two-column record: its first data "
            "line does not hold two numbers (time [s], acceleration)",
        )
    try:
        data = np.loadtxt(io.StringIO(text), comments=_COMMENT, skiprows=skip, ndmin=2)
    except ValueError:
        data = None
    if data is None or data.shape[1] != 2 or not np.all(np.isfinite(data)):
        _text_error(lines[skip:], skip, rec)
    check_count(len(data), rec, "the file holds")
    t, a = data[:, 0], data[:, 1]
    rec.npts, rec.t0, rec.values = len(a), float(t[0]), np.ascontiguousarray(a)
    rows = (
        [
            no
            for no, line in enumerate(lines, start=1)
            if no > skip and line.strip() and line.strip()[0] not in _COMMENT
        ]
        if not _uniform(t)
        else []
    )
    rec.dt = uniform_step(t, rec, lambda i: f"line {rows[i]}" if rows else f"sample {i + 1}")


_TO_SPACE = str.maketrans(",;", "  ")
_COMMENT = ("#", "%", "!")


def _uniform(t: np.ndarray) -> bool:
    dt = (t[-1] - t[0]) / (len(t) - 1)
    return bool(
        dt > 0
        and np.all(np.diff(t) > 0)
        and np.max(np.abs(t - t[0] - dt * np.arange(len(t)))) <= 0.01 * dt
    )


def _text_error(lines: list[str], offset: int, rec: RecordFile) -> None:
    """Find and refuse the first malformed line of a two-column record (the slow path)."""
    for no, line in enumerate(lines, start=offset + 1):
        toks = line.split()
        if not toks or toks[0][0] in _COMMENT:
            continue
        if len(toks) != 2:
            raise SceneError(
                rec.field,
                f"{rec.path!r}: line {no} holds {len(toks)} values; "
                "two are expected (time, acceleration)",
            )
        for tok in toks:
            if not (_is_number(tok) and np.isfinite(float(tok))):
                raise SceneError(
                    rec.field,
                    f"{rec.path!r}: line {no} holds {excerpt(tok)}: not finite or not a number",
                )
    raise SceneError(rec.field, f"{rec.path!r}: the values cannot be read as two columns")


def _is_number(tok: str) -> bool:
    try:
        float(tok)
        return True
    except ValueError:
        return False


def uniform_step(t: np.ndarray, rec: RecordFile, where) -> float:
    """The step of evenly spaced time stamps [s]; refuses uneven or decreasing ones."""
    dt = float(t[-1] - t[0]) / (len(t) - 1)
    _check_dt(dt, rec, "the time step")
    steps = np.diff(t)
    bad = np.flatnonzero(steps <= 0)
    if bad.size:
        raise SceneError(
            rec.field,
            f"{rec.path!r}: time stamps must increase; {where(bad[0] + 1)} "
            f"is at {t[bad[0] + 1]:g} s after {t[bad[0]]:g} s",
        )
    off = np.abs(t - t[0] - dt * np.arange(len(t)))
    if off.max() > 0.01 * dt:
        i = int(np.argmax(off))
        raise SceneError(
            rec.field,
            f"{rec.path!r}: time stamps must be evenly spaced (step "
            f"{dt:g} s); {where(i)} is {off[i]:.3g} s off the grid: resample the "
            "record or print its times with more digits",
        )
    if t[0] != 0.0:
        rec.note(f"time starts at {t[0]:g} s; the record is shifted to start at 0 s")
    return dt
