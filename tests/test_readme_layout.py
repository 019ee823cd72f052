"""The README's "Layout" lists every module of the package with its one job.

The block between ``<!-- layout:begin -->`` and ``<!-- layout:end -->`` is generated from the
modules' own docstrings (first sentence), so a new module without a docstring or a module
missing from the README fails here. Regenerate with ``python tests/test_readme_layout.py``.
"""

from __future__ import annotations

import ast
import re
import sys
import textwrap
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
README = ROOT / "README.md"
BEGIN, END = "<!-- layout:begin -->", "<!-- layout:end -->"

#: Top-level folders and the package each one installs as (pyproject ``package-dir``).
FOLDERS = (
    ("src/deckpound", "deckpound"),
    ("models", "deckpound.models"),
    ("opensees_build", "deckpound.opensees_build"),
    ("analytic", "deckpound.analytic"),
    ("compare", "deckpound.compare"),
)
WIDTH = 100


def first_sentence(path: Path) -> str:
    """The first sentence of a module's docstring ('' when it has none)."""
    doc = ast.get_docstring(ast.parse(path.read_text(encoding="utf-8"))) or ""
    para = " ".join(doc.strip().split("\n\n")[0].split())
    m = re.match(r"(.+?[.])(\s|$)", para)
    return (m.group(1) if m else para).rstrip(".")


def layout_block() -> str:
    """The generated Layout block (Markdown)."""
    lines = [
        "Top-level folders are installed as packages (``pyproject.toml`` ``package-dir``):",
        "",
    ]
    for folder, package in FOLDERS:
        lines.append(f"**`{folder}/` → `{package}`**")
        lines.append("")
        for path in sorted((ROOT / folder).glob("*.py")):
            if path.name == "__main__.py":
                continue
            job = first_sentence(path)
            item = f"- `{path.name}`: {job}"
            lines.extend(textwrap.wrap(item, WIDTH, subsequent_indent="  ", break_on_hyphens=False))
        lines.append("")
    lines.append(
        "Also: `tests/` (pytest; `-m slow` for the whole-record and memory checks), "
        "`data/golden/` (golden OpenSees command log of the benchmark), `docs/results/` "
        "(latest benchmark, skips, stress and sequence tables and figures), `.ci/run` "
        "(CI: the README's test command)."
    )
    return "\n".join(lines)


def readme_block(text: str) -> str | None:
    m = re.search(re.escape(BEGIN) + r"\n(.*?)\n" + re.escape(END), text, re.S)
    return m.group(1) if m else None


def test_every_module_has_a_docstring():
    missing = [
        f"{folder}/{p.name}"
        for folder, _ in FOLDERS
        for p in sorted((ROOT / folder).glob("*.py"))
        if p.name != "__main__.py" and not first_sentence(p)
    ]
    assert not missing, f"modules without a docstring: {missing}"


def test_readme_layout_is_generated():
    block = readme_block(README.read_text(encoding="utf-8"))
    assert block is not None, f"README lacks {BEGIN} … {END}"
    assert block == layout_block(), "README Layout is stale: run python tests/test_readme_layout.py"


if __name__ == "__main__":
    text = README.read_text(encoding="utf-8")
    if readme_block(text) is None:
        sys.exit(f"README lacks {BEGIN} … {END}")
    new = re.sub(
        re.escape(BEGIN) + r"\n.*?\n" + re.escape(END),
        lambda _: f"{BEGIN}\n{layout_block()}\n{END}",
        text,
        flags=re.S,
    )
    README.write_text(new, encoding="utf-8")
    print(f"wrote the Layout block of {README}")
