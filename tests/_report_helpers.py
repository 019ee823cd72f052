"""Read the report's generated sentences back into claims, to check them against its tables.

A claim is (subject, direction, keys, lo, hi): "raises the peak rotation in runs 6–7
(×2.30–2.56)" gives ("raises", {6, 7}, 2.30, 2.56); "changes it by less than 2 % in run 1"
gives ("unchanged", {1}, nan, nan). Keys are run numbers (``in run(s) …``), friction
coefficients (``at μ = …``) or engine labels (``in OpenSees, …``).
"""

from __future__ import annotations

import math
import re

import pandas as pd

VERB = re.compile(r"(?:, | and )?(?=\b(?:raises|lowers|changes) (?:the peak rotation|it)\b)")
CLAUSE = re.compile(
    r"^(raises|lowers|changes) (?:the peak rotation|it) "
    r"(?:by less than [\d.]+ % )?(in|at) (.+?)"
    r"(?: \(×([\d.]+)(?:–([\d.]+))?\))?$"
)


def split_list(text: str) -> list[str]:
    """``a, b and c`` → [a, b, c]."""
    text = text.strip()
    parts = re.split(r", | and ", text)
    return [p.strip() for p in parts if p.strip()]


def expand_runs(text: str) -> set[int]:
    """``runs 1–2 and 4`` → {1, 2, 4}."""
    text = re.sub(r"^runs? ", "", text.strip())
    out: set[int] = set()
    for part in split_list(text):
        if "–" in part:
            a, b = part.split("–")
            out.update(range(int(a), int(b) + 1))
        else:
            out.add(int(part))
    return out


def mu_values(text: str) -> set[float]:
    """``μ = 0.1 and 0.2`` → {0.1, 0.2}."""
    return {float(v) for v in split_list(re.sub(r"^μ = ", "", text.strip()))}


def claims(sentence: str) -> list[tuple[str, str, float, float]]:
    """(direction, keys text, lo, hi) of each clause of an effect sentence."""
    out = []
    chunks = [c.strip() for c in VERB.split(sentence.strip())]
    for chunk in (c for c in chunks if re.match(r"(raises|lowers|changes) ", c)):
        chunk = re.sub(r"(\.|:.*)$", "", chunk)
        m = CLAUSE.match(chunk)
        assert m, chunk
        word, _, keys, lo, hi = m.groups()
        direction = "unchanged" if word == "changes" else word
        lo_v = float(lo) if lo else math.nan
        hi_v = float(hi) if hi else lo_v
        out.append((direction, keys, lo_v, hi_v))
    return out


def shown_as(value: float, shown: float) -> bool:
    """``value`` rounds to ``shown`` at 3 significant digits."""
    return math.isclose(value, shown, rel_tol=6e-3)


def read_table(path) -> pd.DataFrame:
    """A report CSV with the units stripped from its headers."""
    frame = pd.read_csv(path)
    frame.columns = [c.split(" [")[0] for c in frame.columns]
    return frame


def check_clauses(found: list[tuple[str, str, float, float]], truth: dict, keys_of) -> None:
    """Every key of ``truth`` (key → ratio) appears in exactly one clause, whose direction
    and ×range agree with the ratios of its keys."""
    from deckpound.compare.report.text import direction

    seen = set()
    for word, keys_text, lo, hi in found:
        keys = keys_of(keys_text)
        assert keys and not keys & seen, (keys_text, seen)
        seen |= keys
        ratios = [truth[k] for k in keys]
        assert all(direction(r) == word for r in ratios), (word, keys_text, ratios)
        if word != "unchanged":
            assert shown_as(min(ratios), lo) and shown_as(max(ratios), hi), (ratios, lo, hi)
    assert seen == set(truth), (seen, set(truth))
