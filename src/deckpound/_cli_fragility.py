"""CLI: ``fragility fit`` — a lognormal fragility (median, dispersion) from stripe counts."""

from __future__ import annotations

import argparse
import csv
import json
import math
import re

from deckpound.models.errors import SceneError
from deckpound.models.file_io import split_unit_label

from ._cli_args import int_in
from ._terminal import terminal_text

#: the columns a stripes CSV must have (others are ignored)
STRIPE_COLUMNS = ("im", "n", "exceed")


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("fragility", help="lognormal fragility functions from analysis results")
    fsub = p.add_subparsers(dest="fragility_command", metavar="ACTION")
    fsub.required = True
    f = fsub.add_parser(
        "fit",
        help="maximum-likelihood median and dispersion from stripes (im, n, exceed)",
        description="Fit P(exceed | im) = Φ(ln(im/median)/beta) to multiple-stripe counts by "
        "maximum likelihood (binomial, Baker 2015). STRIPES.csv has a header with the columns "
        "im (IM level > 0), n (records run at it) and exceed (records exceeding the limit "
        "state), one row per stripe (a unit may follow a name: 'im [g]'); other columns are "
        "ignored. Records are not identified "
        "in stripe counts, so --bootstrap is parametric: it redraws each stripe's count from "
        "the fitted curve (Binomial(n, P(im))) and refits.",
    )
    f.add_argument("stripes", metavar="STRIPES.csv", help="CSV with columns im, n, exceed")
    out = f.add_mutually_exclusive_group()
    out.add_argument(
        "--json",
        action="store_true",
        help='print only {"median": ..., "beta": ...} on stdout',
    )
    out.add_argument(
        "--bootstrap",
        type=int_in(1, 1_000_000),
        default=None,
        metavar="N",
        help="also a 90%% interval of median and beta from N parametric bootstrap resamples "
        "of the binomial counts (records are not identified in stripes)",
    )
    f.add_argument(
        "--seed", type=int_in(0, 2**63 - 1), default=0, help="bootstrap seed (default 0)"
    )
    f.set_defaults(func=_fit)


def read_stripes_csv(path: str) -> tuple[list[float], list[float], list[float], list[int]]:
    """(im, n, exceed, line number) per stripe row of a stripes CSV; a missing column, an empty file or a value that is
    not a number is a :class:`SceneError` naming the file, the line and the column. Header cells
    may carry a unit (``im [g]``, ``n [-]``), as in the tables deckpound writes."""
    # an unreadable file raises OSError (exit status 3) here, before any parsing
    with open(path, encoding="utf-8-sig", newline="") as stream:  # -sig: a spreadsheet's BOM
        try:
            text = stream.read()
        except UnicodeDecodeError as err:
            raise SceneError(
                path, f"is not a UTF-8 text CSV (byte {err.start}: {err.reason})"
            ) from None
    reader = csv.reader(text.splitlines())
    try:
        header = next(reader, None)
        if header is None:
            raise SceneError(path, "is empty; expected a header with the columns im, n, exceed")
        # a header cell may state its unit ("im [g]", "n [-]": the tables deckpound writes)
        names = [split_unit_label(h.strip())[0] for h in header]
        missing = [c for c in STRIPE_COLUMNS if c not in names]
        if missing:
            raise SceneError(
                path,
                f"has no column {', '.join(map(repr, missing))} in its header line "
                f"({', '.join(map(repr, names))}); required: im, n, exceed",
            )
        where = {c: names.index(c) for c in STRIPE_COLUMNS}
        columns: dict[str, list[float]] = {c: [] for c in STRIPE_COLUMNS}
        lines: list[int] = []
        for row in reader:
            if not any(cell.strip() for cell in row):
                continue  # blank line
            line = reader.line_num
            for name, k in where.items():
                cell = row[k].strip() if k < len(row) else ""
                try:
                    value = float(cell)
                except ValueError:
                    raise SceneError(
                        f"{path} line {line}, column {name}",
                        f"must be a number, got {cell!r}",
                    ) from None
                if not math.isfinite(value):
                    raise SceneError(
                        f"{path} line {line}, column {name}", f"must be finite, got {cell!r}"
                    )
                columns[name].append(value)
            lines.append(line)
    except csv.Error as err:
        raise SceneError(path, f"is not a readable CSV: {err}") from None
    if not columns["im"]:
        raise SceneError(path, "has a header but no stripe rows")
    return columns["im"], columns["n"], columns["exceed"], lines


def _fit(args) -> int:
    from deckpound.compare.studies import fragility

    im, n, exceed, lines = read_stripes_csv(args.stripes)
    try:
        fit = fragility.fit_stripes(im, n, exceed)
    except fragility.FragilityDataError as err:
        raise SceneError(_field_in_file(args.stripes, err.field, lines), err.reason) from None
    if args.json:
        print(json.dumps({"median": fit.median, "beta": fit.beta}))
        return 0
    runs, hits = int(sum(n)), int(sum(exceed))
    print(f"fragility fit of {terminal_text(args.stripes)}: P(exceed | im) = Φ(ln(im/median)/beta)")
    print(
        f"  stripes         {fit.n_levels} IM levels from {min(im):g} to {max(im):g}, "
        f"{runs} runs, {hits} exceedances"
    )
    print(
        f"  median          {fit.median:.6g} (IM unit)  standard error of ln(median) "
        f"{fit.se_ln_median:.3g}"
    )
    print(f"  beta            {fit.beta:.6g}  standard error {fit.se_beta:.3g}")
    print(
        f"  log-likelihood  {fit.loglik:.6f}  (Σ z ln p + (n − z) ln(1 − p), "
        "without the binomial coefficients)"
    )
    if args.bootstrap:
        bands = fragility.parametric_bootstrap_stripes(
            im, n, exceed, n_resamples=args.bootstrap, seed=args.seed
        )
        lo_m, hi_m = bands.median_interval()
        lo_b, hi_b = bands.beta_interval()
        fitted = len(bands.medians)
        print(
            f"  bootstrap       parametric (binomial counts redrawn from the fit), seed "
            f"{args.seed}: {fitted} of {args.bootstrap} resamples fitted, "
            f"{bands.skipped} skipped (could not be fitted)"
        )
        print(f"                  median 90% interval [{lo_m:.6g}, {hi_m:.6g}]")
        print(f"                  beta   90% interval [{lo_b:.6g}, {hi_b:.6g}]")
    return 0


def _field_in_file(path: str, field: str, lines: list[int]) -> str:
    """'exceed[3]' of the fitter as 'FILE line 5, column exceed'; other fields as 'FILE'."""
    m = re.fullmatch(r"(\w+)\[(\d+)\]", field)
    if m and int(m.group(2)) < len(lines):
        return f"{path} line {lines[int(m.group(2))]}, column {m.group(1)}"
    return f"{path} (column {field})" if field in STRIPE_COLUMNS else path
