#!/usr/bin/env python3
"""``mapkit build`` time and memory: a git revision against the working tree.

On a shared machine the load changes from minute to minute, so two build
timings taken apart compare the load as much as the code. Here each plan is
built by ``REF`` (a copy from ``git archive``) and by the working tree one
right after the other, the order alternating per round, each build in its
own process: wall time, CPU time (user + system, all threads), the region
stage's seconds (from the build's summary line), peak memory (``ru_maxrss``)
and the 1-minute load average when the build started (the machine's cores
are shared: CPU time is the steadier measure). The last column says whether
the two ``.lmap`` files are the same byte for byte.

    python tools/bench_build_ab.py HEAD                          # maps/flat.dxf
    python tools/bench_build_ab.py HEAD~2 plan_a.dxf plan_b.dxf --rounds 2
    python tools/bench_build_ab.py HEAD plan.dxf -- --walls 'A-WALL*'   # options for both builds
"""

from __future__ import annotations

import argparse
import filecmp
import os
import re
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from mapkit_harness.tables import Table, add_report_option, reported

ROOT = Path(__file__).resolve().parent.parent

#: The region stage's seconds in the summary line ``mapkit build`` prints.
_REGIONS = re.compile(r"\bregions ([0-9.]+)s")


def build(root: Path, plan: Path, out: Path, extra: list[str]) -> dict:
    """One ``mapkit build`` of ``plan`` with the code under ``root``, in a
    process of its own: its wall and CPU seconds, region-stage seconds,
    peak memory (MB), the load average at its start."""
    env = {**os.environ, "PYTHONPATH": str(root)}
    load = os.getloadavg()[0]
    t0 = time.perf_counter()
    proc = subprocess.Popen([sys.executable, "-m", "mapkit", "build", str(plan), "-o", str(out), *extra],
                            cwd=root, env=env, stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True)
    stdout = proc.stdout.read()
    _, status, usage = os.wait4(proc.pid, 0)
    wall = time.perf_counter() - t0
    proc.returncode = os.waitstatus_to_exitcode(status)
    if proc.returncode:
        raise SystemExit(f"error: the build of {plan} with {root} failed (exit {proc.returncode})")
    stage = _REGIONS.search(stdout)
    return {"wall": wall, "cpu": usage.ru_utime + usage.ru_stime, "regions": float(stage.group(1)) if stage else float("nan"),
            "mb": usage.ru_maxrss / 1024.0, "load": load}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description="A/B time and memory of mapkit build: REF against the working tree.")
    ap.add_argument("ref", help="git revision to compare against (e.g. HEAD)")
    ap.add_argument("plans", nargs="*", default=[str(ROOT / "maps/flat.dxf")], help="plans to build (default maps/flat.dxf)")
    ap.add_argument("--rounds", type=int, default=1, help="builds of each plan by each side; the order alternates")
    add_report_option(ap)
    argv = list(sys.argv[1:] if argv is None else argv)
    cut = argv.index("--") if "--" in argv else len(argv)  # after --: options for both builds
    args = ap.parse_args(argv[:cut])
    args.extra = argv[cut + 1 :]
    return reported(args.report, lambda: run(args), __file__, argv)


def run(args) -> int:
    """The benchmark as ``main``'s arguments say; prints the table."""
    extra = args.extra
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        archive = subprocess.run(["git", "-C", str(ROOT), "archive", args.ref], capture_output=True)
        if archive.returncode:
            print(f"error: git archive {args.ref} failed: {archive.stderr.decode().strip()}", file=sys.stderr)
            return 2
        (tmp / "ref").mkdir()
        subprocess.run(["tar", "-x", "-C", str(tmp / "ref")], input=archive.stdout, check=True)
        roots = {"ref": tmp / "ref", "tree": ROOT}
        table = Table("plan", "round", f"{args.ref} wall s", "tree wall s", "wall ratio", f"{args.ref} CPU s", "tree CPU s",
                      "CPU ratio", f"{args.ref} regions s", "tree regions s", f"{args.ref} MB", "tree MB", "load (1 min)",
                      "same bytes")
        for plan in args.plans:
            plan = Path(plan).resolve()
            for r in range(args.rounds):
                got = {}
                for side in (("tree", "ref") if r % 2 else ("ref", "tree")):
                    got[side] = build(roots[side], plan, tmp / f"{side}.lmap", extra)
                a, b = got["ref"], got["tree"]
                same = filecmp.cmp(tmp / "ref.lmap", tmp / "tree.lmap", shallow=False)
                table.row(plan.name, r + 1, f"{a['wall']:.1f}", f"{b['wall']:.1f}", f"{b['wall'] / a['wall']:.3f}",
                          f"{a['cpu']:.1f}", f"{b['cpu']:.1f}", f"{b['cpu'] / a['cpu']:.3f}", f"{a['regions']:.1f}",
                          f"{b['regions']:.1f}", f"{a['mb']:.0f}", f"{b['mb']:.0f}", f"{a['load']:.1f} / {b['load']:.1f}",
                          "yes" if same else "NO")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
