"""3D segments one already has (a line-mapping tool, a survey, a BIM export)
to a :class:`~mapkit.scene.Scene`.

Two forms, metres unless ``--units`` (or the JSON's ``"units"``) says
otherwise:

- JSON: ``{"segments": [[x1, y1, z1, x2, y2, z2], ...] or [{"from": [x, y,
  z], "to": [x, y, z], "kind": "floor"}, ...], "outline": [[x, y], ...]
  (one ring, or a list of rings), "walls": [[[x, y], ...], ...], "units":
  "m"}``; ``outline`` and ``walls`` are optional;
- CSV: one segment a row, ``x1,y1,z1,x2,y2,z2[,kind]``, a header row
  allowed.

A segment's ``kind`` is one of the map's kinds (``floor``, ``ceiling``,
``vertical``, ``jamb``, ``lintel``, ``window``, ``horizontal``,
``oblique``); without one it is read from the geometry: vertical,
horizontal at the lowest level (floor) or the highest (ceiling), other
horizontal, oblique.

The free space is the ``outline`` less the ``walls`` (wall solids seen
from above, which also hide what is behind them). Without walls, the
segments at floor level are the walls' faces (thin walls on the far side
from the rooms they bound, ``SEGMENTS_WALL_FACE``); without an outline, the rooms those faces enclose
once door-wide gaps are shut (``SEGMENTS_CLOSE_GAP``): doorways then belong
to no room, so give an outline when the robot's route matters there.
"""

from __future__ import annotations

import csv
import json
import math
from pathlib import Path

import numpy as np
import shapely
from shapely.geometry import MultiPolygon, Polygon

from linemap.geometry import segment_is_vertical
from linemap.lmap import KIND_NAMES, SegmentKind
from mapkit.importers import warn_decision
from mapkit.errors import MapkitError
from mapkit.options import BuildOptions
from mapkit.scene import Scene
from mapkit.shapes import polygon_parts
from mapkit.tolerances import (
    AXIS_DEG,
    MAX_COORDINATE,
    MIN_FREE_AREA,
    SEGMENTS_CLOSE_GAP,
    SEGMENTS_LEVEL,
    SEGMENTS_WALL_FACE,
)
from mapkit.units import parse_units

SUFFIXES = (".csv",)
DESCRIPTION = 'a segments file ({"segments": [[x1, y1, z1, x2, y2, z2], ...], optional "outline" and "walls"})'


def accepts(doc) -> bool:
    """Is this parsed JSON a segments file?"""
    return isinstance(doc, dict) and "segments" in doc


def load_scene(path: Path, options: BuildOptions) -> Scene:
    """Import a segments file (see the module docstring)."""
    path = Path(path)
    if path.suffix.lower() == ".csv":
        rows, outline, walls, units = _read_csv(path), None, None, None
    else:
        doc = json.loads(path.read_bytes())
        rows, outline, walls, units = doc["segments"], doc.get("outline"), doc.get("walls"), doc.get("units")
        if units is not None and not isinstance(units, str):
            raise MapkitError(f"{path}: \"units\" must be a unit name such as \"m\" or \"mm\", got {units!r}")
    scale = parse_units(options.units or units or "m") * options.scale
    segments, kinds = _segments(path, rows, scale)
    warnings: list[str] = []
    keep = np.linalg.norm(segments[:, 1] - segments[:, 0], axis=1) >= options.min_edge_length
    if not keep.all():
        warn_decision(warnings, f"{int((~keep).sum())} segment(s) shorter than --min-edge-length "
                        f"{options.min_edge_length:g} m left out")
        segments, kinds = segments[keep], kinds[keep]
    if len(segments) == 0:
        raise MapkitError(f"{path}: no segment of --min-edge-length {options.min_edge_length:g} m or more")
    floor_z, top = float(segments[..., 2].min()), float(segments[..., 2].max())
    if top - floor_z <= SEGMENTS_LEVEL:
        # No height to the building: a map's walls must stand above its floor.
        raise MapkitError(f"{path}: every segment lies at one height ({floor_z:g} m): a map needs walls standing "
                          "above the floor; check the file's z column (x1,y1,z1,x2,y2,z2)")
    at_floor = (np.abs(segments[:, :, 2] - floor_z) <= SEGMENTS_LEVEL).all(axis=1)
    faces = shapely.union_all(shapely.linestrings(segments[at_floor, :, :2]))
    rooms = _enclosed(faces)
    if walls is not None:
        wall_solids = _polygons(path, "walls", walls, scale, rings_are_polygons=True)
    else:  # the faces thickened away from the rooms they bound
        wall_solids = shapely.difference(faces.buffer(SEGMENTS_WALL_FACE, cap_style="flat"), rooms)
    if outline is not None:
        area = _polygons(path, "outline", outline, scale)
    elif rooms.is_empty:
        raise MapkitError(f"{path}: give an \"outline\" (JSON): the floor-level segments enclose no room")
    else:
        area = rooms
    free = shapely.difference(area, wall_solids)
    if options.robot_radius > 0:
        free = free.buffer(-options.robot_radius)
    free = MultiPolygon([p for p in polygon_parts(free) if p.area >= MIN_FREE_AREA])
    if free.is_empty:
        raise MapkitError(f"{path}: no free space is left for the robot; check the outline, --robot-radius and --units")
    counts = np.bincount(kinds, minlength=len(KIND_NAMES))
    info = dict(format="segments", units_scale=scale, warnings=warnings, segments=int(len(segments)),
                kinds={name: int(c) for name, c in zip(KIND_NAMES, counts) if c}, free_area_m2=float(free.area))
    return Scene(walls=MultiPolygon(polygon_parts(wall_solids)), openings=[], free_space=free,
                 wall_height=top - floor_z, segments=segments - [0.0, 0.0, floor_z], kinds=kinds, info=info)


def _read_csv(path: Path) -> list:
    """Rows of a CSV segments file (a header row is skipped)."""
    try:
        with open(path, newline="", encoding="utf-8-sig") as f:
            rows = [r for r in csv.reader(f) if r and any(c.strip() for c in r)]
    except UnicodeDecodeError as e:
        raise MapkitError(f"{path}: not UTF-8 text (byte {e.start}); save the CSV as UTF-8") from None
    except csv.Error as e:  # a NUL byte, a field past the csv module's size limit
        raise MapkitError(f"{path}: not a readable CSV ({e}); one segment a row: x1,y1,z1,x2,y2,z2[,kind]") from None
    if not rows:
        raise MapkitError(f"{path}: no rows; one segment a row: x1,y1,z1,x2,y2,z2[,kind]")
    if rows and not _is_number(rows[0][0]):
        rows = rows[1:]
    return rows


def _segments(path: Path, rows, scale: float) -> tuple[np.ndarray, np.ndarray]:
    """(N, 2, 3) metres and (N,) kinds (uint8) of the rows; MapkitError naming the first bad row."""
    if not isinstance(rows, list) or not rows:
        raise MapkitError(f"{path}: \"segments\" must be a non-empty list of [x1, y1, z1, x2, y2, z2] or "
                          "{\"from\", \"to\", \"kind\"}")
    pts, names = [], []
    for i, row in enumerate(rows):
        if isinstance(row, dict):
            ends = [row.get("from"), row.get("to")]
            xyz = [v for end in ends for v in end] if all(isinstance(e, list) for e in ends) else []
            kind = row.get("kind")
        elif isinstance(row, (list, tuple)):
            xyz, kind = list(row[:6]), (row[6] if len(row) > 6 else None)
        else:
            xyz, kind = [], None
        try:
            values = [float(v) for v in xyz]
        except (TypeError, ValueError, OverflowError):
            values = []
        if len(values) != 6 or not all(math.isfinite(v) for v in values):
            raise MapkitError(f"{path}: segment {i + 1} is not six finite numbers x1, y1, z1, x2, y2, z2: {row!r}"[:300])
        if max(abs(v) for v in values) * scale > MAX_COORDINATE:
            raise MapkitError(f"{path}: segment {i + 1} has a coordinate farther than {MAX_COORDINATE:g} m from the "
                              f"origin (a damaged value?); check that row and the units: {row!r}"[:300])
        if kind not in (None, "") and str(kind).strip().lower() not in KIND_NAMES:
            raise MapkitError(f"{path}: segment {i + 1} has kind {kind!r}; use one of {', '.join(KIND_NAMES)}")
        pts.append(values)
        names.append(None if kind in (None, "") else str(kind).strip().lower())
    segments = np.asarray(pts, dtype=float).reshape(-1, 2, 3) * scale
    kinds = _infer_kinds(segments)
    for i, name in enumerate(names):
        if name is not None:
            kinds[i] = KIND_NAMES.index(name)
    return segments, kinds


def _infer_kinds(segments: np.ndarray) -> np.ndarray:
    """(N,) kinds read from the geometry (see the module docstring)."""
    z = segments[:, :, 2]
    level = np.abs(z[:, 1] - z[:, 0]) <= SEGMENTS_LEVEL
    kinds = np.full(len(segments), SegmentKind.OBLIQUE, dtype=np.uint8)
    kinds[level] = SegmentKind.HORIZONTAL
    kinds[level & (np.abs(z.mean(axis=1) - z.min()) <= SEGMENTS_LEVEL)] = SegmentKind.FLOOR
    kinds[level & (np.abs(z.mean(axis=1) - z.max()) <= SEGMENTS_LEVEL)] = SegmentKind.CEILING
    kinds[segment_is_vertical(segments, AXIS_DEG)] = SegmentKind.VERTICAL
    return kinds


def _polygons(path: Path, what: str, value, scale: float, rings_are_polygons: bool = False) -> MultiPolygon:
    """Polygons of an ``outline`` (a ring or a list of rings, holes by
    even-odd) or of ``walls`` (a list of rings, each a solid)."""
    if not isinstance(value, list):
        raise MapkitError(f"{path}: \"{what}\" must be rings of at least 3 [x, y] points")
    rings = value if value and isinstance(value[0], list) and value[0] and isinstance(value[0][0], list) else [value]
    polys = []
    for ring in rings:
        try:
            with np.errstate(over="ignore"):
                xy = np.asarray(ring, dtype=float) * scale
        except (TypeError, ValueError, OverflowError):
            xy = np.zeros((0, 2))
        if xy.ndim != 2 or xy.shape[1] != 2 or len(xy) < 3 or not np.isfinite(xy).all():
            raise MapkitError(f"{path}: \"{what}\" must be rings of at least 3 [x, y] points")
        if np.abs(xy).max() > MAX_COORDINATE:
            raise MapkitError(f"{path}: \"{what}\" has a point farther than {MAX_COORDINATE:g} m from the origin "
                              "(a damaged value?); check it and the units")
        polys.append(shapely.make_valid(Polygon(xy)))
    if rings_are_polygons:
        return MultiPolygon(polygon_parts(shapely.union_all(polys)))
    out = polys[0]
    for p in polys[1:]:
        out = shapely.symmetric_difference(out, p)
    return MultiPolygon(polygon_parts(out))


def _enclosed(faces) -> MultiPolygon:
    """The rooms the wall faces ``faces`` (lines) enclose once gaps up to
    ``SEGMENTS_CLOSE_GAP`` wide are shut: the holes of the faces thickened
    by half that, grown back."""
    half = SEGMENTS_CLOSE_GAP / 2
    thick = faces.buffer(half, cap_style="square", join_style="mitre")
    holes = [Polygon(r) for p in polygon_parts(thick) for r in p.interiors]
    rooms = [h.buffer(half, join_style="mitre") for h in holes]
    return MultiPolygon(polygon_parts(shapely.union_all(rooms))) if rooms else MultiPolygon()


def _is_number(text: str) -> bool:
    try:
        float(text)
        return True
    except ValueError:
        return False

