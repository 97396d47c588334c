#!/usr/bin/env python3
"""Time the VIR partition (mapkit.vir.build_regions) step by step.

Cases: the synthetic apartment, and any plan given on the command line
(through the importer and the edge stage, as `mapkit build` does). For each:
best-of-``--repeat`` seconds per step, regions, quadtree leaves, mean list
length, map size (assemble_map + save_map); with ``--check N``, the superset
property and the list/seen ratio at N seeded random points against the
brute-force reference in mapkit_harness/visibility_oracle.py.

    python tools/bench_vir.py
    python tools/bench_vir.py maps/flat.dxf --check 200
    python tools/bench_vir.py hall --check 100
    python tools/bench_vir.py tests/data/barcelona-pavilion.dxf --walls Walls --walls Columns --windows Crystal
"""

from __future__ import annotations

import argparse
import tempfile
from pathlib import Path

import numpy as np

from mapkit_harness.tables import Table, add_report_option, reported

STEPS = ["time_visibility_polygons_s", "time_segment_regions_s", "time_grow_s", "time_quadtree_s", "time_merge_s", "time_geometry_s", "time_total_s"]


def load_case(path: str | None, opts):
    """(name, segments, kinds, walls, free_space, camera dict); ``path`` None
    is the synthetic apartment, "hall" the synthetic open hall."""
    if path in (None, "hall"):
        from mapkit_harness.plans import apartment, open_hall

        sc = apartment() if path is None else open_hall()
        name = "synthetic apartment" if path is None else "synthetic open hall"
        return name, sc.segments, sc.kinds, sc.walls, sc.free_space, opts.camera
    from mapkit.edges import extract_edges
    from mapkit.importers import load_scene

    scene = load_scene(path, opts)
    if scene.segments is not None:
        segs, kinds = np.asarray(scene.segments, float), np.asarray(scene.kinds, np.uint8)
    else:
        segs, kinds = extract_edges(scene, opts)
    return Path(path).name, segs, kinds, scene.walls, scene.free_space, opts.camera


def check(part, segs, walls, free, camera, n: int) -> tuple[int, float, float]:
    """(misses, mean list length at the points, mean seen count) at n points."""
    import shapely

    from mapkit_harness.visibility_oracle import VisibilityOracle, random_points

    oracle = VisibilityOracle(segs, walls, camera.height_m, camera.elevation_range(), 10.0, 0.3)
    polys = np.array(part.polygons + [None])[:-1]
    tree = shapely.STRtree(polys)
    misses, listed, seen = 0, [], []
    for q in random_points(free, n, np.random.default_rng(1)):
        vis = oracle.visible(q)
        near = tree.query(shapely.Point(q), predicate="dwithin", distance=0.05)
        misses += sum(len(np.setdiff1d(vis, part.lists[r])) > 0 for r in near)
        inside = tree.query(shapely.Point(q), predicate="intersects")
        listed.append(max(len(part.lists[r]) for r in inside))
        seen.append(len(vis))
    return misses, float(np.mean(listed)), float(np.mean(seen))


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("plans", nargs="*", help="DXF plans or meshes, or 'hall' for the synthetic open hall (the synthetic apartment always runs)")
    ap.add_argument("--walls", action="append", default=[], help="wall layer globs, as for mapkit build")
    ap.add_argument("--windows", action="append", default=[], help="window layer globs")
    ap.add_argument("--repeat", type=int, default=3, help="runs per case; the best is shown")
    ap.add_argument("--check", type=int, default=0, metavar="N", help="check the property at N random points")
    ap.add_argument("--min-cell", type=float, default=None)
    ap.add_argument("--merge-growth", type=float, default=None)
    add_report_option(ap)
    args = ap.parse_args(argv)
    return reported(args.report, lambda: run(args), __file__, argv)


def run(args) -> int:
    """The benchmark as ``main``'s arguments say; prints the table."""
    from mapkit.assemble import assemble_map
    from linemap.lmap import save_map
    from mapkit.options import BuildOptions
    from mapkit.vir import RegionSettings, build_regions
    from linemap.camera import Camera

    opts = BuildOptions(walls=args.walls, windows=args.windows)
    camera = Camera.from_dict(opts.camera)
    extra = {k: v for k, v in (("min_cell", args.min_cell), ("merge_growth", args.merge_growth)) if v is not None}
    checked = [f"misses at {args.check} points", "list / seen"] if args.check else []
    table = Table("plan", "segments", "regions", "leaves", "mean list", "map KiB", *(f"{k[5:-2]} s" for k in STEPS),
                  *checked)
    for path in [None, *args.plans]:
        name, segs, kinds, walls, free, _ = load_case(path, opts)
        best = None
        for _ in range(max(1, args.repeat)):
            part = build_regions(segs, walls, free, camera, RegionSettings(**extra))
            if best is None or part.stats["time_total_s"] < best.stats["time_total_s"]:
                best = part
        st = best.stats
        m = assemble_map(segs, kinds, best.polygons, best.lists, walls, {"wall_height": 2.5})
        with tempfile.TemporaryDirectory() as tmp:
            size = save_map(Path(tmp) / "bench.lmap", m)
        row = [name, len(segs), st["regions"], st["quadtree_leaves"], f"{st['mean_list_length']:.1f}",
               f"{size / 1024:.1f}", *(f"{st[k]:.2f}" for k in STEPS)]
        if args.check:
            misses, listed, seen = check(best, segs, walls, free, camera, args.check)
            row += [misses, f"{listed:.1f} / {seen:.1f} = {listed / seen:.2f}"]
        table.row(*row)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
