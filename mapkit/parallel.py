"""Vectorised shapely calls over chunks of their arrays, in a few threads.

Shapely 2 releases the GIL inside its vectorised calls, so GEOS work on
different chunks of an array runs on different cores. Every element's result
is computed by the same call on the same inputs whichever chunk it falls in,
and the chunks' results are put back in order: the output is the output of
one call on the whole arrays, bit for bit.

GEOS geometries may be read by several threads at once, with one exception:
a *prepared* geometry builds its indexes on first use, unguarded. Chunks that
run at the same time must not share a prepared geometry (split by geometry,
see ``bounds``).
"""

from __future__ import annotations

import os
from concurrent.futures import ThreadPoolExecutor

import numpy as np

#: The default number of threads is the number of cores this process may
#: run on, but at most this many (GEOS overlays gain little past it, and
#: each thread holds its own chunk's temporaries).
MAX_DEFAULT_JOBS = 4

#: Chunks per thread when the arrays are split evenly: a thread that gets
#: the slow chunks (many vertices) is not left alone at the end.
CHUNKS_PER_WORKER = 4


def default_jobs() -> int:
    """The number of cores available to this process, at most ``MAX_DEFAULT_JOBS``."""
    try:
        cores = len(os.sched_getaffinity(0))
    except AttributeError:  # no affinity on this platform (macOS, Windows)
        cores = os.cpu_count() or 1
    return max(1, min(cores, MAX_DEFAULT_JOBS))


def map_chunks(fn, arrays, workers: int, bounds=None):
    """``fn(*arrays)``, computed as ``fn(*(a[i:j] for a in arrays))`` over
    consecutive chunks ``[i, j)`` in ``workers`` threads, the results (1-D
    arrays, one element per row) concatenated in order.

    ``fn`` must treat rows independently. ``bounds`` (K + 1,) ints, the chunk
    boundaries (from 0 to the row count); by default ``CHUNKS_PER_WORKER``
    even chunks per thread. With ``workers <= 1``: ``fn(*arrays)``, one call."""
    arrays = list(arrays)
    n = len(arrays[0])
    if workers <= 1 or n < 2:
        return fn(*arrays)
    if bounds is None:
        bounds = np.linspace(0, n, workers * CHUNKS_PER_WORKER + 1).astype(np.int64)
    cuts = [(int(i), int(j)) for i, j in zip(bounds[:-1], bounds[1:]) if j > i]
    if len(cuts) < 2:
        return fn(*arrays)
    with ThreadPoolExecutor(max_workers=min(workers, len(cuts))) as pool:
        parts = list(pool.map(lambda c: fn(*(a[c[0] : c[1]] for a in arrays)), cuts))
    return np.concatenate(parts)


def split_by_owner(owner: np.ndarray, n_owners: int, workers: int) -> tuple[np.ndarray, np.ndarray]:
    """Chunks of rows such that no two chunks share an owner (a prepared
    geometry), with about equal row counts: returns ``(order, bounds)``,
    the rows grouped by chunk (in their order within each) and the chunk
    boundaries in ``order``, for :func:`map_chunks`."""
    n_chunks = max(1, workers * CHUNKS_PER_WORKER)
    count = np.cumsum(np.bincount(owner, minlength=n_owners))
    # Owner k goes to the chunk holding its first row's share of the rows.
    chunk_of_owner = (np.concatenate([[0], count[:-1]]) * n_chunks // max(1, len(owner))).astype(np.int16)
    chunk = chunk_of_owner[owner]
    order = np.argsort(chunk, kind="stable")  # a radix sort on 16-bit keys
    bounds = np.searchsorted(chunk[order], np.arange(n_chunks + 1))
    return order, bounds


__all__ = ["default_jobs", "map_chunks", "split_by_owner"]
