#!/usr/bin/env python3
"""Latency of `matcher.localize`: a git revision against the working tree.

A machine whose speed drifts over minutes (shared cores, turbo) makes two
benchmark runs half an hour apart disagree by more than most changes are
worth. Here two worker processes, one importing the matcher of ``REF`` (a
copy from ``git archive``) and one the working tree's, localise the same
simulated frames alternately, frame by frame, so the drift falls on both
alike. Per PEQ: the median latency of each (best of ``--repeat`` runs per
frame) and the median of the per-frame ratios.

    python tools/bench_ab.py HEAD             # uncommitted changes against HEAD
    python tools/bench_ab.py HEAD~3 --peq 4 5
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

from mapkit_harness.simulate import PEQ, PEQ_HELP
from mapkit_harness.tables import Table, add_report_option, reported

ROOT = Path(__file__).resolve().parent.parent

#: The worker: reads "peq index" lines, prints the best-of-N milliseconds.
#: It runs as ``python -c`` in the revision's folder with that folder on
#: PYTHONPATH (:func:`worker_env`): both come before the installed project on
#: the import path, so it imports the revision's ``matcher`` and harness by name.
_WORKER = r"""
import sys, time
poses, repeat = int(sys.argv[1]), int(sys.argv[2])
import numpy as np, matcher
try:
    from mapkit_harness.simulate import make_frame, paper_camera
except ImportError:  # a revision from before the harness was a package: its simulator sat in tools/
    from simulate import make_frame, paper_camera
linemap = matcher.load_map("maps/flat.lmap")
camera = paper_camera(1.2, 0.0)
frames = {}
for line in sys.stdin:
    peq, i = map(int, line.split())
    if peq not in frames:
        rng = np.random.default_rng([0, peq])
        frames[peq] = [make_frame(linemap, camera, rng, peq, 1.0, 1.0, clutter=3) for _ in range(poses)]
        for fr in frames[peq]:  # warm the map's caches
            matcher.localize(linemap, camera, fr.lines, fr.prior, fr.dt, fr.dyaw)
    fr, best = frames[peq][i], float("inf")
    for _ in range(repeat):
        t0 = time.perf_counter()
        matcher.localize(linemap, camera, fr.lines, fr.prior, fr.dt, fr.dyaw)
        best = min(best, time.perf_counter() - t0)
    print(best * 1e3, flush=True)
"""


def worker_env(root: str) -> dict[str, str]:
    """The environment of a worker running the revision in ``root``: its
    folder (and its tools/, where old revisions kept the simulator) first on
    the import path."""
    return dict(os.environ, PYTHONPATH=os.pathsep.join([root, os.path.join(root, "tools")]))


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description="A/B latency of matcher.localize: REF against the working tree.")
    ap.add_argument("ref", help="git revision to compare against (e.g. HEAD)")
    ap.add_argument("--peq", type=int, nargs="+", default=[3, 4, 5], choices=sorted(PEQ),
                    help="PEQ levels to time (default 3 4 5). " + PEQ_HELP)
    ap.add_argument("--poses", type=int, default=100, help="frames per PEQ (seed 0, as tools/bench_paper.py)")
    ap.add_argument("--repeat", type=int, default=3, help="runs per frame; the best counts")
    add_report_option(ap)
    args = ap.parse_args(argv)
    return reported(args.report, lambda: run(args), __file__, argv)


def run(args) -> int:
    """The benchmark as ``main``'s arguments say; prints the table."""
    with tempfile.TemporaryDirectory() as tmp:
        archive = subprocess.run(["git", "-C", str(ROOT), "archive", args.ref], capture_output=True)
        if archive.returncode:
            print(f"error: git archive {args.ref} failed: {archive.stderr.decode().strip()}", file=sys.stderr)
            return 2
        subprocess.run(["tar", "-x", "-C", tmp], input=archive.stdout, check=True)
        procs = {name: subprocess.Popen([sys.executable, "-c", _WORKER, str(args.poses), str(args.repeat)],
                                        cwd=root, env=worker_env(root),
                                        stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True)
                 for name, root in (("ref", tmp), ("tree", str(ROOT)))}
        table = Table("PEQ", f"{args.ref} ms (median)", "working tree ms (median)", "per-frame ratio (median)")
        for peq in args.peq:
            ms = {"ref": [], "tree": []}
            for i in range(args.poses):
                for name in (("ref", "tree") if i % 2 else ("tree", "ref")):  # alternate who goes first
                    procs[name].stdin.write(f"{peq} {i}\n")
                    procs[name].stdin.flush()
                    ms[name].append(float(procs[name].stdout.readline()))
            a, b = np.array(ms["ref"]), np.array(ms["tree"])
            table.row(peq, f"{np.median(a):.2f}", f"{np.median(b):.2f}", f"{np.median(b / a):.3f}")
        for p in procs.values():
            p.stdin.close()
            p.wait()
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
