"""Where a compiled step loop spends its time: perf samples binned over its machine code.

Repository tooling (not part of the package). numba registers no symbols with perf for code it
loads from its cache, and each engine's step loop is one compiled function with its stages
inlined, so ``perf report`` shows the loop as a bare address range. This tool makes that range
readable in three steps::

    perf record -F 10000 -o prof/perf.data .venv/bin/python tools/loop_profile.py dump prof
    perf script -i prof/perf.data -F ip > prof/ips.txt
    .venv/bin/python tools/loop_profile.py annotate prof

``dump`` runs the engine on the scene ``--runs`` times (after one untimed run that loads or
compiles the kernels), then copies the step loop's machine code from the process's memory to
``DIR/code<k>.bin`` with its address (``DIR/loop.json``; one file per compiled version of the
loop in the process). ``annotate`` takes the version with the most samples of ``DIR/ips.txt``,
disassembles it (``objdump``), counts the samples that fall inside it, and prints the share
of each region between the call targets found in the code (the loop itself and the compiled
functions it calls, e.g. the Takeda update), then the hottest 256-byte blocks; it writes
``DIR/annotated.asm``, every instruction with its sample count.

Where a sample sits says which instructions wait, not which source line they came from: read
the annotated code around a hot block (its loads, divisions, calls). Results depend on the
compiled code, which depends on the cache directory: profile the build you time. The loop runs
with the engine's floating-point mode (subnormals flushed by default); stage micro-benchmarks
taken outside the loop without it measure subnormal arithmetic instead.
"""

from __future__ import annotations

import argparse
import bisect
import ctypes
import itertools
import json
import re
import shutil
import statistics
import subprocess
import sys
from collections import Counter
from pathlib import Path

#: the step loop function of each engine (module, function)
LOOPS = {
    "compliance": ("deckpound.analytic.compliance.newmark", "newmark_run"),
    "nonsmooth": ("deckpound.analytic.nonsmooth.moreau_jean", "moreau_jean_run"),
}
#: largest code copy [B]: the loops are ~130 kB; the copy stops at the end of their mapping
MAX_CODE = 1 << 20
BLOCK = 256
_CALL_TARGET = re.compile(r"movabs \$(0x[0-9a-f]+),%r")
_ASM_LINE = re.compile(r"^\s*([0-9a-f]+):\t")


def _mapping_end(address: int) -> int:
    """One past the end of the memory mapping of this process that holds ``address``."""
    for line in Path("/proc/self/maps").read_text().splitlines():
        lo, hi = (int(x, 16) for x in line.split()[0].split("-"))
        if lo <= address < hi:
            return hi
    raise RuntimeError(f"address {address:#x} is in no mapping of this process")


def dump(folder: Path, engine: str, scene_name: str, runs: int) -> dict:
    """Run ``engine`` on ``scene_name`` ``runs`` times, then write the machine code of every
    compiled version of its step loop in this process (``code<k>.bin``: the process may hold
    others, for other model sizes, besides the scene's) and ``loop.json`` (their addresses,
    sizes and names, and the runs' µs/step) into ``folder``. Returns the JSON's content."""
    import importlib

    import deckpound as dp

    scene = dp.load_scene(scene_name)
    dp.run(scene, engine=engine)  # loads or compiles the kernels: not profiled on purpose
    us = [dp.run(scene, engine=engine).meta["us_per_step"] for _ in range(runs)]
    module, name = LOOPS[engine]
    dispatcher = getattr(importlib.import_module(module), name)
    folder.mkdir(parents=True, exist_ok=True)
    loops = []
    for k, cres in enumerate(dispatcher.overloads.values()):
        symbol = cres.fndesc.llvm_func_name
        base = cres.library.get_pointer_to_function(symbol)
        size = min(MAX_CODE, _mapping_end(base) - base)
        (folder / f"code{k}.bin").write_bytes(ctypes.string_at(base, size))
        loops.append({"file": f"code{k}.bin", "function": symbol, "base": base, "size": size})
    info = {
        "engine": engine,
        "scene": scene_name,
        "loops": loops,
        "runs": runs,
        "us_per_step_median": statistics.median(us) if us else None,
    }
    (folder / "loop.json").write_text(json.dumps(info, indent=1))
    return info


def read_ips(text: str) -> list[int]:
    """The sampled instruction addresses of ``perf script -F ip`` output (one hex per line)."""
    return [int(tok, 16) for tok in text.split()]


def call_targets(asm: str, base: int, size: int) -> list[int]:
    """Offsets inside the code of the absolute call targets (``movabs $addr, %reg``) that fall
    in [base, base + size): the compiled functions the loop calls, placed after it."""
    found = {int(m, 16) - base for m in _CALL_TARGET.findall(asm)}
    return sorted(off for off in found if 0 < off < size)


def sample_offsets(ips: list[int], base: int, size: int) -> Counter:
    """Samples per offset inside [base, base + size)."""
    return Counter(ip - base for ip in ips if base <= ip < base + size)


def region_shares(counts: Counter, targets: list[int], size: int) -> list[tuple[int, int, int]]:
    """(start, end, samples) of each region between call targets (the loop from 0, then each
    called function), regions without samples left out."""
    bounds = [0, *targets, size]
    out = []
    for lo, hi in itertools.pairwise(bounds):
        n = sum(v for off, v in counts.items() if lo <= off < hi)
        if n:
            out.append((lo, hi, n))
    return out


def hot_blocks(counts: Counter, top: int = 20) -> list[tuple[int, int]]:
    """The ``top`` :data:`BLOCK`-byte blocks by samples: (block start offset, samples)."""
    blocks: Counter = Counter()
    for off, n in counts.items():
        blocks[off - off % BLOCK] += n
    return blocks.most_common(top)


def annotated(asm: str, counts: Counter) -> str:
    """``asm`` (objdump of the code at offset 0) with each instruction's samples in front."""
    lines = []
    for line in asm.splitlines():
        m = _ASM_LINE.match(line)
        n = counts.get(int(m.group(1), 16), 0) if m else 0
        lines.append(f"{n:7d} {line}" if m else f"{'':7s} {line}")
    return "\n".join(lines) + "\n"


def _disassembled(path: Path) -> str:
    objdump = shutil.which("objdump")
    if objdump is None:
        raise SystemExit("loop_profile: objdump (binutils) is needed to disassemble the loop")
    return subprocess.run(
        [objdump, "-D", "-b", "binary", "-mi386:x86-64", str(path)],
        check=True,
        capture_output=True,
        text=True,
    ).stdout


def profiled_loop(loops: list[dict], ips: list[int]) -> tuple[dict, Counter]:
    """The dumped loop (an entry of ``loop.json``'s ``loops``) with the most samples, and its
    samples per offset: the version the profiled runs executed."""
    counted = [(loop, sample_offsets(ips, loop["base"], loop["size"])) for loop in loops]
    return max(counted, key=lambda lc: sum(lc[1].values()))


def annotate(folder: Path) -> str:
    """Read ``folder``'s ``loop.json``, code files and ``ips.txt``; write ``annotated.asm``
    for the loop version with the most samples; return the report text."""
    info = json.loads((folder / "loop.json").read_text())
    ips = read_ips((folder / "ips.txt").read_text())
    loop, counts = profiled_loop(info["loops"], ips)
    asm = _disassembled(folder / loop["file"])
    base, size = loop["base"], loop["size"]
    total = sum(counts.values())
    if total == 0:
        raise SystemExit(f"loop_profile: no sample of {folder / 'ips.txt'} is in the loop's code")
    (folder / "annotated.asm").write_text(annotated(asm, counts))
    lines = [
        f"{info['engine']} on {info['scene']}: {'.'.join(LOOPS[info['engine']])} "
        f"({len(info['loops'])} compiled version(s) in the process, {loop['file']} profiled)",
        f"{total} of {len(ips)} samples inside the loop's code ({size} B at {base:#x})",
        "regions (the loop, then the functions it calls), share of the loop's samples:",
    ]
    regions = region_shares(counts, call_targets(asm, base, size), size)
    starts = [lo for lo, _, _ in regions]
    for lo, hi, n in regions:
        lines.append(f"  {lo:#8x}-{hi:#8x}  {n:7d}  {100 * n / total:5.1f} %")
    lines.append(f"hottest {BLOCK}-byte blocks (region start in brackets):")
    for off, n in hot_blocks(counts):
        region = starts[max(0, bisect.bisect_right(starts, off) - 1)] if starts else 0
        lines.append(f"  {off:#8x} [{region:#x}]  {n:7d}  {100 * n / total:5.1f} %")
    lines.append(f"every instruction with its samples: {folder / 'annotated.asm'}")
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    sub = parser.add_subparsers(dest="command", required=True)
    d = sub.add_parser("dump", help="run the engine, then copy its step loop's code")
    d.add_argument("folder", type=Path)
    d.add_argument("--engine", choices=sorted(LOOPS), default="compliance")
    d.add_argument("--scene", default="saiidi-4span", help="built-in scene")
    d.add_argument("--runs", type=int, default=60, help="profiled runs")
    a = sub.add_parser("annotate", help="bin perf's samples over the dumped code")
    a.add_argument("folder", type=Path)
    args = parser.parse_args(argv)
    if args.command == "dump":
        if args.runs < 1:
            parser.error(f"--runs must be at least 1, got {args.runs}")
        info = dump(args.folder, args.engine, args.scene, args.runs)
        loop = ".".join(LOOPS[args.engine])
        print(f"{loop}: {len(info['loops'])} compiled version(s) -> {args.folder}")
        return 0
    for name in ("loop.json", "ips.txt"):
        if not (args.folder / name).is_file():
            parser.error(f"{args.folder / name} is missing (module docstring: the three steps)")
    print(annotate(args.folder))
    return 0


if __name__ == "__main__":
    sys.exit(main())
