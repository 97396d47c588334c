"""Every threshold of the matcher, in one documented place.

Lengths in metres, angles in degrees, image quantities in pixels. The
defaults fit a detector whose lines are good to about 1 px in position and
1 degree in orientation (LSD on a sharp 640x480 frame; the paper's simulated
noise); a noisier source should widen ``line_px`` / ``line_deg``, and every
test derived from them widens with it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields


@dataclass(frozen=True)
class Tolerances:
    #: Bound on the perpendicular offset error of a detected line, pixels.
    #: With ``line_deg`` it sets, per image line, the largest angle by which
    #: its interpretation plane can be off (see constraints.plane_noise):
    #: every unary, binary and vertical test is widened by that angle, so a
    #: true correspondence passes whenever the noise stays within the bounds.
    line_px: float = 1.5
    #: Bound on the orientation error of a detected line, degrees.
    line_deg: float = 1.5
    #: Bound on how far a detected line's end point may be off along the
    #: line, pixels (end points are the least reliable part of a line).
    line_end_px: float = 4.0
    #: Error of the map and of the calibration (wall positions, camera
    #: height), metres: added to every position residual's tolerance. A
    #: height error dh moves a floor line's strip by dh * distance / height,
    #: so this is the one to raise for a robot whose camera height varies.
    model_m: float = 0.01
    #: Yaw step of the pose grid used by the consistency tests, degrees. The
    #: position tolerances grow by half a step times the range, so a coarser
    #: grid is faster but prunes less.
    yaw_step_deg: float = 1.0
    #: A hypothesis needs this many correspondences: three independent line
    #: correspondences are the fewest that fix a 3-DOF pose.
    min_matches: int = 3
    #: Relative minimum number of matches: sets with fewer than the largest
    #: consistent set minus this are dropped. 0 keeps stage 1 small; when
    #: stage 2 finds the largest sets padded with wrong matches it searches
    #: again with 1 (pipeline._doubtful).
    match_slack: int = 0
    #: Consistency of a set of correspondences at the least-squares point of
    #: its strips: each correspondence's normalised residual (residual over
    #: tolerance) squared must stay below this. 1.5 = 1.22 times the
    #: tolerance: the least-squares point is not the true pose, but the
    #: tolerances already bound the noise (true matches sit below 0.3).
    q_max: float = 1.5
    #: Acceptance threshold on the paper's score E of the best hypothesis:
    #: the paper's value. E of a correct match with 1 px / 1 deg noise is
    #: about 1e-4 on the simulated flats (docs/matcher.md); hypotheses that
    #: survive stage 2 wrongly are aliases that fit as well, so E alone does
    #: not reject them (see the benchmark).
    e_accept: float = 2e-3
    #: A best hypothesis that stage 2 left one match short of the largest
    #: stage-1 set is doubted, and stage 1 searches again for sets one
    #: smaller, when its E is above this: twice the E of a correct match at
    #: the default noise (about 1e-4). Over seeds 0 to 4 at PEQ 3 and 5, of
    #: 75 such frames the remains of padded sets scored 2.9e-4 and 4.4e-4,
    #: and all but two of the others below 1.9e-4 (docs/matcher.md). Scale
    #: it with ``e_accept`` for a noisier detector.
    e_doubt: float = 2e-4
    #: Stage 1 stops enumerating after this many consistent sets (a guard
    #: against pathological scenes; the result says so when it is hit).
    #: Leaves are tested for visibility only at the end, so sets that will
    #: fail it count too.
    max_sets: int = 1500
    #: ...or after this many tree nodes: a work budget (0.1 to 0.7 ms
    #: each; ``time_budget_ms`` bounds the wall clock) for scenes where the
    #: lines leave the pose nearly undetermined, such as a row of door jambs
    #: along one wall; the sets found by then (the first dives follow the
    #: best-fitting candidates) are kept. The two hardest frames of the
    #: benchmark (seed 0, PEQ 5) reach this budget, and the sets found by
    #: then hold the true one.
    max_nodes: int = 2000
    #: Wall-clock budget of one call, milliseconds (inf: none), for a robot
    #: that must answer at its frame rate. The searches (stage 1's tree, the
    #: second search, the resection) stop at 70 % of it, keeping what they
    #: found, and the final tests of their sets at 100 %; stage 2 then runs
    #: on what passed (at most ``max_hypotheses``: a few milliseconds).
    #: ``result.stage1["out_of_time"]`` says when it cut anything, and a
    #: failure's reason says so. The work before the tree is not cut (a few
    #: milliseconds, 40 on the largest views of the benchmark). A frame that
    #: runs out ends not localised far more often than wrong (the table in
    #: docs/matcher.md, from tools/bench_budget.py). In lost mode it bounds
    #: the whole call: regions are tried, the largest first, until it is
    #: spent.
    time_budget_ms: float = math.inf
    #: Stage 1 hands at most this many hypotheses to stage 2: the largest
    #: sets, then those that fit best at their grid pose (mean normalised
    #: residual). The paper saw
    #: fewer than 25 at its worst prior; more come only from scenes where
    #: the lines leave the pose undetermined (looking along a wall), and the
    #: number of sets found is reported with the result's diagnostics.
    max_hypotheses: int = 25
    #: How far outside the map's regions the camera may stand, metres. The
    #: regions are the floor the robot's centre can reach (the builder's
    #: robot radius from the walls, 0.2 m by default); a camera mounted off
    #: the centre may be up to that offset outside them. Poses farther out
    #: (inside a wall, behind the building) are rejected in both stages.
    free_space_m: float = 0.1
    #: Lines shorter than this many pixels are ignored: their orientation is
    #: too uncertain to constrain anything.
    min_line_px: float = 15.0
    #: Image lines may stick out of the image by this many pixels (noise on
    #: end points of lines clipped at the border).
    image_margin_px: float = 5.0

    def __post_init__(self) -> None:
        for f in fields(self):
            v = getattr(self, f.name)
            if not (v == v) or v < 0:
                raise ValueError(f"tolerance {f.name} must be >= 0, got {v}")
        if self.yaw_step_deg <= 0 or self.yaw_step_deg > 10:
            raise ValueError(f"tolerance yaw_step_deg must be in (0, 10], got {self.yaw_step_deg}")
        if self.min_matches < 2:
            raise ValueError(f"tolerance min_matches must be >= 2, got {self.min_matches}")


DEFAULT = Tolerances()

#: Segments whose direction is within this many degrees of the vertical are
#: vertical (same value as the map builder's axis tolerance).
VERTICAL_AXIS_DEG = 2.0
