"""The ``zind`` fuzz family: a ZInD-shaped floor (three rooms, doors, a
window, an opening, an island) with values made NaN, huge, tiny or of the
wrong type, keys and items deleted, lists emptied or repeated, values
nested thousands deep, the text cut short; or floors of random rooms; then
``mapkit build`` (mostly) or ``preview``, and a built map read by
``FOLLOW_UPS``.
"""

from __future__ import annotations

import json
import math
import random
from functools import lru_cache

from .cases import Case, follow_ups
from .mutations import mutate_json_doc, random_ring

#: Metres per plan coordinate of the ZInD-shaped floor the cases start from.
ZIND_SCALE = 0.5


def _zind_local(world, centre, unit: float, rotation_deg: float) -> list:
    """World points (n, 2) in metres -> a panorama's own frame (the inverse of
    ``mapkit.importers.zind.annotations._plan_to_world``)."""
    a = math.radians(rotation_deg)
    c, s = math.cos(a), math.sin(a)
    out = []
    for x, y in world:
        px, py = (x - centre[0]) / ZIND_SCALE, (-(y - centre[1])) / ZIND_SCALE
        lx, ly = px * c + py * s, -px * s + py * c  # (plan - shift) @ rot.T
        out.append([round(lx / (unit / ZIND_SCALE), 6), round(ly / (unit / ZIND_SCALE), 6)])
    return out


def _zind_pano(centre, outline, ceiling_m, rotation_deg=0.0, unit=1.25, gaps=None, internal=(), primary=True):
    """A panorama annotating the room ``outline`` (world metres) from ``centre``:
    ZInD's layout in the panorama's frame, heights in its units."""
    gaps = gaps or {}
    layout = {"vertices": _zind_local(outline, centre, unit, rotation_deg), "internal":
              [_zind_local(v, centre, unit, rotation_deg) for v in internal]}
    for kind in ("doors", "windows", "openings"):
        layout[kind] = [p for a, b, lo, hi in gaps.get(kind, ())
                        for p in (*_zind_local([a, b], centre, unit, rotation_deg), [lo / unit - 1, hi / unit - 1])]
    return {"label": "room", "is_primary": primary, "is_inside": True, "is_ceiling_flat": True,
            "ceiling_height": ceiling_m / unit, "camera_height": 1.0, "floor_number": 1,
            "image_path": "panos/none.jpg", "layout_raw": layout, "layout_complete": layout,
            "floor_plan_transformation": {"translation": [centre[0] / ZIND_SCALE, -centre[1] / ZIND_SCALE],
                                          "rotation": rotation_deg, "scale": unit / ZIND_SCALE}}


@lru_cache(maxsize=None)
def base_zind() -> dict:
    """A ZInD-shaped floor of three rooms (one of two partial rooms, one with
    a kitchen island, panoramas turned), doors seen from both sides, a
    window, an opening; ``mapkit build`` makes a map of it."""
    a, b, c = [(0, 0), (5, 0), (5, 4), (0, 4)], [(5.2, 0), (9.2, 0), (9.2, 4), (5.2, 4)], \
        [(0, 4.2), (4, 4.2), (4, 7), (0, 7)]
    door_ab, door_ba = ((5.0, 1.0), (5.0, 2.0), 0.0, 2.0), ((5.2, 2.0), (5.2, 1.0), 0.0, 2.0)
    door_ac, door_ca = ((1.0, 4.0), (2.0, 4.0), 0.0, 2.1), ((2.0, 4.2), (1.0, 4.2), 0.0, 2.1)
    floor = {
        "complete_room_01": {
            "partial_room_01": {"pano_1": _zind_pano((2.5, 2.0), a, 2.5, 30.0, gaps={
                "doors": [door_ab, door_ac], "windows": [((0.0, 1.0), (0.0, 2.5), 0.9, 2.1)]})},
            "partial_room_02": {"pano_2": _zind_pano((1.0, 1.0), a, 2.52, -75.0, 1.2, primary=True),
                                "pano_3": _zind_pano((3.5, 3.0), a, 2.48, 190.0, 1.3, primary=False)}},
        "complete_room_02": {"partial_room_03": {"pano_4": _zind_pano(
            (7.2, 2.0), b, 2.4, 0.0, gaps={"doors": [door_ba], "openings": [((6.0, 0.0), (8.0, 0.0), 0.0, 2.45)]},
            internal=[[(7.0, 2.5), (8.0, 2.5), (8.0, 3.2), (7.0, 3.2)]])}},
        "complete_room_03": {"partial_room_04": {"pano_5": _zind_pano((2.0, 5.6), c, 2.6, 120.0,
                                                                      gaps={"doors": [door_ca]})}},
    }
    return {"scale_meters_per_coordinate": {"floor_01": ZIND_SCALE}, "merger": {"floor_01": floor},
            "redraw": {"floor_01": {}}}


def _random_zind(rng: random.Random) -> tuple[dict, str]:
    """A ZInD-shaped floor of random rooms (outlines that may cross, overlap,
    be huge or tiny) and random gaps on them."""
    size = rng.choice((0.01, 1.0, 5.0, 50.0, 1e4))
    floor = {}
    for k in range(rng.randint(1, 6)):
        centre = (rng.uniform(-2, 2) * size, rng.uniform(-2, 2) * size)
        ring = random_ring(rng, centre, size)
        gaps = {}
        for kind in ("doors", "windows", "openings"):
            gaps[kind] = []
            for _ in range(rng.randint(0, 3)):
                i = rng.randrange(len(ring))
                a, b = ring[i], ring[(i + 1) % len(ring)]
                t0, t1 = sorted((rng.random(), rng.random()))
                gaps[kind].append(((a[0] + t0 * (b[0] - a[0]), a[1] + t0 * (b[1] - a[1])),
                                   (a[0] + t1 * (b[0] - a[0]), a[1] + t1 * (b[1] - a[1])),
                                   rng.uniform(-1, 2), rng.uniform(0, 4)))
        internal = [random_ring(rng, centre, size / 4)] if rng.random() < 0.3 else []
        floor[f"complete_room_{k}"] = {"partial_room_0": {"pano_0": _zind_pano(
            centre, ring, rng.uniform(0.5, 4.0), rng.uniform(-360, 360), rng.uniform(0.5, 2), gaps, internal)}}
    doc = {"scale_meters_per_coordinate": {"floor_01": ZIND_SCALE}, "merger": {"floor_01": floor},
           "redraw": {"floor_01": {}}}
    return doc, f"random: {len(floor)} rooms, size {size:g}"


def zind_case(rng: random.Random, name: str = "zind") -> Case:
    """A damaged or random ZInD floor and ``mapkit build`` (or ``preview``) on it."""
    if rng.random() < 0.2:
        doc, note = _random_zind(rng)
        text = json.dumps(doc)
        if rng.random() < 0.3:
            text, more = mutate_json_doc(doc, rng)
            note += f"; {more}"
    else:
        text, note = mutate_json_doc(base_zind(), rng)
    cmd = rng.choices(("build", "preview"), weights=(9, 1))[0]
    argv = [cmd, "zind_data.json", "-o", "out.lmap" if cmd == "build" else "out.png"]
    return Case("zind", name, {"zind_data.json": text.encode()}, ["mapkit", *argv], note, **follow_ups(argv))
