#!/usr/bin/env python3
"""Where a tiled build's memory and time go, tile by tile, on a generated
office of n x n rooms (``mapkit_harness.plans.office_grid``).

``memory``: the tiles built in this process (``--here``) or each in a
process of its own (mapkit.tile_runner.ChildTiles, the default), then the
join and the map's assembly; per tile its peak (VmHWM, reset before each
tile) and the resident memory left after it, then each stage's peak.

``within``: tiles built with their segments' regions computed within the
whole floor's free space and within the free space near the tile
(``mapkit.tiles.free_space_near``): processor seconds of each, and whether
the regions, lists and outlines are the same bit for bit.

    python tools/probe_tiles.py memory --rooms 10 --tile-side 13
    python tools/probe_tiles.py memory --rooms 10 --tile-side 13 --here
    python tools/probe_tiles.py within --rooms 20 --tile-side 26 --tiles 8

``profile``: one tile (the middle one, or ``--tiles``) built under
cProfile, one thread: the functions that took the most time, cumulative
(wall-clock seconds as cProfile counts them: read the shares).

    python tools/probe_tiles.py profile --rooms 20 --tile-side 26
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

import numpy as np


def _mem() -> dict:
    """This process's resident memory now and its peak since the last reset, MB."""
    out = {}
    with open("/proc/self/status") as f:
        for line in f:
            key, value = line.split(":", 1)
            if key in ("VmRSS", "VmHWM"):
                out[key] = int(value.split()[0]) / 1024
    return out


def _reset_peak() -> None:
    """Start VmHWM again from the resident memory now (Linux)."""
    with open("/proc/self/clear_refs", "w") as f:
        f.write("5")


def _floor(rooms: int):
    from linemap.camera import Camera
    from mapkit.edges import extract_edges
    from mapkit.importers import load_scene
    from mapkit.options import BuildOptions
    from mapkit.tiles import Floor
    from mapkit.vir import RegionSettings
    from mapkit_harness.plans import office_grid

    options = BuildOptions()
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "office.dxf"
        office_grid(path, n=rooms)
        scene = load_scene(path, options)
    segments, kinds = extract_edges(scene, options)
    floor = Floor(np.asarray(segments, float), scene.walls, scene.free_space,
                  Camera.from_dict(options.camera).to_dict(), RegionSettings.from_options(options))
    return floor, kinds, options


def memory(args) -> None:
    from mapkit import tiles
    from mapkit.assemble import assemble_map
    from mapkit.memory import release_memory
    from mapkit.pipeline import _drop_unseen, _single_part_regions
    from mapkit.tile_runner import ChildTiles

    floor, kinds, options = _floor(args.rooms)
    plan = tiles.plan_tiles(floor.free_space, floor.settings, args.tile_side)
    release_memory()
    print(f"office {args.rooms}x{args.rooms}: {len(floor.segments)} segments, {len(plan.tiles)} tiles of "
          f"{plan.side:.1f} m; after the import {_mem()['VmRSS']:.0f} MB", flush=True)
    t0 = time.process_time()
    if args.here:
        out = []
        for tile in plan.tiles:
            _reset_peak()
            t = time.process_time()
            out.append(tiles.build_tile(floor, plan, tile, options.jobs))
            peak = _mem()["VmHWM"]
            release_memory()
            print(f"tile {tile.index}: {out[-1].stats['segments']} segments, {time.process_time() - t:.0f} s, "
                  f"peak {peak:.0f} MB, left {_mem()['VmRSS']:.0f} MB", flush=True)
    else:
        import resource

        out = ChildTiles(options.jobs).run(floor, plan)
        print(f"tiles in their own processes: this one's peak {_mem()['VmHWM']:.0f} MB, now "
              f"{_mem()['VmRSS']:.0f} MB; largest tile process "
              f"{resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss / 1024:.0f} MB", flush=True)
    _reset_peak()
    part = tiles.join_tiles(out, floor, plan)
    print(f"join: peak {_mem()['VmHWM']:.0f} MB, {len(part.polygons)} regions; this process "
          f"{time.process_time() - t0:.0f} s", flush=True)
    del out
    release_memory()
    _reset_peak()
    polygons, lists = _single_part_regions(part.polygons, part.lists)
    segments, kinds, lists, _ = _drop_unseen(floor.segments, kinds, lists)
    assemble_map(segments, kinds, polygons, lists, floor.occluders, {})
    print(f"assemble: peak {_mem()['VmHWM']:.0f} MB", flush=True)


def within(args) -> None:
    from mapkit import tiles

    floor, _, _ = _floor(args.rooms)
    plan = tiles.plan_tiles(floor.free_space, floor.settings, args.tile_side)
    near = tiles.free_space_near
    for i in args.tiles or [len(plan.tiles) // 2]:
        tile = plan.tiles[i]
        got = []
        for f in (lambda free_space, bounds, settings: free_space, near):
            tiles.free_space_near = f
            t = time.process_time()
            built = tiles.build_tile(floor, plan, tile, 1)
            got.append((time.process_time() - t, built))
        tiles.free_space_near = near
        (ta, a), (tb, b) = got
        lists = all(np.array_equal(getattr(a, k), getattr(b, k)) for k in ("keys", "ids", "list_ends"))
        outlines = all(np.array_equal(getattr(a, k), getattr(b, k)) for k in ("wkb", "wkb_ends"))
        print(f"tile {i} ({tile.place()}), {a.stats['segments']} segments: within the whole floor {ta:.1f} s, "
              f"near the tile {tb:.1f} s ({tb / ta:.2f}); regions {len(a.keys)} and {len(b.keys)}; "
              f"lists the same: {lists}; outlines the same: {outlines}", flush=True)


def profile(args) -> None:
    import cProfile
    import pstats

    from mapkit import tiles

    floor, _, _ = _floor(args.rooms)
    plan = tiles.plan_tiles(floor.free_space, floor.settings, args.tile_side)
    for i in args.tiles or [len(plan.tiles) // 2]:
        tile = plan.tiles[i]
        prof = cProfile.Profile()
        t = time.process_time()
        built = prof.runcall(tiles.build_tile, floor, plan, tile, 1)
        print(f"tile {i} ({tile.place()}), {built.stats['segments']} segments, {len(built.keys)} regions: "
              f"{time.process_time() - t:.1f} processor s under the profiler", flush=True)
        pstats.Stats(prof).sort_stats("cumulative").print_stats(30)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("what", choices=["memory", "within", "profile"])
    ap.add_argument("--rooms", type=int, default=10)
    ap.add_argument("--tile-side", type=float, default=13.0)
    ap.add_argument("--here", action="store_true", help="memory: the tiles in this process, one after the other")
    ap.add_argument("--tiles", type=int, nargs="*", help="within, profile: these tiles (default: the middle one)")
    args = ap.parse_args(argv)
    {"memory": memory, "within": within, "profile": profile}[args.what](args)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
