"""Small HTML tables for notebooks (``_repr_html_`` of scenes, results and comparisons)."""

from __future__ import annotations

import html

__all__ = ["html_table", "short_text"]


def html_table(title: str, rows: dict[str, str]) -> str:
    """A two-column HTML table (field, value) under a bold title; every text escaped with
    ``html.escape``, so a scene name holding markup shows as text and runs no script."""
    body = "".join(
        f"<tr><th style='text-align:left'>{html.escape(str(k))}</th>"
        f"<td style='text-align:left'>{html.escape(str(v))}</td></tr>"
        for k, v in rows.items()
    )
    return f"<b>{html.escape(str(title))}</b><table>{body}</table>"


def short_text(text: str, limit: int = 60) -> str:
    """``text`` cut to ``limit`` characters (an ellipsis marks the cut): a long user string
    must not make a one-line ``repr`` long."""
    text = str(text)
    return text if len(text) <= limit else text[: limit - 1] + "…"
