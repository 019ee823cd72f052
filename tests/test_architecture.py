"""The shape of the house: layers with one direction, no import cycles, no private names
across modules.

The layers (``[tool.importlinter]`` in ``pyproject.toml``): models → the engines (analytic,
opensees_build, independent of each other) → compare → the API and the CLI. Imports inside
functions count like any other. The package is installed from four folders
(``package-dir``), so the checks run on a mirror tree with the installed layout.
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
FOLDERS = {
    "models": "models",
    "analytic": "analytic",
    "opensees_build": "opensees_build",
    "compare": "compare",
}


@pytest.fixture(scope="module")
def mirror(tmp_path_factory) -> Path:
    """``deckpound/`` as installed: src/deckpound's modules and the four subpackages."""
    top = tmp_path_factory.mktemp("mirror")
    package = top / "deckpound"
    package.mkdir()
    for module in (ROOT / "src" / "deckpound").glob("*.py"):
        (package / module.name).symlink_to(module)
    for name, folder in FOLDERS.items():
        (package / name).symlink_to(ROOT / folder, target_is_directory=True)
    return top


def _graph(mirror: Path) -> dict[str, set[str]]:
    """Module → modules it imports (anywhere in it), from grimp in a fresh process (the
    installed ``deckpound`` must not shadow the mirror)."""
    code = (
        "import grimp, json\n"
        "g = grimp.build_graph('deckpound', cache_dir=None)\n"
        "print(json.dumps({m: sorted(g.find_modules_directly_imported_by(m)) for m in g.modules}))"
    )
    env = {**os.environ, "PYTHONPATH": str(mirror)}
    out = subprocess.run(
        [sys.executable, "-c", code],
        cwd=mirror,
        env=env,
        capture_output=True,
        text=True,
        check=True,
        timeout=300,
    )
    import json

    return {m: set(v) for m, v in json.loads(out.stdout).items()}


def test_the_layers_contract_holds(mirror):
    lint = Path(sys.executable).with_name("lint-imports")
    env = {**os.environ, "PYTHONPATH": str(mirror)}
    out = subprocess.run(
        [str(lint), "--no-cache", str(ROOT / "pyproject.toml")],
        cwd=mirror,
        env=env,
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert out.returncode == 0, out.stdout[-4000:] + out.stderr[-2000:]
    assert "0 broken" in out.stdout
