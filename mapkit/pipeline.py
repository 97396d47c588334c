"""``mapkit build``: plan or mesh in, :class:`~linemap.lmap.LineMap` out.

The stages, in order, each in its own module and each taking plain data
from the one before (no module imports a later stage)::

    mapkit.importers   plan.dxf / mesh  ->  Scene  (mapkit.scene)
                       importers/dxf/: read, units, layers, entities,
                         reconstruct (walls, openings, enclosure)
                       importers/mesh/: load, section, edges, hidden
                       importers/ifc/: read, geometry, connections,
                         storey (a Scene per storey; mapkit.building
                         builds each and writes the manifest)
    mapkit.edges       Scene  ->  3D segments (N, 2, 3) + kinds
                       (a mesh importer gives its own segments instead)
    mapkit.visibility  segments + walls  ->  where each segment is seen from
    mapkit.vir         ->  view-invariant regions and their segment lists
    mapkit.assemble    ->  LineMap (flat arrays, region lookup grid)
    linemap.lmap       LineMap  <->  .lmap file

Shared by the stages: :mod:`mapkit.shapes` (polygon parts and rings),
:mod:`mapkit.tolerances` (every threshold), :mod:`mapkit.options`,
:mod:`mapkit.units`, :mod:`mapkit.errors`.

This module only wires the stages, times them, and records what was done
in the map's META.
"""

from __future__ import annotations

import json
import logging
import math
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from mapkit import __version__
from mapkit.assemble import assemble_map
from mapkit.errors import MapkitError
from linemap.lmap import LineMap, SegmentKind, file_sha256
from mapkit.options import BuildOptions
from mapkit.progress import step
from mapkit.shapes import polygon_parts

log = logging.getLogger("mapkit")


@dataclass
class BuildReport:
    """What a build did: seconds per stage and the resulting counts."""

    seconds: dict[str, float] = field(default_factory=dict)
    counts: dict[str, int] = field(default_factory=dict)
    warnings: list[str] = field(default_factory=list)


def build_map(plan: str | Path, options: BuildOptions | None = None, progress: bool = False,
              runner=None) -> tuple[LineMap, BuildReport]:
    """Run the whole pipeline on a DXF plan or a mesh; nothing is written.
    ``runner`` (:class:`mapkit.tile_runner.DaskTiles`; None: this process)
    runs the tiles of a floor built in tiles."""
    from mapkit.importers import load_scene

    options = options or BuildOptions()
    options.validate()  # again: fields may have been set since construction
    plan = Path(plan)
    t = time.perf_counter()
    with step("import", progress):
        scene = load_scene(plan, options)
    return build_map_of_scene(scene, plan, options, progress, import_seconds=time.perf_counter() - t, runner=runner)


def build_map_of_scene(scene, plan: str | Path, options: BuildOptions | None = None, progress: bool = False,
                       import_seconds: float = 0.0, runner=None) -> tuple[LineMap, BuildReport]:
    """The pipeline from an imported ``scene`` of the file ``plan`` (named
    and hashed in the map's META): edges, regions, the map; nothing is
    written. One scene of a file with several (a building's storeys)."""
    from linemap.camera import Camera

    from mapkit.edges import extract_edges

    options = options or BuildOptions()
    options.validate()
    camera = Camera.from_dict(options.camera)
    report = BuildReport()
    plan = Path(plan)
    report.seconds["import"] = import_seconds
    if scene.camera_height is not None and options.camera_from_source:
        camera = Camera.from_dict({**camera.to_dict(), "height_m": round(float(scene.camera_height), 4)})

    _check_floor(scene.free_space, options, plan)  # before the edges too: GEOS's buffers misbehave kilometres out
    t = time.perf_counter()
    if scene.segments is not None:
        segments, kinds = np.asarray(scene.segments, float), np.asarray(scene.kinds, np.uint8)
    else:
        with step("edges", progress):
            segments, kinds = extract_edges(scene, options)
    report.seconds["edges"] = time.perf_counter() - t
    if len(segments) == 0:
        raise MapkitError(f"{plan}: no straight wall edges found; check the layer choice with 'mapkit preview'")

    _check_region_time(segments, scene, options, plan)
    t = time.perf_counter()
    part = _build_regions(segments, scene, camera, options, progress, runner)
    report.seconds["regions"] = time.perf_counter() - t

    t = time.perf_counter()
    polygons, lists = _single_part_regions(part.polygons, part.lists)
    segments, kinds, lists, dropped = _drop_unseen(segments, kinds, lists)
    counts = {
        "segments": int(len(segments)),
        "segments_never_visible_dropped": dropped,
        "regions": len(polygons),
        "mean_list_length": float(np.mean([len(x) for x in lists])) if lists else 0.0,
    }
    meta = {
        "units": "m",
        "generator": f"mapkit {__version__}",
        "source": {"name": plan.name, "sha256": file_sha256(plan), "bytes": plan.stat().st_size},
        "build": options.to_meta(),
        "camera": camera.to_dict(),
        "wall_height": float(scene.wall_height),
        "scene": _jsonable(scene.info),
        # A georeferenced plan moved to a local origin (importers' "origin_offset_m").
        **({"origin_offset_m": scene.info["origin_offset_m"]} if "origin_offset_m" in scene.info else {}),
        # No timings here: the same plan and options give the same bytes.
        "stats": _rounded({"counts": counts, "regions": {k: v for k, v in part.stats.items() if not k.startswith("time")}}),
    }
    with step("assemble", progress):
        linemap = assemble_map(segments, kinds, polygons, lists, scene.walls, meta)
    report.seconds["assemble"] = time.perf_counter() - t
    report.counts = {**counts, "tiles": part.stats["tiles"]} if "tiles" in part.stats else counts
    report.warnings = list(scene.info.get("warnings", []))
    return linemap, report


def _build_regions(segments: np.ndarray, scene, camera, options: BuildOptions, progress: bool, runner):
    """The region stage: in one piece (:func:`mapkit.vir.build_regions`), or
    in tiles (:mod:`mapkit.tiles`) when ``options.tile_side`` is set or the
    floor's predicted peak memory is past ``options.memory_budget``; in the
    latter case, unless ``runner`` says otherwise, each tile in a process of
    its own (:class:`mapkit.tile_runner.ChildTiles`)."""
    from mapkit.tile_runner import ChildTiles
    from mapkit.tiles import Floor, build_regions_in_tiles, plan_tiles, predicted_peak_mb, tile_side_for_budget
    from mapkit.vir import RegionSettings, build_regions

    settings = RegionSettings.from_options(options)
    past_budget = predicted_peak_mb(scene.free_space.area) > options.memory_budget
    side = options.tile_side
    if side is None and past_budget:
        side = tile_side_for_budget(scene.free_space, settings, options.memory_budget)
    if side is None:
        return build_regions(segments, scene.walls, scene.free_space, camera, settings, progress=progress,
                             workers=options.jobs)
    plan = plan_tiles(scene.free_space, settings, side)
    log.info("region stage in %d tiles of %.1f m", len(plan.tiles), plan.side)
    floor = Floor(np.asarray(segments, dtype=float), scene.walls, scene.free_space, camera.to_dict(), settings)
    if runner is None and past_budget:
        runner = ChildTiles(options.jobs)
    return build_regions_in_tiles(floor, plan, runner, progress, options.jobs)


def _check_floor(free_space, options: BuildOptions, plan: Path) -> None:
    """MapkitError naming --max-floor-area when the free space's bounding
    box is larger than the region builder is allowed to work on."""
    if free_space is None or free_space.is_empty:
        return
    x0, y0, x1, y1 = free_space.bounds
    area = (x1 - x0) * (y1 - y0)
    if area > options.max_floor_area:
        raise MapkitError(
            f"{plan.name}: the floor spans {x1 - x0:.0f} x {y1 - y0:.0f} m ({area:.3g} m2), more than the "
            f"{options.max_floor_area:g} m2 a map is built for (MAX_FLOOR_AREA_M2: the region builder's time and "
            f"memory grow with it, about 2 GB at 10^6 m2); check the units, or raise it with --max-floor-area"
        )


def _check_region_time(segments: np.ndarray, scene, options: BuildOptions, plan: Path) -> None:
    """MapkitError naming --max-region-seconds-per-100m2 when the region
    stage's predicted time (``mapkit.region_cost``) is past the seconds per
    100 m2 of free space a building needs (``MAX_REGION_SECONDS_PER_100M2``;
    floors under ``REGION_BOUND_MIN_AREA_M2`` count as that large): wall
    sections tangled by faces that cross the building, segments kilometres
    long."""
    from mapkit.region_cost import region_cost
    from mapkit.tolerances import REGION_BOUND_MIN_AREA_M2

    if scene.free_space is None or scene.free_space.is_empty:
        return
    area = float(scene.free_space.area)
    counted = max(area, REGION_BOUND_MIN_AREA_M2)
    allowed = options.max_region_seconds_per_100m2 * counted / 100.0
    cost = region_cost(segments, scene.walls, max_range=options.max_range,
                       min_visible_length=options.min_visible_length, stop_above=allowed)
    if cost.seconds > allowed:
        tests = f", {cost.sight_tests:.2g} sight tests" if math.isfinite(cost.sight_tests) else ""
        raise MapkitError(
            f"{plan.name}: the region stage would take about {cost.seconds:.3g} s ({cost.points} sample points"
            f"{tests}) over {area:.0f} m2 of free space, "
            f"{100.0 * cost.seconds / counted:.3g} s per 100 m2 where buildings need up to 8 (limit "
            f"{options.max_region_seconds_per_100m2:g}, MAX_REGION_SECONDS_PER_100M2): walls tangled by faces that "
            f"cross the building, or segments kilometres long? repair the input, or raise the limit with "
            f"--max-region-seconds-per-100m2"
        )


def _single_part_regions(polygons, lists):
    """Split multi-part regions: the file and GeoJSON hold one polygon per region."""
    out_p, out_l = [], []
    for geom, lst in zip(polygons, lists):
        for part in polygon_parts(geom):
            if part.area > 0:
                out_p.append(part)
                out_l.append(np.asarray(lst, dtype=np.int64))
    return out_p, out_l


def _drop_unseen(segments, kinds, lists):
    """Remove segments that no region lists (e.g. outer faces of exterior walls)
    and renumber the lists; ids stay dense indices into the segment array."""
    seen = np.zeros(len(segments), dtype=bool)
    for lst in lists:
        seen[lst] = True
    new_id = np.cumsum(seen) - 1
    lists = [new_id[np.asarray(lst, dtype=np.int64)] for lst in lists]
    return segments[seen], kinds[seen], lists, int((~seen).sum())


def _jsonable(obj):
    """A JSON-safe copy (numpy scalars, tuples, paths and the like made plain)."""
    return json.loads(json.dumps(obj, default=lambda v: v.item() if hasattr(v, "item") else str(v)))


def _rounded(obj, digits: int = 6):
    """JSON-safe copy with floats rounded: summation-order noise must not change the file."""
    if isinstance(obj, dict):
        return {k: _rounded(v, digits) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [_rounded(v, digits) for v in obj]
    obj = _jsonable(obj)
    return round(obj, digits) if isinstance(obj, float) else obj


def kind_counts(m: LineMap) -> dict[str, int]:
    """Number of segments per kind label, every kind listed."""
    c = np.bincount(m.kinds, minlength=len(SegmentKind))
    return {k.label: int(c[k]) for k in SegmentKind}
