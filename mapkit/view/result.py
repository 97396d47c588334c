"""Reading what the matcher wrote: a result JSON and, optionally, image lines.

Shapes (docs/architecture.md)::

    result  {"ok": true, "pose": {"x": .., "y": .., "yaw_deg": ..}, "score": E,
             "matches": [[segment_id, line_index], ...], "reason": "...",
             "lines": [[u1, v1, u2, v2], ...]}      # "lines" optional
    lines   {"lines": [[u1, v1, u2, v2], ...]}

Validated at the door: a bad file raises :class:`~mapkit.errors.MapkitError`
naming the file and the field, which the CLI prints as one line.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from mapkit.errors import MapkitError


@dataclass
class MatchResult:
    """A matcher result as the inspector uses it (yaw in radians)."""

    ok: bool
    x: float | None = None
    y: float | None = None
    yaw: float | None = None
    score: float | None = None
    matches: np.ndarray = field(default_factory=lambda: np.zeros((0, 2), dtype=np.int64))  # (K, 2) segment, line
    lines: np.ndarray | None = None  # (M, 2, 2) pixels, when the result or --lines gives them
    reason: str = ""
    raw: dict = field(default_factory=dict)

    @property
    def has_pose(self) -> bool:
        return self.x is not None


def _read_json(path: Path, what: str) -> dict:
    try:
        d = json.loads(Path(path).read_text())
    except FileNotFoundError:
        raise MapkitError(f"{what} file {path} not found; check the path") from None
    except (json.JSONDecodeError, UnicodeDecodeError) as exc:
        raise MapkitError(f"{what} file {path} is not valid JSON ({exc})") from None
    except RecursionError:
        raise MapkitError(f"{what} file {path} is not valid JSON (nested too deeply)") from None
    except OSError as exc:
        raise MapkitError(f"{what} file {path} could not be read ({exc.strerror or exc})") from None
    if not isinstance(d, dict):
        raise MapkitError(f"{what} file {path} must hold a JSON object")
    return d


def parse_lines(value, source: str) -> np.ndarray:
    """[[u1, v1, u2, v2], ...] -> (M, 2, 2) float array; MapkitError if malformed."""
    try:
        arr = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError):
        raise MapkitError(f"{source}: 'lines' must be a list of [u1, v1, u2, v2]") from None
    if arr.size == 0:
        return np.zeros((0, 2, 2))
    if arr.ndim != 2 or arr.shape[1] != 4 or not np.isfinite(arr).all():
        raise MapkitError(f"{source}: 'lines' must be a list of [u1, v1, u2, v2] finite numbers, got shape {arr.shape}")
    return arr.reshape(-1, 2, 2)


def load_lines(path: str | Path) -> np.ndarray:
    """Read a lines.json file: (M, 2, 2) pixel end points."""
    d = _read_json(Path(path), "lines")
    if "lines" not in d:
        raise MapkitError(f"lines file {path} lacks the 'lines' list")
    return parse_lines(d["lines"], f"lines file {path}")


def parse_result(d: dict, source: str = "result", n_segments: int | None = None) -> MatchResult:
    """Validate a result dict; segment ids are checked against ``n_segments`` if given."""
    ok = bool(d.get("ok", False))
    res = MatchResult(ok=ok, reason=str(d.get("reason", "")), raw=d)
    pose = d.get("pose")
    if pose is not None:
        try:
            res.x, res.y = float(pose["x"]), float(pose["y"])
            res.yaw = math.radians(float(pose["yaw_deg"]))
        except (KeyError, TypeError, ValueError):
            raise MapkitError(f"{source}: 'pose' needs numeric x, y and yaw_deg") from None
        if not all(math.isfinite(v) for v in (res.x, res.y, res.yaw)):
            raise MapkitError(f"{source}: 'pose' holds a non-finite number")
    elif ok:
        raise MapkitError(f"{source}: ok is true but there is no 'pose'")
    if d.get("score") is not None:
        try:
            res.score = float(d["score"])
        except (TypeError, ValueError):
            raise MapkitError(f"{source}: 'score' must be a number") from None
    matches = d.get("matches") or []
    try:
        m = np.asarray(matches, dtype=np.int64).reshape(-1, 2)
    except (TypeError, ValueError):
        raise MapkitError(f"{source}: 'matches' must be a list of [segment_id, line_index] integer pairs") from None
    if n_segments is not None and len(m) and (m[:, 0].min() < 0 or m[:, 0].max() >= n_segments):
        raise MapkitError(f"{source}: a match names segment {int(m[:, 0].max())}, but the map has {n_segments}; "
                          "was the result computed on another map?")
    if len(m) and m[:, 1].min() < 0:
        raise MapkitError(f"{source}: a match names image line {int(m[:, 1].min())}; line indices start at 0")
    res.matches = m
    if d.get("lines") is not None:
        res.lines = parse_lines(d["lines"], source)
    return res


def load_result(path: str | Path, n_segments: int | None = None, lines_path: str | Path | None = None) -> MatchResult:
    """Read a result file; ``lines_path`` (a lines.json) overrides the result's own lines."""
    res = parse_result(_read_json(Path(path), "result"), f"result file {path}", n_segments)
    if lines_path is not None:
        res.lines = load_lines(lines_path)
    if res.lines is not None and len(res.matches) and res.matches[:, 1].max() >= len(res.lines):
        raise MapkitError(f"result file {path}: a match names image line {int(res.matches[:, 1].max())}, "
                          f"but there are {len(res.lines)} lines")
    return res
