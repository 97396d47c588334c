"""The ``.lmap`` binary format: the one module that owns its layout.

Both halves of the project go through here: the map builder writes with
:func:`save_map`, the runtime matcher reads with :func:`load_map`. It needs
numpy and the standard library only, so a robot can load a map without the
authoring stack. The layout is documented in ``docs/lmap-format.md``; keep
the two in step.

Layout (all integers little-endian)::

    file    = header chunk*
    header  = magic(8) major(u2) minor(u2) n_chunks(u4)                 16 bytes
    chunk   = tag(4s) codec(u4) raw_size(u8) stored_size(u8) crc32(u4)  28 bytes
              payload(stored_size)

``codec`` 0 is raw, 1 is zlib. ``crc32`` covers the stored payload. Every
size is checked against the file length before anything is read, every
array length against the counts in ``META``, every index against its range.
"""

from __future__ import annotations

import hashlib
import json
import math
import os
import zlib
from dataclasses import dataclass, field
from enum import IntEnum
from pathlib import Path
from typing import Any, TypeVar

import numpy as np

T = TypeVar("T")

from linemap.atomic import write_atomic
from linemap.camera import Camera, CameraError
from linemap.errors import InputError
from linemap.regions import concat_ranges

MAGIC = b"\x89LMP\r\n\x1a\n"  # PNG-style: catches text-mode and 7-bit mangling
FORMAT_MAJOR = 1  # bump when an old reader cannot read the new file
FORMAT_MINOR = 0  # bump for additions an old reader can ignore

_HEADER = np.dtype([("magic", "S8"), ("major", "<u2"), ("minor", "<u2"), ("n_chunks", "<u4")])
_CHUNK = np.dtype(
    [("tag", "S4"), ("codec", "<u4"), ("raw_size", "<u8"), ("stored_size", "<u8"), ("crc32", "<u4")]
)
_RAW, _ZLIB = 0, 1

#: Region polygon vertices are stored as integers of this many metres.
COORD_QUANTUM_M = 1e-4
#: A file's chunks may inflate to this many times the file's size (and at
#: least the floor below) before anything is allocated: real maps compress
#: a few tens of times (the visible lists are XOR-ed row to row); a crafted
#: chunk that claims more is refused instead of inflating to gigabytes.
MAX_INFLATION = 256
RAW_FLOOR_BYTES = 64 << 20
#: The visible lists may hold this many entries per byte of file (real maps:
#: under 5), and META this many bytes and levels of nesting.
MAX_LIST_ENTRIES_PER_BYTE = 64
MAX_META_BYTES = 16 << 20
MAX_META_DEPTH = 32
#: A map may span at most this many metres: the builder refuses plans over
#: 2 km (mapkit.tolerances.PLAUSIBLE_EXTENT), so a map larger than this was
#: crafted, and the matcher's rasters of it would be needlessly coarse.
MAX_EXTENT_M = 10_000.0


class LmapError(InputError):
    """A ``.lmap`` file is unreadable: wrong magic, newer version, truncated,
    corrupt (checksum) or inconsistent. The message says which and what to do."""


class SegmentKind(IntEnum):
    """What a 3D model segment is. Stored as one byte per segment."""

    FLOOR = 0  # wall/floor junction
    CEILING = 1  # wall/ceiling junction
    VERTICAL = 2  # vertical corner of walls (convex or concave)
    JAMB = 3  # vertical edge at a door or window opening
    LINTEL = 4  # horizontal edge at the head of a door opening
    WINDOW = 5  # horizontal edge at a window sill or head
    HORIZONTAL = 6  # any other horizontal edge
    OBLIQUE = 7  # neither horizontal nor vertical (meshes)

    @property
    def label(self) -> str:
        return self.name.lower()

    @property
    def is_vertical(self) -> bool:
        return self in (SegmentKind.VERTICAL, SegmentKind.JAMB)


KIND_NAMES = [k.label for k in SegmentKind]


@dataclass
class LineMap:
    """A map: 3D model segments plus view-invariant regions (VIR).

    Arrays (lengths in metres, world frame x, y horizontal, z up):

    - ``segments`` (N, 2, 3) float64: end points of each model segment; the
      segment id is its row index and is stable for the life of the file.
    - ``kinds`` (N,) uint8: :class:`SegmentKind` values.
    - ``ring_points`` (P, 2) float64, ``ring_offsets`` (K+1,) int64: region
      outlines; ring k is ``ring_points[ring_offsets[k]:ring_offsets[k+1]]``,
      not repeating its first point.
    - ``ring_region`` (K,) int64, sorted: the region each ring belongs to;
      ``ring_is_hole`` (K,) bool. A region is every ring with its id under
      the even-odd rule, so multi-part regions and holes both work.
    - ``list_offsets`` (R+1,) int64, ``list_indices`` (L,) int64: the sorted
      visible segment ids of region r are
      ``list_indices[list_offsets[r]:list_offsets[r+1]]``.
    - ``grid_origin`` (2,), ``grid_cell`` float, ``grid_shape`` (ny, nx):
      a lookup grid; ``grid_offsets`` (ny*nx+1,) and ``grid_regions``: the
      regions that may meet cell ``iy*nx + ix``. Lookups need no shapely.
    - ``wall_points`` (Q, 2), ``wall_offsets`` (W+1,), ``wall_is_hole`` (W,):
      outlines of the wall solids seen from above (the occluders), rings as
      for regions, all one even-odd set; ``meta["wall_height"]`` is their height.
    - ``meta``: JSON-able dict: units, build parameters, camera, source hash.
    """

    segments: np.ndarray
    kinds: np.ndarray
    ring_points: np.ndarray
    ring_offsets: np.ndarray
    ring_region: np.ndarray
    ring_is_hole: np.ndarray
    list_offsets: np.ndarray
    list_indices: np.ndarray
    grid_origin: np.ndarray
    grid_cell: float
    grid_shape: tuple[int, int]
    grid_offsets: np.ndarray
    grid_regions: np.ndarray
    wall_points: np.ndarray
    wall_offsets: np.ndarray
    wall_is_hole: np.ndarray
    meta: dict[str, Any] = field(default_factory=dict)
    version: tuple[int, int] = (FORMAT_MAJOR, FORMAT_MINOR)

    @property
    def n_segments(self) -> int:
        return int(len(self.segments))

    @property
    def n_regions(self) -> int:
        return int(len(self.list_offsets) - 1)

    def wall_rings(self) -> list[np.ndarray]:
        """Wall outlines as a list of (n, 2) rings (even-odd: holes are rings too)."""
        o = self.wall_offsets
        return [self.wall_points[o[i] : o[i + 1]] for i in range(len(o) - 1)]

    def region_rings(self, region: int) -> list[tuple[np.ndarray, bool]]:
        """The rings of one region as (points (n, 2), is_hole) pairs."""
        ks = np.nonzero(self.ring_region == region)[0]
        o = self.ring_offsets
        return [(self.ring_points[o[k] : o[k + 1]], bool(self.ring_is_hole[k])) for k in ks]

    def region_list(self, region: int) -> np.ndarray:
        """Sorted ids of the segments visible from region ``region``."""
        return self.list_indices[self.list_offsets[region] : self.list_offsets[region + 1]]

    def __post_init__(self) -> None:
        self._lookup = None  # built on first query: see linemap.regions
        self._derived: dict[tuple, Any] = {}

    def derived(self, kind: type[T], *args) -> T:
        """``kind(self, *args)``, made on the first call and kept with the
        map: the per-map data a runtime derives once (the matcher's
        :class:`~matcher.map_index.MapIndex`, say), keyed by its type and
        ``args`` (hashable). The map must not be mutated after."""
        key = (kind, *args)
        hit = self._derived.get(key)
        if hit is None:
            hit = self._derived[key] = kind(self, *args)
        return hit

    # Queries live in their own module to keep the format module about bytes.
    def regions_at(self, x: float, y: float) -> np.ndarray:
        """Ids of the regions containing the point (x, y); empty outside the map."""
        return self._query().regions_near(x, y, 0.0)

    def regions_near(self, x: float, y: float, radius: float) -> np.ndarray:
        """Sorted ids of the regions meeting the closed disk of ``radius`` around (x, y)."""
        return self._query().regions_near(x, y, radius)

    def segments_for_regions(self, regions: np.ndarray) -> np.ndarray:
        """Sorted union of the visible lists of ``regions``."""
        regions = np.asarray(regions, dtype=np.int64)
        if regions.size == 0:
            return np.zeros(0, dtype=np.int64)
        starts = self.list_offsets[regions]
        take = self.list_indices[concat_ranges(starts, self.list_offsets[regions + 1] - starts)]
        return np.unique(take)

    def candidate_segments(self, x: float, y: float, radius: float) -> np.ndarray:
        """Segments visible from somewhere in the disk: method.md section 3's set L."""
        return self.segments_for_regions(self.regions_near(x, y, radius))

    def region_centres(self) -> np.ndarray:
        """(R, 2) area-weighted centroid of each region (holes subtracted)."""
        return self._query().centres

    def region_radii(self) -> np.ndarray:
        """(R,) distance from each region's centre to its farthest vertex."""
        return self._query().radii

    def region_areas(self) -> np.ndarray:
        """(R,) floor area of each region, square metres (holes subtracted)."""
        return self._query().areas

    def _query(self):
        if self._lookup is None:
            from linemap.regions import RegionLookup

            self._lookup = RegionLookup(self)
        return self._lookup


# --------------------------------------------------------------------------
# Writing


def save_map(path: str | os.PathLike, linemap: LineMap) -> int:
    """Write ``linemap`` to ``path`` atomically (temporary file, then rename).

    Returns the file size in bytes. On any failure nothing is left at ``path``
    (an existing file there stays as it was).
    """
    validate(linemap)
    blob = encode(linemap)
    write_atomic(path, blob)
    return len(blob)


def encode(m: LineMap) -> bytes:
    """The bytes of a ``.lmap`` file for ``m`` (see module docstring)."""
    n, r = m.n_segments, m.n_regions
    dq = _quantize_deltas(m.ring_points)
    dw = _quantize_deltas(m.wall_points)
    meta = dict(m.meta)
    meta["counts"] = {
        "segments": n,
        "regions": r,
        "rings": int(len(m.ring_region)),
        "points": int(len(m.ring_points)),
        "list_entries": int(len(m.list_indices)),
        "grid_entries": int(len(m.grid_regions)),
        "wall_rings": int(len(m.wall_is_hole)),
        "wall_points": int(len(m.wall_points)),
    }
    meta["grid"] = {
        "origin": [float(v) for v in m.grid_origin],
        "cell": float(m.grid_cell),
        "shape": [int(v) for v in m.grid_shape],
    }
    meta["coord_quantum_m"] = COORD_QUANTUM_M
    chunks = [
        (b"META", json.dumps(meta, sort_keys=True).encode("utf-8"), _ZLIB),
        (b"SEGM", np.asarray(m.segments, dtype="<f8").reshape(-1).tobytes(), _ZLIB),
        (b"KIND", np.asarray(m.kinds, dtype="u1").tobytes(), _ZLIB),
        (b"ROFF", np.asarray(m.ring_offsets, dtype="<u4").tobytes(), _ZLIB),
        (b"RREG", np.asarray(m.ring_region, dtype="<u4").tobytes(), _ZLIB),
        (b"RHOL", np.asarray(m.ring_is_hole, dtype="u1").tobytes(), _ZLIB),
        (b"RPTS", dq.astype("<i4").reshape(-1).tobytes(), _ZLIB),
        (b"VLST", _xor_bitsets(m.list_offsets, m.list_indices, n), _ZLIB),
        (b"GOFF", np.asarray(m.grid_offsets, dtype="<u4").tobytes(), _ZLIB),
        (b"GREG", np.asarray(m.grid_regions, dtype="<u4").tobytes(), _ZLIB),
        (b"WOFF", np.asarray(m.wall_offsets, dtype="<u4").tobytes(), _ZLIB),
        (b"WHOL", np.asarray(m.wall_is_hole, dtype="u1").tobytes(), _ZLIB),
        (b"WPTS", dw.astype("<i4").reshape(-1).tobytes(), _ZLIB),
    ]
    return write_chunks([(tag, codec, raw) for tag, raw, codec in chunks])


def write_chunks(chunks, raw_sizes: dict | None = None) -> bytes:
    """A file of ``chunks`` ``(tag, codec, payload)`` (payload before
    compression), with the header and checksums; ``raw_sizes`` (tag -> int)
    overrides the raw size a chunk declares (tests of hostile files)."""
    header = np.zeros((), dtype=_HEADER)
    header["magic"], header["major"], header["minor"] = MAGIC, FORMAT_MAJOR, FORMAT_MINOR
    header["n_chunks"] = len(chunks)
    out = [header.tobytes()]
    for tag, codec, raw in chunks:
        stored, size = _stored(raw, codec)
        ch = np.zeros((), dtype=_CHUNK)
        ch["tag"], ch["codec"], ch["raw_size"] = tag, codec, (raw_sizes or {}).get(tag, size)
        ch["stored_size"], ch["crc32"] = len(stored), zlib.crc32(stored)
        out += [ch.tobytes(), stored]
    return b"".join(out)


def _stored(raw, codec: int) -> tuple[bytes, int]:
    """A chunk's stored payload and its raw size; ``raw`` is bytes or an
    iterator of byte blocks (compressed as they come: the same bytes as
    compressing them joined, without holding them joined)."""
    if isinstance(raw, (bytes, bytearray, memoryview)):
        return (zlib.compress(raw, 9) if codec == _ZLIB else bytes(raw)), len(raw)
    if codec != _ZLIB:
        raw = b"".join(raw)
        return raw, len(raw)
    z, out, size = zlib.compressobj(9), [], 0
    for block in raw:
        out.append(z.compress(block))
        size += len(block)
    out.append(z.flush())
    return b"".join(out), size


def read_chunks(data: bytes) -> list[list]:
    """``[tag, codec, payload]`` (payload inflated) of each chunk of a
    well-formed file, for tools and tests that rewrite a map's chunks; it
    trusts the file (:func:`decode` is the reader that checks everything)."""
    header = np.frombuffer(data, dtype=_HEADER, count=1)[0]
    pos, out = _HEADER.itemsize, []
    for _ in range(int(header["n_chunks"])):
        ch = np.frombuffer(data, dtype=_CHUNK, count=1, offset=pos)[0]
        pos += _CHUNK.itemsize
        stored = data[pos:pos + int(ch["stored_size"])]
        pos += len(stored)
        out.append([bytes(ch["tag"]), int(ch["codec"]), zlib.decompress(stored) if int(ch["codec"]) == _ZLIB else stored])
    return out


def _quantize_deltas(points: np.ndarray) -> np.ndarray:
    """(P, 2) metres -> (P, 2) int64 deltas of quantised coordinates.

    The whole point stream is delta-encoded (first point from the origin):
    neighbouring vertices are close, so the stream compresses well."""
    q = np.round(np.asarray(points, dtype=np.float64).reshape(-1, 2) / COORD_QUANTUM_M).astype(np.int64)
    dq = np.diff(q, axis=0, prepend=np.zeros((1, 2), dtype=np.int64))
    if len(dq) and np.abs(dq).max() >= 2**31:
        raise LmapError("coordinates exceed the format's range (about 200 km from the origin); "
                        "move the drawing near (0, 0) in the CAD program")
    return dq


def _lists_to_bitsets(offsets: np.ndarray, indices: np.ndarray, n: int) -> np.ndarray:
    """CSR lists -> (R, ceil(N/8)) uint8 packed bitsets, bit i set if i is listed."""
    r = len(offsets) - 1
    dense = np.zeros((r, max(n, 1)), dtype=bool)
    rows = np.repeat(np.arange(r), np.diff(offsets))
    dense[rows, np.asarray(indices, dtype=np.int64)] = True
    return np.packbits(dense[:, :n] if n else dense[:, :0], axis=1, bitorder="little")


def _xor_bitsets(offsets: np.ndarray, indices: np.ndarray, n: int):
    """The VLST payload, a block of rows at a time (bytes blocks): each
    region's packed bitset (:func:`_lists_to_bitsets`) XOR-ed with the
    previous region's; neighbouring regions see nearly the same segments,
    so the stream is mostly zeros. Blocks of about 4 MB of dense rows: the
    whole (R, N) table of a large floor (80,000 regions of 40,000 segments)
    would take gigabytes."""
    offsets = np.asarray(offsets, dtype=np.int64)
    r = len(offsets) - 1
    block = max(1, (1 << 22) // max(n, 1))
    prev = np.zeros((1, (n + 7) // 8), dtype=np.uint8)
    for r0 in range(0, r, block):
        r1 = min(r, r0 + block)
        bits = _lists_to_bitsets(offsets[r0:r1 + 1] - offsets[r0], indices[offsets[r0]:offsets[r1]], n)
        x = bits.copy()
        x[0] ^= prev[0]
        x[1:] ^= bits[:-1]
        prev = bits[-1:]
        yield x.tobytes()


# --------------------------------------------------------------------------
# Reading


def load_map(path: str | os.PathLike) -> LineMap:
    """Read and fully validate a ``.lmap`` file.

    Raises :class:`LmapError` (a ``ValueError``) with a message that names the
    problem for a wrong magic, a newer version, truncation, a checksum
    mismatch or inconsistent contents; ``FileNotFoundError`` if it is absent.
    """
    path = Path(path)
    if path.is_dir():
        raise LmapError(f"{path} is a directory, not a .lmap file")
    data = path.read_bytes()
    return decode(data, name=str(path))


def decode(data: bytes, name: str = "<bytes>") -> LineMap:
    """Parse the bytes of a ``.lmap`` file (see :func:`load_map`)."""
    if len(data) < _HEADER.itemsize or data[:8] != MAGIC:
        raise LmapError(f"{name} is not a .lmap map (wrong magic); build one with 'mapkit build'")
    header = np.frombuffer(data, dtype=_HEADER, count=1)[0]
    major, minor = int(header["major"]), int(header["minor"])
    if major > FORMAT_MAJOR:
        raise LmapError(
            f"{name} is format {major}.{minor}, newer than this reader ({FORMAT_MAJOR}.x); "
            "upgrade mapkit or rebuild the map"
        )
    if major < 1:
        raise LmapError(f"{name} has invalid format version {major}.{minor}")
    pos = _HEADER.itemsize
    raw: dict[bytes, bytes] = {}
    budget = max(RAW_FLOOR_BYTES, MAX_INFLATION * len(data))  # bytes all chunks may inflate to
    n_chunks = int(header["n_chunks"])
    if n_chunks * _CHUNK.itemsize > len(data):
        raise LmapError(f"{name} is truncated or corrupt: it claims {n_chunks} chunks, more than its {len(data)} "
                        "bytes hold; rebuild or re-copy it")
    for i in range(n_chunks):
        if pos + _CHUNK.itemsize > len(data):
            raise LmapError(f"{name} is truncated (chunk {i} header missing); rebuild or re-copy it")
        ch = np.frombuffer(data, dtype=_CHUNK, count=1, offset=pos)[0]
        pos += _CHUNK.itemsize
        size = int(ch["stored_size"])
        tag = bytes(ch["tag"])
        label = tag.decode("ascii", "replace")
        if pos + size > len(data):
            raise LmapError(f"{name} is truncated (chunk {label} cut short); rebuild or re-copy it")
        stored = memoryview(data)[pos : pos + size]
        pos += size
        if zlib.crc32(stored) != int(ch["crc32"]):
            raise LmapError(f"{name} is corrupt: checksum mismatch in chunk {label}; rebuild or re-copy it")
        raw_size = int(ch["raw_size"])
        if raw_size > budget:
            raise LmapError(f"{name} is corrupt: chunk {label} claims {raw_size} bytes, more than a map of "
                            f"{len(data)} bytes can hold; rebuild or re-copy it")
        budget -= raw_size
        chunk = _Chunk(stored, int(ch["codec"]), raw_size, name, label)
        if chunk.codec not in (_ZLIB, _RAW):
            raise LmapError(f"{name} uses unknown codec {chunk.codec} in chunk {label}")
        # The visible lists are read a block of rows at a time as they are
        # inflated (_lists_from_bitsets): whole, they are regions x segments
        # / 8 bytes (416 MB for an office of 40 x 40 rooms).
        raw[tag] = chunk if tag == b"VLST" else b"".join(chunk.blocks(raw_size))
    if pos != len(data):
        raise LmapError(f"{name} has {len(data) - pos} unexpected trailing bytes; re-copy it")
    return _from_chunks(raw, name, (major, minor))


class _Chunk:
    """A chunk's stored payload (checksum checked), inflated on demand a
    block at a time; ``name`` (the file) and ``label`` (the tag) are for errors."""

    def __init__(self, stored: memoryview, codec: int, raw_size: int, name: str, label: str):
        self.stored, self.codec, self.raw_size = stored, codec, raw_size
        self.name, self.label = name, label

    def __len__(self) -> int:
        return self.raw_size

    def blocks(self, block_bytes: int):
        """The raw payload as ``bytes`` blocks of ``block_bytes`` (the last
        shorter). Never inflates more than a block plus one byte past the
        size the header states: a corrupt or hostile chunk cannot inflate to
        gigabytes before it is rejected."""
        if self.codec == _RAW:
            if len(self.stored) != self.raw_size:
                raise LmapError(f"{self.name} is corrupt: chunk {self.label} has the wrong size")
            for p in range(0, self.raw_size, max(block_bytes, 1)):
                yield bytes(self.stored[p:p + block_bytes])
            return
        inflate, tail, left = zlib.decompressobj(), self.stored, self.raw_size
        wrong_size = LmapError(f"{self.name} is corrupt: chunk {self.label} has the wrong size")
        try:
            while left:
                want = min(block_bytes, left)
                out = inflate.decompress(tail, want)
                tail = inflate.unconsumed_tail
                while len(out) < want and tail:
                    out += inflate.decompress(tail, want - len(out))
                    tail = inflate.unconsumed_tail
                if len(out) != want:  # the stream ended early
                    raise wrong_size
                left -= want
                yield out
            extra = inflate.decompress(tail, 1)
        except zlib.error as exc:
            raise LmapError(f"{self.name} is corrupt: chunk {self.label} does not decompress ({exc})") from None
        if extra or not inflate.eof:
            raise wrong_size


def _need(raw: dict[bytes, bytes], tag: bytes, name: str) -> bytes:
    if tag not in raw:
        raise LmapError(f"{name} lacks the {tag.decode()} chunk; rebuild it with 'mapkit build'")
    return raw[tag]


def _array(raw, tag, dtype, count, name, width=1) -> np.ndarray:
    buf = _need(raw, tag, name)
    dt = np.dtype(dtype)
    if len(buf) != dt.itemsize * count * width:
        raise LmapError(
            f"{name} is inconsistent: chunk {tag.decode()} holds {len(buf) // dt.itemsize} values, "
            f"expected {count * width}"
        )
    return np.frombuffer(buf, dtype=dt)


def _from_chunks(raw: dict[bytes, bytes], name: str, version: tuple[int, int]) -> LineMap:
    meta_bytes = _need(raw, b"META", name)
    if len(meta_bytes) > MAX_META_BYTES or _json_depth(meta_bytes) > MAX_META_DEPTH:
        raise LmapError(f"{name} has an unreadable META chunk (too large or nested too deeply); rebuild it")
    try:
        meta = json.loads(meta_bytes.decode("utf-8"))
        counts, grid = meta["counts"], meta["grid"]
        n, r, k, p = (int(counts[key]) for key in ("segments", "regions", "rings", "points"))
        n_list, n_grid = int(counts["list_entries"]), int(counts["grid_entries"])
        n_wall_rings, n_wall_points = int(counts["wall_rings"]), int(counts["wall_points"])
        ny, nx = (int(v) for v in grid["shape"])
        origin = np.asarray(grid["origin"], dtype=np.float64)
        cell = float(grid["cell"])
        quantum = float(meta["coord_quantum_m"])
    except (ValueError, KeyError, TypeError, OverflowError, RecursionError) as exc:
        raise LmapError(f"{name} has an unreadable META chunk ({exc}); rebuild it") from None
    if min(n, r, k, p, n_list, n_grid, ny, nx, n_wall_rings, n_wall_points) < 0 or origin.shape != (2,) or not cell > 0:
        raise LmapError(f"{name} has impossible counts in META; rebuild it")
    file_bytes = sum(len(v) for v in raw.values())
    if n_list > MAX_LIST_ENTRIES_PER_BYTE * max(file_bytes, 1 << 16):
        raise LmapError(f"{name} claims {n_list} visible-list entries, more than a map of its size holds; rebuild it")
    _check_meta(meta, name)

    segments = _array(raw, b"SEGM", "<f8", n, name, 6).astype(np.float64).reshape(n, 2, 3)
    kinds = _array(raw, b"KIND", "u1", n, name).copy()
    ring_offsets = _array(raw, b"ROFF", "<u4", k + 1, name).astype(np.int64)
    ring_region = _array(raw, b"RREG", "<u4", k, name).astype(np.int64)
    ring_is_hole = _array(raw, b"RHOL", "u1", k, name).astype(bool)
    dq = _array(raw, b"RPTS", "<i4", p, name, 2).astype(np.int64).reshape(p, 2)
    ring_points = np.cumsum(dq, axis=0).astype(np.float64) * quantum
    nbytes = (n + 7) // 8
    vlst = _need(raw, b"VLST", name)
    if len(vlst) != r * nbytes:
        raise LmapError(f"{name} is inconsistent: chunk VLST holds {len(vlst)} values, expected {r * nbytes}")
    list_offsets, list_indices = _lists_from_bitsets(vlst, r, n, n_list, name)
    grid_offsets = _array(raw, b"GOFF", "<u4", ny * nx + 1, name).astype(np.int64)
    grid_regions = _array(raw, b"GREG", "<u4", n_grid, name).astype(np.int64)
    wall_offsets = _array(raw, b"WOFF", "<u4", n_wall_rings + 1, name).astype(np.int64)
    wall_is_hole = _array(raw, b"WHOL", "u1", n_wall_rings, name).astype(bool)
    dw = _array(raw, b"WPTS", "<i4", n_wall_points, name, 2).astype(np.int64).reshape(n_wall_points, 2)
    wall_points = np.cumsum(dw, axis=0).astype(np.float64) * quantum

    m = LineMap(segments=segments, kinds=kinds, ring_points=ring_points, ring_offsets=ring_offsets,
                ring_region=ring_region, ring_is_hole=ring_is_hole, list_offsets=list_offsets,
                list_indices=list_indices, grid_origin=origin, grid_cell=cell, grid_shape=(ny, nx),
                grid_offsets=grid_offsets, grid_regions=grid_regions, wall_points=wall_points,
                wall_offsets=wall_offsets, wall_is_hole=wall_is_hole, meta=meta, version=version)
    if len(list_indices) != n_list:
        raise LmapError(f"{name} is inconsistent: {len(list_indices)} list entries, META says {n_list}")
    validate(m, name)
    return m


def _lists_from_bitsets(vlst: _Chunk, r: int, n: int, n_list: int, name: str) -> tuple[np.ndarray, np.ndarray]:
    """``(offsets (R+1,), indices (<= n_list,))`` of the visible lists from
    the VLST chunk (``r`` XOR-ed bitsets of ``n`` bits), inflated and
    expanded a block of rows at a time: memory stays near the output's
    (``n_list`` int64, plus the blocks' int32 before they are joined), not
    the table's (``r x n / 8`` bytes); more entries than META's ``n_list``
    are refused before they are stored (nothing is allocated from META's
    word: a crafted count could ask for gigabytes)."""
    nbytes = (n + 7) // 8
    counts = np.zeros(r, dtype=np.int64)
    parts, prev, total, r0 = [], None, 0, 0
    block = max(1, (1 << 22) // max(n, 1))  # rows of about 4 M bits: 4 MB once unpacked
    for raw in vlst.blocks(block * nbytes):
        chunk = np.frombuffer(raw, dtype=np.uint8).reshape(-1, nbytes)
        if prev is not None:
            chunk = chunk.copy()
            chunk[0] ^= prev
        bits = np.bitwise_xor.accumulate(chunk, axis=0)
        prev = bits[-1]
        rows, cols = _set_bits(bits, n)
        if total + len(cols) > n_list:
            raise LmapError(f"{name} is inconsistent: its visible lists hold more than the {n_list} entries META "
                            "says; rebuild it with 'mapkit build'")
        parts.append(cols.astype(np.int32 if n < 2**31 else np.int64))  # half the memory until joined
        total += len(cols)
        counts[r0:r0 + len(chunk)] = np.bincount(rows, minlength=len(chunk))
        r0 += len(chunk)
    offsets = np.zeros(r + 1, dtype=np.int64)
    np.cumsum(counts, out=offsets[1:])
    return offsets, (np.concatenate(parts).astype(np.int64) if parts else np.zeros(0, dtype=np.int64))


def _set_bits(bits: np.ndarray, n: int) -> tuple[np.ndarray, np.ndarray]:
    """``(rows, cols)`` of the set bits among the first ``n`` of each row of
    ``bits`` (rows, ceil(n / 8)) uint8 little-bit-order bitsets, row by row
    in ascending column order. Only the non-zero bytes are unpacked: a list
    names a few dozen of tens of thousands of segments."""
    r_idx, b_idx = np.nonzero(bits)
    k, bit = np.nonzero(np.unpackbits(bits[r_idx, b_idx][:, None], axis=1, bitorder="little"))
    rows, cols = r_idx[k], b_idx[k] * 8 + bit
    keep = cols < n  # the padding bits of the last byte are not segments
    return rows[keep], cols[keep]


def _json_depth(text: bytes) -> int:
    """The deepest nesting of brackets and braces in JSON ``text`` (an upper
    bound: brackets inside strings count too)."""
    depth = best = 0
    for c in text.translate(None, b'"\\:,0123456789.eE+-truefalsn \n\t'):
        if c in b"[{":
            depth += 1
            best = max(best, depth)
        elif c in b"]}" and depth:
            depth -= 1
    return best


#: The JSON types each META entry the commands read (``mapkit info``,
#: ``view``) may have, when present. ``source`` is the plan's file name or
#: (what ``mapkit build`` writes) an object with the string ``name``.
META_TYPES = {"units": (str,), "generator": (str,), "source": (str, dict), "build": (dict,), "scene": (dict,),
              "stats": (dict,)}
_JSON_TYPE_NAMES = {str: "string", dict: "object"}


def _check_meta(meta, name: str) -> None:
    """The parts of META that readers use: an object, the entries of
    :data:`META_TYPES` of their types, a positive finite wall height, cameras
    that are valid cameras, the origin offset of a georeferenced plan."""
    def bad(msg: str) -> LmapError:
        return LmapError(f"{name} has an invalid META chunk: {msg}; rebuild it with 'mapkit build'")

    if not isinstance(meta, dict):
        raise bad("it is not a JSON object")
    for key, kinds in META_TYPES.items():
        if key in meta and not isinstance(meta[key], kinds):
            wanted = " or ".join(f"a JSON {_JSON_TYPE_NAMES[k]}" for k in kinds)
            raise bad(f"{key} must be {wanted}, got {str(meta[key])[:80]!r}")
    if isinstance(meta.get("source"), dict) and not isinstance(meta["source"].get("name"), str):
        raise bad("source lacks its file name (a string 'name')")
    wh = meta.get("wall_height")
    if wh is not None and not (isinstance(wh, (int, float)) and not isinstance(wh, bool) and math.isfinite(wh)
                               and wh > 0):
        raise bad(f"wall_height must be a positive number of metres, got {wh!r}")
    offset = meta.get("origin_offset_m")
    if offset is not None and not (isinstance(offset, list) and len(offset) == 2 and all(
            isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v) for v in offset)):
        raise bad(f"origin_offset_m must be two finite numbers of metres, got {offset!r}")
    build = meta.get("build")
    for where, cam in (("camera", meta.get("camera")), ("build camera", build.get("camera")
                                                        if isinstance(build, dict) else None)):
        if cam is None:
            continue
        if not isinstance(cam, dict):
            raise bad(f"{where} must be an object")
        for key in ("width", "height", "fx", "fy", "cx", "cy", "height_m", "pitch_deg"):
            v = cam.get(key)
            if not (isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)):
                raise bad(f"{where} lacks a numeric {key}")
        try:
            Camera.from_dict(cam)
        except CameraError as exc:
            raise bad(f"{where}: {exc}") from None


def validate(m: LineMap, name: str = "map") -> None:
    """Check shapes, finiteness and every index range; raise :class:`LmapError`."""
    n, r = m.n_segments, m.n_regions

    def bad(msg: str) -> LmapError:
        return LmapError(f"{name} is inconsistent: {msg}; rebuild it with 'mapkit build'")

    if m.segments.shape != (n, 2, 3) or not np.isfinite(m.segments).all():
        raise bad("segments must be a finite (N, 2, 3) array")
    # The largest coordinate difference, not the norm: squaring a crafted
    # map's 1e155 m coordinates would overflow (a numpy warning on stderr).
    if n and (np.abs(m.segments[:, 1] - m.segments[:, 0]).max(axis=1) < 1e-9).any():
        raise bad("a segment has zero length")
    if m.kinds.shape != (n,) or (n and int(m.kinds.max()) >= len(SegmentKind)):
        raise bad("segment kinds out of range")
    k = len(m.ring_region)
    offs = m.ring_offsets
    if offs.shape != (k + 1,) or (k + 1 and offs[0] != 0) or offs[-1] != len(m.ring_points):
        raise bad("ring offsets do not cover the ring points")
    if k and (np.diff(offs) < 3).any():
        raise bad("a region ring has fewer than 3 points")
    if k and ((m.ring_region >= r).any() or (np.diff(m.ring_region) < 0).any()):
        raise bad("ring region ids out of range or unsorted")
    if r and k and len(np.unique(m.ring_region)) != r:
        raise bad("a region has no outline")
    if m.ring_is_hole.shape != (k,):
        raise bad("ring hole flags have the wrong length")
    lo = m.list_offsets
    if lo.shape != (r + 1,) or lo[0] != 0 or lo[-1] != len(m.list_indices) or (np.diff(lo) < 0).any():
        raise bad("visibility list offsets are malformed")
    if len(m.list_indices) and (m.list_indices.min() < 0 or m.list_indices.max() >= n):
        raise bad("a visibility list names a segment that does not exist")
    ny, nx = m.grid_shape
    if np.shape(m.grid_origin) != (2,) or not np.isfinite(m.grid_origin).all():
        raise bad("the lookup grid's origin must be two finite numbers")
    if not (math.isfinite(m.grid_cell) and m.grid_cell > 0):
        raise bad("the lookup grid's cell must be a positive number of metres")
    go = m.grid_offsets
    if go.shape != (ny * nx + 1,) or go[0] != 0 or go[-1] != len(m.grid_regions) or (np.diff(go) < 0).any():
        raise bad("lookup grid offsets are malformed")
    if len(m.grid_regions) and (m.grid_regions.max() >= r):
        raise bad("the lookup grid names a region that does not exist")
    if not np.isfinite(m.ring_points).all():
        raise bad("region outlines hold non-finite coordinates")
    w = len(m.wall_is_hole)
    wo = m.wall_offsets
    if wo.shape != (w + 1,) or wo[0] != 0 or wo[-1] != len(m.wall_points) or (np.diff(wo) < 3).any():
        raise bad("wall outline offsets are malformed")
    if not np.isfinite(m.wall_points).all():
        raise bad("wall outlines hold non-finite coordinates")
    xy = [a.reshape(-1, 2) for a in (m.segments[..., :2], m.ring_points, m.wall_points) if a.size]
    if xy:
        span = float(np.ptp(np.concatenate([np.min(a, axis=0, keepdims=True) for a in xy]
                                           + [np.max(a, axis=0, keepdims=True) for a in xy]), axis=0).max())
        if span > MAX_EXTENT_M:
            raise bad(f"it spans {span:.3g} m, more than any building ({MAX_EXTENT_M:g} m, linemap.lmap.MAX_EXTENT_M)")


def file_sha256(path: str | os.PathLike) -> str:
    """Hex SHA-256 of a file: recorded in META to tie a map to its source plan."""
    h = hashlib.sha256()
    with open(path, "rb") as fh:
        for block in iter(lambda: fh.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()
