#!/usr/bin/env python3
"""Time the inspector (``mapkit view``) on grid flats of growing size.

For each map (mapkit_harness.plans.grid_flat, or .lmap files given
on the command line) it prints a table row: the seconds to build the scene
(Inspector start), until a websocket client holds every static node
(from the start; this includes the 0.5 s of quiet that ends the client's
wait), for a click plus a pose change, and until Debian's headless chromium shows the
first frame with the map drawn (software WebGL; skipped with --no-browser).
Best of ``--repeat``. The tests check that these things happen; how fast
they happen on a given machine is this script's job.

    python tools/bench_view.py
    python tools/bench_view.py maps/flat.lmap --repeat 3
    python tools/bench_view.py --no-browser
"""

from __future__ import annotations

import argparse
import contextlib
import sys
import time
from pathlib import Path

from mapkit_harness.tables import Table, add_report_option, reported

#: The built-in cases: (name, grid_flat arguments).
CASES = [
    ("grid flat 3 x 2 rooms", {}),
    ("grid flat 7 x 5 rooms (pavilion size)", {"rooms": (7, 5), "room_size": (5.0, 4.5), "cell": 0.4}),
]


def time_map(m, repeat: int, browser) -> dict[str, float]:
    """Best-of-``repeat`` seconds of each step for one map."""
    from mapkit.view.server import Inspector
    from mapkit_harness.inspector import open_and_wait, scene_names

    best: dict[str, float] = {}

    def keep(name: str, seconds: float) -> None:
        best[name] = min(best.get(name, float("inf")), seconds)

    for _ in range(repeat):
        t0 = time.perf_counter()
        ins = Inspector(m, port=0)
        try:
            keep("build", ins.build_seconds)
            scene_names(ins.port, timeout=30)
            keep("client", time.perf_counter() - t0)
            x, y = m.region_centres()[m.n_regions // 2]
            t1 = time.perf_counter()
            ins.select_at(x, y)
            ins.panel.pose.dt.value = 1.0
            ins.update_pose()
            keep("interact", time.perf_counter() - t1)
            if browser is not None:
                _, seconds = open_and_wait(browser, ins)
                keep("browser", seconds)
                browser.navigate("about:blank")
        finally:
            ins.stop()
    return best


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("maps", nargs="*", help=".lmap files (default: the grid flats of mapkit_harness.plans)")
    ap.add_argument("--repeat", type=int, default=2, help="runs per map; the best is shown (default 2)")
    ap.add_argument("--no-browser", action="store_true", help="skip the chromium first-frame timing")
    add_report_option(ap)
    args = ap.parse_args(argv)
    return reported(args.report, lambda: run(args), __file__, argv)


def run(args) -> int:
    """The benchmark as ``main``'s arguments say; prints the table."""
    from linemap.lmap import load_map
    from mapkit_harness.plans import grid_flat

    cases = [(Path(p).name, load_map(p)) for p in args.maps] or [(name, grid_flat(**kw)) for name, kw in CASES]
    # viser's server thread says "Server stopped" on stdout when it gets to
    # it, which under load is after Inspector.stop() has returned: the table
    # goes to the stdout this run was given, anything else printed meanwhile
    # to stderr.
    out = sys.stdout
    with contextlib.ExitStack() as stack:
        stack.enter_context(contextlib.redirect_stdout(sys.stderr))
        browser = None
        if not args.no_browser:
            from mapkit_harness.browser import Chromium
            from mapkit_harness.inspector import HEIGHT, WIDTH

            browser = stack.enter_context(Chromium(WIDTH, HEIGHT))
        print(f"best of {args.repeat}; seconds", file=out)
        print(file=out)
        table = Table("map", "segments", "regions", "scene built", "all nodes at a client", "click + pose",
                      "first frame in chromium", file=out)
        for name, m in cases:
            t = time_map(m, args.repeat, browser)
            shown = f"{t['browser']:.2f}" if "browser" in t else "-"
            table.row(name, m.n_segments, m.n_regions, f"{t['build']:.2f}", f"{t['client']:.2f}",
                      f"{t['interact']:.3f}", shown)
    return 0


if __name__ == "__main__":
    sys.exit(main())
