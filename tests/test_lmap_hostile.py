"""Crafted maps: valid checksums, hostile contents. A robot loads maps it is
sent, and the CRCs catch accidents, not intent: each case ends in a
one-line LmapError, quickly and without allocating far beyond the file's
size (peak memory measured with tracemalloc, which sees numpy's buffers)."""

from __future__ import annotations

import json
import tracemalloc
from pathlib import Path

import numpy as np
import pytest

from linemap.lmap import LmapError, decode
from linemap.lmap import read_chunks as _read_chunks
from linemap.lmap import write_chunks as _write_chunks

ROOT = Path(__file__).resolve().parent.parent


@pytest.fixture(scope="module")
def chunks():
    return _read_chunks((ROOT / "maps" / "flat.lmap").read_bytes())


def _with_meta(chunks, edit):
    out = [list(c) for c in chunks]
    for c in out:
        if c[0] == b"META":
            meta = json.loads(c[2])
            edit(meta)
            c[2] = json.dumps(meta).encode()
    return out


def _refused(blob: bytes, match: str):
    """Decode ``blob``: a one-line LmapError matching ``match``; peak memory
    under 10 times the file's size plus 16 MB."""
    tracemalloc.start()
    try:
        with pytest.raises(LmapError, match=match) as info:
            decode(blob, "crafted.lmap")
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert "\n" not in str(info.value)
    assert peak < 10 * len(blob) + (16 << 20), peak


def test_the_untouched_chunks_decode(chunks):
    assert decode(_write_chunks(chunks)).n_segments == 264


def test_visible_lists_that_inflate_to_gigabytes(chunks):
    """Huge segment and region counts with zero bitsets: a few hundred
    kilobytes of zlib that would inflate to gigabytes and expand eight times."""
    n, r = 200_000, 100_000

    def huge(meta):
        meta["counts"].update(segments=n, regions=r)

    out = _with_meta(chunks, huge)
    for c in out:
        if c[0] == b"VLST":
            c[2] = bytes((n + 7) // 8 * 64)  # stands for r rows: the raw size below claims them
    blob = _write_chunks(out, {b"VLST": (n + 7) // 8 * r})
    _refused(blob, "claims .* bytes, more than a map of")


def test_a_raw_size_past_two_to_the_63(chunks):
    _refused(_write_chunks(chunks, {b"SEGM": 2**64 - 1}), "claims .* bytes")


def test_meta_nested_too_deeply(chunks):
    out = [list(c) for c in chunks]
    for c in out:
        if c[0] == b"META":
            c[2] = b"[" * 100_000 + b"]" * 100_000
    _refused(_write_chunks(out), "unreadable META")


@pytest.mark.parametrize("edit, match", [
    (lambda m: m["camera"].pop("height_m"), "camera lacks a numeric height_m"),
    (lambda m: m["camera"].update(fx="wide"), "camera lacks a numeric fx"),
    (lambda m: m.update(wall_height=-2.5), "wall_height must be a positive number"),
    (lambda m: m.update(wall_height=float("nan")), "wall_height must be a positive number"),
    (lambda m: m["counts"].update(list_entries=10**12), "visible-list entries"),
    (lambda m: m["counts"].update(list_entries=10), "more than the 10 entries"),
])
def test_meta_with_impossible_contents(chunks, edit, match):
    _refused(_write_chunks(_with_meta(chunks, edit)), match)


def test_more_chunks_than_the_file_holds(chunks):
    blob = bytearray(_write_chunks(chunks))
    blob[12:16] = np.uint32(10**9).tobytes()
    _refused(bytes(blob), "claims 1000000000 chunks")
