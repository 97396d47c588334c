"""The .lmap format: round trip, every corruption branch, atomic writes, lookups."""

from __future__ import annotations

import json
import zlib

import numpy as np
import pytest
import shapely
from shapely.geometry import Point, box

from mapkit.assemble import assemble_map, region_geometry
from linemap.lmap import (
    _CHUNK,
    _HEADER,
    FORMAT_MAJOR,
    LmapError,
    SegmentKind,
    decode,
    encode,
    load_map,
    save_map,
)


def grid_map(nx=6, ny=4, cell=1.0, n_segments=40, seed=0):
    """A map of nx*ny square regions (one with a hole) and random lists."""
    rng = np.random.default_rng(seed)
    polys, lists = [], []
    for j in range(ny):
        for i in range(nx):
            p = box(i * cell, j * cell, (i + 1) * cell, (j + 1) * cell)
            if (i, j) == (2, 1):
                p = p.difference(box(i + 0.3, j + 0.3, i + 0.6, j + 0.6))
            polys.append(p)
            lists.append(np.sort(rng.choice(n_segments, size=rng.integers(0, 12), replace=False)))
    segs = rng.uniform(-1, 7, size=(n_segments, 2, 3))
    kinds = rng.integers(0, len(SegmentKind), size=n_segments)
    walls = box(-0.3, -0.3, nx * cell + 0.3, ny * cell + 0.3).difference(box(0, 0, nx * cell, ny * cell))
    m = assemble_map(segs, kinds, polys, lists, walls, {"units": "m", "note": "test"})
    return m, polys, lists


def test_round_trip_preserves_everything(tmp_path):
    m, polys, lists = grid_map()
    path = tmp_path / "t.lmap"
    size = save_map(path, m)
    assert size == path.stat().st_size
    m2 = load_map(path)
    assert m2.version == (FORMAT_MAJOR, 0)
    np.testing.assert_array_equal(m2.segments, m.segments)
    np.testing.assert_array_equal(m2.kinds, m.kinds)
    np.testing.assert_allclose(m2.ring_points, m.ring_points, atol=1e-4)
    np.testing.assert_array_equal(m2.ring_offsets, m.ring_offsets)
    np.testing.assert_array_equal(m2.ring_is_hole, m.ring_is_hole)
    np.testing.assert_array_equal(m2.grid_offsets, m.grid_offsets)
    np.testing.assert_array_equal(m2.grid_regions, m.grid_regions)
    np.testing.assert_allclose(m2.wall_points, m.wall_points, atol=1e-4)
    for r, lst in enumerate(lists):
        np.testing.assert_array_equal(m2.region_list(r), np.unique(lst))
        assert region_geometry(m2, r).symmetric_difference(polys[r]).area < 1e-6
    assert m2.meta["note"] == "test"


def test_lookup_matches_shapely_at_random_points():
    m, polys, _ = grid_map(nx=7, ny=5, cell=0.8)
    rng = np.random.default_rng(1)
    for x, y, r in zip(rng.uniform(-1, 6.5, 300), rng.uniform(-1, 5, 300), rng.uniform(0, 1.2, 300)):
        expect = sorted(i for i, p in enumerate(polys) if p.distance(Point(x, y)) <= r)
        got = m.regions_near(x, y, r).tolist()
        # Tolerate disagreement only for disks that graze a region boundary.
        diff = set(expect) ^ set(got)
        assert all(abs(polys[i].distance(Point(x, y)) - r) < 1e-9 for i in diff), (x, y, r, diff)


def test_region_with_hole_excludes_hole():
    m, _, _ = grid_map()
    assert 2 + 1 * 6 not in m.regions_at(2.45, 1.45).tolist()
    assert m.regions_at(2.1, 1.1).tolist() == [2 + 6]


def test_candidate_segments_is_union_of_lists():
    m, _, lists = grid_map()
    regs = m.regions_near(1.5, 1.5, 0.6)
    expect = np.unique(np.concatenate([lists[r] for r in regs]))
    np.testing.assert_array_equal(m.candidate_segments(1.5, 1.5, 0.6), expect)


def test_query_rejects_non_finite():
    m, _, _ = grid_map()
    with pytest.raises(ValueError, match="finite"):
        m.regions_near(float("nan"), 0.0, 1.0)


def test_centres_are_area_centroids():
    m, polys, _ = grid_map()
    c = m.region_centres()
    for r, p in enumerate(polys):
        np.testing.assert_allclose(c[r], [p.centroid.x, p.centroid.y], atol=1e-6)


def test_areas_subtract_holes():
    m, polys, _ = grid_map()
    np.testing.assert_allclose(m.region_areas(), [p.area for p in polys], atol=1e-9)
    assert m.region_areas()[1 * 6 + 2] == pytest.approx(1.0 - 0.09)  # the cell with the hole


# --------------------------------------------------------------- corruption


def _chunks(blob: bytes):
    """(tag, header offset, payload offset, payload size) of each chunk."""
    pos, out = _HEADER.itemsize, []
    n = int(np.frombuffer(blob, _HEADER, 1)[0]["n_chunks"])
    for _ in range(n):
        ch = np.frombuffer(blob, _CHUNK, 1, pos)[0]
        size = int(ch["stored_size"])
        out.append((bytes(ch["tag"]), pos, pos + _CHUNK.itemsize, size))
        pos += _CHUNK.itemsize + size
    return out


def _replace_chunk(blob: bytes, tag: bytes, raw: bytes) -> bytes:
    """Re-encode one chunk with a valid checksum (to reach the consistency checks)."""
    for t, hpos, ppos, size in _chunks(blob):
        if t == tag:
            stored = zlib.compress(raw)
            ch = np.frombuffer(blob, _CHUNK, 1, hpos)[0].copy()
            ch["raw_size"], ch["stored_size"], ch["crc32"] = len(raw), len(stored), zlib.crc32(stored)
            return blob[:hpos] + ch.tobytes() + stored + blob[ppos + size :]
    raise KeyError(tag)


@pytest.fixture(scope="module")
def blob():
    return encode(grid_map()[0])


def test_wrong_magic(blob):
    with pytest.raises(LmapError, match="wrong magic"):
        decode(b"PK\x03\x04" + blob[4:])
    with pytest.raises(LmapError, match="wrong magic"):
        decode(b"")


def test_newer_major_version(blob):
    bad = bytearray(blob)
    bad[8:10] = np.uint16(FORMAT_MAJOR + 1).tobytes()
    with pytest.raises(LmapError, match="newer than this reader"):
        decode(bytes(bad))


def test_newer_minor_version_is_read(blob):
    ok = bytearray(blob)
    ok[10:12] = np.uint16(7).tobytes()
    assert decode(bytes(ok)).version == (FORMAT_MAJOR, 7)


@pytest.mark.parametrize("cut", [20, 60, -10, -1])
def test_truncation(blob, cut):
    with pytest.raises(LmapError, match="truncated"):
        decode(blob[:cut])


def test_checksum_mismatch(blob):
    for tag, _, ppos, size in _chunks(blob):
        bad = bytearray(blob)
        bad[ppos + size // 2] ^= 0xFF
        with pytest.raises(LmapError, match="checksum mismatch"):
            decode(bytes(bad))


def test_trailing_bytes(blob):
    with pytest.raises(LmapError, match="trailing"):
        decode(blob + b"\0\0")


def test_missing_chunk(blob):
    tag, hpos, ppos, size = _chunks(blob)[-1]
    header = np.frombuffer(blob, _HEADER, 1)[0].copy()
    header["n_chunks"] -= 1
    with pytest.raises(LmapError, match="lacks the WPTS chunk"):
        decode(header.tobytes() + blob[_HEADER.itemsize : hpos])


def test_bad_meta(blob):
    with pytest.raises(LmapError, match="META"):
        decode(_replace_chunk(blob, b"META", b"{not json"))
    meta = json.loads(zlib.decompress(blob[_chunks(blob)[0][2] : _chunks(blob)[0][2] + _chunks(blob)[0][3]]))
    del meta["counts"]
    with pytest.raises(LmapError, match="META"):
        decode(_replace_chunk(blob, b"META", json.dumps(meta).encode()))


def test_wrong_array_length(blob):
    with pytest.raises(LmapError, match="KIND holds"):
        decode(_replace_chunk(blob, b"KIND", b"\0" * 3))


def test_out_of_range_segment_kind(blob):
    m = grid_map()[0]
    kinds = np.full(m.n_segments, 200, dtype=np.uint8)
    with pytest.raises(LmapError, match="kinds out of range"):
        decode(_replace_chunk(blob, b"KIND", kinds.tobytes()))


def test_out_of_range_grid_region(blob):
    m = grid_map()[0]
    greg = m.grid_regions.astype("<u4").copy()
    greg[0] = 10_000
    with pytest.raises(LmapError, match="region that does not exist"):
        decode(_replace_chunk(blob, b"GREG", greg.tobytes()))


def test_out_of_range_ring_region(blob):
    m = grid_map()[0]
    rreg = m.ring_region.astype("<u4").copy()
    rreg[-1] = 10_000
    with pytest.raises(LmapError, match="ring region ids"):
        decode(_replace_chunk(blob, b"RREG", rreg.tobytes()))


def test_malformed_offsets(blob):
    m = grid_map()[0]
    roff = m.ring_offsets.astype("<u4").copy()
    roff[-1] += 5
    with pytest.raises(LmapError, match="ring offsets"):
        decode(_replace_chunk(blob, b"ROFF", roff.tobytes()))


def test_non_finite_segments(blob):
    m = grid_map()[0]
    segs = m.segments.astype("<f8").copy()
    segs[0, 0, 0] = np.nan
    with pytest.raises(LmapError, match="finite"):
        decode(_replace_chunk(blob, b"SEGM", segs.tobytes()))


def test_zero_length_segment(blob):
    m = grid_map()[0]
    segs = m.segments.astype("<f8").copy()
    segs[3, 1] = segs[3, 0]
    with pytest.raises(LmapError, match="a segment has zero length"):
        decode(_replace_chunk(blob, b"SEGM", segs.tobytes()))


def _meta(blob):
    _, _, ppos, size = _chunks(blob)[0]
    return json.loads(zlib.decompress(blob[ppos : ppos + size]))


def test_non_finite_grid_origin(blob):
    meta = _meta(blob)
    meta["grid"]["origin"] = [float("nan"), 0.0]
    with pytest.raises(LmapError, match="lookup grid's origin must be two finite numbers"):
        decode(_replace_chunk(blob, b"META", json.dumps(meta).encode()))


def test_infinite_count_in_meta(blob):
    meta = _meta(blob)
    meta["counts"]["segments"] = float("inf")
    with pytest.raises(LmapError, match="unreadable META chunk"):
        decode(_replace_chunk(blob, b"META", json.dumps(meta).encode()))


def test_chunk_inflating_past_its_size_is_stopped(blob):
    """A chunk whose zlib stream inflates to far more than its header
    states is rejected without inflating it all."""
    tag, hpos, ppos, size = _chunks(blob)[1]
    stored = zlib.compress(b"\0" * (50 << 20))  # 50 MB of zeros in about 50 kB
    ch = np.frombuffer(blob, _CHUNK, 1, hpos)[0].copy()
    ch["stored_size"], ch["crc32"] = len(stored), zlib.crc32(stored)
    with pytest.raises(LmapError, match=f"chunk {tag.decode()} has the wrong size"):
        decode(blob[:hpos] + ch.tobytes() + stored + blob[ppos + size :])


def test_chunk_names_read_as_text(blob):
    with pytest.raises(LmapError) as e:
        decode(blob[: _chunks(blob)[2][2] + 3])
    assert "b'" not in str(e.value) and "cut short" in str(e.value)


def test_unknown_codec(blob):
    tag, hpos, ppos, size = _chunks(blob)[1]
    ch = np.frombuffer(blob, _CHUNK, 1, hpos)[0].copy()
    ch["codec"] = 9
    with pytest.raises(LmapError, match="unknown codec"):
        decode(blob[:hpos] + ch.tobytes() + blob[ppos:])


def test_directory_is_an_error(tmp_path):
    with pytest.raises(LmapError, match="directory"):
        load_map(tmp_path)


def test_missing_file(tmp_path):
    with pytest.raises(FileNotFoundError):
        load_map(tmp_path / "absent.lmap")


# --------------------------------------------------------------- atomicity


def test_failed_save_leaves_previous_file(tmp_path, monkeypatch):
    m, _, _ = grid_map()
    path = tmp_path / "t.lmap"
    save_map(path, m)
    before = path.read_bytes()

    def boom(*a, **k):
        raise OSError("disk full")

    monkeypatch.setattr("linemap.atomic.os.fsync", boom)
    with pytest.raises(OSError, match="disk full"):
        save_map(path, grid_map(seed=5)[0])
    assert path.read_bytes() == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["t.lmap"]


def test_invalid_map_is_not_written(tmp_path):
    m, _, _ = grid_map()
    m.list_indices = m.list_indices + 1000
    with pytest.raises(LmapError, match="segment that does not exist"):
        save_map(tmp_path / "bad.lmap", m)
    assert not (tmp_path / "bad.lmap").exists()


def test_grid_cells_list_every_region_they_meet():
    m, polys, _ = grid_map(nx=5, ny=3, cell=0.7)
    ny, nx = m.grid_shape
    for iy in range(ny):
        for ix in range(nx):
            x0, y0 = m.grid_origin + np.array([ix, iy]) * m.grid_cell
            cell = box(x0, y0, x0 + m.grid_cell, y0 + m.grid_cell)
            k = iy * nx + ix
            listed = set(m.grid_regions[m.grid_offsets[k] : m.grid_offsets[k + 1]].tolist())
            assert {i for i, p in enumerate(polys) if shapely.intersects(p, cell)} <= listed


def test_saved_map_has_ordinary_file_mode(tmp_path):
    import os

    path = tmp_path / "t.lmap"
    save_map(path, grid_map()[0])
    mask = os.umask(0)
    os.umask(mask)
    assert path.stat().st_mode & 0o777 == 0o666 & ~mask


def test_the_lists_are_encoded_a_block_of_rows_at_a_time_as_the_whole_table_would_be():
    """VLST of a map too large for a dense table of its lists (3 blocks of
    rows here): the bytes of the whole table XOR-ed row to row, compressed
    the same."""
    import zlib

    from linemap.lmap import _lists_to_bitsets, _stored, _xor_bitsets

    n, r = 1000, 9000
    # Runs of equal lists, as neighbouring regions have: the XOR-ed stream is mostly zeros.
    rows, indices = np.nonzero(np.repeat(np.random.default_rng(46).random((r // 100, n)) < 0.03, 100, axis=0))
    offsets = np.concatenate([[0], np.cumsum(np.bincount(rows, minlength=r))])
    bits = _lists_to_bitsets(offsets, indices, n)
    xbits = bits.copy()
    xbits[1:] ^= bits[:-1]
    blocks = list(_xor_bitsets(offsets, indices, n))
    assert len(blocks) == 3 and b"".join(blocks) == xbits.tobytes()
    stored, size = _stored(iter(blocks), 1)
    assert size == xbits.nbytes and stored == zlib.compress(xbits.tobytes(), 9)


def _wide_map(n_segments: int, n_regions: int, run: int, per_list: int, seed: int = 46):
    """A map of many segments and regions, as a large floor's: one triangle
    per region, runs of ``run`` neighbouring regions seeing the same
    ``per_list`` random segments (VLST: ``n_regions x n_segments / 8`` bytes
    inflated, mostly zeros once XOR-ed)."""
    from linemap.lmap import LineMap

    rng = np.random.default_rng(seed)
    segs = np.zeros((n_segments, 2, 3))
    segs[:, 0, 0] = np.arange(n_segments) * 0.01
    segs[:, 1, 0] = segs[:, 0, 0] + 0.005
    segs[:, 1, 2] = 3.0
    tri = np.array([[0.0, 0.0], [0.4, 0.0], [0.0, 0.4]])
    corner = 0.5 * np.stack([np.arange(n_regions) % 200, np.arange(n_regions) // 200], axis=1)
    ring_points = (tri[None] + corner[:, None, :]).reshape(-1, 2)
    lists = np.sort(np.concatenate([rng.choice(n_segments, per_list, replace=False)
                                    for _ in range(n_regions // run)]).reshape(-1, per_list), axis=1)
    list_indices = np.repeat(lists, run, axis=0).reshape(-1)
    m = LineMap(segments=segs, kinds=np.zeros(n_segments, np.uint8), ring_points=ring_points,
                ring_offsets=np.arange(n_regions + 1) * 3, ring_region=np.arange(n_regions),
                ring_is_hole=np.zeros(n_regions, bool), list_offsets=np.arange(n_regions + 1) * per_list,
                list_indices=list_indices, grid_origin=np.zeros(2), grid_cell=1000.0,
                grid_shape=(1, 1), grid_offsets=np.array([0, n_regions]), grid_regions=np.arange(n_regions),
                wall_points=tri * 2, wall_offsets=np.array([0, 3]), wall_is_hole=np.zeros(1, bool),
                meta={"units": "m"})
    return m


@pytest.mark.slow
def test_the_lists_are_decoded_a_block_of_rows_at_a_time():
    """Decoding a map whose lists inflate to 120 MB (24,000 regions of
    40,000 segments: hundreds of blocks of rows) gives back the same lists
    and never holds the inflated table: peak memory (tracemalloc, which sees
    numpy's buffers and zlib's output) a small part of it."""
    import tracemalloc

    m = _wide_map(n_segments=40_000, n_regions=24_000, run=40, per_list=30)
    blob = encode(m)
    inflated = m.n_regions * ((m.n_segments + 7) // 8)
    tracemalloc.start()
    try:
        m2 = decode(blob)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    np.testing.assert_array_equal(m2.list_offsets, m.list_offsets)
    np.testing.assert_array_equal(m2.list_indices, m.list_indices)
    assert peak < inflated / 4, (peak, inflated)
