"""Drawing units of a DXF plan: from ``$INSUNITS``, an override, or a guess.

A DXF coordinate is a number in the drawing's units; everything downstream
works in metres. ``$INSUNITS`` is often 0 ("unitless") in real files, and
sometimes wrong, so the extent of the drawing is checked for plausibility.
"""

from __future__ import annotations

import math

import numpy as np

from mapkit.errors import ImplausibleUnitsError, MapkitError
from mapkit.units import UNIT_METRES, canonical_units
from mapkit.tolerances import (DOOR_UNITS_MIN_DOORS, DOOR_WIDTH_PLAUSIBLE, GAP_UNITS_AGREE_SHARE,
                               PLAUSIBLE_EXTENT, TYPICAL_DOOR_WIDTH, TYPICAL_EXTENT, TYPICAL_WALL_THICKNESS, ZERO)

#: $INSUNITS code -> unit name (codes of the DXF reference; the rest are
#: astronomical or micro units no floor plan uses).
INSUNITS = {1: "in", 2: "ft", 4: "mm", 5: "cm", 6: "m", 7: "km", 10: "yd", 14: "dm", 21: "us-ft"}

#: Units tried, in order, when the file has none (metric CAD first); drawings
#: whose $MEASUREMENT says imperial try inches and feet instead.
_GUESSES = ("m", "mm", "cm")
_GUESSES_IMPERIAL = ("in", "ft")

#: Units of the imperial system: a plan read in one of them and too small
#: was probably drawn in another of them (``rescale_hint``).
_IMPERIAL_UNITS = frozenset({"in", "ft", "yd", "us-ft"})


def _plausible(extent_m: float) -> bool:
    lo, hi = PLAUSIBLE_EXTENT
    return lo <= extent_m <= hi


def decide_units(
    insunits: int, override: str | None, extent: float, imperial: bool = False
) -> tuple[str, float, str | None]:
    """Choose the drawing units.

    ``insunits`` is the header code, ``override`` the user's ``--units`` (or
    None), ``extent`` the largest side of the drawing's bounding box in
    drawing units, ``imperial`` whether ``$MEASUREMENT`` is 0 (English).
    Returns ``(unit name, metres per unit, warning or None)``; raises
    MapkitError when stated units (header or override) make the plan no
    building's size.
    """
    if override or insunits in INSUNITS:
        name = canonical_units(override) if override else INSUNITS[insunits]
        factor = UNIT_METRES[name]
        if extent > 0 and not _plausible(extent * factor):
            # Not a building: too large a plan would run out of memory, too
            # small a one holds no free space. Refused before any work.
            lo, hi = PLAUSIBLE_EXTENT
            said = "--units says" if override else "the drawing says its units are"
            likely = _likely_units(extent, imperial)
            raise (MapkitError if override else ImplausibleUnitsError)(
                f"{said} {name} but then the plan is {_fmt(extent * factor)} across, not a building "
                f"({_fmt(lo)} to {_fmt(hi)}); pass the right --units (in {likely} it is "
                f"{_fmt(extent * UNIT_METRES[likely])} across)"
            )
        return name, factor, None
    # No usable units: pick the unit that makes the building a plausible size.
    name = _likely_units(extent, imperial)
    factor = UNIT_METRES[name]
    code = f"$INSUNITS {insunits}" if insunits else "$INSUNITS 0, unitless"
    warning = (
        f"the drawing has no units ({code}); assumed {name} from its extent of "
        f"{extent:.4g} units ({_fmt(extent * factor)}); pass --units to override"
    )
    return name, factor, warning


#: Units a floor plan is drawn in, tried when its doors say its header is wrong.
_DRAWING_UNITS = ("mm", "cm", "dm", "m", "in", "ft")


def units_from_doors(door_widths_m, unit: str, extent_m: float) -> tuple[str, str] | None:
    """The unit the doors say a drawing is in, when its stated or guessed
    ``unit`` makes them no door's width: ``door_widths_m`` the widths of
    its door drawings as read in ``unit`` (metres), ``extent_m`` its
    extent as read. Returns ``(unit, warning)``, or None when the doors
    agree with ``unit``, are too few to tell (``DOOR_UNITS_MIN_DOORS``), or
    no unit gives them a plausible width and the plan a plausible extent."""
    widths = [float(w) for w in door_widths_m if w > 0]
    if len(widths) < DOOR_UNITS_MIN_DOORS:
        return None
    median = float(sorted(widths)[len(widths) // 2])
    lo, hi = DOOR_WIDTH_PLAUSIBLE
    if lo <= median <= hi:
        return None

    def ratio(u: str) -> float:
        return UNIT_METRES[u] / UNIT_METRES[unit]

    best = min(_DRAWING_UNITS, key=lambda u: abs(math.log10(median * ratio(u) / TYPICAL_DOOR_WIDTH)))
    if best == unit or not lo <= median * ratio(best) <= hi or not _plausible(extent_m * ratio(best)):
        return None
    return best, (f"read in {unit}, the drawing's {len(widths)} doors are a median {median:.2f} m wide, no "
                  f"door's width; read in {best} instead (doors {median * ratio(best):.2f} m, the plan "
                  f"{_fmt(extent_m * ratio(best))} across); pass --units to override")


def units_from_evidence(door_widths_m, gap_widths_m, thickness_m: float | None, unit: str,
                        extent_m: float) -> tuple[str, str] | None:
    """The unit a drawing without units (``unit`` only guessed from its
    extent) is drawn in, told by two signs independent of its extent: its
    doors' width (the door drawings when there are ``DOOR_UNITS_MIN_DOORS``
    or more, else its doorway gaps when ``DOOR_UNITS_MIN_DOORS`` or more) and
    its walls' thickness (:func:`.wall_thickness.wall_thickness`, or None),
    all metres as read in ``unit``; ``extent_m`` the plan's extent as read.

    Every standard unit of either system is tried (a header's $MEASUREMENT
    says how it was set up, not how it was drawn: plans in centimetres or
    metres come with it set to inches): of those that make the plan a
    building's size (``PLAUSIBLE_EXTENT``), the one whose extent, doors and
    walls are together closest, in log scale, to ``TYPICAL_EXTENT``,
    ``TYPICAL_DOOR_WIDTH`` and ``TYPICAL_WALL_THICKNESS``: three signs, each
    weak alone (doorway gaps mix jambs and wide openings, a plan may be a
    room or a campus), that together tell centimetres from inches. Returns
    ``(unit, warning naming --units)`` when that is not ``unit``; None when
    it is, or when the doors are too few to tell."""
    doors = [float(w) for w in door_widths_m if w > 0]
    what = f"{len(doors)} door drawings"
    if len(doors) < DOOR_UNITS_MIN_DOORS:
        doors = [float(w) for w in gap_widths_m if w > 0]
        what = f"{len(doors)} doorways (gaps in its walls)"
        if len(doors) < DOOR_UNITS_MIN_DOORS:
            return None
    door = float(np.median(doors))

    def ratio(u: str) -> float:
        return UNIT_METRES[u] / UNIT_METRES[unit]

    def misfit(u: str) -> float:
        return _building_misfit(extent_m, thickness_m, ratio(u)) + abs(math.log10(door * ratio(u) / TYPICAL_DOOR_WIDTH))

    fits = [u for u in _DRAWING_UNITS if _plausible(extent_m * ratio(u))]
    if not fits:
        return None
    best = min(fits, key=misfit)
    if best == unit:
        return None
    walls = "" if thickness_m is None else f", its walls {thickness_m * ratio(best):.2f} m thick"
    return best, (f"the drawing has no units and was read in {unit} from its extent, but its {what} are then a "
                  f"median {door:.2f} m wide; read in {best} instead (doors {door * ratio(best):.2f} m{walls}, the "
                  f"plan {_fmt(extent_m * ratio(best))} across); pass --units to override")


def units_from_size_and_doors(extent: float, door_widths, gap_widths, stated: str,
                              thickness: float | None = None) -> tuple[str, str] | None:
    """The one unit that makes a drawing both a building's size and its
    doors a door's width, when its header's ``stated`` unit makes it no
    building (:class:`~mapkit.errors.ImplausibleUnitsError`): ``extent``
    its largest side, ``door_widths`` the widths of its door drawings and
    ``gap_widths`` of its doorway gaps, all in drawing units. The doors
    judge when any are drawn, else the gaps (``DOOR_UNITS_MIN_DOORS`` or
    more). Returns ``(unit, warning naming --units)``, or None when no unit
    or several fit (a 2 m door is a door in metres and in feet).

    A plan that draws neither (openings left out, walls hatched solid) is
    judged by its walls' ``thickness`` (drawing units,
    :func:`.wall_thickness.wall_thickness`; None: not drawn as pairs of
    lines): of the units of the header's own system (metric or imperial: a
    metric template's mm over a plan drawn in metres) that make it a
    building's size, the one that puts its extent and its walls' thickness
    together closest to ``TYPICAL_EXTENT`` and ``TYPICAL_WALL_THICKNESS``."""
    widths = [float(w) for w in door_widths if w > 0]
    what = f"{len(widths)} door drawing(s)"
    if not widths:
        widths = [float(w) for w in gap_widths if w > 0]
        what = f"{len(widths)} doorways (gaps in its walls)"
        if len(widths) < DOOR_UNITS_MIN_DOORS:
            return _unit_by_size_and_walls(extent, thickness, stated)
    median = float(np.median(widths))
    lo, hi = DOOR_WIDTH_PLAUSIBLE
    fits = [u for u in _DRAWING_UNITS
            if _plausible(extent * UNIT_METRES[u]) and lo <= median * UNIT_METRES[u] <= hi]
    if len(fits) != 1:
        return None
    unit = fits[0]
    return unit, (f"the drawing says its units are {stated} but then the plan is {_fmt(extent * UNIT_METRES[stated])} "
                  f"across; only {unit} makes it a building ({_fmt(extent * UNIT_METRES[unit])} across) and its {what} "
                  f"a door's width (a median {median * UNIT_METRES[unit]:.2f} m): read in {unit}; pass --units to "
                  "override")


def _unit_by_size_and_walls(extent: float, thickness: float | None, stated: str) -> tuple[str, str] | None:
    """:func:`units_from_size_and_doors` of a plan that draws no doors and
    no doorway gaps: the unit its size and walls' ``thickness`` say (see
    there), or None without double-line walls or when no unit of the
    header's system makes it a building."""
    if thickness is None or thickness <= 0:
        return None
    system = _GAP_UNITS["imperial" if stated in _IMPERIAL_UNITS else "metric"]
    fits = [u for u in system if _plausible(extent * UNIT_METRES[u])]
    if not fits:
        return None
    unit = min(fits, key=lambda u: _off_typical(extent * UNIT_METRES[u])
               + abs(math.log10(thickness * UNIT_METRES[u] / TYPICAL_WALL_THICKNESS)))
    return unit, (f"the drawing says its units are {stated} but then the plan is {_fmt(extent * UNIT_METRES[stated])} "
                  f"across; it draws no doors, and {unit} makes it a building ({_fmt(extent * UNIT_METRES[unit])} "
                  f"across) with walls {thickness * UNIT_METRES[unit]:.2f} m thick, closest of the "
                  f"{'imperial' if stated in _IMPERIAL_UNITS else 'metric'} units to a building's: read in {unit}; "
                  "pass --units to override")


#: Units of each system a plan's doorway gaps may tell apart: each a
#: factor of 10 (metric) or 12 (imperial) from the next, more than the
#: spread of real doorways' widths.
_GAP_UNITS = {"metric": ("mm", "cm", "dm", "m"), "imperial": ("in", "ft")}


def _gaps_no_door_fits(gap_widths_m) -> tuple[np.ndarray, float] | None:
    """The positive doorway widths (metres as read) and their median, when
    there are ``DOOR_UNITS_MIN_DOORS`` of them or more and the median is no
    door's width (``DOOR_WIDTH_PLAUSIBLE``); None otherwise."""
    widths = np.asarray([w for w in gap_widths_m if w > 0], dtype=float)
    if len(widths) < DOOR_UNITS_MIN_DOORS:
        return None
    median = float(np.median(widths))
    lo, hi = DOOR_WIDTH_PLAUSIBLE
    if lo <= median <= hi:
        return None
    return widths, median


def units_from_gaps(gap_widths_m, unit: str, extent_m: float, thickness_m: float | None = None,
                    max_wall_thickness: float = 0.0) -> tuple[str, str] | None:
    """The unit the doorway gaps of a plan without door symbols say it is
    in, when its stated or guessed ``unit`` makes them no door's width:
    ``gap_widths_m`` the free widths of its doorways as read in ``unit``
    (metres, :func:`.doorway_gaps.doorway_gaps`), ``extent_m`` its extent
    and ``thickness_m`` its walls' thickness
    (:func:`.wall_thickness.wall_thickness`; None: single wall lines), as
    read. Returns ``(unit, warning)``, or None when the gaps agree with
    ``unit``, are too few (``DOOR_UNITS_MIN_DOORS``), or no unit of the same
    system makes most of them a door's width (``GAP_UNITS_AGREE_SHARE``)
    and the plan closer to a building: the signs independent of the gaps,
    its extent and its walls' thickness, together closer (log scale) to
    ``TYPICAL_EXTENT`` and ``TYPICAL_WALL_THICKNESS`` than as read. A
    header's mm over a plan drawn in cm makes a 120 m building 12 m across,
    nearer a typical building's size, but its walls 3 cm thick, no wall's
    thickness: the walls outweigh the extent there. The thickness counts
    only when both readings make it a wall's (``max_wall_thickness``, the
    ``--max-wall-thickness`` beyond which double lines are no wall): in a
    small plan of single wall lines it measures rooms facing each other, a
    room's width in one of the two readings."""
    gaps = _gaps_no_door_fits(gap_widths_m)
    if gaps is None:
        return None
    widths, median = gaps
    lo, hi = DOOR_WIDTH_PLAUSIBLE
    system = _GAP_UNITS["imperial" if unit in _IMPERIAL_UNITS else "metric"]

    def ratio(u: str) -> float:
        return UNIT_METRES[u] / UNIT_METRES[unit]

    best = min(system, key=lambda u: abs(math.log10(median * ratio(u) / TYPICAL_DOOR_WIDTH)))
    if best == unit or not lo <= median * ratio(best) <= hi or not _plausible(extent_m * ratio(best)):
        return None
    agree = float(np.mean((widths * ratio(best) >= lo) & (widths * ratio(best) <= hi)))
    if thickness_m is not None and thickness_m * max(1.0, ratio(best)) > max_wall_thickness:
        thickness_m = None  # double lines no wall is in one of the readings: rooms, not walls
    if agree < GAP_UNITS_AGREE_SHARE or _building_misfit(extent_m, thickness_m, ratio(best)) >= \
            _building_misfit(extent_m, thickness_m, 1.0):
        return None
    walls = "" if not thickness_m else f", its walls {thickness_m * ratio(best):.2f} m thick"
    return best, (f"read in {unit}, the drawing draws no doors and its {len(widths)} doorways (gaps in its walls) are "
                  f"a median {median:.3g} m wide, no door's width; read in {best} instead (doorways "
                  f"{median * ratio(best):.2f} m{walls}, the plan {_fmt(extent_m * ratio(best))} across); pass --units "
                  f"to override")


def _building_misfit(extent_m: float, thickness_m: float | None, ratio: float) -> float:
    """How far (log10, summed) a plan ``extent_m`` across with walls
    ``thickness_m`` thick (None: not measured, no term), both metres as
    read and multiplied by ``ratio``, is from a typical building's size and
    walls."""
    off = _off_typical(extent_m * ratio)
    if thickness_m is not None and thickness_m > 0:
        off += abs(math.log10(thickness_m * ratio / TYPICAL_WALL_THICKNESS))
    return off


def scale_from_gaps(gap_widths_m) -> tuple[int, float, float] | None:
    """What the doorway gaps of a plan say of a scale no unit gives (a plan
    drawn at a fraction of its size, one traced over a scan in pixels):
    ``(count, median, scale)``, the scale that makes their median
    ``TYPICAL_DOOR_WIDTH`` (two significant digits), from ``gap_widths_m``
    (metres as read); None when they are too few (``DOOR_UNITS_MIN_DOORS``)
    or already a door's width. Only an estimate (real doorways are 0.7 to
    2 m wide): named in a refusal, never applied."""
    gaps = _gaps_no_door_fits(gap_widths_m)
    if gaps is None:
        return None
    widths, median = gaps
    return len(widths), median, float(f"{TYPICAL_DOOR_WIDTH / median:.2g}")


def rescale_hint(width_m: float, depth_m: float, unit: str, insunits: int | None, override: str | None,
                 scale: float, doorways=None) -> str:
    """What to pass for a plan read too small for a building (its walls span
    ``width_m`` x ``depth_m`` metres read in ``unit`` times ``scale``, the
    ``--scale``): the unit as read and where it came from (``override``, the
    ``--units``, or the ``insunits`` header code), then the ``--units`` of
    the same system (metric or imperial) that puts the plan closest to a
    typical building's size, or when none is closer than as read (a gallery
    drawn at 1:10 in metres), a ``--scale``: the one its ``doorways`` (the
    widths of the gaps in its walls, metres as read) say, when they are
    enough and no door's width (:func:`scale_from_gaps`), else a power of
    ten. One clause, e.g. "the walls span only 1.2 x 1.0 m as read in mm (its
    $INSUNITS 4 says mm): if it is drawn in cm, give --units cm (then 12 x 10 m)".
    """
    if override:
        source = f"--units {override}"
    elif insunits in INSUNITS:
        source = f"its $INSUNITS {insunits} says {unit}"
    else:
        source = f"assumed from its extent, $INSUNITS {insunits or 0}"
    read = f"the walls span only {width_m:.1f} x {depth_m:.1f} m as read in {unit} ({source})"
    extent = max(width_m, depth_m, ZERO.distance)
    system = _GUESSES_IMPERIAL if unit in _IMPERIAL_UNITS else _GUESSES
    best = min(system, key=lambda u: _off_typical(extent * UNIT_METRES[u] / UNIT_METRES[unit]))
    ratio = UNIT_METRES[best] / UNIT_METRES[unit]
    if best != unit and _plausible(extent * ratio) and _off_typical(extent * ratio) < _off_typical(extent):
        return (f"{read}: if it is drawn in {best}, give --units {best} "
                f"(then {width_m * ratio:.0f} x {depth_m * ratio:.0f} m)")
    by_gaps = scale_from_gaps(doorways if doorways is not None else [])
    if by_gaps is not None and by_gaps[2] > 1 and _plausible(extent * by_gaps[2]):
        # No unit makes it a building: the scale its doorways say (an
        # estimate, so named rather than applied).
        count, median, times = by_gaps
        return (f"{read} and its {count} doorways (gaps in its walls) are a median {median:.2g} m wide: if they are "
                f"doors about {TYPICAL_DOOR_WIDTH:g} m wide, give --scale {scale * times:.3g} "
                f"(then {width_m * times:.0f} x {depth_m * times:.0f} m)")
    times = 10 ** max(1, round(math.log10(TYPICAL_EXTENT / extent)))
    return (f"{read}: if it is drawn at 1/{times} of its size, give --scale {scale * times:g} "
            f"(then {width_m * times:.0f} x {depth_m * times:.0f} m)")


def _off_typical(metres: float) -> float:
    """How far (log10) an extent of ``metres`` is from a typical building's."""
    return abs(math.log10(max(metres, ZERO.distance) / TYPICAL_EXTENT))


def _likely_units(extent: float, imperial: bool) -> str:
    """The unit that puts an ``extent`` (drawing units) closest to a typical
    building's size, in log scale."""
    guesses = _GUESSES_IMPERIAL if imperial else _GUESSES
    return min(guesses, key=lambda u: abs(math.log10(max(extent * UNIT_METRES[u], ZERO.distance) / TYPICAL_EXTENT)))


def _fmt(metres: float) -> str:
    return f"{metres / 1000:.3g} km" if metres >= 1000 else f"{metres:.3g} m"
