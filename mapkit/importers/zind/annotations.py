"""ZInD's ``zind_data.json``: one floor's rooms, openings and panoramas in metres.

ZInD (Zillow Indoor Dataset) annotates each panorama with its room's layout
in the panorama's own frame (camera at the origin, camera height 1) and a
``floor_plan_transformation`` (rotation, scale, translation) that places it
on the floor's merged plan; ``scale_meters_per_coordinate`` turns plan
coordinates into metres. We read the *merger* geometry, whose frame the
panoramas' poses are given in (the *redraw* plan is a cleaned copy that
does not line up with them exactly), and for each complete room the
``layout_complete`` of its primary panorama.

World frame. ZInD's layouts are mirrored against the panoramas: its
spherical convention (``code/transformations.py``) takes the azimuth as
``atan2(-x, y)``, so a right-handed world with z up is the plan with y
negated: ``world = (X, -Y) * scale_meters_per_coordinate`` for plan
coordinates (X, Y). Everything here is in that world frame, metres.

Openings (doors, windows, ZInD's "openings") are triples: the two ends on
the plan and (bottom, top) heights relative to the camera in the
panorama's units.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from mapkit.errors import MapkitError
from mapkit.tolerances import MAX_COORDINATE

#: What ZInD calls the three kinds of gap in a wall.
OPENING_KINDS = ("doors", "windows", "openings")


@dataclass(frozen=True)
class ZindOpening:
    """A door, window or opening: ``ends`` (2, 2) world metres, heights above the floor."""

    kind: str  # "door", "window" or "opening"
    ends: np.ndarray
    bottom: float
    top: float


@dataclass(frozen=True)
class ZindPano:
    """A panorama and where it was taken.

    ``position`` (2,) world metres; the map from world directions to the
    panorama's own frame is :meth:`local_directions`.
    """

    name: str
    room: str
    label: str
    image_path: str
    position: np.ndarray
    rotation_deg: float
    camera_height: float
    is_primary: bool
    is_inside: bool

    def local_directions(self, world: np.ndarray) -> np.ndarray:
        """(n, 3) world directions -> (n, 3) the same directions in the panorama's frame.

        Undoes the mirror (y negated) and the plan rotation; ZInD's rotation
        acts on row vectors as ``local @ R`` with ``R = [[c, s], [-s, c]]``.
        """
        a = math.radians(self.rotation_deg)
        rot = np.array([[math.cos(a), math.sin(a)], [-math.sin(a), math.cos(a)]])
        plan = np.asarray(world, float)[:, :2] * (1.0, -1.0)
        local_xy = plan @ rot.T
        return np.column_stack([local_xy, np.asarray(world, float)[:, 2]])

    def pixel_of(self, local: np.ndarray, width: int) -> np.ndarray:
        """(n, 3) directions in the panorama's frame -> (n, 2) pixels (u, v) of a
        ``width`` x ``width / 2`` equirectangular image, ZInD's convention
        (azimuth ``atan2(-x, y)`` 0 at the centre column, up at the top row)."""
        x, y, z = np.asarray(local, float).T
        theta = np.arctan2(-x, y)
        phi = np.arcsin(np.clip(z / np.linalg.norm(local, axis=1), -1.0, 1.0))
        u = (theta + math.pi) / (2 * math.pi) * (width - 1)
        v = (1.0 - (phi + math.pi / 2) / math.pi) * (width / 2 - 1)
        return np.column_stack([u, v])


@dataclass(frozen=True)
class ZindRoom:
    """A complete room: ``outline`` (n, 2) world metres, its ceiling height,
    its openings and its free-standing parts (``internal``: kitchen islands)."""

    name: str
    label: str
    outline: np.ndarray
    ceiling_height: float
    openings: list[ZindOpening]
    internal: list[np.ndarray] = field(default_factory=list)


@dataclass(frozen=True)
class ZindFloor:
    """One floor: its rooms, its panoramas, the camera height (metres)."""

    name: str
    rooms: list[ZindRoom]
    panos: list[ZindPano]
    camera_height: float
    warnings: list[str]


def looks_like_zind(doc) -> bool:
    """Whether a parsed JSON document has ZInD's top-level structure."""
    return isinstance(doc, dict) and "merger" in doc and ("redraw" in doc or "scale_meters_per_coordinate" in doc)


def read_json(path: Path):
    """The parsed JSON of ``path``; a one-line error if it is not JSON."""
    try:
        return json.loads(Path(path).read_bytes())
    except (ValueError, RecursionError) as e:  # JSONDecodeError and UnicodeDecodeError are ValueErrors
        raise MapkitError(f"{path}: not valid JSON ({str(e).splitlines()[0][:120]})") from None


def read_floor(path: Path, floor_name: str | None = None) -> ZindFloor:
    """One floor of a ZInD tour (the first, with a warning if there are several,
    unless ``floor_name`` names one). Raises MapkitError on anything malformed."""
    doc = read_json(path)
    if not looks_like_zind(doc):
        raise MapkitError(f"{path}: not a ZInD annotation file (no top-level 'merger' and 'redraw')")
    try:
        return _floor(doc, floor_name)
    except _Malformed as e:
        raise MapkitError(f"{path}: malformed ZInD annotations: {e}") from None


class _Malformed(Exception):
    """Where in the document a field is missing or of the wrong type."""


def _floor(doc: dict, floor_name: str | None) -> ZindFloor:
    merger = _field(doc, "merger", dict, "")
    floors = sorted(merger)
    if not floors:
        raise _Malformed("'merger' holds no floor")
    warnings = []
    if floor_name is None:
        name = floors[0]
        if len(floors) > 1:
            warnings.append(f"the tour has {len(floors)} floors ({', '.join(floors)}); building '{name}' "
                            "(choose one with --floor-name)")
    elif floor_name in merger:
        name = floor_name
    else:
        raise MapkitError(f"no floor '{floor_name}' in the tour; its floors are {', '.join(floors)}")
    scales = _field(doc, "scale_meters_per_coordinate", dict, "")
    scale = scales.get(name)
    if scale is None:
        raise MapkitError(f"floor '{name}' has no scale (ZInD leaves scale_meters_per_coordinate None where its "
                          "calibration failed): it cannot be built in metres; choose another with --floor-name")
    scale = _number(scale, f"scale_meters_per_coordinate/{name}", positive=True)
    rooms, panos = [], []
    for room_name, partials in sorted(_field(merger, name, dict, "merger").items()):
        where = f"merger/{name}/{room_name}"
        room, room_panos = _room(room_name, _dict(partials, where), scale, where)
        rooms.append(room)
        panos += room_panos
    if not rooms:
        raise _Malformed(f"merger/{name} holds no room")
    _check_reach(np.array([p.camera_height for p in panos]), f"merger/{name}: a panorama's camera height")
    camera = float(np.median([p.camera_height for p in panos]))
    return ZindFloor(name, rooms, panos, camera, warnings)


def _room(room_name: str, partials: dict, scale: float, where: str) -> tuple[ZindRoom, list[ZindPano]]:
    """A complete room from the primary panorama of its first partial room that has one;
    its ceiling the median of its partial rooms' (each from its primary panorama)."""
    if not partials:
        raise _Malformed(f"{where} holds no partial room")
    panos, ceilings, chosen = [], [], None
    for partial_name, pano_dict in sorted(partials.items()):
        here = f"{where}/{partial_name}"
        entries = sorted(_dict(pano_dict, here).items())
        if not entries:
            raise _Malformed(f"{here} holds no panorama")
        partial = []
        for pano_name, data in entries:
            pano, local_unit = _pano(pano_name, room_name, _dict(data, f"{here}/{pano_name}"), scale, f"{here}/{pano_name}")
            partial.append((pano, local_unit, data, f"{here}/{pano_name}"))
        primary = next((p for p in partial if p[0].is_primary), partial[0])
        ceilings.append(_number(primary[2].get("ceiling_height"), f"{primary[3]}/ceiling_height", positive=True) * primary[1])
        if chosen is None or (primary[0].is_primary and not chosen[0].is_primary):
            chosen = primary
        panos += [p[0] for p in partial]
    pano, unit, data, here = chosen
    layout_key = "layout_complete" if "layout_complete" in data else "layout_raw"
    layout = _field(data, layout_key, dict, here)
    here = f"{here}/{layout_key}"
    to_world = _plan_to_world(data, scale, here)
    outline = to_world(_points(_field(layout, "vertices", list, here), f"{here}/vertices", 3))
    cam_local = _number(data.get("camera_height", 1.0), f"{here}/camera_height", positive=True)
    openings = []
    for key in OPENING_KINDS:
        openings += _openings(layout.get(key, []), key, to_world, cam_local, unit, f"{here}/{key}")
    islands = layout.get("internal") or []
    if not isinstance(islands, list):
        raise _Malformed(f"{here}/internal must be a list of outlines")
    internal = [to_world(_points(v, f"{here}/internal", 3)) for v in islands]
    _check_reach(outline, f"{here}/vertices")
    for xy in internal:
        _check_reach(xy, f"{here}/internal")
    for o in openings:
        _check_reach(o.ends, f"{here}/{o.kind}s")
    _check_reach(np.array(ceilings), f"{where}: a ceiling_height")
    room = ZindRoom(room_name, pano.label, outline, float(np.median(ceilings)), openings, internal)
    return room, panos


def _pano(name: str, room: str, data: dict, scale: float, where: str) -> tuple[ZindPano, float]:
    """A panorama and its unit (metres per unit of its own frame)."""
    t = _field(data, "floor_plan_transformation", dict, where)
    s = _number(t.get("scale"), f"{where}/floor_plan_transformation/scale", positive=True)
    unit = s * scale
    rotation = _number(t.get("rotation"), f"{where}/floor_plan_transformation/rotation")
    translation = _points([t.get("translation")], f"{where}/floor_plan_transformation/translation", 1)[0]
    camera = _number(data.get("camera_height", 1.0), f"{where}/camera_height", positive=True)
    pano = ZindPano(
        name=name, room=room, label=str(data.get("label", "")), image_path=str(data.get("image_path", "")),
        position=translation * scale * (1.0, -1.0), rotation_deg=rotation, camera_height=camera * unit,
        is_primary=bool(data.get("is_primary", False)), is_inside=bool(data.get("is_inside", True)),
    )
    return pano, unit


def _plan_to_world(data: dict, scale: float, where: str):
    """The function taking a panorama's (n, 2) local points to world metres
    (infinite where a damaged value overflows: :func:`_check_reach` says so)."""
    t = data["floor_plan_transformation"]
    a = math.radians(float(t["rotation"]))
    rot = np.array([[math.cos(a), math.sin(a)], [-math.sin(a), math.cos(a)]])
    s, shift = float(t["scale"]), np.asarray(t["translation"], float)

    def to_world(local):
        with np.errstate(over="ignore", invalid="ignore"):
            return (local @ rot * s + shift) * scale * (1.0, -1.0)

    return to_world


def _check_reach(xy: np.ndarray, where: str) -> None:
    """_Malformed unless the world coordinates ``xy`` (points or heights,
    metres) are finite and within ``MAX_COORDINATE`` of the origin (a
    damaged value, once scaled, is not)."""
    if xy.size and not (np.isfinite(xy).all() and np.abs(xy).max() <= MAX_COORDINATE):
        raise _Malformed(f"{where} lies farther than {MAX_COORDINATE:g} m from the origin once placed on the plan "
                         "(a damaged value or transformation?)")


def _openings(triples, key: str, to_world, cam_local: float, unit: float, where: str) -> list[ZindOpening]:
    """ZInD's flat list of (end, end, (bottom, top)) triples as openings."""
    if not isinstance(triples, list) or len(triples) % 3:
        raise _Malformed(f"{where} must be a list of (end, end, (bottom, top)) triples")
    pts = _points(triples, where, 0) if triples else np.zeros((0, 2))
    out = []
    for k in range(0, len(pts), 3):
        ends = to_world(pts[k:k + 2])
        bottom, top = ((float(v) + cam_local) * unit for v in pts[k + 2])
        _check_reach(np.array([bottom, top]), f"{where}: the heights of {key} {k // 3 + 1}")
        out.append(ZindOpening(key.rstrip("s"), ends, bottom, top))
    return out


def _field(d: dict, key: str, kind: type, where: str):
    if not isinstance(d, dict) or key not in d:
        raise _Malformed(f"{where or 'the top level'} has no '{key}'")
    value = d[key]
    if not isinstance(value, kind):
        raise _Malformed(f"{where + '/' if where else ''}{key} must be a {kind.__name__}")
    return value


def _dict(value, where: str) -> dict:
    if not isinstance(value, dict):
        raise _Malformed(f"{where} must be an object")
    return value


def _number(value, where: str, positive: bool = False) -> float:
    try:
        v = float(value)
    except (TypeError, ValueError, OverflowError):
        raise _Malformed(f"{where} must be a number, got {str(value)[:40]!r}") from None
    if not math.isfinite(v) or (positive and v <= 0):
        raise _Malformed(f"{where} must be a {'positive' if positive else 'finite'} number, got {v}")
    return v


def _points(value, where: str, at_least: int) -> np.ndarray:
    """(n, 2) finite floats from a list of pairs."""
    try:
        a = np.asarray(value, dtype=float)
    except (TypeError, ValueError, OverflowError):
        raise _Malformed(f"{where} must be a list of (x, y) pairs") from None
    if a.ndim != 2 or a.shape[1] != 2 or len(a) < at_least or not np.isfinite(a).all():
        raise _Malformed(f"{where} must be a list of at least {at_least} finite (x, y) pairs")
    return a
