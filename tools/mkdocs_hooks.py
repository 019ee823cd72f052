"""mkdocs hooks (``hooks:`` in mkdocs.yml): the API reference pages and the package layout
that mkdocstrings reads.

Repository tooling (not installed with the package). Two jobs:

* **The installed layout for griffe.** The package is installed from five folders
  (``[tool.setuptools] package-dir`` in pyproject.toml: ``src/deckpound`` → ``deckpound``,
  ``models`` → ``deckpound.models``, ...). griffe, which reads the sources for mkdocstrings,
  finds a package by walking folders and cannot follow that mapping (nor the editable install's
  import hook), so :func:`on_config` builds a mirror of the installed layout out of symbolic
  links in a temporary folder and puts it first on ``sys.path``, where mkdocstrings' Python
  handler looks (the handler is created after this hook runs). The sources are read, not
  imported.
* **The API pages.** :func:`on_files` adds ``api/<package>.md`` for every installed package,
  one section per module (subpackages included, ``__main__`` left out), each ``::: module``
  rendered from the module's docstrings; they are generated at every build, so a new module is
  documented without a step to forget. ``nav`` in mkdocs.yml lists the pages.
"""

from __future__ import annotations

import atexit
import shutil
import sys
import tempfile
import tomllib
from pathlib import Path

from mkdocs.plugins import event_priority
from mkdocs.structure.files import File

ROOT = Path(__file__).resolve().parents[1]

PYPROJECT = ROOT / "pyproject.toml"
#: what each installed package is for (the layer it is, from the bottom up)
INTRO = {
    "deckpound.models": "The engine-independent description: scene, plan model, excitation, "
    "result, and the engine contract every engine implements.",
    "deckpound.analytic": "The compliance and nonsmooth engines: numba kernels and their drivers.",
    "deckpound.opensees_build": "The OpenSees engine: the model built in openseespy, its exports "
    "as Tcl and Python scripts.",
    "deckpound.compare": "Runs any subset of the engines and compares them: the engine registry, "
    "alignment, metrics, studies, the report and the measurements.",
    "deckpound": "The Python API (`import deckpound as dp`) and the `deckpound` command line.",
}


def packages() -> dict[str, Path]:
    """Installed package → its folder, top-level packages only (``package-dir``)."""
    config = tomllib.loads(PYPROJECT.read_text(encoding="utf-8"))
    dirs = config["tool"]["setuptools"]["package-dir"]
    return {name: ROOT / folder for name, folder in dirs.items()}


def modules(package: str, folder: Path) -> list[str]:
    """Every module of ``package`` in ``folder`` and its subpackages (not ``__main__``), the
    package first, then in name order."""
    out = [package]
    for path in sorted(folder.rglob("*.py")):
        if path.name == "__main__.py":
            continue
        rel = path.relative_to(folder).with_suffix("")
        if "__pycache__" in rel.parts:
            continue
        if rel.name == "__init__":
            rel = rel.parent
            if rel == Path("."):
                continue
        out.append(".".join((package, *rel.parts)))
    return sorted(dict.fromkeys(out), key=lambda m: (m != package, m))


def page_name(package: str) -> str:
    """The file name of ``package``'s page (``models.md`` for ``deckpound.models``)."""
    return (package.split(".", 1)[1] if "." in package else package) + ".md"


def pages() -> dict[str, str]:
    """Page path in the docs (``api/models.md``) → its Markdown, for every installed package."""
    pkgs = packages()
    out = {}
    for package in INTRO:
        lines = [f"# `{package}`", "", INTRO[package], ""]
        for module in modules(package, pkgs[package]):
            lines += [f"## `{module}`", "", f"::: {module}", ""]
        out[f"api/{page_name(package)}"] = "\n".join(lines)
    return out


def mirror(target: Path) -> Path:
    """Build the installed layout under ``target`` from symbolic links: ``deckpound/`` holds
    links to the entries of its folder and one link per subpackage folder."""
    pkgs = packages()
    top = target / "deckpound"
    top.mkdir(parents=True)
    for entry in pkgs["deckpound"].iterdir():
        if entry.name != "__pycache__":
            (top / entry.name).symlink_to(entry)
    for name, folder in pkgs.items():
        link = target / Path(*name.split("."))
        parent = pkgs.get(name.rsplit(".", 1)[0])
        if name == "deckpound" or (parent is not None and folder == parent / link.name):
            continue  # reached through its parent package's folder
        if link.parent.is_symlink() or not link.parent.is_dir():
            raise RuntimeError(f"cannot mirror {name} ({folder}): build its parent package first")
        link.symlink_to(folder)
    return target


@event_priority(100)  # before mkdocstrings reads sys.path into its search paths
def on_config(config):
    target = Path(tempfile.mkdtemp(prefix="deckpound-api-"))
    atexit.register(shutil.rmtree, target, ignore_errors=True)
    sys.path.insert(0, str(mirror(target)))
    return config


def on_files(files, config):
    for path, text in pages().items():
        files.append(File.generated(config, path, content=text))
    return files
