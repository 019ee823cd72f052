"""The documentation builds and holds together: mkdocs in strict mode (every docstring the API
reference renders included), every page in the navigation, every link of the README and the
pages resolving, every ``deckpound`` command they name existing, and a README short enough to
read whose first lines are the set-up the CI runs."""

from __future__ import annotations

import argparse
import ast
import importlib
import re
import subprocess
import sys
from pathlib import Path

import mkdocs_hooks
import pytest
import yaml

from deckpound.cli import build_parser

ROOT = Path(__file__).resolve().parents[2]
DOCS = ROOT / "docs"
README = ROOT / "README.md"
#: the longest README a newcomer reads through (issue 29)
README_LINES = 200
LINK = re.compile(r"(?<!!)\[[^\]]*\]\(([^)\s]+)\)|!\[[^\]]*\]\(([^)\s]+)\)")


def _nav_pages(nav) -> list[str]:
    out = []
    for item in nav:
        for value in item.values() if isinstance(item, dict) else [item]:
            out += _nav_pages(value) if isinstance(value, list) else [value]
    return out


def _config() -> dict:
    # mkdocs.yml uses no custom YAML tags, so the safe loader reads it
    return yaml.safe_load((ROOT / "mkdocs.yml").read_text(encoding="utf-8"))


def _pages() -> list[Path]:
    """The Markdown pages of docs/ (the stored data files under docs/results excluded)."""
    return sorted(p for p in DOCS.rglob("*.md") if "results" not in p.relative_to(DOCS).parts)


def test_docs_build_in_strict_mode(tmp_path):
    done = subprocess.run(
        [sys.executable, "-m", "mkdocs", "build", "--strict", "-q", "-d", str(tmp_path / "site")],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert done.returncode == 0, done.stderr[-4000:]
    for page in _nav_pages(_config()["nav"]):
        assert (tmp_path / "site" / page.removesuffix(".md") / "index.html").is_file() or (
            page == "index.md" and (tmp_path / "site" / "index.html").is_file()
        ), f"{page} was not built"


def test_every_page_is_in_the_nav():
    nav = set(_nav_pages(_config()["nav"]))
    written = {p.relative_to(DOCS).as_posix() for p in _pages()}
    generated = set(mkdocs_hooks.pages())
    assert written - nav == set(), f"pages missing from mkdocs.yml's nav: {sorted(written - nav)}"
    assert nav - written - generated == set(), f"nav entries without a page: {nav - written}"
    assert generated <= nav, f"API pages missing from the nav: {sorted(generated - nav)}"


def test_every_module_has_a_docstring_for_the_api_reference():
    """The API reference shows each module's docstring: a module without one is a blank
    section (its job then stated nowhere)."""
    missing = []
    for package, folder in mkdocs_hooks.packages().items():
        for module in mkdocs_hooks.modules(package, folder):
            rel = Path(*module.split(".")[1:]) if "." in module else Path()
            path = folder / rel.relative_to(Path(*package.split(".")[1:]))
            path = path / "__init__.py" if path.is_dir() else path.with_suffix(".py")
            if not ast.get_docstring(ast.parse(path.read_text(encoding="utf-8"))):
                missing.append(module)
    assert not missing, f"modules without a docstring: {missing}"


def _links(path: Path) -> list[str]:
    text = re.sub(r"```.*?```", "", path.read_text(encoding="utf-8"), flags=re.S)
    return [a or b for a, b in LINK.findall(text)]


@pytest.mark.parametrize("page", [README, *_pages()], ids=lambda p: p.name)
def test_every_link_resolves(page):
    generated = {DOCS / p for p in mkdocs_hooks.pages()}
    broken = []
    for target in _links(page):
        if re.match(r"^[a-z]+:", target) or target.startswith("#"):
            continue  # a URL or an anchor of the page itself
        path = (page.parent / target.split("#")[0]).resolve()
        if not path.exists() and path not in generated:
            broken.append(target)
    assert not broken, f"{page.name}: links to nothing: {broken}"


#: the repository's folders: a path in backticks that starts with one of them names a file of
#: the repository (``DIR/report.md``, ``cmp/metrics.csv`` are a command's outputs, not files)
FOLDERS = (
    "src",
    "models",
    "analytic",
    "opensees_build",
    "compare",
    "tests",
    "tools",
    "data",
    "docs",
)


@pytest.mark.parametrize("page", [README, *_pages()], ids=lambda p: p.name)
def test_every_repository_path_named_exists(page):
    """A module or file the docs name in backticks (``analytic/kernel_load.py``) exists: a
    moved or renamed file leaves no stale pointer."""
    text = page.read_text(encoding="utf-8")
    folders = "|".join(FOLDERS)
    named = re.findall(rf"`((?:{folders})/[A-Za-z0-9_./-]+)`", text)
    missing = sorted({p for p in named if not (ROOT / p).exists() and "*" not in p})
    assert not missing, f"{page.name} names files that do not exist: {missing}"


def _resolves(name: str) -> bool:
    """True when ``name`` (``deckpound.compare.warmup.byte_compile``) is a module or an
    attribute reached from the longest importable module prefix."""
    parts = name.split(".")
    for i in range(len(parts), 0, -1):
        try:
            obj = importlib.import_module(".".join(parts[:i]))
        except ImportError:
            continue
        for attr in parts[i:]:
            if not hasattr(obj, attr):
                return False
            obj = getattr(obj, attr)
        return True
    return False


@pytest.mark.parametrize("page", [README, *_pages()], ids=lambda p: p.name)
def test_every_python_name_named_exists(page):
    """A module, class or function the docs name in backticks (``deckpound.models.plan``)
    exists under that name."""
    text = page.read_text(encoding="utf-8")
    named = set(re.findall(r"`(deckpound(?:\.[A-Za-z_][A-Za-z0-9_]*)+)", text))
    missing = sorted(n for n in named if not _resolves(n))
    assert not missing, f"{page.name} names what does not exist: {missing}"


def _commands(parser: argparse.ArgumentParser) -> dict[str, set[str] | None]:
    """Every ``deckpound`` command → its subcommands (None when it has none)."""
    out = {}
    for action in parser._subparsers._group_actions:  # argparse keeps them only here
        for name, sub in action.choices.items():
            nested = [a for a in sub._actions if isinstance(a, argparse._SubParsersAction)]
            out[name] = set(nested[0].choices) if nested else None
    return out


def test_every_command_the_docs_name_exists():
    commands = _commands(build_parser())
    unknown = []
    for page in [README, *_pages()]:
        text = page.read_text(encoding="utf-8")
        code = "\n".join(re.findall(r"```.*?```|`[^`\n]+`", text, flags=re.S))
        code = re.sub(r"#.*", "", code)  # comments of the examples, an export's header
        named = re.findall(r"(?<!import )\bdeckpound ([a-z][a-z-]*)(?: ([a-z][a-z0-9-]*))?", code)
        for first, second in named:
            if first not in commands:
                unknown.append(f"{page.name}: deckpound {first}")
            elif commands[first] is not None and second and second not in commands[first]:
                unknown.append(f"{page.name}: deckpound {first} {second}")
    assert not unknown, f"commands the docs name that do not exist: {sorted(set(unknown))}"


def test_readme_is_short_and_opens_with_the_set_up_the_ci_runs():
    lines = README.read_text(encoding="utf-8").splitlines()
    assert len(lines) <= README_LINES, f"README has {len(lines)} lines (at most {README_LINES})"
    block = lines[lines.index("```bash") + 1 :][:2]
    assert [ln.split("#")[0].strip() for ln in block] == [
        "./run.sh paper -o deckpound-report",
        "./run.sh test",
    ]
    assert lines.index("```bash") < 6, "the set-up commands must open the README"
    ci = (ROOT / ".ci" / "run").read_text(encoding="utf-8").strip().splitlines()[-1]
    assert ci == "./run.sh test", "CI must run the README's test command"
