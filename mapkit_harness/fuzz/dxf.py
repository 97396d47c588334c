"""The ``dxf`` fuzz family: ``maps/flat.dxf`` and the real plans of
``tests/data`` with group code / value lines deleted, swapped, duplicated,
numbers replaced by huge, NaN, infinite or garbage values, group codes
damaged, the file cut short; then ``mapkit build`` (mostly), ``preview`` or
``layers``, and a built map read by ``FOLLOW_UPS``.
"""

from __future__ import annotations

import random

from .cases import DATA, ROOT, Case, follow_ups, source_bytes
from .mutations import mutate_lines

DXF_SOURCES = {"flat": ROOT / "maps" / "flat.dxf", "thehouse": DATA / "thehouse.dxf",
               "barcelona": DATA / "barcelona-pavilion.dxf", "bulge_apse": DATA / "dxf" / "bulge_apse.dxf",
               "nested_blocks": DATA / "dxf" / "nested_blocks.dxf"}

#: DXF group codes of coordinates and other floats (points, heights, scales, bulges, angles).
DXF_FLOAT_CODES = {str(c) for c in (*range(10, 60), *range(110, 150), *range(210, 240), *range(1010, 1060))}
#: ... and counts, flags (MINSERT's rows and columns, polyline vertex counts).
DXF_INT_CODES = {str(c) for c in (*range(60, 80), 90, 91)}


def _dxf_entities_span(lines: list[str]) -> range:
    """Line indices of the ENTITIES and BLOCKS sections (where damage matters)."""
    start = next((i for i, s in enumerate(lines) if s.strip() in ("BLOCKS", "ENTITIES")), 0)
    return range(start, len(lines))


def _dxf_value_lines(lines: list[str]) -> list[int]:
    span = _dxf_entities_span(lines)
    return [i + 1 for i in span[::1] if i + 1 < len(lines) and (i - span.start) % 2 == 0 and
            lines[i].strip() in DXF_FLOAT_CODES | DXF_INT_CODES]


def _dxf_code_lines(lines: list[str]) -> list[int]:
    span = _dxf_entities_span(lines)
    return [i for i in span if (i - span.start) % 2 == 0]


def dxf_case(rng: random.Random, name: str = "dxf", sources=None) -> Case:
    """A damaged DXF plan and a mapkit command on it."""
    src = rng.choice(sources or sorted(DXF_SOURCES))
    text = source_bytes(DXF_SOURCES[src]).decode("latin-1")
    bad, note = mutate_lines(text, rng, numbers_at=_dxf_value_lines, codes_at=_dxf_code_lines)
    files = {"plan.dxf": bad.encode("latin-1")}
    cmd = rng.choices(("build", "preview", "layers"), weights=(8, 1, 1))[0]
    argv = {"build": ["build", "plan.dxf", "-o", "out.lmap"], "preview": ["preview", "plan.dxf", "-o", "out.png"],
            "layers": ["layers", "plan.dxf"]}[cmd]
    if src == "thehouse" and cmd != "layers":
        argv += ["--walls", "s001-*", "--units", "m"]
    return Case("dxf", name, files, ["mapkit", *argv], f"{src}: {note}", **follow_ups(argv))
