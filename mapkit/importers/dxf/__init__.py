"""DXF floor plans -> :class:`~mapkit.scene.Scene`.

Reads the file (recovering damaged ones), decides the units, sorts layers
into roles, flattens the linework of each role into strokes in metres and
hands them to :func:`mapkit.importers.dxf.reconstruct.reconstruct_scene`.

    file --read--> ezdxf document (damaged files recovered)
         --units--> drawing units to metres
         --layers, layer_roles--> the role of each layer
         --entities--> strokes per role (curves flattened, blocks expanded)
         --reconstruct--> Scene: wall solids (walls), door and window
                          openings (openings), free space

:mod:`.strokes` holds the plain data the reconstruction takes (``Stroke``,
``PlanDrawing``); it knows nothing of DXF.
"""

from __future__ import annotations

import logging
from collections import Counter
from dataclasses import replace
from functools import partial
from pathlib import Path

import numpy as np
import shapely
from ezdxf import bbox

from mapkit.errors import ImplausibleUnitsError, MapkitError, NoWallsError
from mapkit.importers import warn_decision
from mapkit.importers.dxf.door_swings import find_door_swings
from mapkit.importers.dxf.self_check import enforce
from mapkit.importers.dxf.entities import SILENT, check_entity_count, flatten_entities
from mapkit.importers.dxf.layers import layer_counts, resolve_layer_roles
from mapkit.importers.dxf.loose_swings import adopt_loose_swings
from mapkit.importers.dxf.read import model_space, read_dxf
from mapkit.importers.dxf.sheets import choose_plan, find_plans, nearest_plan, plans_met
from mapkit.importers.dxf.openings import drawing_items
from mapkit.importers.dxf.doorway_gaps import wall_doorway_gaps
from mapkit.importers.dxf.swing_layer import adopt_swing_layer
from mapkit.importers.dxf.units import (INSUNITS, decide_units, units_from_doors, units_from_evidence, units_from_gaps,
                                        units_from_size_and_doors)
from mapkit.importers.dxf.wall_thickness import wall_thickness
from mapkit.options import BuildOptions
from mapkit.importers.dxf.reconstruct import reconstruct_scene
from mapkit.importers.dxf.room_layers import door_lines_apart
from mapkit.importers.dxf.strokes import PlanDrawing
from mapkit.scene import Scene
from mapkit.units import UNIT_METRES
from mapkit.tolerances import (CURVE_SAGITTA, DOOR_UNITS_MIN_DOORS, DXF_FAR_FACTOR, DXF_FAR_MIN_ENTITIES,
                               LOCAL_ORIGIN_BEYOND_M)

SUFFIXES = (".dxf",)

log = logging.getLogger("mapkit")

#: Roles whose geometry builds the scene (the rest is only shown in previews).
_USED_ROLES = ("walls", "doors", "windows", "floor")


def load_scene(path: Path, options: BuildOptions) -> Scene:
    """Import a DXF plan; see the module docstring. Raises MapkitError for user-fixable problems."""
    drawing, info = load_drawing(Path(path), options)
    cam_h = float(options.camera.get("height_m", 1.2))
    if cam_h >= options.wall_height:
        # Visibility treats walls as full-height screens: seen from above
        # their tops, what they hide in the map is in view.
        message = (f"camera height {cam_h:g} m is not below the walls' {options.wall_height:g} m: the map's "
                   "visibility lists assume walls hide what is behind them; check --camera-height and --wall-height")
        log.warning(message)
        info.setdefault("warnings", []).append(message)
    scene = reconstruct_scene(drawing, options, info)
    # The map checks itself against its drawing before it is written (:mod:`.self_check`).
    enforce(scene, drawing, options.robot_radius, options.accept_inconsistent,
            partial(warn_decision, scene.info.setdefault("warnings", [])))
    return scene


def load_drawing(path: Path, options: BuildOptions, document: tuple | None = None) -> tuple[PlanDrawing, dict]:
    """The plan's strokes per role, and ``info`` (units, layers, warnings) so far.

    ``document`` is the ``(ezdxf document, warnings)`` :func:`.read.read_dxf`
    gave for ``path`` when the caller has read it already ('mapkit layers':
    parsing a large drawing takes as long as the rest of this); read here
    otherwise. The document is only read, its warnings list not changed.
    """
    doc, warnings = document if document is not None else read_dxf(path)
    warnings = list(warnings)
    for w in warnings:
        log.warning(w)
    check_entity_count(model_space(doc), doc.blocks, options.max_entities)
    counts = layer_counts(doc)
    try:
        roles, role_warnings, room_outlines = resolve_layer_roles(counts, options)
    except NoWallsError:
        # No layer is walls by name: the one holding the plan's door swings
        # is, read in their unit (:mod:`.swing_layer`); else the refusal stands.
        adopted = adopt_swing_layer(doc, counts, options)
        if adopted is None:
            raise
        roles, role_warnings, room_outlines = adopted.roles, [adopted.warning], []
        if adopted.unit is not None:
            options = replace(options, units=adopted.unit)
    for w in role_warnings:
        log.warning(w)
    warnings += role_warnings

    msp = model_space(doc)
    # Dimensions, text and the like are never built (entities.SILENT): they
    # neither size the plan nor count as far outliers. (Their boxes are also
    # costly: a DIMENSION's is its whole rendered block.)
    used = [e for e in msp if e.dxftype() not in SILENT
            and (roles.get(_layer(e)) in _USED_ROLES or (e.dxftype() == "INSERT" and _layer(e) == "0"))]
    extent, far = _extent(used)
    insunits = int(doc.header.get("$INSUNITS", 0) or 0)
    unit, per_unit, unit_warning = _units(msp, roles, far, extent, doc.header, options)
    if unit_warning:
        log.warning(unit_warning)
        warnings.append(unit_warning)
    factor = per_unit * float(options.scale)

    def note(message: str) -> None:
        log.warning(message)
        warnings.append(message)

    unit, factor, strokes, swing_strokes = _flatten_in_units(  # the unit guessed when the header gives none
        msp, roles, far, (unit, options.units is None and insunits not in INSUNITS), factor, extent, options, note)
    offset = local_origin([s for s in strokes if roles.get(s.layer) in _USED_ROLES] + swing_strokes)
    if offset is not None:
        strokes = [replace(s, coords=s.coords - offset) for s in strokes]
        swing_strokes = [replace(s, coords=s.coords - offset) for s in swing_strokes]
        note(f"the drawing lies {np.hypot(*offset) / 1000:.0f} km from its origin (georeferenced); moved to a "
             f"local origin at ({offset[0]:.0f}, {offset[1]:.0f}) m, kept in the map as origin_offset_m "
             f"('mapkit export --drawing-coordinates' puts it back)")
    strokes, swing_strokes, plans, others = _one_plan(strokes, swing_strokes, roles, options.plan_number, note)
    drawing = _by_role(strokes, swing_strokes, roles, set(room_outlines), note)
    for s in others:  # the sheet's other plans: shown in previews, not built
        drawing.ignored.setdefault(s.layer, []).append(s)

    info = {
        "source": path.name,
        "format": "dxf",
        "units": unit,
        "insunits": insunits,
        "scale": factor,
        "layers": {
            role: sorted(name for name, r in roles.items() if r == role and sum(counts[name].values()))
            for role in _USED_ROLES
        }
        | {"ignored": sorted(name for name, r in roles.items() if r in ("ignore", None) and sum(counts[name].values()))},
        "entities": dict(sum(counts.values(), Counter())),
        "warnings": warnings,
    }
    if offset is not None:
        info["origin_offset_m"] = [float(v) for v in offset]
    if len(plans) > 1:
        info["plans"] = [p.to_dict() for p in plans]
    return drawing, info


def _flatten(msp, roles: dict, far: list, factor: float, options: BuildOptions, note) -> tuple[list, list]:
    """The strokes (metres) of the model space's entities, less those ``far``
    outside the rest, and apart from them the strokes of the door swings
    drawn on wall layers (:mod:`.door_swings`); what was left out is
    ``note``-d."""
    far_ids = {id(e) for e in far}
    swings = find_door_swings([e for e in msp if roles.get(_layer(e)) == "walls" and id(e) not in far_ids], factor)
    left_out = far_ids | {id(e) for pair in swings for e in pair}
    strokes, skipped = flatten_entities([e for e in msp if id(e) not in left_out], factor, CURVE_SAGITTA / factor,
                                        lambda layer: True, max_entities=options.max_entities)
    first_group = 1 + max((s.group for s in strokes if s.group is not None), default=-1)
    if swings:
        note(f"{len(swings)} door swing(s) (an arc and its leaf) drawn on the wall layer(s) "
             f"{_names(sorted({_layer(a) for a, _ in swings}))} taken as doors")
    for e in far:
        skipped[f"{e.dxftype()} (far outside the rest of the drawing, handle {e.dxf.get('handle', '?')} "
                f"on layer {_layer(e)})"] += 1
    if skipped:
        note("skipped unsupported entities: " + ", ".join(f"{n} {kind}" for kind, n in sorted(skipped.items())))
    return strokes, _swing_strokes(swings, factor, first_group)


def _one_plan(strokes: list, swing_strokes: list, roles: dict, choice: int | None, note):
    """The strokes of the one plan to build of a sheet that holds several
    (:mod:`.sheets`), its door swings, the sheet's plans, and the other
    plans' strokes; a drawing of one plan as it is."""
    walls = [s for s in strokes if roles.get(s.layer) == "walls"]
    plans, of_wall = find_plans(walls)
    if len(plans) <= 1:
        if choice not in (None, 1):
            raise MapkitError(f"--plan {choice}: the drawing holds one plan; leave --plan out")
        return strokes, swing_strokes, plans, []
    chosen = choose_plan(plans, choice)
    plan_of = {id(s): int(n) for s, n in zip(walls, of_wall)}

    def ours(s) -> bool:
        n = plan_of.get(id(s))
        if n is None:
            box = (*s.coords.min(axis=0), *s.coords.max(axis=0))
            # A stroke across two plans (a sheet's frame, a grid line) is no one plan's.
            n = 0 if len(plans_met(plans, box)) > 1 else nearest_plan(plans, box)
        return n == chosen.number

    note(f"the drawing holds {len(plans)} separate plans: " + "; ".join(p.describe() for p in plans)
         + f"; building #{chosen.number}" + ("" if choice else " (the largest); choose another with --plan N"))
    return ([s for s in strokes if ours(s)], [s for s in swing_strokes if ours(s)], plans,
            [s for s in strokes if not ours(s)])


def _by_role(strokes: list, swing_strokes: list, roles: dict, room_outlines: set[str] = frozenset(),
             note=None) -> PlanDrawing:
    """The strokes sorted by their layer's role (door swings are doors
    whatever their layer: those on wall layers, ``swing_strokes``, and those
    on layers of another role hinged on a wall, :mod:`.loose_swings`, which
    are ``note``-d); those of other layers kept for previews. The
    strokes of ``room_outlines`` layers (:mod:`.room_layers`) are walls and
    also the "rooms" role; in such a plan each straight door line is a door."""
    drawing = PlanDrawing()
    if swing_strokes:
        drawing.strokes["doors"] = list(swing_strokes)
    for s in strokes:
        role = roles.get(s.layer)
        if role in _USED_ROLES:
            drawing.strokes.setdefault(role, []).append(s)
            if s.layer in room_outlines:
                drawing.strokes.setdefault("rooms", []).append(s)
        else:
            drawing.ignored.setdefault(s.layer, []).append(s)
    taken = adopt_loose_swings(drawing, 1 + max((s.group for s in strokes + swing_strokes if s.group is not None),
                                                default=-1))
    if taken and note is not None:
        note(f"{sum(taken.values())} door swing(s) hinged on a wall, drawn on the layer(s) {_names(sorted(taken))} "
             "read as something else, taken as doors")
    if room_outlines and drawing.role("doors"):
        first = 1 + max((s.group for s in strokes + swing_strokes + drawing.role("doors") if s.group is not None),
                        default=-1)
        drawing.strokes["doors"] = door_lines_apart(drawing.role("doors"), first)
    return drawing


def _swing_strokes(swings, factor: float, first_group: int) -> list:
    """The strokes of each door swing ``(arc, leaf)``, one group per swing
    (numbered from ``first_group``): one door drawing each."""
    out = []
    for k, pair in enumerate(swings):
        strokes, _ = flatten_entities(list(pair), factor, CURVE_SAGITTA / factor, lambda layer: True)
        out += [replace(s, group=first_group + k) for s in strokes]
    return out


def _names(layers: list[str]) -> str:
    return ", ".join(f"'{n}'" for n in layers)


def _flatten_in_units(msp, roles: dict, far: list, unit_guessed: tuple[str, bool], factor: float, extent: float,
                      options: BuildOptions, note) -> tuple[str, float, list, list]:
    """:func:`_flatten` in the drawing's unit (``unit_guessed``: its name and
    whether it was only guessed from the extent, the header giving none;
    ``factor`` metres per drawing unit; ``extent`` the plan's, drawing
    units), read again in another unit when the user gave neither
    ``--units`` nor ``--scale`` and: the unit was guessed and its doors and
    walls say another (:func:`.units.units_from_evidence`); or the header's
    unit makes its doors (:func:`.units.units_from_doors`), in a plan
    without door symbols its doorway gaps (:func:`.units.units_from_gaps`),
    no door's width. Returns the unit, the factor and the strokes."""
    unit, guessed = unit_guessed
    first_notes: list[str] = []
    strokes, swing_strokes = _flatten(msp, roles, far, factor, options, first_notes.append)
    told = None
    if options.units is None and float(options.scale) == 1.0:
        widths = door_widths(strokes, roles)
        walls = [s for s in strokes if roles.get(s.layer) == "walls"]
        if guessed:
            told = units_from_evidence(widths, wall_doorway_gaps(walls), wall_thickness(walls), unit, extent * factor)
        elif len(widths) >= DOOR_UNITS_MIN_DOORS:
            told = units_from_doors(widths, unit, extent * factor)
        else:  # too few door symbols to tell: the gaps in its walls tell
            told = units_from_gaps(wall_doorway_gaps(walls), unit, extent * factor, wall_thickness(walls),
                                   options.max_wall_thickness)
    if told is None:
        for message in first_notes:
            note(message)
        return unit, factor, strokes, swing_strokes
    unit, message = told  # the header (or the guess) is wrong: read again in the unit its doors or gaps say
    note(message)
    factor = UNIT_METRES[unit]
    return (unit, factor, *_flatten(msp, roles, far, factor, options, note))


def _units(msp, roles: dict, far: list, extent: float, header, options: BuildOptions) -> tuple[str, float, str | None]:
    """The drawing's unit, metres per unit and a warning or None
    (:func:`.units.decide_units`). When the header's unit makes the plan no
    building, the one unit that makes it a building with doors a door's
    width, if exactly one does (:func:`_unit_by_size_and_doors`); --units
    and --scale are the user's word: never overruled."""
    insunits = int(header.get("$INSUNITS", 0) or 0)
    try:
        return decide_units(insunits, options.units, extent, header.get("$MEASUREMENT", 1) == 0)
    except ImplausibleUnitsError:
        told = None
        if float(options.scale) == 1.0:
            told = _unit_by_size_and_doors(msp, roles, far, extent, INSUNITS.get(insunits, "m"))
        if told is None:
            raise
        return told[0], UNIT_METRES[told[0]], told[1]


def _unit_by_size_and_doors(msp, roles: dict, far: list, extent: float, stated: str) -> tuple[str, str] | None:
    """:func:`.units.units_from_size_and_doors` of the drawing: its door
    drawings' and doorway gaps' widths and its walls' thickness measured in
    drawing units (the wall and door layers flattened as drawn)."""
    far_ids = {id(e) for e in far}
    entities = [e for e in msp if roles.get(_layer(e)) in ("walls", "doors") and id(e) not in far_ids]
    strokes, _ = flatten_entities(entities, 1.0, CURVE_SAGITTA, lambda layer: True)
    walls = [s for s in strokes if roles.get(s.layer) == "walls"]
    return units_from_size_and_doors(extent, door_widths(strokes, roles), wall_doorway_gaps(walls), stated,
                                     wall_thickness(walls))


def door_widths(strokes: list, roles: dict) -> list[float]:
    """The width of each door drawing of the door layers' ``strokes``
    (metres as read): the longer side of its minimum rotated rectangle (a
    leaf and its swing, a door line, a door block). The strokes too long
    for a door (:func:`.openings.door_strokes`) are kept here: that bound is
    in metres, and read in the wrong unit every door may exceed it."""
    widths = []
    for item in drawing_items([s for s in strokes if roles.get(s.layer) == "doors"]):
        box = shapely.minimum_rotated_rectangle(item)
        xy = np.asarray(box.exterior.coords if box.geom_type == "Polygon" else box.coords, dtype=float)
        widths.append(float(np.hypot(*np.diff(xy, axis=0).T).max()) if len(xy) > 1 else 0.0)
    return widths


def local_origin(strokes) -> np.ndarray | None:
    """The offset ``(x, y)`` (metres, whole) to subtract from a georeferenced
    plan's coordinates: the lower-left corner of the building geometry's
    bounding box, when all of it lies farther than ``LOCAL_ORIGIN_BEYOND_M``
    from the file's origin; None for a plan drawn near its origin."""
    if not strokes:
        return None
    points = np.concatenate([s.coords for s in strokes])
    lo, hi = points.min(axis=0), points.max(axis=0)
    # The box's point nearest the origin: 0 on an axis the box straddles.
    nearest = np.where(lo > 0, lo, np.where(hi < 0, hi, 0.0))
    if not np.isfinite(nearest).all() or np.hypot(*nearest) <= LOCAL_ORIGIN_BEYOND_M:
        return None
    return np.floor(lo)


def _extent(entities) -> tuple[float, list]:
    """Largest side of the bounding box of ``entities``, drawing units (0 if
    none), leaving out entities with non-finite coordinates and those far
    outside the rest (``DXF_FAR_FACTOR``), which are returned as the second
    item to be left out of the plan."""
    kept, lows, highs = [], [], []
    for e in entities:
        box = _box(e)
        if box is None:
            continue
        a, b = box
        if np.isfinite(a).all() and np.isfinite(b).all():
            kept.append(e)
            lows.append(a)
            highs.append(b)
    if not kept:
        return 0.0, []
    lo, hi = np.array(lows, dtype=float), np.array(highs, dtype=float)
    far = np.zeros(len(kept), dtype=bool)
    if len(kept) >= DXF_FAR_MIN_ENTITIES:
        centres = 0.5 * (lo + hi)
        dist = np.linalg.norm(centres - np.median(centres, axis=0), axis=1)
        # The spread of the centres, or the typical entity's size when most
        # centres coincide (concentric circles).
        reach = max(float(np.percentile(dist, 90)), float(np.median(np.linalg.norm(hi - lo, axis=1))))
        far = dist > DXF_FAR_FACTOR * reach
    near = ~far
    extent = float((hi[near].max(axis=0) - lo[near].min(axis=0)).max())
    return extent, [e for e, f in zip(kept, far) if f]


def _box(entity) -> tuple[tuple[float, float], tuple[float, float]] | None:
    """The ``(x, y)`` corners (low, high) of an entity's bounding box,
    drawing units; None for an entity without extent or a broken one.

    A LINE's box is its end points' (what ezdxf's fast box gives, without
    its per-call set-up: the college floors hold thousands of lines)."""
    if entity.dxftype() == "LINE":
        start, end = entity.dxf.start, entity.dxf.end
        x0, y0, x1, y1 = start.x, start.y, end.x, end.y
        return (min(x0, x1), min(y0, y1)), (max(x0, x1), max(y0, y1))
    try:
        box = bbox.extents([entity], fast=True)
    except Exception:  # noqa: BLE001 - a broken entity (a vertex without a location); flattening names it
        return None
    if not box.has_data:
        return None
    return (box.extmin.x, box.extmin.y), (box.extmax.x, box.extmax.y)


def _layer(entity) -> str:
    return entity.dxf.get("layer", "0")
