"""The ``lmap`` fuzz family: ``maps/flat.lmap`` with flipped bits,
overwritten bytes, cuts and appended bytes, or its chunks re-encoded with
valid checksums around a damaged payload (what a hostile sender makes);
then every command that reads a map (``mapkit info``, ``view --html``,
``export``) and one of ``mapkit query``, ``info --json`` or ``matcher
localize``.
"""

from __future__ import annotations

import json
import math
import random

from .cases import FOLLOW_UPS, ROOT, Case, source_bytes
from .matcher_inputs import base_camera, base_frame
from .mutations import json_paths, mutate_bytes


def lmap_chunks(blob: bytes) -> list[list]:
    """[tag, codec, payload] of each chunk of a valid file (payload inflated)."""
    from linemap.lmap import read_chunks

    return read_chunks(blob)


def lmap_encode(chunks) -> bytes:
    """A file of ``chunks`` with valid checksums."""
    from linemap.lmap import write_chunks

    return write_chunks(chunks)


def _mutate_meta(payload: bytes, rng: random.Random) -> tuple[bytes, str]:
    """META's JSON with one value replaced by something hostile."""
    meta = json.loads(payload)
    path = rng.choice(json_paths(meta))
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
    blob = source_bytes(ROOT / "maps" / "flat.lmap")
    if rng.random() < 0.5:
        bad, note = mutate_bytes(blob, rng)
    else:  # valid checksums around a damaged payload: what a hostile sender makes
        chunks = lmap_chunks(blob)
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
        bad = lmap_encode(chunks)
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
