"""Crafted maps: valid checksums, hostile contents. A robot loads maps it is
sent, and the CRCs catch accidents, not intent: each case ends in a
one-line LmapError, quickly and without allocating far beyond the file's
size (peak memory measured with tracemalloc, which sees numpy's buffers)."""

from __future__ import annotations

import json
import tracemalloc
import zlib
from pathlib import Path

import numpy as np
import pytest

from linemap.lmap import _CHUNK, _HEADER, LmapError, decode

ROOT = Path(__file__).resolve().parent.parent


def _read_chunks(blob: bytes) -> list[list]:
    """[tag, codec, payload] of each chunk of a valid file (payload inflated)."""
    header = np.frombuffer(blob, dtype=_HEADER, count=1)[0]
    pos, out = _HEADER.itemsize, []
    for _ in range(int(header["n_chunks"])):
        ch = np.frombuffer(blob, dtype=_CHUNK, count=1, offset=pos)[0]
        pos += _CHUNK.itemsize
        stored = blob[pos:pos + int(ch["stored_size"])]
        pos += len(stored)
        payload = zlib.decompress(stored) if int(ch["codec"]) == 1 else stored
        out.append([bytes(ch["tag"]), int(ch["codec"]), payload])
    return out


def _write_chunks(chunks, raw_sizes: dict | None = None) -> bytes:
    """A file of ``chunks`` with correct checksums; ``raw_sizes`` overrides
    the raw size a chunk declares."""
    header = np.zeros((), dtype=_HEADER)
    header["magic"], header["major"], header["minor"], header["n_chunks"] = b"\x89LMP\r\n\x1a\n", 1, 0, len(chunks)
    parts = [header.tobytes()]
    for tag, codec, payload in chunks:
        stored = zlib.compress(payload, 9) if codec == 1 else payload
        ch = np.zeros((), dtype=_CHUNK)
        ch["tag"], ch["codec"], ch["stored_size"], ch["crc32"] = tag, codec, len(stored), zlib.crc32(stored)
        ch["raw_size"] = (raw_sizes or {}).get(tag, len(payload))
        parts += [ch.tobytes(), stored]
    return b"".join(parts)


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
