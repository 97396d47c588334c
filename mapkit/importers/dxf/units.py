"""Drawing units of a DXF plan: from ``$INSUNITS``, an override, or a guess.

A DXF coordinate is a number in the drawing's units; everything downstream
works in metres. ``$INSUNITS`` is often 0 ("unitless") in real files, and
sometimes wrong, so the extent of the drawing is checked for plausibility.
"""

from __future__ import annotations

import math

from mapkit.errors import MapkitError
from mapkit.units import UNIT_METRES, canonical_units
from mapkit.tolerances import PLAUSIBLE_EXTENT, TYPICAL_EXTENT, ZERO

#: $INSUNITS code -> unit name (codes of the DXF reference; the rest are
#: astronomical or micro units no floor plan uses).
INSUNITS = {1: "in", 2: "ft", 4: "mm", 5: "cm", 6: "m", 7: "km", 10: "yd", 14: "dm", 21: "us-ft"}

#: Units tried, in order, when the file has none (metric CAD first); drawings
#: whose $MEASUREMENT says imperial try inches and feet instead.
_GUESSES = ("m", "mm", "cm")
_GUESSES_IMPERIAL = ("in", "ft")


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
            raise MapkitError(
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


def _likely_units(extent: float, imperial: bool) -> str:
    """The unit that puts an ``extent`` (drawing units) closest to a typical
    building's size, in log scale."""
    guesses = _GUESSES_IMPERIAL if imperial else _GUESSES
    return min(guesses, key=lambda u: abs(math.log10(max(extent * UNIT_METRES[u], ZERO.distance) / TYPICAL_EXTENT)))


def _fmt(metres: float) -> str:
    return f"{metres / 1000:.3g} km" if metres >= 1000 else f"{metres:.3g} m"
