"""Fuzz campaign: damaged and hostile inputs for every entry point, each
case under a time and memory bound.

    python tools/fuzz.py                                  # small campaign
    python tools/fuzz.py --dxf 2000 --mesh 500 --zind 500 --segments 500 --lmap 500 --matcher 2000 --save /tmp/fuzz-failures

Families (each case is drawn from ``random.Random(f"{family}:{seed}:{i}")``,
so a run is reproducible and any case can be drawn again by its number):

- ``dxf``: ``maps/flat.dxf`` and the real plans of ``tests/data`` with group
  code / value lines deleted, swapped, duplicated, numbers replaced by huge,
  NaN, infinite or garbage values, group codes damaged, the file cut short;
  then ``mapkit build`` (mostly), ``preview`` or ``layers``.
- ``mesh``: every mesh format (OBJ, OFF, ASCII and binary PLY and STL, GLB)
  with the same kind of damage to its text lines or its bytes (flipped bits,
  overwritten floats, counts, truncation); then ``mapkit build``.
- ``zind``: a ZInD-shaped floor (three rooms, doors, a window, an opening,
  an island) with values made NaN, huge, tiny or of the wrong type, keys
  and items deleted, lists emptied or repeated, values nested thousands
  deep, the text cut short; or floors of random rooms; then ``mapkit
  build`` (mostly) or ``preview``.
- ``segments``: segments files, CSV (the example map's segments) with
  cells damaged, removed or added, lines or bytes damaged, and JSON (two
  rooms with an outline and walls) damaged as ZInD's; or random segments;
  then ``mapkit build``.
- ``lmap``: ``maps/flat.lmap`` with flipped bits, overwritten bytes, cuts
  and appended bytes, or its chunks re-encoded with valid checksums around
  a damaged payload; then ``mapkit info``, ``view --html`` and ``export``,
  and ``mapkit query``, ``info --json`` or ``matcher localize``.
- ``matcher``: random values for every input of the matcher: lines files and
  arrays of odd shapes and dtypes, camera files (ours, OpenCV's, ROS's),
  priors, ``dt``, ``dyaw``, budgets, images of odd sizes and dtypes, and the
  JSON Lines frame files of ``matcher track``.

A map the build families' ``mapkit build`` writes is then read by the
commands that read maps (``FOLLOW_UPS``: ``mapkit info``, ``info --json``,
``view --html``, ``export``): damage that passes the importer must not trip
them either.

Each case must end in a clean one-line error (exit 2 on the command line, an
``InputError`` through the Python API), a falsy result with its reason (exit
1), or a valid result. Anything else is a failure: a bug (an internal error,
exit 3; an exception escaping; any other exception through the API, even a
one-line ``ValueError``; a crash; an error message of more than one line) or
a run past the bound (killed after ``--bound-s`` seconds, or out of the
``--mem-gb`` address-space limit). Every case runs in a forked child;
``--save DIR`` writes each failing case as a folder (its input files and
``case.json`` with the commands), and ``--replay DIR`` runs such a folder
again.
"""

from __future__ import annotations

import argparse
import contextlib
import io
import json
import math
import os
import random
import resource
import signal
import struct
import sys
import time
import traceback
from dataclasses import dataclass, field
from functools import lru_cache
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
DATA = ROOT / "tests" / "data"
FAMILIES = ("dxf", "mesh", "zind", "segments", "lmap", "matcher")
#: The example map in a case's command; ``{ROOT}`` is the checkout, so saved cases run from any clone.
FLAT_LMAP = "{ROOT}/maps/flat.lmap"

#: Outcomes; the first three are what a case may end in.
ERROR, VALID, FALSY, BUG, OVER = "clean error", "valid", "falsy", "bug", "over bound"

#: What reads a map a case's command wrote (``out.lmap``), run in turn while each ends valid.
FOLLOW_UPS = (["mapkit", "info", "out.lmap"], ["mapkit", "info", "out.lmap", "--json"],
              ["mapkit", "view", "out.lmap", "--html", "out.html"],
              ["mapkit", "export", "out.lmap", "--geojson", "out.geojson"])


@dataclass
class Case:
    """One input and the commands run on it: ``files`` (name -> bytes) are
    written into a fresh folder; ``call`` is ``["mapkit", *argv]``,
    ``["matcher", *argv]`` or ``["api", function, {arguments}]`` with file
    names of that folder wherever a path belongs; ``then``: commands of the
    same form run after it, in turn, while each ends valid (those that read
    what the one before wrote, or the same input another way);
    ``then_valid``: they read what ``call`` wrote (a map ``mapkit build``
    wrote), so any other end of theirs, even a clean error, is a bug."""

    family: str
    name: str
    files: dict[str, bytes]
    call: list
    note: str = ""
    then: list = field(default_factory=list)
    then_valid: bool = False


@dataclass
class Outcome:
    kind: str
    detail: str = ""
    seconds: float = 0.0
    case: Case | None = field(default=None, repr=False)


# ---- mutations of text and bytes ---------------------------------------------

#: Values a damaged number becomes.
BAD_NUMBERS = ("nan", "NaN", "inf", "-inf", "1e308", "-1e308", "1e30", "4.14e16", "999999999", "-999999999",
               "0", "-0", "1e-320", "abc", "", " ", "12.5.3", "0x10", "1e", "--1", "\x00", "9" * 400)
#: Values a damaged group code becomes.
BAD_CODES = ("0", "8", "10", "2", "70", "999", "-1", "1071", "abc", "", "  10", "1e3")


def _is_number(s: str) -> bool:
    try:
        float(s)
        return True
    except ValueError:
        return False


def mutate_lines(text: str, rng: random.Random, numbers_at=None, codes_at=None) -> tuple[str, str]:
    """``text`` with 1-3 line-level mutations; returns it and what was done.
    ``numbers_at``/``codes_at``: candidate line indices for number and group
    code damage (default: every line that parses as a number)."""
    lines = text.split("\n")
    done = []
    wanted, tries = rng.choice((1, 1, 2, 3)), 0
    while len(done) < wanted and tries < 10:
        tries += 1
        n = len(lines)
        if n < 2:
            break
        op = rng.choice(("number", "number", "number", "code", "delete", "swap", "duplicate", "truncate", "scale"))
        nums = numbers_at(lines) if numbers_at else [i for i, s in enumerate(lines) if _is_number(s.strip())]
        if op in ("number", "scale") and nums:
            i = rng.choice(nums)
            if op == "number":
                lines[i] = rng.choice(BAD_NUMBERS)
            else:
                with contextlib.suppress(ValueError, OverflowError):
                    lines[i] = repr(float(lines[i]) * 10.0 ** rng.randint(2, 12))
            done.append(f"{op}@{i}")
        elif op == "code" and codes_at:
            cands = codes_at(lines)
            if cands:
                i = rng.choice(cands)
                lines[i] = rng.choice(BAD_CODES)
                done.append(f"code@{i}")
        elif op == "delete":
            i, k = rng.randrange(n), rng.randint(1, 4)
            del lines[i:i + k]
            done.append(f"delete@{i}+{k}")
        elif op == "swap":
            i, j = rng.randrange(n), rng.randrange(n)
            lines[i], lines[j] = lines[j], lines[i]
            done.append(f"swap@{i},{j}")
        elif op == "duplicate":
            i, k = rng.randrange(n), rng.randint(2, 40)
            lines[i:i] = lines[i:i + k] * rng.randint(1, 20)
            done.append(f"duplicate@{i}+{k}")
        elif op == "truncate":
            i = rng.randrange(n)
            lines = lines[:i] + ([lines[i][:rng.randrange(len(lines[i]) + 1)]] if rng.random() < 0.5 else [])
            done.append(f"truncate@{i}")
    return "\n".join(lines), " ".join(done)


#: Byte patterns that overwrite binary numbers: float32/float64 NaN, inf, huge, and huge counts.
BAD_BYTES = (struct.pack("<f", math.nan), struct.pack("<f", math.inf), struct.pack("<f", 3e38),
             struct.pack("<d", math.nan), struct.pack("<d", 1e300), struct.pack("<I", 0xFFFFFFFF),
             struct.pack("<I", 0x7FFFFFFF), struct.pack("<I", 1_000_000), b"\x00" * 4, b"\xff" * 8)


def mutate_bytes(blob: bytes, rng: random.Random) -> tuple[bytes, str]:
    """``blob`` with 1-3 byte-level mutations; returns it and what was done."""
    b = bytearray(blob)
    done = []
    for _ in range(rng.choice((1, 1, 2, 3))):
        op = rng.choice(("flip", "flip", "overwrite", "overwrite", "truncate", "append", "insert", "delete", "empty"))
        n = len(b)
        if op == "empty" or n == 0:
            b = bytearray()
            done.append("empty")
            break
        i = rng.randrange(n)
        if op == "flip":
            for _ in range(rng.randint(1, 8)):
                j = rng.randrange(n)
                b[j] ^= 1 << rng.randrange(8)
            done.append(f"flip@{i}")
        elif op == "overwrite":
            pat = rng.choice(BAD_BYTES) if rng.random() < 0.7 else bytes(rng.randrange(256) for _ in range(8))
            b[i:i + len(pat)] = pat
            done.append(f"overwrite@{i}")
        elif op == "truncate":
            del b[i:]
            done.append(f"truncate@{i}")
        elif op == "append":
            b += bytes(rng.randrange(256) for _ in range(rng.randint(1, 64)))
            done.append("append")
        elif op == "insert":
            b[i:i] = bytes(rng.randrange(256) for _ in range(rng.randint(1, 16)))
            done.append(f"insert@{i}")
        else:
            del b[i:i + rng.randint(1, 16)]
            done.append(f"delete@{i}")
    return bytes(b), " ".join(done)


# ---- DXF -----------------------------------------------------------------------

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


@lru_cache(maxsize=None)
def _source(path: Path) -> bytes:
    return path.read_bytes()


def dxf_case(rng: random.Random, name: str = "dxf", sources=None) -> Case:
    """A damaged DXF plan and a mapkit command on it."""
    src = rng.choice(sources or sorted(DXF_SOURCES))
    text = _source(DXF_SOURCES[src]).decode("latin-1")
    bad, note = mutate_lines(text, rng, numbers_at=_dxf_value_lines, codes_at=_dxf_code_lines)
    files = {"plan.dxf": bad.encode("latin-1")}
    cmd = rng.choices(("build", "preview", "layers"), weights=(8, 1, 1))[0]
    argv = {"build": ["build", "plan.dxf", "-o", "out.lmap"], "preview": ["preview", "plan.dxf", "-o", "out.png"],
            "layers": ["layers", "plan.dxf"]}[cmd]
    if src == "thehouse" and cmd != "layers":
        argv += ["--walls", "s001-*", "--units", "m"]
    return Case("dxf", name, files, ["mapkit", *argv], f"{src}: {note}", **_follow_ups(argv))


def _follow_ups(argv: list) -> dict:
    """``then`` and ``then_valid`` of a case: the commands that read the map
    ``argv`` writes, if it builds one."""
    return {"then": [list(c) for c in FOLLOW_UPS] if argv[0] == "build" else [], "then_valid": True}


# ---- meshes --------------------------------------------------------------------

@lru_cache(maxsize=None)
def mesh_sources() -> dict[str, bytes]:
    """Every mesh format, from the committed meshes (hospital.stl exported
    to the formats not committed)."""
    import trimesh

    out = {"hospital.stl": _source(DATA / "hospital.stl"), "simple_room.glb": _source(DATA / "simple_room.glb")}
    for p in sorted((DATA / "mesh").glob("*.obj")):
        out[p.name] = _source(p)
    hospital = trimesh.load(DATA / "hospital.stl", force="mesh")
    out["hospital.obj"] = trimesh.exchange.obj.export_obj(hospital).encode()
    out["hospital.off"] = trimesh.exchange.off.export_off(hospital).encode()
    out["hospital_ascii.ply"] = trimesh.exchange.ply.export_ply(hospital, encoding="ascii")
    out["hospital_binary.ply"] = trimesh.exchange.ply.export_ply(hospital, encoding="binary")
    out["hospital_ascii.stl"] = trimesh.exchange.stl.export_stl_ascii(hospital).encode()
    return out


def _is_text_mesh(name: str, blob: bytes) -> bool:
    return name.endswith((".obj", ".off")) or "ascii" in name


def mesh_case(rng: random.Random, name: str = "mesh") -> Case:
    """A damaged mesh of some format and ``mapkit build`` on it."""
    sources = mesh_sources()
    src = rng.choice(sorted(sources))
    blob = sources[src]
    if _is_text_mesh(src, blob) and rng.random() < 0.7:
        text, note = mutate_lines(blob.decode("latin-1"), rng)
        blob = text.encode("latin-1")
    else:
        blob, note = mutate_bytes(blob, rng)
    ext = "." + src.rsplit(".", 1)[1]
    return Case("mesh", name, {"model" + ext: blob}, ["mapkit", "build", "model" + ext, "-o", "out.lmap"],
                f"{src}: {note}", **_follow_ups(["build"]))


# ---- JSON documents ------------------------------------------------------------

#: Values any value of a JSON document may become: NaN, infinities, huge and
#: tiny numbers (10**400 overflows a float), wrong types.
HOSTILE_JSON_VALUES = (math.nan, math.inf, -math.inf, 1e308, -1e308, 1e30, -1e30, 0, -1, 1e-320, 2 ** 70,
                       10 ** 400, "x", "", "1.5", None, True, False, [], {}, [1, 2], [[1, 2]], [[[1, 2]]],
                       {"x": 1})


def _json_paths(doc) -> list[list]:
    """Every path (keys and indices) into ``doc``, the first 20 items of each list."""
    paths = []

    def walk(node, path):
        items = node.items() if isinstance(node, dict) else enumerate(node[:20]) if isinstance(node, list) else ()
        for k, v in items:
            paths.append(path + [k])
            walk(v, path + [k])

    walk(doc, [])
    return paths


def mutate_json_doc(doc, rng: random.Random) -> tuple[str, str]:
    """``doc`` with 1-3 mutations at random places (a value made hostile or
    scaled, a key or item deleted, a list emptied or repeated, a value
    nested thousands deep), as JSON text, sometimes then cut short or with
    lines deleted, swapped or duplicated; returns it and what was done."""
    doc = json.loads(json.dumps(doc))
    done, nests = [], {}
    for _ in range(rng.choice((1, 1, 2, 3))):
        paths = _json_paths(doc)
        if not paths:
            break
        path = rng.choice(paths)
        parent = doc
        for k in path[:-1]:
            parent = parent[k]
        key, value = path[-1], parent[path[-1]]
        op = rng.choice(("value", "value", "value", "scale", "delete", "empty", "repeat", "nest"))
        if op == "scale" and isinstance(value, (int, float)) and not isinstance(value, bool):
            parent[key] = value * rng.choice((-1, 1e3, 1e9, 1e-9, 1e300))
        elif op == "delete":
            del parent[key]
        elif op == "empty" and isinstance(value, (list, dict)):
            parent[key] = type(value)()
        elif op == "repeat" and isinstance(value, list):
            parent[key] = value * rng.choice((2, 50, 600))
        elif op == "nest":  # written into the text below: json.dumps would recurse too deep
            marker = f"@nest{len(nests)}@"
            nests[marker] = rng.choice((3, 50, 5000, 100_000))
            parent[key] = marker
        else:
            op = "value"
            parent[key] = rng.choice(HOSTILE_JSON_VALUES)
        done.append(f"{op}@{'/'.join(map(str, path))}")
    text = json.dumps(doc, indent=rng.choice((None, 1)))
    for marker, depth in nests.items():
        text = text.replace(json.dumps(marker), "[" * depth + "1" + "]" * depth)
    r = rng.random()
    if r < 0.1:
        cut = rng.randrange(len(text) + 1)
        text = text[:cut]
        done.append(f"truncate@{cut}")
    elif r < 0.2:
        text, note = mutate_lines(text, rng)
        done.append(note)
    return text, " ".join(done)


def _random_ring(rng: random.Random, centre: tuple[float, float], size: float) -> list[list[float]]:
    """3-30 points around ``centre`` at random angles and radii (often crossing itself)."""
    n = rng.randint(3, 30)
    angles = sorted(rng.uniform(0, 2 * math.pi) for _ in range(n)) if rng.random() < 0.7 else \
        [rng.uniform(0, 2 * math.pi) for _ in range(n)]
    return [[round(centre[0] + rng.uniform(0.1, 1) * size * math.cos(a), 4),
             round(centre[1] + rng.uniform(0.1, 1) * size * math.sin(a), 4)] for a in angles]


# ---- ZInD annotations ----------------------------------------------------------

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
        ring = _random_ring(rng, centre, size)
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
        internal = [_random_ring(rng, centre, size / 4)] if rng.random() < 0.3 else []
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
    return Case("zind", name, {"zind_data.json": text.encode()}, ["mapkit", *argv], note, **_follow_ups(argv))


# ---- segments files ------------------------------------------------------------

def _box_rows(x0: float, y0: float, w: float, d: float, h: float) -> list[list[float]]:
    """A w x d room h high at (x0, y0): 4 floor, 4 ceiling and 4 vertical segments."""
    c = [(x0, y0), (x0 + w, y0), (x0 + w, y0 + d), (x0, y0 + d)]
    rows = [[*c[i], z, *c[(i + 1) % 4], z] for z in (0.0, h) for i in range(4)]
    return rows + [[x, y, 0.0, x, y, h] for x, y in c]


@lru_cache(maxsize=None)
def base_segments() -> dict:
    """A segments JSON file of two rooms with an outline, walls, units and
    rows of both forms (lists and {"from", "to", "kind"})."""
    rows = _box_rows(0, 0, 4, 3, 2.5) + _box_rows(4.2, 0, 3, 3, 2.5)
    rows[-4:] = [{"from": r[:3], "to": r[3:], "kind": "vertical"} for r in rows[-4:]]
    rows.append({"from": [4.0, 1.0, 2.0], "to": [4.0, 2.0, 2.0], "kind": "lintel"})
    return {"segments": rows, "outline": [[0, 0], [7.2, 0], [7.2, 3], [0, 3]],
            "walls": [[[4.0, 0], [4.2, 0], [4.2, 1.0], [4.0, 1.0]], [[4.0, 2.0], [4.2, 2.0], [4.2, 3], [4.0, 3]]],
            "units": "m"}


@lru_cache(maxsize=None)
def base_segments_csv() -> str:
    """The example map's segments with their kinds, a CSV with a header row."""
    from linemap.lmap import KIND_NAMES, load_map

    m = load_map(ROOT / "maps" / "flat.lmap")
    rows = ["x1,y1,z1,x2,y2,z2,kind"] + [",".join(f"{v:.4f}" for v in s.ravel()) + f",{KIND_NAMES[k]}"
                                          for s, k in zip(m.segments, m.kinds)]
    return "\n".join(rows) + "\n"


#: What a damaged CSV cell becomes.
BAD_CELLS = BAD_NUMBERS + ("wall", "FLOOR", " floor ", "vertical,", '"', '"1,2"', "\ufeff", "é")


def _mutate_csv(text: str, rng: random.Random) -> tuple[str, str]:
    """A CSV with 1-3 cells damaged, removed or added; then sometimes line damage."""
    rows = text.split("\n")
    done = []
    for _ in range(rng.choice((1, 1, 2, 3))):
        i = rng.randrange(len(rows))
        cells = rows[i].split(",")
        j = rng.randrange(len(cells))
        op = rng.choice(("cell", "cell", "cell", "drop", "add", "scale"))
        if op == "cell":
            cells[j] = rng.choice(BAD_CELLS)
        elif op == "drop":
            del cells[j]
        elif op == "add":
            cells.insert(j, rng.choice(BAD_CELLS + ("1.0", "floor")))
        else:
            with contextlib.suppress(ValueError, OverflowError):
                cells[j] = repr(float(cells[j]) * 10.0 ** rng.randint(2, 300))
        rows[i] = ",".join(cells)
        done.append(f"{op}@{i},{j}")
    text = "\n".join(rows)
    if rng.random() < 0.3:
        text, note = mutate_lines(text, rng)
        done.append(note)
    return text, " ".join(done)


def _random_segment_rows(rng: random.Random) -> tuple[list, str]:
    """1-150 segments at random, some on a few levels, within a random size
    (up to a floor 30 m across, or 100 km: refused by its size; a floor of
    100 m of random segments builds as slowly as a building that large)."""
    size = rng.choice((0.01, 1.0, 10.0, 30.0, 1e5))
    levels = [0.0, rng.uniform(0.5, 4) * min(size, 10)]
    rows = []
    for _ in range(rng.randint(1, 150)):
        p, q = [rng.uniform(0, size) for _ in range(2)], [rng.uniform(0, size) for _ in range(2)]
        r = rng.random()
        if r < 0.4:
            z = rng.choice(levels)
            rows.append([*p, z, *q, z])
        elif r < 0.7:
            rows.append([*p, levels[0], *p, levels[1]])
        else:
            rows.append([*p, rng.uniform(0, size), *q, rng.uniform(0, size)])
    return [[round(v, 4) for v in row] for row in rows], f"random: {len(rows)} segments, size {size:g}"


def segments_case(rng: random.Random, name: str = "segments") -> Case:
    """A damaged or random segments file (CSV or JSON) and ``mapkit build`` on it."""
    form = rng.choice(("csv", "json", "json"))
    if form == "csv":
        if rng.random() < 0.2:
            rows, note = _random_segment_rows(rng)
            text = "\n".join(",".join(map(str, r)) for r in rows)
        else:
            text, note = base_segments_csv(), "flat.csv"
        if rng.random() < 0.15:
            blob, more = mutate_bytes(text.encode(), rng)
        else:
            text, more = _mutate_csv(text, rng)
            blob = text.encode()
        note += f": {more}"
    else:
        if rng.random() < 0.2:
            rows, note = _random_segment_rows(rng)
            doc = {"segments": rows}
            if rng.random() < 0.5:
                doc["outline"] = _random_ring(rng, (rng.uniform(0, 50), rng.uniform(0, 50)), rng.uniform(0.1, 100))
        else:
            doc, note = base_segments(), "two rooms"
        text, more = mutate_json_doc(doc, rng) if doc is base_segments() or rng.random() < 0.5 else \
            (json.dumps(doc), "")
        blob, note = text.encode(), f"{note}: {more}"
    fname = f"segments.{form}"
    argv = ["build", fname, "-o", "out.lmap"]
    if rng.random() < 0.1:
        argv += ["--units", rng.choice(("mm", "cm", "ft", "in", "km"))]
    return Case("segments", name, {fname: blob}, ["mapkit", *argv], note, **_follow_ups(argv))


# ---- .lmap ---------------------------------------------------------------------

def _lmap_chunks(blob: bytes) -> list[list]:
    """[tag, codec, payload] of each chunk of a valid file (payload inflated)."""
    from linemap.lmap import read_chunks

    return read_chunks(blob)


def _lmap_encode(chunks) -> bytes:
    """A file of ``chunks`` with valid checksums."""
    from linemap.lmap import write_chunks

    return write_chunks(chunks)


def _mutate_meta(payload: bytes, rng: random.Random) -> tuple[bytes, str]:
    """META's JSON with one value replaced by something hostile."""
    meta = json.loads(payload)
    paths = []

    def walk(node, path):
        if isinstance(node, dict):
            for k, v in node.items():
                paths.append(path + [k])
                walk(v, path + [k])
        elif isinstance(node, list):
            for i, v in enumerate(node[:20]):
                paths.append(path + [i])
                walk(v, path + [i])

    walk(meta, [])
    path = rng.choice(paths)
    parent = meta
    for k in path[:-1]:
        parent = parent[k]
    value = rng.choice((math.nan, math.inf, -1, 0, 1e308, -1e308, "x", None, [], {}, True, [[[[1]]]], 2 ** 70))
    if rng.random() < 0.2:
        del parent[path[-1]]
        return json.dumps(meta).encode(), f"META del {path}"
    parent[path[-1]] = value
    return json.dumps(meta).encode(), f"META {path}={value!r}"


def lmap_case(rng: random.Random, name: str = "lmap") -> Case:
    """A damaged or crafted map and a command that loads it."""
    blob = _source(ROOT / "maps" / "flat.lmap")
    if rng.random() < 0.5:
        bad, note = mutate_bytes(blob, rng)
    else:  # valid checksums around a damaged payload: what a hostile sender makes
        chunks = _lmap_chunks(blob)
        k = rng.randrange(len(chunks))
        tag = chunks[k][0]
        if tag.startswith(b"META") and rng.random() < 0.7:
            chunks[k][2], note = _mutate_meta(chunks[k][2], rng)
        else:
            chunks[k][2], note = mutate_bytes(chunks[k][2], rng)
            note = f"{tag!r} {note}"
        if rng.random() < 0.2:
            chunks.insert(rng.randrange(len(chunks) + 1), rng.choice(chunks))
            note += " +dup chunk"
        bad = _lmap_encode(chunks)
    files = {"m.lmap": bad, "camera.json": json.dumps(base_camera()).encode(),
             "lines.json": json.dumps({"lines": base_frame()["lines"]}).encode()}
    f = base_frame()
    # Every command that reads a map reads this one (one of the last three at random): the
    # loader's checks must cover what each of them reads.
    readers = [[c.replace("out.lmap", "m.lmap") for c in cmd] for cmd in FOLLOW_UPS if "--json" not in cmd]
    readers.append(rng.choice((
        ["mapkit", "info", "m.lmap", "--json"],
        ["mapkit", "query", "m.lmap", "--at", "2.0,6.6", "--radius", "0.3"],
        ["matcher", "localize", "--map", "m.lmap", "--camera", "camera.json", "--lines", "lines.json",
         "--prior", ",".join(map(str, f["prior"])), "--dt", str(f["dt"]), "--dyaw", str(f["dyaw"])])))
    return Case("lmap", name, files, readers[0], note, readers[1:])


# ---- matcher inputs ------------------------------------------------------------

def base_camera() -> dict:
    return {"width": 640, "height": 480, "fx": 900.0, "fy": 900.0, "cx": 320.0, "cy": 240.0,
            "height_m": 1.2, "pitch_deg": 0.0}


@lru_cache(maxsize=None)
def base_frame() -> dict:
    """A frame simulated on maps/flat.lmap that localises (seeded)."""
    import numpy as np

    import matcher
    from mapkit_harness import simulate

    m = matcher.load_map(ROOT / "maps" / "flat.lmap")
    f = simulate.make_frame(m, matcher.Camera.from_dict(base_camera()), np.random.default_rng(4), 2)
    return {"lines": np.round(f.lines.reshape(-1, 4), 3).tolist(), "prior": [round(v, 4) for v in f.prior],
            "dt": f.dt, "dyaw": f.dyaw}


@lru_cache(maxsize=None)
def base_run() -> bytes:
    """Five frames of a simulated run on maps/flat.lmap as JSON Lines, and its start."""
    import numpy as np

    import matcher
    from mapkit_harness.runs import simulate_run

    m = matcher.load_map(ROOT / "maps" / "flat.lmap")
    run = simulate_run(m, matcher.Camera.from_dict(base_camera()), np.random.default_rng(3), frames=5)
    rows = [json.dumps({"t": t, "odom": [round(v, 6) for v in o], "lines": np.round(ls.reshape(-1, 4), 3).tolist()})
            for t, o, ls in zip(run.times, run.odom, run.lines)]
    return ("\n".join(rows) + "\n").encode(), [round(v, 4) for v in run.truth[0]]


#: Values any number of a matcher input may become.
ODD_VALUES = (math.nan, math.inf, -math.inf, 1e308, -1e308, 0, -1, 1e-300, 2 ** 70, "7", "x", None, True, [], {},
              [1, 2], [[1, 2, 3, 4]])


def _mutate_json(node, rng: random.Random, depth: int = 0):
    """A copy of a JSON value with some numbers, lists or keys made odd."""
    r = rng.random()
    if isinstance(node, dict):
        out = {k: _mutate_json(v, rng, depth + 1) if rng.random() < 0.3 else v for k, v in node.items()}
        if out and rng.random() < 0.15:
            out.pop(rng.choice(sorted(out)))
        return out
    if isinstance(node, list):
        if r < 0.05:
            return []
        if r < 0.1 and node:
            return node * rng.choice((2, 50, 600))
        out = [_mutate_json(v, rng, depth + 1) if rng.random() < 0.2 else v for v in node]
        if out and rng.random() < 0.1:
            del out[rng.randrange(len(out))]
        return out
    if r < 0.5:
        return rng.choice(ODD_VALUES)
    if isinstance(node, (int, float)) and not isinstance(node, bool):
        return node * rng.choice((-1, 10, 1e3, 1e9, 0.5))
    return node


def _odd_number_text(rng: random.Random, good: float) -> str:
    return rng.choice((str(good), str(good), "nan", "inf", "-1", "0", "1e308", "-1e-300", "1e9", "x", ""))


def _odd_array(rng: random.Random, base):
    """The base lines (or an odd replacement) as an array of odd shape or dtype."""
    import numpy as np

    arr = np.array(base, dtype=np.float64)
    pick = rng.randrange(12)
    if pick == 0:
        return arr.astype(rng.choice((np.float32, np.int64, np.int8, np.uint8, np.complex128, np.float16, bool)))
    if pick == 1:
        return arr.reshape(rng.choice(((-1,), (-1, 2, 2), (1, -1), (-1, 8) if arr.size % 8 == 0 else (-1, 4))))
    if pick == 2:
        return np.zeros(rng.choice(((0,), (0, 4), (0, 2, 2), (1,), (1, 4), (3, 2, 2, 1), (2, 3), ())))
    if pick == 3:
        a = arr.copy()
        a.flat[rng.randrange(a.size)] = rng.choice((np.nan, np.inf, -np.inf, 1e308, -1e308, 1e-320))
        return a
    if pick == 4:
        return arr.astype(object)
    if pick == 5:
        return np.array([str(v) for v in arr.ravel()]).reshape(arr.shape)
    if pick == 6:
        return np.tile(arr, (rng.choice((50, 300, 3000)), 1))
    if pick == 7:
        a = arr.copy()
        a[:, 2:] = a[:, :2]  # zero-length lines
        return a
    if pick == 8:
        return arr * rng.choice((-1.0, 10.0, 1e6, 0.0))
    if pick == 9:
        return arr[: rng.randrange(4)]
    if pick == 10:
        return np.asfortranarray(arr)[:, ::-1]
    return arr


def _odd_image(rng: random.Random):
    """An image array of odd size or dtype."""
    import numpy as np

    shape = rng.choice(((0, 0), (1, 1), (480, 640), (2, 5000), (5000, 2), (480, 640, 3), (480, 640, 4),
                        (480, 640, 1), (480, 640, 2), (10,), (3, 4, 5, 6), (), (64, 64)))
    dtype = rng.choice((np.uint8, np.uint8, np.uint16, np.int64, np.float32, np.float64, bool, np.int8,
                        np.complex64))
    nrng = np.random.default_rng(rng.randrange(2 ** 32))
    with np.errstate(all="ignore"):
        img = (nrng.random(shape) * rng.choice((1.0, 255.0, 65535.0, 1e30))).astype(dtype) if shape else \
            np.array(1, dtype)
    if img.size and rng.random() < 0.3 and img.dtype.kind == "f":
        img.flat[rng.randrange(img.size)] = rng.choice((np.nan, np.inf))
    if img.ndim >= 2 and img.size and rng.random() < 0.5:  # stripes and blocks LSD will find lines in
        img[..., :: max(1, img.shape[1] // 8)] = 0
    return img


def _npy(arr) -> bytes:
    import numpy as np

    buf = io.BytesIO()
    np.save(buf, arr, allow_pickle=True)
    return buf.getvalue()


def matcher_case(rng: random.Random, name: str = "matcher") -> Case:
    """Random values for one of the matcher's inputs, through its CLI or its API."""
    kind = rng.choice(("lines file", "lines file", "camera file", "options", "image file", "lines array",
                       "image array", "frames"))
    return {"lines file": _lines_file_case, "camera file": _camera_file_case, "options": _options_case,
            "image file": _image_file_case, "lines array": _lines_array_case, "image array": _image_array_case,
            "frames": _frames_case}[kind](rng, name)


def _localize_argv(prior=None, dt=None, dyaw=None, extra=()) -> list:
    f = base_frame()
    prior = prior if prior is not None else ",".join(map(str, f["prior"]))
    return ["matcher", "localize", "--map", FLAT_LMAP, "--camera", "camera.json",
            "--prior", prior, "--dt", str(f["dt"] if dt is None else dt),
            "--dyaw", str(f["dyaw"] if dyaw is None else dyaw), *extra]


def _lines_file_case(rng, name):
    f = base_frame()
    if rng.random() < 0.15:
        text, note = mutate_lines(json.dumps({"lines": f["lines"]}, indent=0), rng)
        blob = text.encode()
    else:
        blob, note = json.dumps(_mutate_json({"lines": f["lines"]}, rng)).encode(), "json"
    files = {"camera.json": json.dumps(base_camera()).encode(), "lines.json": blob}
    return Case("matcher", name, files, _localize_argv(extra=["--lines", "lines.json"]), f"lines file: {note}")


#: Camera files of each format the matcher reads.
CAMERA_SOURCES = ("opencv_calibration.yml", "opencv_calibration.xml", "opencv_calibration.json",
                  "ros_camera_info.yaml")


def _camera_file_case(rng, name):
    f = base_frame()
    files = {"lines.json": json.dumps({"lines": f["lines"]}).encode()}
    if rng.random() < 0.5:
        files["camera.json"], note = json.dumps(_mutate_json(base_camera(), rng)).encode(), "json"
        argv = _localize_argv(extra=["--lines", "lines.json"])
    else:
        src = rng.choice(CAMERA_SOURCES)
        raw = _source(DATA / "cameras" / src)
        if rng.random() < 0.7:
            text, note = mutate_lines(raw.decode(), rng)
            raw = text.encode()
        else:
            raw, note = mutate_bytes(raw, rng)
        ext = src.rsplit(".", 1)[1]
        files["camera." + ext] = raw
        argv = _localize_argv(extra=["--lines", "lines.json", "--height-m", _odd_number_text(rng, 1.2)])
        argv[argv.index("camera.json")] = "camera." + ext
        note = f"{src}: {note}"
    return Case("matcher", name, files, argv, f"camera file: {note}")


def _options_case(rng, name):
    f = base_frame()
    files = {"camera.json": json.dumps(base_camera()).encode(), "lines.json": json.dumps({"lines": f["lines"]}).encode()}
    prior = ",".join(_odd_number_text(rng, v) for v in f["prior"]) if rng.random() < 0.5 else \
        rng.choice(("1,2", "1,2,3,4", "a,b,c", "", "1e308,1e308,1e308", "-1e9,5,720", "5,5,nan"))
    extra = ["--lines", "lines.json"]
    if rng.random() < 0.5:
        extra += ["--budget-ms", _odd_number_text(rng, 200.0)]
    if rng.random() < 0.2:  # lost mode, always under a budget (it takes seconds)
        argv = ["matcher", "localize", "--map", FLAT_LMAP, "--camera", "camera.json",
                "--lost", "--lines", "lines.json", "--budget-ms", rng.choice(("100", "300", "0", "nan", "-5"))]
    elif rng.random() < 0.2:  # the camera on the command line
        argv = _localize_argv(prior, extra=extra)
        i = argv.index("--camera")
        argv[i:i + 2] = ["--camera-k", ",".join(_odd_number_text(rng, v) for v in (900, 900, 320, 240)),
                         "--image-size", rng.choice(("640x480", "0x0", "640", "-640x480", "99999999x99999999",
                                                     "axb")), "--height-m", _odd_number_text(rng, 1.2)]
    else:
        argv = _localize_argv(prior, _odd_number_text(rng, f["dt"]), _odd_number_text(rng, f["dyaw"]), extra)
    return Case("matcher", name, files, argv, "options")


def _image_file_case(rng, name):
    import cv2
    import numpy as np

    img = _odd_image(rng)
    ok, enc = False, None
    encodable = img.dtype in (np.uint8, np.uint16) and img.ndim in (2, 3) and img.size and \
        (img.ndim == 2 or img.shape[2] in (1, 3, 4))
    if encodable:  # else random bytes: PNG cannot hold it (and libpng would say so on stderr)
        ok, enc = cv2.imencode(".png", img)
    blob = enc.tobytes() if ok else bytes(rng.randrange(256) for _ in range(64))
    if rng.random() < 0.3:
        blob, _ = mutate_bytes(blob, rng)
    cam = base_camera()
    if img.ndim >= 2 and rng.random() < 0.8:  # a camera of the image's size, so the lines get to the matcher
        cam.update(width=max(int(img.shape[1]), 1), height=max(int(img.shape[0]), 1),
                   cx=img.shape[1] / 2, cy=img.shape[0] / 2)
    files = {"camera.json": json.dumps(cam).encode(), "image.png": blob}
    return Case("matcher", name, files, _localize_argv(extra=["--image", "image.png", "--budget-ms", "2000"]),
                f"image {img.shape} {img.dtype}")


def _lines_array_case(rng, name):
    f = base_frame()
    args = {"lines": "lines.npy", "camera": base_camera(),
            "prior": [rng.choice((v, v, v, math.nan, 1e308, "x")) for v in f["prior"]] if rng.random() < 0.3 else
            f["prior"],
            "dt": rng.choice((f["dt"], f["dt"], -1.0, 0.0, math.nan, math.inf, 1e9, "0.4", None)),
            "dyaw": rng.choice((f["dyaw"], f["dyaw"], -20.0, 0.0, math.nan, 720.0, 1e300, None))}
    return Case("matcher", name, {"lines.npy": _npy(_odd_array(rng, f["lines"]))}, ["api", "localize", args],
                "lines array")


def _image_array_case(rng, name):
    img = _odd_image(rng)
    args = {"image": "image.npy", "camera": base_camera() if rng.random() < 0.5 else None,
            "min_length": rng.choice((None, None, 0.0, -1.0, math.nan, 1e9, "x"))}
    if args["camera"] and img.ndim >= 2 and rng.random() < 0.8:
        args["camera"].update(width=max(int(img.shape[1]), 1), height=max(int(img.shape[0]), 1),
                              cx=img.shape[1] / 2, cy=img.shape[0] / 2)
    return Case("matcher", name, {"image.npy": _npy(img)}, ["api", "detect_lines", args],
                f"image {img.shape} {img.dtype}")


def _frames_case(rng, name):
    run, start = base_run()
    rows = run.decode().splitlines()
    if rng.random() < 0.3:
        text, note = mutate_lines(run.decode(), rng)
    else:
        i = rng.randrange(len(rows))
        rows[i] = json.dumps(_mutate_json(json.loads(rows[i]), rng))
        if rng.random() < 0.2:
            rows[rng.randrange(len(rows))] = json.dumps({"t": 1.0, "odom": [0, 0, 0], "image": rng.choice(
                ("missing.png", "/etc", "..", "camera.json", "", "/dev/zero"))})
        text, note = "\n".join(rows) + "\n", f"frame {i} json"
    files = {"camera.json": json.dumps(base_camera()).encode(), "run.jsonl": text.encode()}
    argv = ["matcher", "track", "--map", FLAT_LMAP, "--camera", "camera.json",
            "--frames", "run.jsonl", "--relocalise-budget-ms", "300", "--budget-ms", "500", "--out", "traj.txt"]
    argv += ["--lost"] if rng.random() < 0.2 else ["--prior", ",".join(map(str, start)), "--dt", "0.3",
                                                    "--dyaw", "15"]
    return Case("matcher", name, files, argv, f"frames: {note}")


MAKERS = {"dxf": dxf_case, "mesh": mesh_case, "zind": zind_case, "segments": segments_case, "lmap": lmap_case,
          "matcher": matcher_case}


def make_case(family: str, seed: int, i: int) -> Case:
    return MAKERS[family](random.Random(f"{family}:{seed}:{i}"), f"{family}-{seed}-{i}")


# ---- running a case ------------------------------------------------------------

def _classify_cli(prog: str, code, out: str, err: str) -> tuple[str, str]:
    """The outcome of a command line from its exit code and output: exit 2 is
    a clean error only as one line ``PROG: error: ...``; exit 3 (an internal
    error) and any traceback are bugs."""
    if "Traceback" in err:
        return BUG, err[-2000:]
    if code == 0:
        return VALID, ""
    if code == 1 and prog == "matcher":
        # localize prints 'not localised: REASON'; track one line a frame, with its reason
        said = out.strip().splitlines()
        reason = next((ln for ln in said if ln.startswith("not localised")), said[-1] if said else "")
        return (FALSY, reason) if reason else (BUG, f"exit 1 without a reason: {err[-500:]}")
    if code == 2:
        errors = [ln for ln in err.splitlines() if ln.strip() and not ln.startswith(f"{prog}: warning:")]
        if len(errors) == 1 and errors[0].startswith(f"{prog}: error: out of memory"):
            return OVER, errors[0]  # the --mem-gb limit
        if len(errors) == 1 and errors[0].startswith(f"{prog}: error: "):
            return ERROR, errors[0]
        return BUG, f"exit 2 but not one error line: {err[-1000:]}"
    return BUG, f"exit {code}: {err[-1000:]}"


def _api(function: str, args: dict):
    """Run an API case; returns the outcome kind and its detail."""
    import numpy as np

    import matcher

    cam = matcher.Camera.from_dict(args["camera"]) if args.get("camera") else None
    if function == "localize":
        m = matcher.load_map(ROOT / "maps" / "flat.lmap")
        lines = np.load(args["lines"], allow_pickle=True)
        res = matcher.localize(m, cam, lines, args["prior"], args["dt"], args["dyaw"])
        if not res:
            return (FALSY, res.reason) if res.reason else (BUG, "falsy result without a reason")
        return VALID, ""
    kwargs = {} if args.get("min_length") is None else {"min_length": args["min_length"]}
    lines = matcher.detect_lines(np.load(args["image"], allow_pickle=True), cam, **kwargs)
    if not (isinstance(lines, np.ndarray) and lines.ndim == 3 and lines.shape[1:] == (2, 2)
            and np.isfinite(lines).all()):
        return BUG, f"detect_lines returned {type(lines).__name__} {getattr(lines, 'shape', '')}"
    return VALID, ""


def run_case_here(case: Case) -> tuple[str, str]:
    """Run ``case`` in this process, in the current directory (its files
    written there): its call, then each of ``case.then`` while the one
    before ended valid; returns (kind, detail) of the first that did not
    (the detail naming a follow-up's command), or (VALID, ""). May not
    return (a hang)."""
    for fname, blob in case.files.items():
        Path(fname).write_bytes(blob)
    for k, call in enumerate([case.call, *case.then]):
        kind, detail = run_call(call)
        if kind != VALID:
            if k and case.then_valid and kind in (ERROR, FALSY):
                kind, detail = BUG, f"a map the case wrote is refused: {detail}"
            return kind, (f"then {' '.join(map(str, call))}: {detail}" if k else detail)
    return VALID, ""


def run_call(call: list) -> tuple[str, str]:
    """Run one command or API call of a case in the current directory; (kind, detail)."""
    from linemap.errors import InputError

    what = call[0]
    if what == "api":
        try:
            return _api(call[1], call[2])
        except InputError as exc:
            msg = str(exc)
            return (ERROR, msg) if msg and "\n" not in msg else (BUG, f"InputError not one line: {msg!r}")
        except MemoryError:
            return OVER, "MemoryError"
        except Exception:  # noqa: BLE001 - the point of the exercise: any other exception is a bug, ValueError too
            return BUG, traceback.format_exc()[-2000:]
    argv = [a.replace("{ROOT}", str(ROOT)) if isinstance(a, str) else a for a in call[1:]]
    if what == "mapkit":
        from mapkit.cli import main
    else:
        from matcher.cli import main
    out, err = io.StringIO(), io.StringIO()
    code = None
    try:
        with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
            try:
                code = main(argv)
            except SystemExit as exc:  # argparse's errors
                code = exc.code
    except MemoryError:
        return OVER, "MemoryError"
    except Exception:  # noqa: BLE001
        said = err.getvalue()[-500:]
        return BUG, (f"stderr: {said}\n" if said else "") + traceback.format_exc()[-2000:]
    return _classify_cli(what, code, out.getvalue(), err.getvalue())


def _child(case: Case, folder: Path, conn, mem_bytes: int) -> None:
    try:
        resource.setrlimit(resource.RLIMIT_AS, (mem_bytes, mem_bytes))
        folder.mkdir(parents=True, exist_ok=True)
        os.chdir(folder)
        with open(os.devnull, "w") as null:  # C libraries' own complaints on fd 2
            os.dup2(null.fileno(), 2)
        result = run_case_here(case)
    except BaseException as exc:  # noqa: BLE001
        result = (OVER, "MemoryError") if isinstance(exc, MemoryError) else (BUG, repr(exc))
    try:
        conn.send(result)
    finally:
        os._exit(0)


def start_case(case: Case, folder: Path, mem_gb: float):
    """Fork a child running ``case`` in ``folder``; returns (pid, connection, start time)."""
    import multiprocessing

    recv, send = multiprocessing.Pipe(duplex=False)
    sys.stdout.flush()
    sys.stderr.flush()
    pid = os.fork()
    if pid == 0:
        recv.close()
        _child(case, folder, send, int(mem_gb * 2 ** 30))
    send.close()
    return pid, recv, time.monotonic()


def finish_case(pid: int, conn, t0: float, bound_s: float, block: bool = True) -> Outcome | None:
    """The outcome of a started case (None if still running and not ``block``)."""
    left = bound_s - (time.monotonic() - t0)
    if conn.poll(max(left, 0) if block else 0):
        try:
            kind, detail = conn.recv()
        except EOFError:  # the child died without a word: a crash
            kind, detail = BUG, "child died"
        _, status = os.waitpid(pid, 0)
        if os.WIFSIGNALED(status):
            kind, detail = BUG, f"killed by signal {os.WTERMSIG(status)}"
        conn.close()
        return Outcome(kind, detail, time.monotonic() - t0)
    if time.monotonic() - t0 < bound_s:
        return None
    os.kill(pid, signal.SIGKILL)
    os.waitpid(pid, 0)
    conn.close()
    return Outcome(OVER, f"still running after {bound_s:g} s", time.monotonic() - t0)


def run_bounded(case: Case, folder: Path, bound_s: float = 60.0, mem_gb: float = 3.0) -> Outcome:
    """Run ``case`` in a forked child in ``folder`` under a time bound and an
    address-space limit."""
    out = finish_case(*start_case(case, folder, mem_gb), bound_s)
    out.case = case
    return out


def save_case(case: Case, outcome: Outcome, folder: Path) -> Path:
    """Write a failing case as a folder: its files and case.json."""
    d = folder / case.name
    d.mkdir(parents=True, exist_ok=True)
    for fname, blob in case.files.items():
        (d / fname).write_bytes(blob)
    (d / "case.json").write_text(json.dumps({"family": case.family, "call": case.call, "then": case.then,
                                             "then_valid": case.then_valid, "note": case.note,
                                             "outcome": outcome.kind, "detail": outcome.detail}, indent=1,
                                            default=str))
    return d


def load_case(folder: Path) -> Case:
    meta = json.loads((folder / "case.json").read_text())
    files = {p.name: p.read_bytes() for p in folder.iterdir() if p.name != "case.json" and p.is_file()}
    return Case(meta["family"], folder.name, files, meta["call"], meta.get("note", ""), meta.get("then", []),
                meta.get("then_valid", False))


# ---- the campaign --------------------------------------------------------------

def preload() -> None:
    """Import what the cases run before forking, so that each child starts warm."""
    import cv2  # noqa: F401
    import ezdxf  # noqa: F401
    import shapely  # noqa: F401
    import trimesh  # noqa: F401

    import mapkit.assemble  # noqa: F401
    import mapkit.cli  # noqa: F401
    import mapkit.edges  # noqa: F401
    import mapkit.importers.dxf  # noqa: F401
    import mapkit.importers.mesh  # noqa: F401
    import mapkit.importers.segments  # noqa: F401
    import mapkit.importers.zind  # noqa: F401
    import mapkit.pipeline  # noqa: F401
    import mapkit.preview  # noqa: F401
    import mapkit.view.snapshot  # noqa: F401
    import mapkit.vir  # noqa: F401
    import mapkit.visibility  # noqa: F401
    import matcher.cli  # noqa: F401
    import matcher.cli_track  # noqa: F401
    import matcher.lost  # noqa: F401
    import matcher.tracking.tracker  # noqa: F401

    base_frame()
    base_run()
    base_segments_csv()


def campaign(counts: dict[str, int], seed: int, workers: int, bound_s: float, mem_gb: float, save: Path | None,
             scratch: Path, progress: bool = True, minutes: float = math.inf) -> dict[str, dict[str, int]]:
    """Run every case, ``workers`` at a time, the families interleaved in
    proportion to their counts (so that a campaign stopped after ``minutes``
    has run a share of each); returns counts per family and outcome."""
    todo = sorted(((fam, i) for fam in FAMILIES for i in range(counts.get(fam, 0))),
                  key=lambda c: ((c[1] + 0.5) / counts[c[0]], FAMILIES.index(c[0])))
    started = time.monotonic()
    stop_at = started + 60.0 * minutes
    table = {fam: {k: 0 for k in (ERROR, VALID, FALSY, BUG, OVER)} for fam in FAMILIES if counts.get(fam)}
    preload()
    for fam in table:  # build the shared inputs once, before forking
        make_case(fam, seed, 0)
    running = []
    done = 0
    while todo or running:
        if time.monotonic() > stop_at and todo:
            print(f"stopping: {minutes:g} minutes are up, {len(todo)} cases not started", file=sys.stderr)
            todo = []
        while todo and len(running) < workers:
            fam, i = todo.pop(0)
            case = make_case(fam, seed, i)
            running.append((case, *start_case(case, scratch / case.name, mem_gb)))
        time.sleep(0.005)
        for entry in list(running):
            case, pid, conn, t0 = entry
            out = finish_case(pid, conn, t0, bound_s, block=False)
            if out is None:
                continue
            running.remove(entry)
            done += 1
            table[case.family][out.kind] += 1
            _clean(scratch / case.name)
            if out.kind in (BUG, OVER):
                where = save_case(case, out, save) if save else None
                print(f"{case.name}: {out.kind} ({case.note}) {out.detail.strip().splitlines()[-1:]}"
                      + (f" -> {where}" if where else ""), file=sys.stderr)
            if progress and done % 100 == 0:
                print(f"{done} cases done, {time.monotonic() - started:.0f} s", file=sys.stderr)
    return table


def _clean(folder: Path) -> None:
    import shutil

    shutil.rmtree(folder, ignore_errors=True)


def print_table(table: dict, seconds: float) -> None:
    cols = (ERROR, VALID, FALSY, BUG, OVER)
    print("| family | cases | clean errors | valid results | falsy results | bugs | over time bound |")
    print("|---|---|---|---|---|---|---|")
    for fam, row in table.items():
        print(f"| {fam} | {sum(row.values())} | " + " | ".join(str(row[c]) for c in cols) + " |")
    print(f"({seconds:.0f} s wall clock)")


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--dxf", type=int, default=40, help="DXF cases (default 40)")
    ap.add_argument("--mesh", type=int, default=20, help="mesh cases (default 20)")
    ap.add_argument("--zind", type=int, default=40, help="ZInD annotation cases (default 40)")
    ap.add_argument("--segments", type=int, default=40, help="segments-file cases (default 40)")
    ap.add_argument("--lmap", type=int, default=100, help=".lmap cases (default 100)")
    ap.add_argument("--matcher", type=int, default=100, help="matcher-input cases (default 100)")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--workers", type=int, default=2, help="cases run at once (default 2)")
    ap.add_argument("--bound-s", type=float, default=60.0, help="time bound of one case, seconds (default 60)")
    ap.add_argument("--mem-gb", type=float, default=3.0, help="address-space limit of one case, GiB (default 3)")
    ap.add_argument("--save", type=Path, metavar="DIR", help="write each failing case into DIR")
    ap.add_argument("--minutes", type=float, default=math.inf,
                    help="start no case after this many minutes (the table counts the cases run)")
    ap.add_argument("--replay", type=Path, metavar="CASE_DIR", help="run one saved case and print its outcome")
    args = ap.parse_args(argv)
    import tempfile

    with tempfile.TemporaryDirectory(prefix="fuzz-") as scratch:
        if args.replay:
            out = run_bounded(load_case(args.replay), Path(scratch) / "case", args.bound_s, args.mem_gb)
            print(f"{out.kind} in {out.seconds:.1f} s: {out.detail}")
            return 0 if out.kind in (ERROR, VALID, FALSY) else 1
        t0 = time.monotonic()
        counts = {"dxf": args.dxf, "mesh": args.mesh, "zind": args.zind, "segments": args.segments, "lmap": args.lmap,
                  "matcher": args.matcher}
        table = campaign(counts, args.seed, args.workers, args.bound_s, args.mem_gb, args.save, Path(scratch),
                         minutes=args.minutes)
    print(f"seed {args.seed}, {args.workers} workers, bound {args.bound_s:g} s and {args.mem_gb:g} GiB a case")
    print_table(table, time.monotonic() - t0)
    bad = sum(row[BUG] + row[OVER] for row in table.values())
    return 1 if bad else 0


if __name__ == "__main__":
    os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
    os.environ.setdefault("OMP_NUM_THREADS", "1")
    raise SystemExit(main())
