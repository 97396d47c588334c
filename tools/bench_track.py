#!/usr/bin/env python3
"""Benchmark the tracker (matcher.Tracker) on simulated runs.

Each run is drawn by mapkit_harness/runs.py (route through the map's free
space, 1 px line noise, 2 clutter lines a frame, odometry with 3 % distance
noise and 1.5 degrees per metre drift) on the example map and on the real
drawings in tests/data (built here with mapkit), with and without a kidnap
half-way. The table gives per map and kind of run:

- frames: frames in the runs;
- localised: frames with a trusted pose (state tracking);
- within 5 cm/1 deg: frames whose estimate (whatever the state) is that
  close to the truth; "seeing" the same over the frames that show at least
  3 map lines (the others can only coast on odometry);
- ATE m / odometry ATE m: root mean square position error of the
  estimates, and of odometry alone started at the true first pose;
- wrong: frames with a trusted pose over 50 cm or 10 degrees off;
- reloc frames: after a kidnap, frames until the first trusted pose within
  5 cm / 1 degree (max over runs), and in brackets how many of them showed
  at least 5 map lines (what lost mode needs; a robot set down facing a
  bare wall sees nothing to relocalise on);
- ms/frame: median time of a tracked frame, and of a ``localize`` call with
  PEQ 1 bounds (0.2 m, 10 degrees) on the same frames, and their ratio.

    python tools/bench_track.py                   # 3 runs of 150 frames per map and kind
    python tools/bench_track.py --runs 1 --frames 100 --maps flat
"""

from __future__ import annotations

import argparse
import math
import statistics
import tempfile
import time
from pathlib import Path

import numpy as np

import matcher
from matcher.tracking.route_plot import odometry_route

from mapkit_harness.runs import run_camera, simulate_run
from mapkit_harness.simulate import pose_error
from mapkit_harness.tables import Table, add_report_option, reported

ROOT = Path(__file__).resolve().parent.parent

#: The maps: name, source, mapkit build options (None: a committed .lmap).
MAPS = {
    "flat": (ROOT / "maps" / "flat.lmap", None),
    # thehouse is a 27 x 45 m site of free-standing blocks: built as the
    # README advises for open plans, with a visibility range that reaches
    # across it (at 10 m most of its floor sees fewer than 3 map lines).
    "thehouse": (ROOT / "tests" / "data" / "thehouse.dxf", ["--walls", "s001-*", "--units", "m", "--max-range", "30"]),
    "barcelona": (ROOT / "tests" / "data" / "barcelona-pavilion.dxf",
                  ["--walls", "Walls", "--walls", "Columns", "--windows", "Crystal"]),
}


def load(name: str, folder: Path):
    src, opts = MAPS[name]
    if opts is None:
        return matcher.load_map(src)
    from mapkit.cli import main as mapkit

    out = folder / f"{name}.lmap"
    if mapkit(["build", str(src), "-o", str(out), "-q", *opts]) != 0:
        raise SystemExit(f"could not build {src}")
    return matcher.load_map(out)


def track_run(linemap, camera, run) -> dict:
    """Follow one run from its true first pose; its figures."""
    t = matcher.Tracker(linemap, camera, prior=run.truth[0], dt=0.2, dyaw=10.0)
    est, ok, ms, wrong, close = [], [], [], 0, []
    seeing = [int((ids >= 0).sum()) >= 3 for ids in run.ids]
    for i in range(len(run.times)):
        out = t.step(run.times[i], run.odom[i], run.lines[i])
        ms.append(out.time_ms)
        est.append(out.estimate)
        ok.append(bool(out))
        if out.estimate is not None:
            e = pose_error(out.estimate, run.truth[i])
            close.append(e[0] <= 0.05 and e[1] <= 1.0)
            if out and (e[0] > 0.5 or e[1] > 10.0):
                wrong += 1
        else:
            close.append(False)
    odo = odometry_route(run.odom, run.truth[0])
    reloc = None
    if run.kidnap is not None:
        back = next((i for i in range(run.kidnap, len(run.times)) if ok[i] and close[i]), len(run.times))
        # Frames lost mode could use: enough map lines in view (it needs 5).
        usable = sum(int((run.ids[i] >= 0).sum()) >= 5 for i in range(run.kidnap, back))
        reloc = (back - run.kidnap if back < len(run.times) else math.inf, usable)
    return {"frames": len(run.times), "ok": sum(ok), "close": sum(close), "wrong": wrong,
            "seeing": sum(seeing), "close_seeing": sum(c for c, v in zip(close, seeing) if v),
            "se": [float(np.hypot(e[0] - g[0], e[1] - g[1]) ** 2) for e, g in zip(est, run.truth) if e is not None],
            "odo_se": [float(np.hypot(o[0] - g[0], o[1] - g[1]) ** 2) for o, g in zip(odo, run.truth)],
            "ms": ms, "reloc": reloc}


def _reloc(relocs: list) -> str:
    """The worst relocalisation of the runs: frames, and of them frames
    showing 5 map lines or more ('inf' for a run that never came back)."""
    if not relocs:
        return "-"
    frames, seeing = max(relocs)
    return f"{frames} ({seeing})" if math.isfinite(frames) else f"inf ({seeing})"


def peq1_ms(linemap, camera, run, rng, every: int = 3) -> list[float]:
    """Milliseconds of ``localize`` with PEQ 1 bounds on every ``every``-th frame."""
    out = []
    for i in range(0, len(run.times), every):
        x, y, yaw = run.truth[i]
        r, phi = 0.2 * math.sqrt(rng.uniform()), rng.uniform(0, 2 * math.pi)
        prior = (x + r * math.cos(phi), y + r * math.sin(phi), yaw + rng.uniform(-10, 10))
        t0 = time.perf_counter()
        matcher.localize(linemap, camera, run.lines[i], prior, 0.2, 10.0)
        out.append((time.perf_counter() - t0) * 1e3)
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description="Benchmark the tracker on simulated runs.")
    ap.add_argument("--maps", nargs="+", default=list(MAPS), choices=list(MAPS))
    ap.add_argument("--runs", type=int, default=3, help="runs per map and kind")
    ap.add_argument("--frames", type=int, default=150)
    ap.add_argument("--seed", type=int, default=0)
    add_report_option(ap)
    args = ap.parse_args(argv)
    return reported(args.report, lambda: run_benchmark(args), __file__, argv)


def run_benchmark(args) -> int:
    """The benchmark as ``main``'s arguments say; prints the table."""
    table = Table("map", "run", "frames", "localised", "within 5 cm/1 deg", "seeing", "within, seeing", "ATE m",
                  "odometry ATE m", "wrong", "reloc frames", "ms/frame", "localize PEQ 1 ms", "ratio")
    with tempfile.TemporaryDirectory() as tmp:
        for name in args.maps:
            linemap = load(name, Path(tmp))
            camera = run_camera(linemap)
            for kind in ("plain", "kidnap"):
                rows, peq = [], []
                for k in range(args.runs):
                    rng = np.random.default_rng([args.seed, k, kind == "kidnap"])
                    run = simulate_run(linemap, camera, rng, args.frames,
                                       kidnap=args.frames // 2 if kind == "kidnap" else None)
                    rows.append(track_run(linemap, camera, run))
                    peq += peq1_ms(linemap, camera, run, rng)
                n = sum(r["frames"] for r in rows)
                ms = statistics.median(m for r in rows for m in r["ms"])
                relocs = [r["reloc"] for r in rows if r["reloc"] is not None]
                ate = math.sqrt(statistics.fmean(s for r in rows for s in r["se"]))
                odo = math.sqrt(statistics.fmean(s for r in rows for s in r["odo_se"]))
                seeing = sum(r["seeing"] for r in rows)
                table.row(name, kind, n, f"{100 * sum(r['ok'] for r in rows) / n:.1f} %",
                          f"{100 * sum(r['close'] for r in rows) / n:.1f} %", seeing,
                          f"{100 * sum(r['close_seeing'] for r in rows) / max(seeing, 1):.1f} %", f"{ate:.3f}",
                          f"{odo:.3f}", sum(r["wrong"] for r in rows), _reloc(relocs), f"{ms:.1f}",
                          f"{statistics.median(peq):.1f}", f"{ms / statistics.median(peq):.2f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
