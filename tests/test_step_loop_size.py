"""The step loops stay short drivers over inlined stages (issue 29, item 3): no function of the
modules that hold a step loop, its stages or the OpenSees model build is longer than about 120
lines or above McCabe complexity 20 (ruff's C901)."""

import ast
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
#: the step loops, their stages and the per-step solvers, and the OpenSees model build
LOOP_MODULES = [
    "analytic/compliance/newmark.py",
    "analytic/compliance/dormand_prince.py",
    "analytic/compliance/adaptive.py",
    "analytic/nonsmooth/moreau_jean.py",
    "analytic/nonsmooth/impulses.py",
    "analytic/nonsmooth/frictional_contact.py",
    "analytic/kernels/lcp.py",
    "analytic/kernels/dense.py",
    "analytic/kernels/contact_laws.py",
    "analytic/kernels/contact_assembly.py",
    "analytic/kernels/peaks.py",
    "analytic/kernels/system.py",
    "analytic/kernels/hysteretic_kernel.py",
    "opensees_build/model.py",
]
MAX_LINES = 120
MAX_COMPLEXITY = 20


@pytest.mark.parametrize("module", LOOP_MODULES)
def test_no_long_function(module):
    tree = ast.parse((ROOT / module).read_text())
    long = [
        f"{node.name}: {node.end_lineno - node.lineno + 1} lines"
        for node in ast.walk(tree)
        if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef)
        and node.end_lineno - node.lineno + 1 > MAX_LINES
    ]
    assert not long, f"{module}: {long}"


def test_no_complex_function():
    ruff = Path(sys.executable).with_name("ruff")
    out = subprocess.run(
        [
            str(ruff),
            "check",
            "--select",
            "C901",
            "--config",
            f"lint.mccabe.max-complexity={MAX_COMPLEXITY}",
            "--output-format",
            "concise",
            *LOOP_MODULES,
        ],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert out.returncode == 0, out.stdout + out.stderr
