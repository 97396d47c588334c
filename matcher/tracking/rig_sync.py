"""The images of a rig's cameras grouped into instants by their time stamps.

A bag holds each camera's images on its own topic; the cameras of a rig
may be triggered together or run free. An *instant* is one image a camera
taken within ``tolerance_s`` of the instant's earliest image: the
tolerance is ``Tracking.rig_sync_share`` (a half) of the slowest camera's
frame period (:func:`sync_tolerance`), so two images of one camera never
fall in one instant and images of the same trigger always do. An instant
that misses a camera is given with that camera's entry None (the tracker's
reader skips it, saying which camera is missing).

The grouping streams: an instant is decided once every camera has an image
after it (a camera's images come in time order), or once an image more
than ``Tracking.rig_sync_wait_s`` past it has come from any camera (a
camera that stopped does not hold the run back, nor every image in
memory).
"""

from __future__ import annotations

import math
from collections import deque
from collections.abc import Iterable, Iterator

import numpy as np

from matcher.tolerances import TRACKING, Tracking


def sync_tolerance(times_per_camera: list[list[float]], settings: Tracking = TRACKING) -> float:
    """The grouping tolerance, seconds: ``settings.rig_sync_share`` of the
    slowest camera's frame period, the median gap between its
    ``times_per_camera`` (seconds, a sample of each camera's first images);
    infinite when no camera has two images (each camera's one image is one
    instant)."""
    periods = [float(np.median(np.diff(np.sort(ts)))) for ts in times_per_camera if len(ts) >= 2]
    periods = [p for p in periods if p > 0]
    return settings.rig_sync_share * max(periods) if periods else math.inf


def instants(stream: Iterable[tuple[int, float, object]], n_cameras: int, tolerance_s: float,
             settings: Tracking = TRACKING) -> Iterator[tuple[float, list]]:
    """Group ``stream``, ``(camera index, time s, item)`` in arrival order
    (each camera's in time order), into instants ``(time, items)``: the
    mean time of the instant's images and one item per camera (None for a
    camera with no image within ``tolerance_s`` of the instant's first)."""
    pending: list[deque] = [deque() for _ in range(n_cameras)]
    newest = -math.inf
    for k, t, item in stream:
        pending[k].append((t, item))
        newest = max(newest, t)
        while any(pending) and (all(pending) or newest > _first(pending) + tolerance_s + settings.rig_sync_wait_s):
            yield _take(pending, tolerance_s)
    while any(pending):
        yield _take(pending, tolerance_s)


def _first(pending: list[deque]) -> float:
    return min(q[0][0] for q in pending if q)


def _take(pending: list[deque], tolerance_s: float) -> tuple[float, list]:
    """The earliest instant of ``pending``, taken off it."""
    t0 = _first(pending)
    taken = [q.popleft() if q and q[0][0] <= t0 + tolerance_s else None for q in pending]
    times = [e[0] for e in taken if e is not None]
    return sum(times) / len(times), [None if e is None else e[1] for e in taken]
