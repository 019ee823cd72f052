"""The shape of the house: layers with one direction, no import cycles, no private names
across modules.

The layers (``[tool.importlinter]`` in ``pyproject.toml``): models → the engines (analytic,
opensees_build, independent of each other) → compare → the API and the CLI. Imports inside
functions count like any other. The package is installed from four folders
(``package-dir``), so the checks run on a mirror tree with the installed layout.
"""

from __future__ import annotations

import ast
import json
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


def test_no_import_cycles(mirror):
    """No two modules import each other, directly or around a loop, anywhere in them (imports
    inside functions included; ``if TYPE_CHECKING:`` imports are not run, so they do not
    count)."""
    code = (
        "import grimp, json\n"
        "g = grimp.build_graph('deckpound', cache_dir=None, exclude_type_checking_imports=True)\n"
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
    graph = {m: set(v) for m, v in json.loads(out.stdout).items()}
    assert len(graph) > 100  # the whole package was read
    cycles = [c for c in _strongly_connected(graph) if len(c) > 1]
    assert not cycles, "\n".join(" <-> ".join(c) for c in cycles)


def _strongly_connected(graph: dict[str, set[str]]) -> list[list[str]]:
    """Tarjan's strongly connected components (iterative)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    found: list[list[str]] = []
    for root in sorted(graph):
        if root in index:
            continue
        work = [(root, iter(sorted(graph[root])))]
        index[root] = low[root] = len(index)
        stack.append(root)
        on_stack.add(root)
        while work:
            node, children = work[-1]
            child = next(children, None)
            if child is None:
                work.pop()
                if work:
                    low[work[-1][0]] = min(low[work[-1][0]], low[node])
                if low[node] == index[node]:
                    component = []
                    while True:
                        top = stack.pop()
                        on_stack.discard(top)
                        component.append(top)
                        if top == node:
                            break
                    found.append(sorted(component))
            elif child not in graph:
                continue
            elif child not in index:
                index[child] = low[child] = len(index)
                stack.append(child)
                on_stack.add(child)
                work.append((child, iter(sorted(graph[child]))))
            elif child in on_stack:
                low[node] = min(low[node], index[child])
    return found


def test_the_cycle_finder_finds_a_cycle():
    graph = {"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}
    assert [c for c in _strongly_connected(graph) if len(c) > 1] == [["a", "b", "c"]]


# -- names: every import names the module that defines the name; private names stay home ----

PACKAGES = {
    "deckpound": ROOT / "src" / "deckpound",
    "deckpound.models": ROOT / "models",
    "deckpound.analytic": ROOT / "analytic",
    "deckpound.opensees_build": ROOT / "opensees_build",
    "deckpound.compare": ROOT / "compare",
}


def _modules() -> dict[str, Path]:
    out = {}
    for package, folder in PACKAGES.items():
        for path in folder.rglob("*.py"):
            parts = path.relative_to(folder).with_suffix("").parts
            if parts[-1] == "__init__":
                parts = parts[:-1]
            out[".".join((package, *parts))] = path
    return out


def _source_of(module: str | None, node: ast.ImportFrom, path: Path) -> str | None:
    """The absolute module an ``ImportFrom`` reads (relative imports resolved)."""
    if node.level == 0:
        return node.module
    if module is None:
        return None
    parts = module.split(".")
    if path.name != "__init__.py":
        parts = parts[:-1]
    parts = parts[: len(parts) - (node.level - 1)]
    return ".".join(parts + ([node.module] if node.module else []))


def _definitions(modules: dict[str, Path]) -> tuple[dict, dict, dict]:
    """Per module: the names it defines, the names it imports (name → source module), and
    its ``__all__``."""
    defined, imported, exported = {}, {}, {}
    for name, path in modules.items():
        tree = ast.parse(path.read_text(encoding="utf-8"))
        own, brought = set(), {}
        for node in tree.body:
            if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef | ast.ClassDef):
                own.add(node.name)
            elif isinstance(node, ast.Assign | ast.AnnAssign):
                targets = node.targets if isinstance(node, ast.Assign) else [node.target]
                own |= {x.id for t in targets for x in ast.walk(t) if isinstance(x, ast.Name)}
                if any(isinstance(t, ast.Name) and t.id == "__all__" for t in targets):
                    exported[name] = [e.value for e in getattr(node.value, "elts", [])]
            elif isinstance(node, ast.ImportFrom):
                source = _source_of(name, node, path)
                brought.update({a.asname or a.name: source for a in node.names})
        defined[name], imported[name] = own, brought
    return defined, imported, exported


def test_no_re_exports_and_no_private_names_across_modules():
    """Outside a package's ``__init__``, a module's ``__all__`` lists only what it defines and
    nobody imports a name from a module that only imported it (tests and tools included); no
    module imports another module's private ``_name`` (a private *module* is imported only
    inside its own package: the private-modules contract)."""
    modules = _modules()
    defined, imported, exported = _definitions(modules)
    found = []
    for name, names in exported.items():
        if modules[name].name != "__init__.py":
            found += [f"{name}.__all__: {n}" for n in names if n in imported[name]]
    readers = {**{str(p): (m, p) for m, p in modules.items()}}
    for folder in (ROOT / "tests", ROOT / "tools"):
        readers.update({str(p): (None, p) for p in folder.rglob("*.py")})
    for module, path in readers.values():
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if not isinstance(node, ast.ImportFrom):
                continue
            source = _source_of(module, node, path)
            for alias in node.names:
                where = f"{path.relative_to(ROOT)}:{node.lineno} {alias.name} from {source}"
                if source in modules and modules[source].name != "__init__.py":
                    if alias.name not in defined[source] and alias.name in imported[source]:
                        found.append(f"re-export: {where}")
                private = alias.name.startswith("_") and not alias.name.startswith("__")
                if module and private and f"{source}.{alias.name}" not in modules:
                    found.append(f"private name: {where}")
    assert not found, "\n".join(found)


#: libraries a module may import inside a function: heavy, and needed by few paths (OpenSees
#: only through opensees_build.ops, which imports it on first use)
HEAVY_LIBRARIES = (
    "openseespy",
    "scipy.signal",
    "pandas",
    "xarray",
    "matplotlib",
    "dask",
    "distributed",
    "pyarrow",
    "meshio",
    "numba",
    "nbclient",
    "nbformat",
)


def _is_library(module: str) -> bool:
    return any(module == h or module.startswith(h + ".") for h in HEAVY_LIBRARIES)


def _heavy_modules(modules: dict[str, Path]) -> set[str]:
    """The package's modules that import a heavy library when they are imported (directly
    or through the package's modules they import at module level)."""
    top: dict[str, set[str]] = {}
    for name, path in modules.items():
        deps = set()
        for node in ast.parse(path.read_text(encoding="utf-8")).body:
            if isinstance(node, ast.Import):
                deps |= {a.name for a in node.names}
            elif isinstance(node, ast.ImportFrom):
                source = _source_of(name, node, path)
                deps.add(source)
                deps |= {f"{source}.{a.name}" for a in node.names}
        top[name] = deps
    heavy: set[str] = set()
    changed = True
    while changed:
        changed = False
        for name, deps in top.items():
            parent = name.rsplit(".", 1)[0]  # importing a module runs its package's __init__
            hit = parent in heavy or any(_is_library(d) or d in heavy for d in deps)
            if hit and name not in heavy:
                heavy.add(name)
                changed = True
    return heavy


def test_imports_inside_functions_are_only_for_heavy_libraries():
    """Below the CLI, an import inside a function is for a heavy library (or a module of the
    package that loads one: the numba kernels, the figures) — never to hide a cycle or a
    dependency. The CLI and the API import their commands on first use, so that
    ``deckpound --help`` starts without loading numba, pandas or matplotlib."""
    modules = _modules()
    heavy = _heavy_modules(modules)
    found = []
    for name, path in modules.items():
        if name.count(".") < 2 and not name.startswith(("deckpound.models", "deckpound.compare")):
            continue  # deckpound.cli, deckpound.api, deckpound._cli_*: the top layer
        for func in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if not isinstance(func, ast.FunctionDef | ast.AsyncFunctionDef):
                continue
            for node in ast.walk(func):
                if isinstance(node, ast.Import):
                    sources = [(a.name, a.name) for a in node.names]
                elif isinstance(node, ast.ImportFrom):
                    source = _source_of(name, node, path)
                    sources = [(source, f"{source}.{a.name}") for a in node.names]
                else:
                    continue
                for source, item in sources:
                    library = _is_library(source)
                    if not (library or source in heavy or item in heavy):
                        found.append(f"{path.relative_to(ROOT)}:{node.lineno} {source}")
    assert not found, "\n".join(found)


def test_the_command_line_starts_without_the_heavy_libraries():
    code = (
        "import sys, deckpound.cli\n"
        "print(sorted({m.split('.')[0] for m in sys.modules} & {'numba', 'matplotlib', "
        "'pandas', 'scipy', 'openseespy', 'dask', 'xarray'}))"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "[]"


def test_an_engine_run_loads_neither_pandas_nor_xarray_nor_matplotlib():
    """Tables, datasets and figures are for what comes after a run: a ``deckpound run`` does
    not pay their import time (about 0.3 s for pandas and xarray)."""
    code = (
        "import sys\n"
        "from deckpound.compare.engines import run_engine\n"
        "from deckpound.models.scene_io import load_scene\n"
        "run_engine('compliance', load_scene('saiidi-4span', ['run.duration=0.2']))\n"
        "print(sorted({m.split('.')[0] for m in sys.modules} & {'pandas', 'xarray', "
        "'matplotlib'}))"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "[]"
