"""Render the report's sections as Markdown and HTML (one list of items, two outputs).

A section is a title and a list of items: a paragraph (``str``), a bullet list
(:class:`Bullets`), a table with its caption (:class:`Table`) or a figure with its caption
(:class:`Figure`). Captions and column headers carry the units; :func:`view` selects, scales
and renames the columns of a table for display (SI in the CSV tables, mrad and mm on the page).
"""

from __future__ import annotations

import html
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd

from deckpound.compare.report.outputs import write_text

#: display scales of the report tables: m → mm, rad → mrad
MM, MRAD = 1e3, 1e3


@dataclass(frozen=True)
class DisplayUnit:
    """How the report shows one quantity: ``scale`` × the value in deckpound's units (kN and
    what it makes: kN·m, kN·m·s) gives it in ``unit``."""

    scale: float
    unit: str

    def moment(self) -> str:
        """The unit of a moment of this force [unit·m]."""
        return f"{self.unit}·m"

    def impulse(self) -> str:
        """The unit of an angular impulse of this force [unit·m·s]."""
        return f"{self.unit}·m·s"


#: the report's one unit for contact (pounding) forces at the deck's corners, normal and
#: tangential, and for their moments and angular impulses about the deck centre, in every
#: figure, table and sentence of the page
CONTACT_FORCE = DisplayUnit(1e-3, "MN")
#: the report's one unit for the bents' forces (their Takeda springs' shear): kN
BENT_FORCE = DisplayUnit(1.0, "kN")


def units_sentence() -> str:
    """The report's units, stated once (in "What was run")."""
    return (
        f"Units on this page: contact (pounding) forces in {CONTACT_FORCE.unit}, their moments "
        f"about the deck centre in {CONTACT_FORCE.moment()} and their angular impulses in "
        f"{CONTACT_FORCE.impulse()}, in every figure, table and sentence; bent forces in "
        f"{BENT_FORCE.unit}; stiffnesses as the scene gives them (kN/m). The CSV tables keep "
        "deckpound's units (kN, m, rad, s), named in their headers; the scene's notes are "
        "quoted as their author wrote them."
    )


@dataclass(frozen=True)
class Table:
    frame: pd.DataFrame
    caption: str = ""


@dataclass(frozen=True)
class Figure:
    src: str  # relative to the report folder
    caption: str


@dataclass(frozen=True)
class Bullets:
    items: tuple[str, ...]


def view(frame: pd.DataFrame, columns: list[tuple[str, str, float]]) -> pd.DataFrame:
    """Columns (name, header, factor) of ``frame`` that exist, multiplied by factor (1 for
    text), renamed to their headers."""
    out = {}
    for name, header, factor in columns:
        if name in frame:
            col = frame[name]
            out[header] = (
                col * factor if factor != 1 and pd.api.types.is_numeric_dtype(col) else col
            )
    return pd.DataFrame(out)


def _cell(v) -> str:
    if isinstance(v, (bool, np.bool_)):
        return "yes" if v else "no"
    if isinstance(v, (float, np.floating)):
        return "—" if not np.isfinite(v) else format(float(v), ".4g")
    return str(v)


def md_table(frame: pd.DataFrame) -> str:
    cols = [str(c) for c in frame.columns]
    lines = ["| " + " | ".join(cols) + " |", "|" + "---|" * len(cols)]
    for row in frame.itertuples(index=False):
        lines.append("| " + " | ".join(_cell(v).replace("|", "\\|") for v in row) + " |")
    return "\n".join(lines)


def html_table(frame: pd.DataFrame) -> str:
    head = "".join(f"<th>{html.escape(str(c))}</th>" for c in frame.columns)
    body = "".join(
        "<tr>" + "".join(f"<td>{html.escape(_cell(v))}</td>" for v in row) + "</tr>"
        for row in frame.itertuples(index=False)
    )
    return f'<table class="t"><thead><tr>{head}</tr></thead><tbody>{body}</tbody></table>'


def _html_text(text: str) -> str:
    parts = html.escape(text).split("**")
    return "".join(f"<b>{p}</b>" if k % 2 else p for k, p in enumerate(parts))


STYLE = (
    "body{font-family:sans-serif;max-width:1050px;margin:2em auto;color:#111;"
    "line-height:1.4}table.t{border-collapse:collapse;font-size:12px;margin:.3em 0}"
    "table.t td,table.t th{border:1px solid #999;padding:2px 6px}"
    "p.cap{font-size:12px;color:#333;margin-top:.1em}"
)


def render(title: str, sections: list[tuple[str, list]], out: Path) -> Path:
    """Write ``report.md`` and ``report.html`` into ``out``; return the .md path."""
    md = [f"# {title}", ""]
    body = [f"<h1>{html.escape(title)}</h1>"]
    for heading, items in sections:
        md += [f"## {heading}", ""]
        body.append(f"<h2>{html.escape(heading)}</h2>")
        for item in items:
            if isinstance(item, Table):
                if item.caption:
                    md += [f"*{item.caption}*", ""]
                    body.append(f'<p class="cap">{_html_text(item.caption)}</p>')
                md += [md_table(item.frame), ""]
                body.append(html_table(item.frame))
            elif isinstance(item, Figure):
                md += [f"![{item.caption}]({item.src})", "", f"*{item.caption}*", ""]
                body.append(
                    f'<p><img src="{html.escape(item.src)}" alt="'
                    f'{html.escape(item.caption)}" style="max-width:100%"></p>'
                    f'<p class="cap">{_html_text(item.caption)}</p>'
                )
            elif isinstance(item, Bullets):
                md += [f"- {b}" for b in item.items] + [""]
                body.append(
                    "<ul>" + "".join(f"<li>{_html_text(b)}</li>" for b in item.items) + "</ul>"
                )
            else:
                md += [item, ""]
                body.append(f"<p>{_html_text(item)}</p>")
    write_text(out / "report.md", "\n".join(md))
    write_text(
        out / "report.html",
        "<!doctype html><html><head><meta charset='utf-8'>"
        f"<title>{html.escape(title)}</title><style>{STYLE}</style></head><body>"
        + "".join(body)
        + "</body></html>",
    )
    return out / "report.md"
