"""Whether a matcher's answer on a simulated frame is right: the true pairs
of the frame, and the pairs the image cannot tell from true ones (two door
jambs one behind the other on the same image column). Used by the
benchmarks (``tools/bench_paper.py``, ``tools/bench_budget.py``) and the
attitude tests."""

from __future__ import annotations

import math

import numpy as np


def is_correct(matches, truth_pairs, min_matches: int = 3, equivalent=None) -> bool:
    """Every match is a true pair; with ``equivalent`` (a set of pairs), a
    pair in it counts as true too (see :func:`indistinguishable`)."""
    s = {tuple(m) for m in matches}
    ok = truth_pairs if equivalent is None else truth_pairs | equivalent
    return len(s) >= min_matches and s <= ok


def level_view(camera, frame):
    """``(camera, frame)`` as the matcher sees them once the frame's own
    pitch and roll are known: the nominal camera (the file's pitch, no
    roll) and the frame's lines moved to it (:mod:`matcher.attitude`); the
    camera and frame themselves for a level frame of an exact camera."""
    from dataclasses import replace

    from matcher import attitude

    if frame.pitch_deg == camera.pitch_deg and frame.roll_deg == camera.roll_deg and not camera.attitude_free:
        return camera, frame
    att = attitude.Attitude(math.radians(frame.pitch_deg), math.radians(frame.roll_deg), 0.0, 0.0)
    return attitude.nominal(camera), replace(frame, lines=attitude.rectify(camera, frame.lines, att))


def indistinguishable(linemap, camera, frame) -> set:
    """Pairs (segment, line) that the image cannot tell from a true pair: the
    line lies on the segment's projection at the true pose (within the
    matcher's fit bound, inside its extent) and the segment is in plain sight.
    Two door jambs or corners one behind the other on the same image column
    are the usual case: swapping them changes nothing in the image."""
    from matcher.stage2.fit import fits, visible
    from matcher.tolerances import DEFAULT

    x, y, yaw = frame.pose
    ids = linemap.candidate_segments(x, y, 0.01)
    if len(ids) == 0:
        return set()
    j = np.arange(len(frame.lines))
    si, li = np.repeat(ids, len(j)), np.tile(j, len(ids))
    poses = np.repeat([[x, y, math.radians(yaw)]], len(si), axis=0)

    class _Img:
        lines = frame.lines

    ok = fits(camera, _Img, poses, linemap.segments[si], li, DEFAULT)[0]
    sel = np.nonzero(ok)[0]
    walls = None
    from matcher.map_geometry.occlusion import wall_edges

    walls = wall_edges(linemap)
    ok[sel] &= visible(camera, poses[sel], linemap.segments[si[sel]], frame.lines[li[sel]], walls, DEFAULT.stage2, DEFAULT.shared)
    return {(int(a), int(b)) for a, b in zip(si[ok], li[ok])}
