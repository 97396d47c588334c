"""Crafted maps: valid checksums, hostile contents (mapkit_harness/crafted_maps.py).
A robot loads maps it is sent, and the CRCs catch accidents, not intent:
each case ends in a one-line LmapError, quickly and without allocating far
beyond the file's size (peak memory measured with tracemalloc, which sees
numpy's buffers; tools/bench_lmap_hostile.py prints it)."""

from __future__ import annotations

import tracemalloc

import pytest

from linemap.lmap import LmapError, decode
from linemap.lmap import write_chunks as _write_chunks


from mapkit_harness.crafted_maps import CASES, example_chunks


@pytest.fixture(scope="module")
def chunks():
    return example_chunks()


def _refused(blob: bytes, match: str):
    """Decode ``blob``: a one-line LmapError matching ``match``; peak memory
    under 10 times the file's size plus 16 MB (the interpreter's own)."""
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


@pytest.mark.parametrize("name, make, match", CASES, ids=[c[0] for c in CASES])
def test_a_crafted_map_is_refused_in_one_line(chunks, name, make, match):
    _refused(make(chunks), match)
