#!/usr/bin/env python3
"""Check a tiled region stage against the one-piece build on a generated
office of n x n rooms (``mapkit_harness.plans.office_grid``): the list of
the region holding each of N seeded random free-space points, compared.

Before merging (``--merge-growth 0``, the default here) the lists must be
equal at every point (docs/tiles.md); with merging, the tiled list must
hold every segment of the tiled unmerged list (the leaves' lists) and the
table shows how often it equals the one-piece merged list.

    python tools/check_tiles.py --rooms 10 --tile-side 40 --points 10000
    python tools/check_tiles.py --rooms 10 --tile-side 40 --merge-growth 0.15
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

import numpy as np
import shapely


def lists_at(part, pts: np.ndarray) -> list:
    """The list of the region of ``part`` holding each point (None off every region)."""
    tree = shapely.STRtree(np.array(part.polygons + [None])[:-1])
    i, j = tree.query(shapely.points(pts), predicate="within")
    out = [None] * len(pts)
    for a, b in zip(i, j):
        out[a] = part.lists[b]
    return out


def main(argv: list[str] | None = None) -> int:
    from linemap.camera import Camera
    from mapkit.edges import extract_edges
    from mapkit.importers import load_scene
    from mapkit.options import BuildOptions
    from mapkit.tiles import Floor, build_regions_in_tiles, plan_tiles
    from mapkit.vir import RegionSettings, build_regions
    from mapkit_harness.plans import office_grid

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rooms", type=int, default=10)
    ap.add_argument("--tile-side", type=float, default=40.0)
    ap.add_argument("--points", type=int, default=10000)
    ap.add_argument("--merge-growth", type=float, default=0.0)
    args = ap.parse_args(argv)
    options = BuildOptions(merge_growth=args.merge_growth)
    with tempfile.TemporaryDirectory() as tmp:
        plan_path = Path(tmp) / "office.dxf"
        office_grid(plan_path, n=args.rooms)
        scene = load_scene(plan_path, options)
    segments, _ = extract_edges(scene, options)
    settings = RegionSettings.from_options(options)
    camera = Camera.from_dict(options.camera)
    t = time.process_time()
    one = build_regions(segments, scene.walls, scene.free_space, camera, settings, workers=options.jobs)
    t_one = time.process_time() - t
    floor = Floor(segments, scene.walls, scene.free_space, camera.to_dict(), settings)
    plan = plan_tiles(scene.free_space, settings, args.tile_side)
    t = time.process_time()
    tiled = build_regions_in_tiles(floor, plan, workers=options.jobs)
    t_tiles = time.process_time() - t
    x0, y0, x1, y1 = scene.free_space.bounds
    pts = np.random.default_rng(46).uniform([x0, y0], [x1, y1], (4 * args.points, 2))
    pts = pts[shapely.contains_xy(scene.free_space, pts[:, 0], pts[:, 1])][: args.points]
    a, b = lists_at(one, pts), lists_at(tiled, pts)
    held = [k for k in range(len(pts)) if a[k] is not None and b[k] is not None]
    equal = sum(np.array_equal(a[k], b[k]) for k in held)
    print(f"office {args.rooms}x{args.rooms}, merge growth {args.merge_growth:g}, {len(plan.tiles)} tiles of "
          f"{plan.side:.1f} m")
    print("| build | regions | mean list | processor s |\n|---|---|---|---|")
    print(f"| one piece | {len(one.polygons)} | {one.stats['mean_list_length']:.2f} | {t_one:.0f} |")
    print(f"| tiles | {len(tiled.polygons)} | {tiled.stats['mean_list_length']:.2f} | {t_tiles:.0f} |")
    print(f"points {len(pts)}, in a region of both {len(held)}, lists equal at {equal}")
    return 0 if args.merge_growth > 0 or equal == len(held) == len(pts) else 1


if __name__ == "__main__":
    raise SystemExit(main())
