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

``against``: one tile (the middle one, or ``--tiles``) built by this
checkout's region code and by that of ``--commit`` (its ``mapkit/tiles.py``,
``vir.py``, ``visibility.py`` and ``visibility_batch.py``, read with ``git
show``), alternately, ``--rounds`` times each, one thread, in this one
process: processor seconds of each, and whether the tile's regions, lists
and outlines are the same bit for bit.

    python tools/probe_tiles.py against --commit HEAD~1 --rooms 20 --tile-side 26

``plan``: what comes before the first tile, under cProfile: the import of
the drawing, the edges, the region stage's checks (predicted time) and the
plan of the tiles at the default budget, and each tile's choice of
segments (``tiles.tile_segments``, which every tile makes first).

    python tools/probe_tiles.py plan --rooms 40
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


_REGION_MODULES = ("visibility_batch", "visibility", "vir", "tiles")


def _modules_of(commit: str) -> dict:
    """The region modules as of ``commit``, loaded under their own names
    (while loading, each sees the others of that commit)."""
    import subprocess
    import sys
    import types

    saved = {m: sys.modules[f"mapkit.{m}"] for m in _REGION_MODULES}
    old = {}
    try:
        for m in _REGION_MODULES:
            src = subprocess.run(["git", "show", f"{commit}:mapkit/{m}.py"], capture_output=True, text=True,
                                 check=True).stdout
            mod = types.ModuleType(f"mapkit.{m}")
            mod.__file__ = f"{commit}:mapkit/{m}.py"
            sys.modules[f"mapkit.{m}"] = mod
            exec(compile(src, mod.__file__, "exec"), mod.__dict__)
            old[m] = mod
    finally:
        sys.modules.update({f"mapkit.{m}": mod for m, mod in saved.items()})
    return old


def _built_with(modules: dict, floor, plan, tile):
    """The tile built with ``modules`` in place of the region modules: (processor s, TileRegions)."""
    import sys

    saved = {m: sys.modules[f"mapkit.{m}"] for m in _REGION_MODULES}
    sys.modules.update({f"mapkit.{m}": mod for m, mod in modules.items()})
    try:
        t = time.process_time()
        built = modules["tiles"].build_tile(floor, plan, tile, 1)
        return time.process_time() - t, built
    finally:
        sys.modules.update({f"mapkit.{m}": mod for m, mod in saved.items()})


def against(args) -> None:
    import importlib

    from mapkit import tiles

    here = {m: importlib.import_module(f"mapkit.{m}") for m in _REGION_MODULES}
    old = _modules_of(args.commit)
    floor, _, _ = _floor(args.rooms)
    plan = tiles.plan_tiles(floor.free_space, floor.settings, args.tile_side)
    for i in args.tiles or [len(plan.tiles) // 2]:
        tile = plan.tiles[i]
        times = {"old": [], "new": []}
        for _ in range(args.rounds):
            for name, mods in (("old", old), ("new", here)):
                seconds, built = _built_with(mods, floor, plan, tile)
                times[name].append(seconds)
                if name == "old":
                    ref = built
        same = all(np.array_equal(getattr(ref, k), getattr(built, k))
                   for k in ("keys", "ids", "list_ends", "wkb", "wkb_ends"))
        old_s, new_s = sum(times["old"]), sum(times["new"])
        print(f"tile {i} ({tile.place()}), {built.stats['segments']} segments, {len(built.keys)} regions: "
              f"{args.commit} {' '.join(f'{t:.1f}' for t in times['old'])} s, this checkout "
              f"{' '.join(f'{t:.1f}' for t in times['new'])} s: {new_s / old_s:.2f} times; "
              f"the same bit for bit: {same}", flush=True)


def plan(args) -> None:
    import cProfile
    import pstats

    prof = cProfile.Profile()
    t = time.process_time()
    prof.enable()
    _plan_stages(args.rooms)
    prof.disable()
    print(f"before the tiles: {time.process_time() - t:.1f} processor s under the profiler", flush=True)
    pstats.Stats(prof).sort_stats("cumulative").print_stats(40)


def _plan_stages(rooms: int) -> None:
    """The stages of ``mapkit build`` up to the first tile, each timed (processor s)."""
    from mapkit import tiles
    from mapkit.pipeline import _check_region_time

    t = time.process_time()
    floor, _, options = _floor(rooms)
    print(f"import and edges: {time.process_time() - t:.1f} s, {len(floor.segments)} segments", flush=True)
    t = time.process_time()
    _check_region_time(floor.segments, _SceneView(floor), options, Path("office.dxf"))
    print(f"predicted region time (the check): {time.process_time() - t:.1f} s", flush=True)
    t = time.process_time()
    side = tiles.tile_side_for_budget(floor.free_space, floor.settings, options.memory_budget)
    the_plan = tiles.plan_tiles(floor.free_space, floor.settings, side or args_side_default(floor))
    print(f"plan: {len(the_plan.tiles)} tiles of {the_plan.side:.1f} m, {time.process_time() - t:.1f} s", flush=True)
    t = time.process_time()
    computed = sum(len(tiles.tile_segments(floor.segments, tile.bounds, floor.settings)) for tile in the_plan.tiles)
    print(f"the tiles' segments: {computed} for {len(floor.segments)}, {time.process_time() - t:.1f} s", flush=True)


class _SceneView:
    """What the region stage's check reads of a scene."""

    def __init__(self, floor):
        self.free_space, self.walls = floor.free_space, floor.occluders


def args_side_default(floor) -> float:
    """A floor within the budget: tiles of a quarter of its width, to time the plan anyway."""
    x0, _, x1, _ = floor.free_space.bounds
    return (x1 - x0) / 4.0


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("what", choices=["memory", "within", "profile", "plan", "against"])
    ap.add_argument("--rooms", type=int, default=10)
    ap.add_argument("--tile-side", type=float, default=13.0)
    ap.add_argument("--here", action="store_true", help="memory: the tiles in this process, one after the other")
    ap.add_argument("--tiles", type=int, nargs="*", help="within, profile: these tiles (default: the middle one)")
    ap.add_argument("--commit", default="HEAD", help="against: the commit whose region code to compare with")
    ap.add_argument("--rounds", type=int, default=2, help="against: builds of the tile by each code")
    args = ap.parse_args(argv)
    {"memory": memory, "within": within, "profile": profile, "plan": plan, "against": against}[args.what](args)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
