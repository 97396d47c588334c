"""The ``segments`` fuzz family: segments files, CSV (the example map's
segments) with cells damaged, removed or added, lines or bytes damaged, and
JSON (two rooms with an outline and walls) damaged as ZInD's; or random
segments; then ``mapkit build`` and a built map read by ``FOLLOW_UPS``.
"""

from __future__ import annotations

import contextlib
import json
import random
from functools import lru_cache

from .cases import ROOT, Case, follow_ups
from .mutations import BAD_NUMBERS, mutate_bytes, mutate_json_doc, mutate_lines, random_ring


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


def mutate_csv(text: str, rng: random.Random) -> tuple[str, str]:
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
            text, more = mutate_csv(text, rng)
            blob = text.encode()
        note += f": {more}"
    else:
        if rng.random() < 0.2:
            rows, note = _random_segment_rows(rng)
            doc = {"segments": rows}
            if rng.random() < 0.5:
                doc["outline"] = random_ring(rng, (rng.uniform(0, 50), rng.uniform(0, 50)), rng.uniform(0.1, 100))
        else:
            doc, note = base_segments(), "two rooms"
        text, more = mutate_json_doc(doc, rng) if doc is base_segments() or rng.random() < 0.5 else \
            (json.dumps(doc), "")
        blob, note = text.encode(), f"{note}: {more}"
    fname = f"segments.{form}"
    argv = ["build", fname, "-o", "out.lmap"]
    if rng.random() < 0.1:
        argv += ["--units", rng.choice(("mm", "cm", "ft", "in", "km"))]
    return Case("segments", name, {fname: blob}, ["mapkit", *argv], note, **follow_ups(argv))
