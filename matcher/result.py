"""The result of a localisation: a value, falsy on failure, carrying the reason."""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field


class Deferred:
    """A value worked out by ``compute()`` when first read (:meth:`get`),
    then kept: what a caller may never need (a pose's standard deviations,
    a pose's coverage of the map) costs nothing until then."""

    __slots__ = ("_compute", "_value")

    def __init__(self, compute) -> None:
        self._compute, self._value = compute, None

    def get(self):
        if self._compute is not None:
            self._value, self._compute = self._compute(), None
        return self._value


class _Counters(Mapping):
    """Read access by name to a frozen dataclass's fields, a field left None
    being absent (``stats["tree_nodes"]``, ``stats.get("resection")``), for
    callers that knew these values as a dict."""

    def __getitem__(self, key: str):
        value = getattr(self, key) if key in self.__dataclass_fields__ else None
        if value is None:
            raise KeyError(key)
        return value

    def __iter__(self):
        return (k for k in self.__dataclass_fields__ if getattr(self, k) is not None)

    def __len__(self) -> int:
        return sum(1 for _ in self)


@dataclass(frozen=True, eq=True)
class SearchStats(_Counters):
    """Stage 1's counters for one localisation (None: stage 1 did not get
    that far): candidate segments and image lines (all, vertical), pairs
    through the unary and vertical tests, correspondences left, pairs of
    them compatible, tree nodes, consistent sets found before the cap of
    hypotheses, sets the resection gave (None: it did not run), whether the
    time budget cut the search, and the milliseconds of its steps."""

    segments: int | None = None
    vertical_segments: int | None = None
    lines: int | None = None
    vertical_lines: int | None = None
    unary_pairs: int | None = None
    vertical_pairs: int | None = None
    correspondences: int | None = None
    compatible_pairs: int | None = None
    out_of_time: bool | None = None
    tree_nodes: int | None = None
    sets_found: int | None = None
    resection: int | None = None
    ms_correspondences: float | None = None
    ms_pairs: float | None = None
    ms_tree: float | None = None


@dataclass(frozen=True, eq=True)
class Timings(_Counters):
    """Milliseconds per step of one call (None: the step did not run):
    candidate selection, each hypothesis source of the strategy (with its
    stage 2 after the first), stage 2 from the end of the first source on,
    the whole call; lost mode also counts the regions and voted places it
    tried. Its JSON (:meth:`LocalizeResult.to_dict`) lists the steps that
    ran, in this order."""

    select: float | None = None
    generate: float | None = None
    second_search: float | None = None
    resection: float | None = None
    verify: float | None = None
    total: float | None = None
    regions_tried: int | None = None
    places_tried: int | None = None


@dataclass(frozen=True)
class LocalizeResult:
    """Pose ``(x, y, yaw_deg)`` of the camera (metres, degrees), the paper's
    score ``E`` of the accepted hypothesis and of the runner-up, the number
    of hypotheses stage 1 produced, the matches ``[[segment_id, line_index],
    ...]`` and the time per stage in milliseconds (:class:`Timings`).
    :attr:`pose_std` is the pose's standard deviations. ``bool(result)`` is
    ``ok``; ``reason`` says why when it is False. A value: made once, by
    :func:`matcher.verdict.decide`'s verdict, never edited (``replace`` gives
    another)."""

    ok: bool
    reason: str = ""
    pose: tuple[float, float, float] | None = None
    score: float | None = None
    runner_up_score: float | None = None
    hypotheses: int = 0
    matches: list[list[int]] = field(default_factory=list)
    time_ms: Timings = field(default_factory=Timings)
    #: Diagnostics for tools and tests (not part of the JSON contract):
    #: every hypothesis's score and matches, in ranked order.
    ranked: list[tuple[float, list[list[int]], tuple[float, float, float]]] = field(default_factory=list, repr=False)
    #: Consistent sets stage 1 found before its cap of hypotheses, and its
    #: counters (correspondences, pairs, tree nodes, ...).
    sets_found: int = 0
    stage1: SearchStats = field(default_factory=SearchStats, repr=False)

    #: The poses the evidence cannot tell apart, when that is why the result
    #: is falsy: dicts of x, y, yaw_deg, matches and score (lost mode).
    candidates: list[dict] = field(default_factory=list)

    #: The frame's own pitch and roll, degrees, when the camera file gives a
    #: roll or their standard deviations (matcher.attitude); else None.
    pitch_deg: float | None = None
    roll_deg: float | None = None

    #: A rig's frame: per camera, in the rig's order, its ``name``, its
    #: ``matches`` ``[[segment_id, line_index], ...]`` (lines counted in its
    #: own list) and the RMS pixel distance of their end points to the
    #: projected segments (``rms_px``); None for a single camera.
    cameras: list[dict] | None = None
    #: The storey of a building the pose is on (its name in the manifest),
    #: when the map searched was a building's (:mod:`matcher.building`); else None.
    storey: str | None = None

    #: Refused because the best pose's matched lines say the camera file's
    #: calibration is wrong (the reason says which parameter); not in the JSON.
    miscalibrated: bool = field(default=False, repr=False)

    #: :attr:`pose_std`, or the :class:`Deferred` that works it out.
    _pose_std: Deferred | tuple | None = field(default=None, repr=False, compare=False)

    def __post_init__(self) -> None:
        # Counters given as dicts (as callers made them before they were typed).
        if isinstance(self.time_ms, dict):
            object.__setattr__(self, "time_ms", Timings(**self.time_ms))
        if isinstance(self.stage1, dict):
            object.__setattr__(self, "stage1", SearchStats(**self.stage1))

    def __bool__(self) -> bool:
        return bool(self.ok)

    @property
    def pose_std(self) -> tuple[float, float, float] | None:
        """Standard deviations ``(x, y, yaw_deg)`` (metres, degrees) of the
        pose that the image noise of the tolerances leaves, to first order
        (:func:`matcher.stage2.covariance.pose_covariance`): for fusing with odometry; a
        view of a few far vertical edges leaves decimetres. None without a
        pose, or when the matches do not fix it. Worked out on first read."""
        return self._pose_std.get() if isinstance(self._pose_std, Deferred) else self._pose_std

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
            "out_of_time": bool(self.stage1.out_of_time),
        }
        if self.pitch_deg is not None:  # only with a camera file that gives an attitude
            d["pitch_deg"], d["roll_deg"] = float(self.pitch_deg), float(self.roll_deg)
        if self.cameras is not None:  # only for a rig's frame
            d["cameras"] = [{"name": c["name"], "matches": [[int(a), int(b)] for a, b in c["matches"]],
                             "rms_px": None if c["rms_px"] is None else round(float(c["rms_px"]), 3)}
                            for c in self.cameras]
        if self.storey is not None:  # only on a building
            d["storey"] = self.storey
        if self.candidates:
            d["candidates"] = [{k: int(v) if k == "matches" else v if k == "storey" else float(v)
                                for k, v in c.items()} for c in self.candidates]
        if not self.ok:
            d["reason"] = self.reason
        return d
