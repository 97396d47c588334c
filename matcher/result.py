"""The result of a localisation: a value, falsy on failure, carrying the reason."""

from __future__ import annotations

import math
from dataclasses import dataclass, field


@dataclass
class LocalizeResult:
    """Pose ``(x, y, yaw_deg)`` of the camera (metres, degrees), the paper's
    score ``E`` of the accepted hypothesis and of the runner-up, the number
    of hypotheses stage 1 produced, the matches ``[[segment_id, line_index],
    ...]`` and the time per stage in milliseconds. ``bool(result)`` is
    ``ok``; ``reason`` says why when it is False."""

    ok: bool
    reason: str = ""
    pose: tuple[float, float, float] | None = None
    score: float | None = None
    runner_up_score: float | None = None
    hypotheses: int = 0
    matches: list[list[int]] = field(default_factory=list)
    time_ms: dict[str, float] = field(default_factory=dict)
    #: Diagnostics for tools and tests (not part of the JSON contract):
    #: every hypothesis's score and matches, in ranked order.
    ranked: list[tuple[float, list[list[int]], tuple[float, float, float]]] = field(default_factory=list, repr=False)
    #: Consistent sets stage 1 found before its cap of hypotheses, and its
    #: counters (correspondences, pairs, tree nodes, ...).
    sets_found: int = 0
    stage1: dict = field(default_factory=dict, repr=False)

    def __bool__(self) -> bool:
        return bool(self.ok)

    def to_dict(self) -> dict:
        """The JSON shape of docs/architecture.md."""

        def num(v):
            return None if v is None or not math.isfinite(v) else float(v)

        d = {
            "ok": bool(self.ok),
            "pose": None
            if self.pose is None
            else {"x": float(self.pose[0]), "y": float(self.pose[1]), "yaw_deg": float(self.pose[2])},
            "score": num(self.score),
            "runner_up_score": num(self.runner_up_score),
            "hypotheses": int(self.hypotheses),
            "matches": [[int(a), int(b)] for a, b in self.matches],
            "time_ms": {k: v if isinstance(v, int) else round(float(v), 3) for k, v in self.time_ms.items()},
        }
        if not self.ok:
            d["reason"] = self.reason
        return d
