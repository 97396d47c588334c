"""The result of a localisation: a value, falsy on failure, carrying the reason."""

from __future__ import annotations

import math
from dataclasses import dataclass, field


@dataclass
class LocalizeResult:
    """Pose ``(x, y, yaw_deg)`` of the camera (metres, degrees), the paper's
    score ``E`` of the accepted hypothesis and of the runner-up, the number
    of hypotheses stage 1 produced, the matches ``[[segment_id, line_index],
    ...]`` and the time per stage in milliseconds. :attr:`pose_std` is the
    pose's standard deviations. ``bool(result)`` is ``ok``; ``reason`` says
    why when it is False."""

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

    #: The poses the evidence cannot tell apart, when that is why the result
    #: is falsy: dicts of x, y, yaw_deg, matches and score (lost mode).
    candidates: list[dict] = field(default_factory=list)

    #: The frame's own pitch and roll, degrees, when the camera file gives a
    #: roll or their standard deviations (matcher.attitude); else None.
    pitch_deg: float | None = None
    roll_deg: float | None = None

    _pose_std: object = field(default=None, repr=False, compare=False)

    def __bool__(self) -> bool:
        return bool(self.ok)

    def pose_std_from(self, compute) -> None:
        """Have :attr:`pose_std` worked out by ``compute()`` when first read."""
        self._pose_std = compute

    @property
    def pose_std(self) -> tuple[float, float, float] | None:
        """Standard deviations ``(x, y, yaw_deg)`` (metres, degrees) of the
        pose that the image noise of the tolerances leaves, to first order
        (:func:`matcher.stage2.covariance.pose_covariance`): for fusing with odometry; a
        view of a few far vertical edges leaves decimetres. None without a
        pose, or when the matches do not fix it. Worked out on first read."""
        if callable(self._pose_std):
            self._pose_std = self._pose_std()
        return self._pose_std

    def to_dict(self) -> dict:
        """The JSON shape of docs/architecture.md."""

        def num(v):
            return None if v is None or not math.isfinite(v) else float(v)

        d = {
            "ok": bool(self.ok),
            "pose": None
            if self.pose is None
            else {"x": float(self.pose[0]), "y": float(self.pose[1]), "yaw_deg": float(self.pose[2])},
            "pose_std": None
            if self.pose_std is None
            else {"x": float(self.pose_std[0]), "y": float(self.pose_std[1]), "yaw_deg": float(self.pose_std[2])},
            "score": num(self.score),
            "runner_up_score": num(self.runner_up_score),
            "hypotheses": int(self.hypotheses),
            "matches": [[int(a), int(b)] for a, b in self.matches],
            "time_ms": {k: v if isinstance(v, int) else round(float(v), 3) for k, v in self.time_ms.items()},
            # Did the time budget cut the search (Tolerances.time_budget_ms)?
            "out_of_time": bool(self.stage1.get("out_of_time", False)),
        }
        if self.pitch_deg is not None:  # only with a camera file that gives an attitude
            d["pitch_deg"], d["roll_deg"] = float(self.pitch_deg), float(self.roll_deg)
        if self.candidates:
            d["candidates"] = [{k: (float(v) if k != "matches" else int(v)) for k, v in c.items()}
                               for c in self.candidates]
        if not self.ok:
            d["reason"] = self.reason
        return d
