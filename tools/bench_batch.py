#!/usr/bin/env python3
"""Benchmark many builds at once: 8 floors built one at a time against
``mapkit build ... --workers 2`` (a local Dask cluster), side by side in one run.

The floors are generated offices of 4 x 4 rooms (``mapkit_harness.plans.office_grid``),
the room size a little larger on each floor so that no two are the same
plan. One at a time: ``mapkit build FLOOR -o FLOOR.lmap`` in a fresh process
per floor, one after the other (what a user's shell loop does), each
process's peak memory its own. At once: :func:`mapkit.batch.run_jobs` on a
local cluster of ``--workers`` processes, the same code path as the command
(its wall time includes starting and stopping the cluster); the peak memory
of each worker process is the largest its tasks reported. Both sides build
with ``--jobs 1`` (one thread per build), so the ratio is the parallelism
of the processes alone; every map is checked to be byte-identical on both
sides. Expect a ratio near the worker count on an idle machine of as many
cores (about 1.8 for 2 workers on 2 cores).

    python tools/bench_batch.py
    python tools/bench_batch.py --floors 4 --rooms 3 --report docs/benchmarks/batch.md
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from mapkit_harness.tables import Table, add_report_option, cpu_count, reported


def make_floors(folder: Path, floors: int, rooms: int) -> list[Path]:
    """``floors`` office plans of ``rooms`` x ``rooms`` rooms, the rooms
    5 m + 0.1 m per floor (each floor its own plan)."""
    from mapkit_harness.plans import office_grid

    paths = []
    for k in range(floors):
        path = folder / f"floor{k + 1}.dxf"
        office_grid(path, n=rooms, room=5.0 + 0.1 * k)
        paths.append(path)
    return paths


def one_at_a_time(floors: list[Path], out: Path) -> tuple[float, list[int]]:
    """Each floor built by its own ``mapkit build`` process, one after the
    other: total wall seconds and each process's peak resident bytes."""
    out.mkdir()
    peaks = []
    t = time.perf_counter()
    for floor in floors:
        cmd = [sys.executable, "-m", "mapkit.cli", "build", str(floor), "-o", str(out / f"{floor.stem}.lmap"),
               "-q", "--jobs", "1"]
        proc = subprocess.Popen(cmd)
        _, status, usage = os.wait4(proc.pid, 0)
        proc.returncode = os.waitstatus_to_exitcode(status)
        if proc.returncode != 0:
            raise RuntimeError(f"mapkit build {floor.name} exited {proc.returncode}")
        peaks.append(usage.ru_maxrss * 1024)  # KiB on Linux
    return time.perf_counter() - t, peaks


def at_once(floors: list[Path], out: Path, workers: int) -> tuple[float, dict[int, int]]:
    """The floors built as Dask tasks on a local cluster of ``workers``
    processes: wall seconds (cluster start and stop included) and the
    peak resident bytes of each worker process (by process id)."""
    from mapkit.batch import BUILT, plan_jobs, run_jobs
    from mapkit.options import BuildOptions

    out.mkdir()
    t = time.perf_counter()
    results = run_jobs(plan_jobs(floors, out), BuildOptions(jobs=1), workers=workers)
    seconds = time.perf_counter() - t
    bad = [r for r in results if r.status != BUILT]
    if bad:
        raise RuntimeError(f"{bad[0].source}: {bad[0].error}")
    peaks: dict[int, int] = {}
    for r in results:
        peaks[r.worker_pid] = max(peaks.get(r.worker_pid, 0), r.peak_rss_bytes)
    return seconds, peaks


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--floors", type=int, default=8, help="floors to build (default 8)")
    ap.add_argument("--rooms", type=int, default=4, help="rooms along each side of a floor (default 4)")
    ap.add_argument("--workers", type=int, default=2, help="local Dask workers (default 2)")
    add_report_option(ap)
    args = ap.parse_args(argv)
    return reported(args.report, lambda: run(args), __file__, argv)


def run(args) -> int:
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        floors = make_floors(tmp, args.floors, args.rooms)
        t_one, peaks_one = one_at_a_time(floors, tmp / "one")
        t_all, peaks_all = at_once(floors, tmp / "all", args.workers)
        differ = [f.stem for f in floors
                  if (tmp / "one" / f"{f.stem}.lmap").read_bytes() != (tmp / "all" / f"{f.stem}.lmap").read_bytes()]
    print(f"{args.floors} floors of {args.rooms} x {args.rooms} rooms, --jobs 1, {cpu_count()} cores\n")
    table = Table("how", "processes", "wall s", "s per floor", "peak MB per process", "speed-up")
    table.row("one at a time (`mapkit build` per floor)", len(peaks_one), f"{t_one:.1f}", f"{t_one / len(floors):.2f}",
              f"{max(peaks_one) / 2**20:.0f} (largest of {len(peaks_one)})", "1.00")
    per_worker = ", ".join(f"{p / 2**20:.0f}" for _, p in sorted(peaks_all.items()))
    table.row(f"at once (`--workers {args.workers}`)", len(peaks_all), f"{t_all:.1f}", f"{t_all / len(floors):.2f}",
              per_worker, f"{t_one / t_all:.2f}")
    print(f"\nratio one-at-a-time / at-once: {t_one / t_all:.2f}; maps byte-identical: "
          f"{'yes' if not differ else 'NO: ' + ', '.join(differ)}")
    return 1 if differ else 0


if __name__ == "__main__":
    raise SystemExit(main())
