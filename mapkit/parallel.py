"""Vectorised shapely calls over chunks of their arrays, in a few threads.

Shapely 2 releases the GIL inside its vectorised calls, so GEOS work on
different chunks of an array runs on different cores. Every element's result
is computed by the same call on the same inputs whichever chunk it falls in,
and the chunks' results are put back in order: the output is the output of
one call on the whole arrays, bit for bit.

GEOS geometries may be read by several threads at once, with one exception:
a *prepared* geometry builds its indexes on first use, unguarded. Chunks that
run at the same time must not share a prepared geometry: :func:`map_owned`
groups rows by the geometry they use.
"""

from __future__ import annotations

import os
import threading

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


def map_chunks(fn, arrays, workers: int):
    """``fn(*arrays)``, computed as ``fn(*(a[i:j] for a in arrays))`` over
    consecutive chunks ``[i, j)`` in ``workers`` threads, the results
    concatenated in order (``fn`` returns an array, or a tuple of arrays
    concatenated member by member).

    ``fn`` must treat rows independently. ``CHUNKS_PER_WORKER`` even chunks
    per thread. With ``workers <= 1``: ``fn(*arrays)``, one call."""
    arrays = list(arrays)
    n = len(arrays[0])
    if workers <= 1 or n < 2:
        return fn(*arrays)
    bounds = np.linspace(0, n, workers * CHUNKS_PER_WORKER + 1).astype(np.int64)
    cuts = [(int(i), int(j)) for i, j in zip(bounds[:-1], bounds[1:]) if j > i]
    if len(cuts) < 2:
        return fn(*arrays)
    parts = run_all([lambda i=i, j=j: fn(*(a[i:j] for a in arrays)) for i, j in cuts], workers)
    if isinstance(parts[0], tuple):
        return tuple(np.concatenate(p) for p in zip(*parts))
    return np.concatenate(parts)


def map_owned(fn, owner: np.ndarray, n_owners: int, workers: int, dtype=bool) -> np.ndarray:
    """``fn(rows)`` (one result per row of ``rows``) over groups of rows in
    ``workers`` threads, the results put back in row order: (R,) ``dtype``.

    Each group holds every row of the owners it has (``owner`` (R,) ints
    below ``n_owners``, e.g. the prepared geometry a row tests), so groups
    running at once share no owner; owners go to groups in order, about
    equal row counts each. A group's rows are found when it runs, so only
    the running groups' index arrays exist at a time."""
    out = np.empty(len(owner), dtype=dtype)
    n_groups = max(1, workers * CHUNKS_PER_WORKER)
    count = np.bincount(owner, minlength=n_owners)
    before = np.cumsum(count) - count
    # Owner k goes to the group holding its first row's share of the rows.
    group = (before * n_groups // max(1, len(owner))).astype(np.int16)[owner]

    def run(g: int) -> None:
        rows = np.flatnonzero(group == g)
        if len(rows):
            out[rows] = fn(rows)  # rows of other groups are other elements

    run_all([lambda g=g: run(g) for g in range(n_groups)], workers)
    return out


def run_all(tasks: list, workers: int) -> list:
    """Call every task (callables without arguments), in order of the list,
    in the calling thread and ``workers - 1`` others; their results in task
    order. The calling thread works too: one thread fewer, and one malloc
    arena fewer (glibc gives each thread its own heap, and GEOS's many small
    blocks fragment it)."""
    results: list = [None] * len(tasks)
    todo = iter(range(len(tasks)))
    lock = threading.Lock()
    errors: list = []

    def work() -> None:
        while not errors:
            with lock:
                k = next(todo, None)
            if k is None:
                return
            try:
                results[k] = tasks[k]()
            except BaseException as exc:  # re-raised in the calling thread
                errors.append(exc)

    others = [threading.Thread(target=work, daemon=True) for _ in range(min(workers, len(tasks)) - 1)]
    for t in others:
        t.start()
    work()
    for t in others:
        t.join()
    if errors:
        raise errors[0]
    return results


__all__ = ["default_jobs", "map_chunks", "map_owned", "run_all"]
