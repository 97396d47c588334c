"""The damage the fuzz families do: to the lines of a text file (numbers,
group codes, lines deleted, swapped, duplicated, the text cut short), to
bytes (flipped bits, overwritten numbers, cuts, insertions), to a JSON
document (values made hostile, keys deleted, lists emptied or repeated,
values nested thousands deep); and random rings of points. Each returns
what it made and a note of what was done.
"""

from __future__ import annotations

import contextlib
import copy
import json
import math
import random
import struct


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


#: Values any value of a JSON document may become: NaN, infinities, huge and
#: tiny numbers (10**400 overflows a float), wrong types.
HOSTILE_JSON_VALUES = (math.nan, math.inf, -math.inf, 1e308, -1e308, 1e30, -1e30, 0, -1, 1e-320, 2 ** 70,
                       10 ** 400, "x", "", "1.5", None, True, False, [], {}, [1, 2], [[1, 2]], [[[1, 2]]],
                       {"x": 1})


def json_paths(doc) -> list[list]:
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
        paths = json_paths(doc)
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
            # A copy: a later mutation may edit inside it, and the table must
            # stay as written for the next case (else the same seed draws
            # differently, and hypothesis calls the family flaky).
            parent[key] = copy.deepcopy(rng.choice(HOSTILE_JSON_VALUES))
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


def random_ring(rng: random.Random, centre: tuple[float, float], size: float) -> list[list[float]]:
    """3-30 points around ``centre`` at random angles and radii (often crossing itself)."""
    n = rng.randint(3, 30)
    angles = sorted(rng.uniform(0, 2 * math.pi) for _ in range(n)) if rng.random() < 0.7 else \
        [rng.uniform(0, 2 * math.pi) for _ in range(n)]
    return [[round(centre[0] + rng.uniform(0.1, 1) * size * math.cos(a), 4),
             round(centre[1] + rng.uniform(0.1, 1) * size * math.sin(a), 4)] for a in angles]
