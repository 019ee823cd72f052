"""``tools/loop_profile.py`` (repository tooling): perf samples binned over a dumped step loop.

The binning is checked on a small hand-made disassembly and sample list; the dump is checked on
the real compliance loop (every compiled version copied from the process, each inside its
mapping)."""

from __future__ import annotations

import importlib.util
import json
from collections import Counter
from pathlib import Path

import pytest

TOOL = Path(__file__).resolve().parents[1] / "tools" / "loop_profile.py"

BASE = 0x7F0000001000
#: an objdump-style listing: the loop at 0x0..0x3ff calls a function placed at 0x400
ASM = """
code.bin:     file format binary

Disassembly of section .data:

0000000000000000 <.data>:
       0:\t55                   \tpush   %rbp
      10:\t48 b8 00 14 00 00 00 \tmovabs $0x7f0000001400,%rax
     1a:\tff d0                \tcall   *%rax
     120:\tc5 fb 59 06          \tvmulsd (%rsi),%xmm0,%xmm0
     400:\t55                   \tpush   %rbp
     410:\tc5 fb 5e c2          \tvdivsd %xmm2,%xmm0,%xmm0
     420:\tc3                   \tret
"""


@pytest.fixture(scope="module")
def tool():
    spec = importlib.util.spec_from_file_location("loop_profile", TOOL)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_samples_are_binned_by_region_and_block(tool):
    ips = [BASE + 0x120] * 3 + [BASE + 0x410] * 5 + [BASE + 0x1A] + [BASE - 8, BASE + 0x800]
    text = "\n".join(f"{ip:x}" for ip in ips)
    assert tool.read_ips(text) == ips
    targets = tool.call_targets(ASM, BASE, 0x800)
    assert targets == [0x400]  # the call target inside the code; outside ones are dropped
    counts = tool.sample_offsets(tool.read_ips(text), BASE, 0x800)
    assert counts == Counter({0x120: 3, 0x410: 5, 0x1A: 1})  # the two outside samples left out
    assert tool.region_shares(counts, targets, 0x800) == [(0, 0x400, 4), (0x400, 0x800, 5)]
    assert tool.hot_blocks(counts) == [(0x400, 5), (0x100, 3), (0x0, 1)]
    lines = tool.annotated(ASM, counts).splitlines()
    assert any(ln.startswith("      5") and "vdivsd" in ln for ln in lines)
    assert any(ln.startswith("      0") and "ret" in ln for ln in lines)
    assert any(ln.strip().startswith("Disassembly") for ln in lines)


def test_a_target_outside_the_code_or_at_its_start_is_no_region(tool):
    asm = "  0:\tmovabs $0x7f0000001000,%rax\n  8:\tmovabs $0x10,%rcx\n"
    assert tool.call_targets(asm, BASE, 0x800) == []


def test_the_version_with_the_most_samples_is_profiled(tool):
    loops = [
        {"file": "code0.bin", "base": BASE, "size": 0x100},
        {"file": "code1.bin", "base": BASE + 0x10000, "size": 0x100},
    ]
    ips = [BASE + 0x10] + [BASE + 0x10000 + 0x20] * 3
    loop, counts = tool.profiled_loop(loops, ips)
    assert loop["file"] == "code1.bin" and counts == Counter({0x20: 3})


def test_dump_copies_every_compiled_version_of_the_compliance_loop(tool, tmp_path):
    """A process that ran another model size first (the two-segment deck of ``two-frame``)
    holds two versions of the loop: both are copied, each inside its mapping."""
    import deckpound as dp

    two = dp.load_scene("two-frame")
    dp.run(two.replace({"run.duration": 0.2, "excitation.duration": 0.2}), engine="compliance")
    info = tool.dump(tmp_path, "compliance", "saiidi-4span", 1)
    assert json.loads((tmp_path / "loop.json").read_text()) == info
    assert info["us_per_step_median"] > 0
    assert len(info["loops"]) >= 2
    for loop in info["loops"]:
        code = (tmp_path / loop["file"]).read_bytes()
        assert len(code) == loop["size"] > 0
        assert code[:16] != bytes(16)  # real code, not a run of zero bytes


def test_annotate_needs_its_three_files(tool, tmp_path, capsys):
    with pytest.raises(SystemExit) as err:
        tool.main(["annotate", str(tmp_path)])
    assert err.value.code == 2
    assert "loop.json is missing" in capsys.readouterr().err


def test_dump_refuses_no_runs(tool, tmp_path, capsys):
    with pytest.raises(SystemExit):
        tool.main(["dump", str(tmp_path), "--runs", "0"])
    assert "--runs must be at least 1, got 0" in capsys.readouterr().err
