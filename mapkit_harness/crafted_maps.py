"""Crafted maps: valid checksums, hostile contents, each with the message
its one-line LmapError must match. A robot loads maps it is sent, and the
CRCs catch accidents, not intent. Shared by tests/test_lmap_hostile.py and
tools/bench_lmap_hostile.py (outside the installed packages)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from linemap.lmap import read_chunks, write_chunks

ROOT = Path(__file__).resolve().parent.parent


def example_chunks():
    """The chunks of the example map (maps/flat.lmap)."""
    return read_chunks((ROOT / "maps" / "flat.lmap").read_bytes())


def with_meta(chunks, edit):
    """``chunks`` with the META document passed through ``edit(meta)``."""
    out = [list(c) for c in chunks]
    for c in out:
        if c[0] == b"META":
            meta = json.loads(c[2])
            edit(meta)
            c[2] = json.dumps(meta).encode()
    return out


def lists_that_inflate_to_gigabytes(chunks) -> bytes:
    """Huge segment and region counts with zero bitsets: a few hundred
    kilobytes of zlib that would inflate to gigabytes and expand eight times."""
    n, r = 200_000, 100_000

    def huge(meta):
        meta["counts"].update(segments=n, regions=r)

    out = with_meta(chunks, huge)
    for c in out:
        if c[0] == b"VLST":
            c[2] = bytes((n + 7) // 8 * 64)  # stands for r rows: the raw size below claims them
    return write_chunks(out, {b"VLST": (n + 7) // 8 * r})


def meta_nested_too_deeply(chunks) -> bytes:
    out = [list(c) for c in chunks]
    for c in out:
        if c[0] == b"META":
            c[2] = b"[" * 100_000 + b"]" * 100_000
    return write_chunks(out)


def more_chunks_than_the_file_holds(chunks) -> bytes:
    blob = bytearray(write_chunks(chunks))
    blob[12:16] = np.uint32(10**9).tobytes()
    return bytes(blob)


#: (name, blob maker taking the example's chunks, what the error must match)
CASES = [
    ("visible lists inflating to gigabytes", lists_that_inflate_to_gigabytes, "claims .* bytes, more than a map of"),
    ("a raw size past 2^63", lambda ch: write_chunks(ch, {b"SEGM": 2**64 - 1}), "claims .* bytes"),
    ("META nested 100 000 deep", meta_nested_too_deeply, "unreadable META"),
    ("camera without height_m", lambda ch: write_chunks(with_meta(ch, lambda m: m["camera"].pop("height_m"))),
     "camera lacks a numeric height_m"),
    ("camera fx not a number", lambda ch: write_chunks(with_meta(ch, lambda m: m["camera"].update(fx="wide"))),
     "camera lacks a numeric fx"),
    ("negative wall height", lambda ch: write_chunks(with_meta(ch, lambda m: m.update(wall_height=-2.5))),
     "wall_height must be a positive number"),
    ("NaN wall height", lambda ch: write_chunks(with_meta(ch, lambda m: m.update(wall_height=float("nan")))),
     "wall_height must be a positive number"),
    ("10^12 visible-list entries",
     lambda ch: write_chunks(with_meta(ch, lambda m: m["counts"].update(list_entries=10**12))), "visible-list entries"),
    ("too few visible-list entries",
     lambda ch: write_chunks(with_meta(ch, lambda m: m["counts"].update(list_entries=10))), "more than the 10 entries"),
    ("10^9 chunks claimed", more_chunks_than_the_file_holds, "claims 1000000000 chunks"),
    # META entries 'mapkit info' and 'mapkit view' read, of the wrong type (once a TypeError in 'info')
    ("source a list", lambda ch: write_chunks(with_meta(ch, lambda m: m.update(source=["flat.dxf"]))),
     "source must be a JSON string or a JSON object"),
    ("source without its name", lambda ch: write_chunks(with_meta(ch, lambda m: m["source"].pop("name"))),
     "source lacks its file name"),
    ("build parameters a list", lambda ch: write_chunks(with_meta(ch, lambda m: m.update(build=[1, 2]))),
     "build must be a JSON object"),
    ("generator a number", lambda ch: write_chunks(with_meta(ch, lambda m: m.update(generator=7))),
     "generator must be a JSON string"),
    ("camera with a negative focal length",
     lambda ch: write_chunks(with_meta(ch, lambda m: m["camera"].update(fx=-457.0))), "camera: camera fx and fy"),
    ("build camera of zero width",
     lambda ch: write_chunks(with_meta(ch, lambda m: m["build"]["camera"].update(width=0))),
     "build camera: camera width and height must be positive"),
]

#: The cases whose META entries load_map once passed and a command then tripped over.
META_SHAPE_CASES = CASES[-6:]
