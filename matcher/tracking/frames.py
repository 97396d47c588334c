"""Frames of a run from a JSON Lines file: one frame a line.

    {"t": 12.5, "odom": [x, y, yaw_deg], "lines": [[u1, v1, u2, v2], ...]}
    {"t": 12.7, "odom": [x, y, yaw_deg], "image": "frames/000123.png"}

``t`` in seconds, ``odom`` the robot's pose in the odometry's own frame
(metres, degrees), ``lines`` undistorted pixels, or ``image`` a path
(relative to the JSON Lines file) whose lines are detected with LSD. A rig's
frame gives each camera's lines or image, one entry a camera in the rig's
order:

    {"t": 12.5, "odom": [x, y, yaw_deg], "cameras": [{"lines": [[u1, v1, u2, v2], ...]}, {"image": "f/1.png"}]}

Blank lines are passed over. A line that cannot be read (or a rig's frame
with entries for another number of cameras) is a frame with its ``error``
set, not the end of the run: a log with one damaged line is still worth
following.
"""

from __future__ import annotations

import json
import math
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from linemap.errors import InputError


@dataclass
class FrameInput:
    """One frame to track: time ``t`` (seconds), odometry ``odom`` ``(x, y,
    yaw_deg)`` or None, image ``lines`` (M, 2, 2) pixels (a rig's frame: a
    list of them, one a camera), ``where`` it came from (for messages), and
    ``error``: why it cannot be used, or ''."""

    t: float
    odom: tuple[float, float, float] | None
    lines: np.ndarray | list | None
    where: str
    error: str = ""


def count_frames(path: str | Path) -> int:
    """Non-blank lines of a JSON Lines file (for a progress bar)."""
    with open(path, "rb") as f:
        return sum(1 for line in f if line.strip())


def check_run_file(path: str | Path) -> None:
    """InputError unless ``path`` holds at least one frame of a run (a JSON
    object with ``"t"`` and ``"odom"`` on one line): a log with damaged lines
    is still followed, but a file with no frame at all (a lines file, a
    camera file, a pretty-printed JSON) is the wrong file, not a run whose
    every frame is skipped."""
    path = Path(path)
    first_problem = ""
    with open(path, "rb") as f:
        for number, raw in enumerate(f, 1):
            if not raw.strip():
                continue
            try:
                d = json.loads(raw)
            except (json.JSONDecodeError, UnicodeDecodeError, RecursionError):
                d = None
            if isinstance(d, dict) and "t" in d and "odom" in d:
                return
            first_problem = first_problem or f"line {number} is {_what_json_is(d)}"
    whole = _whole_json(path)
    what = ("it is a lines file, for 'matcher localize --lines'" if isinstance(whole, dict) and "lines" in whole
            else first_problem or "empty")
    raise InputError(f'{path} holds no frame of a run: {what}; --frames takes JSON Lines, one frame a line: '
                     '{"t": SECONDS, "odom": [x, y, yaw_deg], "lines": [[u1, v1, u2, v2], ...]}, or a ROS bag')


def _what_json_is(d) -> str:
    if d is None:
        return "not JSON"
    if isinstance(d, dict):
        return f"an object without \"t\" and \"odom\" (keys {', '.join(sorted(map(str, d))[:4]) or 'none'})"
    return f"a JSON {type(d).__name__}, not an object"


def _whole_json(path: Path):
    """The file read as one JSON document, or None (a file too large to be a
    lines file is not read whole)."""
    if path.stat().st_size > 64 << 20:
        return None
    try:
        return json.loads(path.read_bytes())
    except (json.JSONDecodeError, UnicodeDecodeError, RecursionError):
        return None


def read_jsonl(path: str | Path, detect=None, rig=None) -> Iterator[FrameInput]:
    """The frames of a JSON Lines file. ``detect(image_path) -> lines``
    turns an ``image`` entry into lines (it may raise InputError, which
    becomes the frame's error); without it an image frame is an error.
    With a ``rig`` (:class:`~linemap.rig.Rig`) the frames are its frames
    (``"cameras"``, one entry a camera) and ``detect(image_path, k)`` takes
    the index of the camera that saw the image."""
    path = Path(path)
    with open(path, "rb") as f:
        for number, raw in enumerate(f, 1):
            if raw.strip():
                yield _frame(raw, f"{path.name} line {number}", path.parent, detect, rig)


def _frame(raw: bytes, where: str, folder: Path, detect, rig) -> FrameInput:
    def bad(why: str, t=math.nan, odom=None) -> FrameInput:
        return FrameInput(t, odom, None, where, why)

    try:
        d = json.loads(raw)
    except (json.JSONDecodeError, UnicodeDecodeError, RecursionError) as exc:
        return bad(f"not valid JSON ({'nested too deeply' if isinstance(exc, RecursionError) else exc})")
    if not isinstance(d, dict):
        return bad('a frame must be a JSON object {"t": ..., "odom": [...], "lines": [...]}')
    t = d.get("t")
    if isinstance(t, bool) or not isinstance(t, (int, float)) or not math.isfinite(t):
        return bad(f'"t" must be the frame\'s time in seconds, got {t!r}')
    odom = d.get("odom")
    if not (isinstance(odom, list) and len(odom) == 3
            and all(isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v) for v in odom)):
        return bad(f'"odom" must be [x, y, yaw_deg], got {odom!r}' if "odom" in d else 'no "odom" [x, y, yaw_deg]', t)
    odom = (float(odom[0]), float(odom[1]), float(odom[2]))
    if rig is not None or "cameras" in d:
        lines, why = _rig_lines(d, rig, folder, detect)
        return bad(why, t, odom) if why else FrameInput(float(t), odom, lines, where)
    if ("lines" in d) == ("image" in d):
        return bad('a frame needs "lines" or "image" (one of them)', t, odom)
    if "lines" in d:
        lines = d["lines"]
        if not _line_list(lines):
            return bad('"lines" must be [[u1, v1, u2, v2], ...] pixels', t, odom)
        return FrameInput(float(t), odom, lines, where)
    image = d["image"]
    if not isinstance(image, str) or not image:
        return bad(f'"image" must be a path, got {image!r}', t, odom)
    if detect is None:
        return bad("image frames need a camera to detect lines with", t, odom)
    try:
        return FrameInput(float(t), odom, detect(folder / image), where)
    except InputError as exc:
        return bad(str(exc), t, odom)


def _rig_lines(d: dict, rig, folder: Path, detect) -> tuple[list | None, str]:
    """``(lines per camera, '')`` of a rig's frame ``d``, or ``(None, why)``
    it cannot be used."""
    if rig is None:
        return None, 'a frame with "cameras" is a camera rig\'s: track it with --rig RIG'
    names = f"{len(rig)}: {', '.join(rig.names)}"
    cams = d.get("cameras")
    if "lines" in d or "image" in d or not isinstance(cams, list):
        return None, f'a rig\'s frame needs "cameras": [{{"lines": ...}} or {{"image": ...}}, ...], one a camera ({names})'
    if len(cams) != len(rig):
        return None, (f"the frame has {len(cams)} camera{'s' * (len(cams) != 1)}, the rig has {names}; "
                      "give one entry per camera, in the rig's order")
    out = []
    for k, (entry, name) in enumerate(zip(cams, rig.names)):
        if not isinstance(entry, dict) or ("lines" in entry) == ("image" in entry):
            return None, f'camera {name}: give {{"lines": [[u1, v1, u2, v2], ...]}} or {{"image": "path"}}'
        if "lines" in entry:
            lines = entry["lines"]
            if not _line_list(lines):
                return None, f'camera {name}: "lines" must be [[u1, v1, u2, v2], ...] pixels'
            out.append(lines)
            continue
        image = entry["image"]
        if not isinstance(image, str) or not image:
            return None, f'camera {name}: "image" must be a path, got {image!r}'
        if detect is None:
            return None, "image frames need a camera to detect lines with"
        try:
            out.append(detect(folder / image, k))
        except InputError as exc:
            return None, f"camera {name}: {exc}"
    return out, ""


def _line_list(lines) -> bool:
    """Is ``lines`` a JSON list with no true/false where pixels belong (the
    rest is checked by the matcher, which names what is wrong)?"""
    return isinstance(lines, list) and not any(isinstance(v, bool) for row in lines if isinstance(row, list)
                                               for v in row)
