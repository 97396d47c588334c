"""Every threshold of the matcher, in one documented place.

:class:`Tolerances` holds what a user tunes (the detector's noise, the
search budgets, acceptance) and, nested in it, the method's inner constants
(sample points, slacks, work sizes), each with the reason for its value. The
inner constants are split by the part of the matcher that reads them, one
frozen class each (:data:`CONSTANTS`): ``tol.map_index``
(:class:`MapIndexConstants`, the per-map structures), ``tol.shared``
(:class:`SharedConstants`, read alike by several parts), ``tol.stage1``,
``tol.stage2``, ``tol.verdict``, ``tol.attitude``, ``tol.lost``. A module
is handed its part's object, so what it depends on shows in its signature.
They were one class, ``Internals`` (``Tolerances.internals``), until the
split: the constants kept their names and values, and the old names fail
with where they went (:func:`constants_owner`). No other module of the
matcher keeps a numeric threshold of its own (tests/test_layout.py walks
their syntax trees for it).

Lengths in metres, angles in degrees, image quantities in pixels. The
defaults fit a detector whose lines are good to about 1 px in position and
1 degree in orientation (LSD on a sharp 640x480 frame; the paper's simulated
noise); a noisier source should widen ``line_px`` / ``line_deg``, and every
test derived from them widens with it.
"""

from __future__ import annotations

import math
import numbers
from dataclasses import dataclass, field, fields
from functools import cached_property

import numpy as np

from linemap.errors import InputError


def _number(v) -> bool:
    """Is ``v`` a real number (not a bool, not a string)? Compared with 0 otherwise it would raise TypeError."""
    return isinstance(v, numbers.Real) and not isinstance(v, bool)


class _Constants:
    """What the inner constants' classes below share. Changing a constant
    changes the method, not its tuning: each comment says what the value
    was chosen against. Every value (each item of a tuple) is a number
    >= 0, checked when one is made; tuples are turned into arrays once (the
    ``*_array`` properties)."""

    def __post_init__(self) -> None:
        for f in fields(self):
            v = getattr(self, f.name)
            for x in (v if isinstance(v, tuple) else (v,)):
                if not _number(x) or not (x == x) or x < 0:
                    raise InputError(f"internal tolerance {type(self).__name__}.{f.name} must be >= 0, got {v!r}")


@dataclass(frozen=True)
class MapIndexConstants(_Constants):
    """Constants of the per-map structures (matcher/map_index.py,
    matcher/map_geometry/): collinear groups, the sight table, the wall faces'
    sides, the free-space raster. Every field is one of
    :data:`matcher.map_index.PART_FIELDS`: a part is built once per map and
    per the values of its fields.

    Held as ``Tolerances.map_index``."""

    #: Two segments are one collinear group (image lines cannot tell them
    #: apart) when parallel within this many degrees...
    collinear_deg: float = 0.5
    #: ...and each one's end points lie within this many metres of the other's line.
    collinear_m: float = 0.01
    #: Raster cell of the free-space distance map, metres: the test's
    #: resolution (a point's distance is its cell's, good to a cell diagonal, 7 cm).
    free_cell_m: float = 0.05
    #: Margin of that raster around the regions, metres: farther points read
    #: as this far (any sane tolerance rejects them anyway).
    free_border_m: float = 1.0
    #: Most cells of that raster: a map larger than ``free_cell_m`` times
    #: its square root across (200 m) gets coarser cells instead of a
    #: raster of gigabytes (a 2 km plan: 0.5 m cells, 128 MB of distances).
    free_max_cells: int = 16_000_000
    #: Rows x ring edges per block of the raster's scanline pass (a work
    #: size, not a tolerance: it bounds that pass's temporaries).
    free_scan_block: int = 4_000_000
    #: Bearings per vertical edge in the map's sight table (half a degree):
    #: how far one sees back from the edge along each.
    sight_bins: int = 720
    #: The sight table's rays start this far from the edge, metres: the edge
    #: stands on a wall face.
    sight_skip_m: float = 0.05
    #: A wall face's side is probed this far from a segment, metres.
    face_probe_m: float = 0.03
    #: Most (ray, wall edge) pairs cast at once: arrays under about 10 MB
    #: each (the first frame on a map casts every vertical edge's rays).
    ray_chunk: int = 1 << 20


@dataclass(frozen=True)
class SharedConstants(_Constants):
    """Constants that several consumers read alike: which segments are
    vertical (stage 1, stage 2, lost mode's votes), the prior's slack (stage
    1's resection and stage 2, matcher/prior.py), the sight-line test's box
    filter (both stages' visibility, matcher/map_geometry/occlusion.py) and the
    searches' share of the time budget (matcher/from_prior.py,
    matcher/lost.py).

    Held as ``Tolerances.shared``."""

    #: Segments whose direction is within this many degrees of the vertical
    #: are vertical (the map builder's axis tolerance, mapkit.tolerances.AXIS_DEG).
    vertical_axis_deg: float = 2.0
    #: A refined pose may leave the prior bounds by this much (metres,
    #: degrees) before the hypothesis is dropped: noise on a pose at the
    #: border. A pose its matches fix loosely gets more: this many of its
    #: standard deviations (six far vertical edges on one side leave the
    #: position uncertain by a decimetre).
    prior_slack_m: float = 0.1
    prior_slack_deg: float = 2.0
    prior_slack_sigmas: float = 3.0
    #: Share of the time budget the searches may use: the final tests of a
    #: few hundred sets found take up to about a third of the search's time.
    search_share: float = 0.7
    #: The structure search (matcher/search/structure/yaw.py) scores the
    #: yaws at which the frame's level lines lie along the map's walls: the
    #: peaks of their directions' correlation within this share of the
    #: best (a rectangular building's two peaks score alike; clutter's
    #: lie well below).
    yaw_peak_share: float = 0.5
    #: A pose found once is searched again as a narrow prior this far
    #: around it (metres, degrees): lost mode's rig seeds (each camera's lost
    #: answers, verified on every camera), the structure search's peaks
    #: (refined to a few centimetres and a degree) and, in lost mode, the
    #: attitude's second runs (the first run's pose is off by what its
    #: attitude was, a few centimetres and tenths of a degree). (The
    #: attitude's second runs used 0.3 m and 5 degrees before the three
    #: were made one.)
    lost_seed_m: float = 0.25
    lost_seed_deg: float = 4.0
    #: Above this many wall edges, sight lines are first tested against the
    #: edges' bounding boxes (below it the filter costs more than it saves).
    box_filter_edges: int = 512


@dataclass(frozen=True)
class Stage1Constants(_Constants):
    """Constants of stage 1 (matcher/search/tree/, and its strategy.py's
    merge of its searches): the correspondences, the pairwise test, the
    interpretation tree's tests at a grid pose, the resection from vertical
    edges.

    Held as ``Tolerances.stage1``."""

    #: Slack of the half-planes, metres: a vertical edge still counts as
    #: ahead from this far behind the camera, a wall face as facing from this
    #: far behind it (pose grid and noise).
    front_slack_m: float = 0.1
    #: A correspondence alone is kept at a grid yaw where its normalised
    #: strip quadratic's minimum is at most this...
    single_fit_max: float = 2.0
    #: ...and a pair shares a pose where their summed quadratic's minimum is
    #: at most this (each term must also stay within ``q_max``).
    pair_fit_max: float = 3.0
    #: The tree tests visibility and free space inside the search only once
    #: a set fixes the position: its feasible points at the best yaw reach
    #: less than this far, metres, in any direction. Before that the best
    #: point may be far from the truth and the tests would prune true sets.
    pinned_m: float = 0.15
    #: A set that leaves the position loose gets a visibility test of its
    #: own once the search has used this share of its node budget: it costs
    #: a few tenths of a millisecond, and the scenes that need it (a row of
    #: door jambs, each jamb line fitting many jambs) are the ones where
    #: loose sets multiply; most frames end well before.
    loose_test_after: float = 0.1
    #: Spacing, metres, of the camera positions that sample a loose set's
    #: feasible region at each yaw, and the most per axis.
    region_step_m: float = 0.15
    region_max: int = 16
    #: Share of the node budget the passes that aim at large sets may spend
    #: without finding one.
    aim_high_share: float = 0.05
    #: Sight lines at a grid pose (a few centimetres off) count as blocked
    #: only where they cross a wall more than this far from both ends,
    #: metres. Looser than ``refined_sight_end_m``, stage 2's: the grid pose
    #: is not the refined one.
    grid_sight_end_m: float = 0.05
    #: Points of a segment tested for visibility at a grid pose (fractions of
    #: its length), when the part its image line shows is not known.
    grid_sight_samples: tuple = (0.02, 0.26, 0.5, 0.74, 0.98)
    #: The part of a segment its image line shows at a grid pose is widened
    #: by this much at both ends before visibility is tested, metres (the
    #: grid pose is a few centimetres and up to half a yaw step off)...
    shown_widen_m: float = 0.1
    #: ...and tested at these fractions of it (it is short: three do).
    shown_samples: tuple = (0.05, 0.5, 0.95)
    #: A segment counts as seen at a grid pose if it is seen from the pose's
    #: point or from one of four points this far around it, metres: that
    #: point is a few centimetres off, and a sight line through a doorway
    #: swings onto a jamb over that distance. Too small loses true sets
    #: behind door jambs; too large keeps a few more false ones for stage 2.
    grid_jitter_m: float = 0.15
    #: Segment points closer than this along the optical axis, metres, count
    #: as behind the camera in the tree's visibility test.
    in_front_m: float = 0.05
    #: When the resection adds hypotheses, the tree's that stage 2 kept stay
    #: with them, at most this many (best ranked first).
    tree_sets_kept: int = 5
    #: A line counts as explained at a resected pose if its bearing is within
    #: this many times its noise bound of a candidate edge's: the pose comes
    #: from three noisy bearings (stage 2 refits and applies the exact test).
    resection_bearing_slack: float = 3.0
    #: Best poses of each batch of triples kept for the final choice.
    resection_keep: int = 200
    #: Most triples solved per frame: a bound on the time on any scene.
    resection_max_triples: int = 200000
    #: Every edge of a triple must stand at least this far in front of its
    #: resected camera, metres: nearer, the solution is a degenerate one.
    resection_min_range_m: float = 0.2
    #: Most (pair, grid yaw) entries the pairwise test handles at once: its
    #: arrays then stay under about 15 MB each.
    pair_chunk: int = 1 << 18
    #: Most triples of correspondences resected in one batch (memory).
    resection_chunk: int = 20000

    @cached_property
    def grid_sight_array(self) -> np.ndarray:
        """``grid_sight_samples`` as an array."""
        return np.array(self.grid_sight_samples)

    @cached_property
    def shown_array(self) -> np.ndarray:
        """``shown_samples`` as an array."""
        return np.array(self.shown_samples)

    @cached_property
    def jitter_array(self) -> np.ndarray:
        """(5, 2) the grid pose's point and the four around it, metres."""
        j = self.grid_jitter_m
        return np.array([[0.0, 0.0], [j, 0.0], [-j, 0.0], [0.0, j], [0.0, -j]])


@dataclass(frozen=True)
class Stage2Constants(_Constants):
    """Constants of stage 2 (matcher/stage2/): the refinement, the fit and
    visibility of matches at a refined pose, the slide of loosely fixed
    poses.

    Held as ``Tolerances.stage2``."""

    #: Gauss-Newton iterations: from the grid start (within half a yaw step
    #: and a few centimetres) the fit converges in 3 to 4.
    refine_iterations: int = 6
    #: Iterations of the refits after matches were dropped or added (they
    #: start at a refined pose).
    refit_iterations: int = 3
    #: With robust weights, this many plain iterations come first: the
    #: stage-1 start may be tens of centimetres off along a weakly fixed
    #: direction, and weighting residuals from there would drop true matches.
    refine_plain_first: int = 2
    #: Gauss-Newton stops once no hypothesis moves more than this (metres and
    #: radians) in one step: a micrometre, far below the pose's noise.
    refine_converged: float = 1e-6
    #: Segments are cut this far in front of the optical centre before
    #: projecting, metres.
    near_plane_m: float = 0.05
    #: A true line's end points lie within its noise bound plus this many
    #: pixels of the projected segment: the refined pose's own error.
    fit_pose_px: float = 2.0
    #: At a refined pose (a centimetre off) a sight line that cuts a wall this
    #: far or more from the segment is blocked, metres: it tells the near and
    #: far faces of a door jamb apart.
    refined_sight_end_m: float = 0.02
    #: Points tested for visibility along the part of a segment a line shows
    #: (fractions of that part, its ends moved in a little: they are the least sure).
    refined_sight_samples: tuple = (0.05, 0.275, 0.5, 0.725, 0.95)
    #: Hypotheses matching this many horizontal segments or more are not
    #: slid: their lines fix the position.
    slide_max_horizontal: int = 2
    #: A pose is slid only if its position is loose by at least this much,
    #: metres (one standard deviation along its worst-fixed axis): a pose
    #: fixed better has no room to slide.
    slide_min_loose_m: float = 0.05
    #: Positions are tried within this many standard deviations along both
    #: axes of the position, and at most this far, metres (a direction the
    #: matches leave free has no standard deviation).
    slide_sigmas: float = 3.0
    slide_max_m: float = 2.0
    #: The positions tried: a grid of this many fractions of that range per
    #: axis; then this many bisections towards the best.
    slide_grid: int = 15
    slide_bisections: int = 8

    @cached_property
    def refined_sight_array(self) -> np.ndarray:
        """``refined_sight_samples`` as an array."""
        return np.array(self.refined_sight_samples)

    @cached_property
    def slide_grid_array(self) -> np.ndarray:
        """(G, 2) fractions of the slide's range along the position's two axes."""
        t = np.linspace(-1, 1, self.slide_grid)
        return np.stack(np.meshgrid(t, t, indexing="ij"), -1).reshape(-1, 2)


@dataclass(frozen=True)
class VerdictConstants(_Constants):
    """Constants of the verdict on the best answer (matcher/verdict.py,
    matcher/ambiguity.py, and the counts it judges with: matcher/frame.py's
    lines needed, matcher/stage2/fit.py's coverage): lines explained by
    chance, the map shown, ambiguity.

    Held as ``Tolerances.verdict``."""

    #: The matcher names the poses it cannot tell apart instead of picking
    #: one: answers explaining as many lines as the best, fitting within this
    #: factor of its E...
    ambiguous_score_ratio: float = 3.0
    #: ...and of its reprojection cost (stage 2's ranking: the summed squared
    #: pixel distances of the lines to their segments; over seeds 0 to 4 the
    #: three rivals of a right answer that E alone let through cost 2.2 to
    #: 10 times more)...
    ambiguous_cost_ratio: float = 2.0
    #: ...at poses farther apart than these (metres, degrees) make the answer
    #: ambiguous (a symmetric room, like rooms)...
    ambiguous_m: float = 0.5
    ambiguous_deg: float = 10.0
    #: ...and farther than this many of the best pose's standard deviations
    #: (a loosely fixed pose's near rivals are the same answer, imprecise).
    ambiguous_sigmas: float = 3.0
    #: An accepted pose must explain more lines the more lines the frame
    #: has: a wrong pose among clutter (blinds, shelves, casings) explains
    #: some by chance, about in proportion to their number. The best pose
    #: must explain ``min_matches`` plus this share of the lines stage 1
    #: searched (``Tolerances.search_lines`` at most). On 80 real views of
    #: the ZInD sample tour at PEQ 1, 3 and 5 the accepted and wrong answers
    #: explained 4 to 9 of 25 lines (median 5.5), the right ones 4 to 14
    #: (median 9): 0.16 (7 of 25) kept 46 of 61 right answers and 4 of 16
    #: wrong ones. A simulated frame of 10 lines needs 4, as the check on
    #: exact fits below already asks.
    chance_fit_share: float = 0.16
    #: An accepted pose must show the map: of the segments it predicts in
    #: view (projected at least this long, pixels, and in plain sight), a
    #: match's collinear groups must hold this share, once it predicts this
    #: many (a picture of stripes fits a few vertical edges anywhere, but not
    #: the floor and ceiling lines those poses would show).
    coverage_min_px: float = 40.0
    coverage_min_share: float = 0.25
    coverage_min_predicted: int = 8
    #: A camera file whose calibration does not fit the lines
    #: (matcher/stage2/calibration_check.py): the accepted pose is fitted
    #: again with one calibration parameter free at a time (indices into
    #: its ``PARAMETERS``: 0 focal scale, 1 height, 2 principal point
    #: column, 3 row). Not the column: a shift of it is a turn of the
    #: camera to within a pixel across a narrow view, and the yaw takes it
    #: up (tools/bench_calibration.py: cx 40 px off left no answer 5
    #: degrees wrong, and judging it refused right ones)...
    calibration_judged: tuple = (0, 1, 3)
    #: ...on this many matched lines at least (fewer leave too few
    #: residuals to tell a calibration from noise)...
    calibration_min_lines: int = 4
    #: ...by Gauss-Newton from the accepted pose (it converges in 3 to 4
    #: steps from there), with these finite-difference steps (a focal
    #: scale, metres, pixels, pixels)...
    calibration_iterations: int = 5
    calibration_steps: tuple = (1e-4, 1e-4, 1e-2, 1e-2)
    #: ...fitted in full only when its first-order drop (one Jacobian at
    #: the accepted pose) reaches this share of the least drop below (the
    #: first order underestimates a large error's drop; on right cameras it
    #: stays far below, so the full fits rarely run)...
    calibration_screen_share: float = 0.3
    #: ...and the pose is refused when freeing one lowers the sum of
    #: squared noise-weighted residuals by this much or more (chi-square of
    #: one degree of freedom: 12 is p = 0.0005 for lines as noisy as their
    #: bounds; the 96 frames tools/bench_calibration.py accepts with the
    #: true camera dropped 4.5 at most, their noise being two thirds of the
    #: bounds; on its tuning seeds, with all four parameters judged, 12
    #: caught 50 of the 115 answers accepted and wrong with a wrong camera
    #: file, 25 only 36)...
    calibration_min_drop: float = 12.0
    #: ...this many times the residual variance it leaves (an F ratio: a
    #: misfit the parameter does not explain is not blamed on it; from 3 to
    #: 10 it changed one catch in the tuning seeds)...
    calibration_min_ratio: float = 5.0
    #: ...with an estimate off the file's by this much or more: a focal
    #: scale (a fraction), a height (metres), a principal point (pixels):
    #: less is within what calibrations usually miss by, and harmless.
    calibration_min_focal: float = 0.05
    calibration_min_height_m: float = 0.05
    calibration_min_centre_px: float = 20.0
    #: A focal scale estimated beyond this factor either way is no estimate:
    #: the lines do not fix the focal length and the fit ran off.
    calibration_max_focal: float = 4.0
    #: A rig's focal lengths profiled (matcher/rig/calibration.py): the
    #: accepted pose verified again (lines matched anew, the pose refitted)
    #: with every camera's focal length scaled by each of these (a ratio of
    #: 1.1 from one to the next, 0.68 to 1.46). A wrong focal length's
    #: answer is a local optimum of the pose and the focal length together:
    #: the fit with the focal length free from there estimates it 1 to 4 %
    #: off when it is 10 to 25 % off; from the scale whose verification
    #: explains the most lines the fit starts in the right basin. Asked
    #: only when the answer's lines reject the focal length to first order
    #: (``calibration_screen_share``), trusted only when that scale explains
    #: ``RigConstants.clear_ratio`` times the files' lines (no new threshold:
    #: a rival calibration is judged as a rival place is).
    calibration_focal_grid: tuple = tuple(round(1.1 ** k, 3) for k in (-4, -3, -2, -1, 1, 2, 3, 4))


@dataclass(frozen=True)
class AttitudeConstants(_Constants):
    """Constants of the frame's own pitch and roll (matcher/attitude.py):
    the estimate from vertical lines, the first runs in pitch bands, the fit
    on their matches, the second runs.

    Held as ``Tolerances.attitude``."""

    #: How many standard deviations of the camera file's pitch and roll the
    #: estimate may stray (and lines that may be vertical edges are looked
    #: for), and by how many of what the fit on the first run's matches
    #: left the second run's tolerances widen: 2.5 keeps 99 % of a Gaussian
    #: error in.
    attitude_sigmas: float = 2.5
    #: The fit on a hypothesis's matches counts when their mean squared
    #: residual, in the lines' noise, is at most this: right ones gave 0.1
    #: to 2.3 (PEQ 3, 20 frames), wrong ones mostly 5 to thousands.
    attitude_fit_cost: float = 3.0
    #: Two fitted attitudes closer than this, degrees, in pitch and roll
    #: are one (one second run): a tenth of a degree moves the picture by
    #: 1.6 px at f = 900, what the second run's widening covers.
    attitude_same_deg: float = 0.1
    #: Most second runs (attitudes tried), most matches first, then the
    #: least residual: on 20 frames at PEQ 3 the right one was among the
    #: first two.
    attitude_second_runs: int = 3
    #: The first runs cover the pitch the vertical lines leave in bands this
    #: wide, degrees, one run each widened by half a band (0.5 degree: 8 px
    #: at f = 900).
    attitude_band_deg: float = 1.0
    #: Each band's run is the interpretation tree alone (no second search,
    #: no resection) with this node budget: it needs one set near the
    #: truth among its best few, not the answer. 500 nodes and 10
    #: hypotheses lost the true set at PEQ 3 to 5 in some frames (92 to
    #: 94 % correct first on the benchmark).
    attitude_band_nodes: int = 1000
    #: ...and at most this many hypotheses for stage 2 (of which the best
    #: ``attitude_fit_keep`` are fitted).
    attitude_band_hypotheses: int = 25
    #: A line's plane noise is a bound (``line_px``, ``line_deg``); as a
    #: standard deviation it counts this share of it (a uniform error's is
    #: 0.58 of its bound).
    attitude_line_sigma: float = 0.6
    #: Scale of the Cauchy weights of the vertical lines' residuals, in their
    #: standard deviations: a horizontal line that nearly passes for a
    #: vertical edge weighs little.
    attitude_robust_c: float = 2.0
    #: Iterations of the estimate from vertical lines (it converges in 3 to 5).
    attitude_iterations: int = 10
    #: The first run's best hypotheses that get the pose, pitch and roll
    #: fitted on their matches (the one with most matches, then the least
    #: residual, sets the attitude of the second run).
    attitude_fit_keep: int = 5
    #: Gauss-Newton iterations of that fit, and its step for the numerical
    #: derivatives (radians and metres; far below the pose's noise).
    attitude_fit_iterations: int = 8
    attitude_fit_step: float = 1e-6


@dataclass(frozen=True)
class LostConstants(_Constants):
    """Constants of lost mode (matcher/lost.py), its pose votes
    (matcher/lost_votes.py) and the trust in a voted or cut-short answer
    (matcher/verdict.py's ``trusted``).

    Held as ``Tolerances.lost``."""

    #: Lost mode multiplies the tree's node and set budgets by this: the
    #: robot is stopped, and one search covers a whole region at any heading.
    lost_budget_factor: int = 10
    #: Lost mode first tries the places this many pairs of horizontal
    #: sightings (or a sighting and a vertical edge) vote for, best first,
    #: each as a narrow prior; the region sweep runs only when none of them
    #: gives an answer. On 40 frames of the example map (seed 7) the true
    #: place was among the first 10 in 31 frames, the first 30 in 33.
    vote_places: int = 12
    #: A voted place's answer stands without the sweep when it explains at
    #: least this share of the frame's usable lines (a wrong place voted by
    #: chance explains a few; on the seed-7 frames of the example map wrong
    #: voted answers explained 44 to 50 %, right ones 62 to 100 %); below it
    #: the sweep looks for regions that explain more.
    vote_trust_share: float = 0.6
    #: Votes use the longest this many horizontal and this many vertical
    #: image lines (the surest; a close view of a door and its frames has
    #: 30 lines, and all of them cost a third of a second of votes).
    vote_lines: int = 12
    #: A voted place's prior: this far (metres) and this many degrees around
    #: it (a cell's half diagonal and half its heading span, with noise).
    vote_prior_m: float = 0.4
    vote_prior_deg: float = 6.0
    #: Map segments sighted: horizontal (further than the vertical axis
    #: tolerance from the vertical) and level, their two ends within this
    #: many metres of one height.
    vote_flat_m: float = 0.02
    #: An image line's plane is cut at a segment's height only within this
    #: many metres of the camera (the map's usual visibility range and a
    #: margin: farther, a pixel's error is decimetres of depth).
    vote_range_m: float = 12.0
    #: The piece seen may pass a segment's ends by this many metres, plus
    #: this share of its distance (depth errors grow with distance).
    vote_slack_m: float = 0.3
    vote_slack_share: float = 0.05
    #: The camera stands at least this far (metres) from a sighted segment's
    #: line and from a vertical edge it sees (the robot's radius, less).
    vote_min_offset_m: float = 0.15
    #: Two sightings meet when their headings are within this many degrees
    #: (a line's heading error at a few metres, with 1 px noise)...
    vote_yaw_deg: float = 3.0
    #: ...and their segments (or a segment and the bearing to an edge) cross
    #: at this many degrees or more (nearly parallel lines meet anywhere).
    vote_cross_deg: float = 25.0
    #: A vote off the map's free space by more than this (metres) is dropped.
    vote_free_m: float = 0.1
    #: Votes are counted in cells this many metres and degrees across (on
    #: the seed-7 frames 0.4 m / 5 deg ranked the truth first-10 in 31 of 40,
    #: 0.25 m / 3 deg in 25, 0.5 m / 6 deg in 29)...
    vote_cell_m: float = 0.4
    vote_cell_deg: float = 5.0
    #: ...and two places kept are at least this far apart (metres, degrees).
    vote_apart_m: float = 0.5
    vote_apart_deg: float = 8.0


@dataclass(frozen=True)
class RigConstants(_Constants):
    """Constants of a rig of cameras (matcher/rig/): each camera's own
    search gives seed poses, every camera's lines verify them together.

    Held as ``Tolerances.rig``."""

    #: Each camera's search hands this many of its best ranked poses to the
    #: joint verification (a narrow view's best is often a look-alike that
    #: the other cameras refute, the true pose a few places down).
    seeds_per_camera: int = 6
    #: Seeds closer than this (metres, degrees) are one: cameras that see
    #: the same place give the same pose to a few millimetres. Not more: a
    #: look-alike a few centimetres off (a jamb's near face for its far one:
    #: 3 cm and 0.5 degrees on a 2-camera run of the example map, seed 3,
    #: frame 10) is another local optimum, and merged with it the true seed
    #: is lost; verified poses with the same matches are one anyway.
    same_seed_m: float = 0.01
    same_seed_deg: float = 0.2
    #: Rounds of (every camera's lines matched at the pose, the pose refitted
    #: on all of them): the seed's pose comes from one narrow view, the first
    #: refit on all cameras moves it by centimetres, the second settles it.
    verify_rounds: int = 2
    #: The best verified pose must explain this many times the lines of the
    #: best pose elsewhere (farther than ``VerdictConstants.ambiguous_m`` or
    #: ``ambiguous_deg``): the lines a wrong place explains by chance,
    #: measured on the frame itself (the other seeds' verified poses), in
    #: place of the share of the searched lines a single view needs
    #: (``chance_fit_share``). Chosen on 4-camera rigs cut from the 32
    #: panoramas of the ZInD sample tour at PEQ 3, seed 0 (right answers'
    #: ratios 1.2 to 49, median 2.5; every wrong one 1.06 to 1.47), with the
    #: coverage and E tests as they are: 9 right, 0 wrong of 32; held out
    #: (seed 1, other headings, fields of view and sizes): 9 right, 0 wrong
    #: (1.3 and 1.7 gave the same on both). The benchmark after it
    #: (docs/benchmarks/real-rigs.md): 0 wrong in 224 rig and panorama calls.
    clear_ratio: float = 1.5
    #: The best pose must explain this share of the frame's searched lines
    #: (every camera's longest, ``search_lines`` each), whatever the other
    #: places: where the verification found no pose elsewhere, the
    #: clear-ratio test has nothing to compare with. Far below a single
    #: view's ``VerdictConstants.chance_fit_share`` (0.16): real rooms fill a
    #: camera with clutter. Chosen on the same rigs: right best poses
    #: explained 0.098 to 0.40 of their searched lines, a wrong one (1.4 m
    #: off, nothing verified elsewhere) 0.04.
    #: With both (and the rig's coverage counting each segment once): seeds
    #: 0 and 1, 14 and 16 right of 32, 0 wrong (11 and 10 before); held out,
    #: seed 2 at PEQ 3 19 right, 0 wrong, whole panoramas 15 right, 0 wrong
    #: (2 before); seed 2 at PEQ 5 2 wrong, look-alikes whose true place no
    #: seed reached, which the old thresholds accept too
    #: (docs/benchmarks/real-rigs.md).
    explained_min_share: float = 0.08
    #: A prior's search stops before the other cameras' trees once the
    #: verdict accepts the best verified pose and the seeds of this many
    #: cameras' own searches verified to it (within ``settled_m`` and
    #: ``settled_deg``): the cameras' trees are 85 % of a rig call's time
    #: (ZInD sample tour, PEQ 3), and two narrow
    #: views that found one place from their own lines are the evidence the
    #: remaining trees would add. One camera's alone is not enough: a look-
    #: alike a few centimetres off (a jamb's near face for its far one)
    #: explains most of the frame too, and a rival only another camera's
    #: tree finds would refuse it.
    settled_cameras: int = 2
    #: Two cameras' seeds verified to one place: within these (metres,
    #: degrees) of each other. The joint refit does not pull them onto one
    #: optimum (each keeps the matches it started from): on a ZInD panorama
    #: (sample tour, frame 1, PEQ 3) the best pose's own camera's other seeds
    #: ended 3 to 11 cm and 1 to 3.5 degrees away, another camera's 11 cm and
    #: 0.6 degrees; the other places verified there lay 0.4 m and 7 degrees
    #: away or more (``VerdictConstants.ambiguous_m`` 0.5). On the whole tour
    #: (seed 0, PEQ 3) the stop leaves right and wrong as they were: 15 and
    #: 14 of 32 right (panoramas, 4-camera rigs), 0 wrong
    #: (docs/benchmarks/real-rigs.md).
    settled_m: float = 0.2
    settled_deg: float = 3.0


#: The fields of :class:`Tolerances` that hold inner constants, and each one's class.
CONSTANTS = {"map_index": MapIndexConstants, "shared": SharedConstants, "stage1": Stage1Constants,
             "stage2": Stage2Constants, "verdict": VerdictConstants, "attitude": AttitudeConstants,
             "lost": LostConstants, "rig": RigConstants}


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
    #: that must answer at its frame rate. The default, 30 s, never cuts a
    #: frame of the benchmarks (milliseconds; lost mode a few seconds) but
    #: ends a hostile one (hundreds of look-alike lines, a tree whose every
    #: node is slow) in a reason instead of minutes of work. The searches (stage 1's tree, the
    #: second search, the resection) stop at 70 % of it, keeping what they
    #: found, and the final tests of their sets at 100 %; stage 2 then runs
    #: on what passed (at most ``max_hypotheses``: a few milliseconds).
    #: ``result.stage1.out_of_time`` says when it cut anything, and a
    #: failure's reason says so. The work before the tree is not cut (a few
    #: milliseconds, 40 on the largest views of the benchmark). A frame that
    #: runs out ends not localised far more often than wrong (the table in
    #: docs/matcher.md, from tools/bench_budget.py). In lost mode it bounds
    #: the whole call: regions are tried, the largest first, until it is
    #: spent.
    time_budget_ms: float = 30_000.0
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
    #: Stage 1 searches with the longest this many usable lines; stage 2
    #: judges and adds back all of them. A photograph gives 40 to 200 lines
    #: (window mullions, blinds, casings, shelves) against some 100
    #: candidate segments: thousands of correspondences pass the unary tests
    #: and the tree runs out of time, while the room's own edges are among
    #: its longest lines. On the 160 views of the ZInD sample tour
    #: (tools/bench_real.py, 1 s budget), with the two limits below and
    #: ``chance_fit_share``, the median call at PEQ 1 went from 0.70 to
    #: 0.23 s, accepted and wrong answers at PEQ 1 to 5 from 3 to 5 % to
    #: 0.6 to 3 %; simulated frames have fewer lines and are untouched.
    search_lines: int = 25
    #: ...of which at most this many vertical edges: a vertical line fixes
    #: one number of the pose (its bearing) and may be any vertical edge in
    #: view, so a wide prior gives (vertical lines) x (door jambs, corners,
    #: window sides) correspondences, 1600 on a real view at PEQ 5.
    search_vertical_lines: int = 10
    #: Image lines may stick out of the image by this many pixels (noise on
    #: end points of lines clipped at the border)...
    image_margin_px: float = 5.0
    #: ...and reach this share of the image's size beyond it, the part
    #: beyond the margin cut off (undistorted lines, unclipped detector
    #: output); lines reaching farther out are another camera's: refused.
    image_reach: float = 0.25
    #: Most image lines a call takes (line preparation compares every pair
    #: of lines): a photo gives a few hundred after merging (``matcher
    #: localize --max-lines`` raises it).
    max_lines: int = 2000
    #: The method's inner constants, one object per part of the matcher
    #: that reads them (:data:`CONSTANTS`); changed as
    #: ``replace(tol, stage1=replace(tol.stage1, pinned_m=0.2))``. The
    #: per-map structures' (collinear groups, sight table, free space)...
    map_index: MapIndexConstants = field(default_factory=MapIndexConstants)
    #: ...those several parts read alike (vertical axis, prior slack)...
    shared: SharedConstants = field(default_factory=SharedConstants)
    #: ...stage 1's (correspondences, the tree, the resection)...
    stage1: Stage1Constants = field(default_factory=Stage1Constants)
    #: ...stage 2's (refinement, fit and visibility, the slide)...
    stage2: Stage2Constants = field(default_factory=Stage2Constants)
    #: ...the verdict's (chance fits, coverage, ambiguity)...
    verdict: VerdictConstants = field(default_factory=VerdictConstants)
    #: ...the frame's own pitch and roll's...
    attitude: AttitudeConstants = field(default_factory=AttitudeConstants)
    #: ...lost mode's (its pose votes)...
    lost: LostConstants = field(default_factory=LostConstants)
    #: ...and a rig of cameras' (matcher/rig/).
    rig: RigConstants = field(default_factory=RigConstants)
    #: How places are ranked before stage 2 verifies them
    #: (:mod:`matcher.search`): "tree" (the paper's interpretation tree),
    #: "structure" (every pose of the prior scored from the scene's
    #: structure), or None: the default per kind of frame
    #: (``matcher.search.DEFAULTS``, chosen on measurement).
    search: str | None = None

    def __post_init__(self) -> None:
        for f in fields(self):
            v = getattr(self, f.name)
            if f.name == "search":
                if v is not None and v not in ("tree", "structure"):
                    raise InputError(f"tolerance search must be 'tree', 'structure' or None, got {v!r}")
                continue
            if f.name in CONSTANTS:
                if not isinstance(v, CONSTANTS[f.name]):
                    raise InputError(f"tolerance {f.name} must be a matcher.tolerances.{CONSTANTS[f.name].__name__}, "
                                     f"got {v!r}")
                continue
            if not _number(v) or not (v == v) or v < 0:
                raise InputError(f"tolerance {f.name} must be >= 0, got {v!r}")
        if self.yaw_step_deg <= 0 or self.yaw_step_deg > 10:
            raise InputError(f"tolerance yaw_step_deg must be in (0, 10], got {self.yaw_step_deg}")
        if self.min_matches < 2:
            raise InputError(f"tolerance min_matches must be >= 2, got {self.min_matches}")
        if self.search_lines < self.min_matches:
            raise InputError(f"tolerance search_lines must be >= min_matches ({self.min_matches}), got {self.search_lines}")

    @property
    def internals(self):
        """Gone: the inner constants were split by consumer (see :data:`SPLIT_INTERNALS`)."""
        raise AttributeError(SPLIT_INTERNALS)


DEFAULT = Tolerances()

#: What code written for the former single class of inner constants is told.
SPLIT_INTERNALS = ("matcher.tolerances.Internals (Tolerances.internals) was split by consumer: each constant keeps "
                   "its name in one of Tolerances.map_index, .shared, .stage1, .stage2, .verdict, .attitude, .lost "
                   "(matcher.tolerances.constants_owner(name) says which; docs/matcher.md, 'Inner constants')")


def constants_owner(name: str) -> str:
    """The field of :class:`Tolerances` whose constants class holds the inner
    constant ``name`` (``"pinned_m"`` -> ``"stage1"``); InputError if none does."""
    for owner, cls in CONSTANTS.items():
        if any(f.name == name for f in fields(cls)):
            return owner
    raise InputError(f"no inner constant is named {name!r} (the fields of {', '.join(c.__name__ for c in CONSTANTS.values())})")


def __getattr__(name: str):
    """The former names fail with where their constants went, not a bare "cannot import"."""
    if name in ("Internals", "DEFAULT_INTERNALS"):
        raise ImportError(SPLIT_INTERNALS)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


@dataclass(frozen=True)
class LineDetection:
    """Thresholds of :func:`matcher.detect_lines` (LSD, then the merging of
    collinear fragments and a minimum length). Pixels and degrees."""

    #: Lines shorter than this many pixels are dropped: their orientation is
    #: too uncertain for the constraints (as ``Tolerances.min_line_px``).
    min_length_px: float = 15.0
    #: Fragments merge when their directions differ by less than this many
    #: degrees (LSD's own angle tolerance is 22.5 degrees per pixel, its
    #: lines are good to about a degree)...
    merge_angle_deg: float = 2.0
    #: ...each one's end points lie within this many pixels of the other's
    #: line (both edges of a stroke up to about 4 px wide)...
    merge_offset_px: float = 4.0
    #: ...and the gap between them along the line is at most this.
    merge_gap_px: float = 10.0
    #: Candidate pairs for merging come from points this far apart along the
    #: lines (a k-d tree on them; smaller finds the same pairs, slower).
    merge_sample_px: float = 8.0
    #: Fragments shorter than this are dropped before merging: LSD returns
    #: hundreds of 2 to 4 px specks on texture, and a line this short adds
    #: at most its length to a merged line. (Kept well below
    #: ``min_length_px``: a line broken in pieces of 5 px still merges.)
    merge_keep_px: float = 4.0
    #: Images of more pixels are refused: LSD's time and memory grow with
    #: the image (a 10000 x 10000 image would need tens of GiB).
    max_image_pixels: float = 40e6

    def __post_init__(self) -> None:
        for f in fields(self):
            v = getattr(self, f.name)
            if not (v == v) or v < 0 or v == math.inf:
                raise InputError(f"line detection setting {f.name} must be a finite number >= 0, got {v}")
        if self.merge_sample_px <= 0:
            raise InputError(f"line detection setting merge_sample_px must be > 0, got {self.merge_sample_px}")


#: The default line detection.
DETECTION = LineDetection()


@dataclass(frozen=True)
class Tracking:
    """Settings of :class:`matcher.Tracker` (following a moving robot with
    odometry). Metres and degrees.

    The odometry noise model is deliberately pessimistic: the errors of a
    wheel odometry are mostly systematic (a wheel radius off by a percent, a
    gyro bias), so the standard deviations it adds grow linearly with the
    distance and the turn, not with their square roots."""

    #: Position error of the odometry per metre driven (a fraction: 0.05 is
    #: 5 cm per metre; wheel odometry on a hard floor is good to 1 to 5 %).
    odom_distance_fraction: float = 0.05
    #: Heading drift of the odometry per metre driven, degrees.
    odom_deg_per_m: float = 2.0
    #: Heading error of the odometry per degree turned (a fraction).
    odom_deg_per_deg: float = 0.05
    #: A frame's search bounds (``dt``, ``dyaw`` of :func:`matcher.localize`)
    #: are this many standard deviations of the estimate.
    bound_sigmas: float = 3.0
    #: The search bounds are never smaller than these (metres, degrees):
    #: the stage 1 pose grid and the image noise leave a few centimetres
    #: and a degree whatever the estimate's own spread.
    min_dt_m: float = 0.1
    min_dyaw_deg: float = 3.0
    #: After an accepted frame, the estimate's standard deviations are at
    #: least these (metres, degrees): ``pose_std`` counts the image noise
    #: only, not the map's own error or a camera mounted a little off.
    accepted_std_floor_m: float = 0.02
    accepted_std_floor_deg: float = 0.3
    #: The tracker is lost, and relocalises with no prior, when the search
    #: bounds grow past these (metres, degrees)...
    max_dt_m: float = 1.0
    max_dyaw_deg: float = 45.0
    #: ...or after this many frames in a row were not localised...
    max_failed_frames: int = 3
    #: ...counting only frames with at least this many usable image lines
    #: (``Tolerances.min_line_px`` long): a view of a bare wall says nothing
    #: against the estimate, and a search of the whole map on it is time lost.
    judging_lines: int = 5
    #: A pose found with no prior is trusted only after this many frames in a
    #: row have been localised from it (one frame's word does not move the robot).
    confirm_frames: int = 2
    #: A frame confirms a pose found with no prior only when the pose
    #: explains at least this share of the frame's usable lines (clutter
    #: leaves the rest). A search of part of the map (the time budget) can
    #: return a pose in the wrong room that explains a few lines well and
    #: the rest not at all, and the frames after it, seen from nearly the
    #: same place, agree with it for the same reason.
    confirm_share: float = 0.6
    #: A pose found with no prior is dropped after this many frames it fails to explain.
    max_candidate_misses: int = 2
    #: At most this many poses are followed at once while relocalising (the
    #: twins of a symmetric room, kept until a frame tells them apart).
    max_candidates: int = 8
    #: Time budget of one relocalisation (lost mode), milliseconds.
    relocalise_budget_ms: float = 1000.0
    #: A bag's image is given the odometry interpolated at its time stamp;
    #: farther than this many seconds from any odometry message, it has none.
    odom_max_gap_s: float = 0.2
    #: A rig's bag: the images of one instant are those within this share
    #: of the slowest camera's frame period of the instant's first image
    #: (a half: two images of one camera never fall in one instant, the
    #: images of one trigger always do; matcher.tracking.rig_sync).
    rig_sync_share: float = 0.5
    #: ...and an instant is given up waiting for a camera's image once an
    #: image this many seconds past it has come (a camera that stopped).
    rig_sync_wait_s: float = 1.0
    #: The frame period of each camera of a rig's bag is measured on its
    #: first this many images (their bag times: no image is decoded).
    rig_period_sample: int = 20

    def __post_init__(self) -> None:
        for f in fields(self):
            v = getattr(self, f.name)
            if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v) or v < 0:
                raise InputError(f"tracking setting {f.name} must be a finite number >= 0, got {v!r}")
        if self.max_dt_m < self.min_dt_m or self.max_dyaw_deg < self.min_dyaw_deg:
            raise InputError("tracking settings: max_dt_m/max_dyaw_deg must be at least min_dt_m/min_dyaw_deg")
        if self.max_candidates < 1 or self.relocalise_budget_ms <= 0:
            raise InputError("tracking settings: max_candidates must be >= 1 and relocalise_budget_ms > 0")


#: The default tracking settings.
TRACKING = Tracking()


@dataclass(frozen=True)
class PanoramaCut:
    """How :mod:`matcher.panorama` cuts an equirectangular panorama into a
    ring of level virtual pinhole cameras. Degrees; the image sizes follow
    from the panorama's own resolution (the same pixels per degree at each
    view's centre). Chosen on measurement: see matcher/panorama.py."""

    #: Views around the ring, evenly spaced: each keeps the lines of its own
    #: sector, 360 / views degrees wide. 4, 6, 8 and 12 views support about
    #: as many map segments on the ZInD sample tour (4 a few fewer); 8 with
    #: ``hfov_deg`` 90 keeps lines up to 45 degrees long whole.
    views: int = 8
    #: Horizontal field of view of each view. Above the sector's width by the
    #: overlap: a line spanning up to ``hfov_deg - 360 / views`` degrees of
    #: azimuth lies whole in the view that keeps it.
    hfov_deg: float = 90.0
    #: Vertical field of view: the floor and ceiling junctions of a room in
    #: one view (+-50 degrees at the view's centre, +-40 at its sides: the
    #: floor from 1.2 to 1.7 m away for a camera 1.435 m high). On the ZInD
    #: sample tour 90 to 130 degrees support as many map segments (a median
    #: of 24 to 25 per panorama); 100 has the most panoramas with at least 6
    #: and 10 of them, with 14 % fewer lines (clutter) than 110 and half
    #: those of 130 (docs/benchmarks/pano-cut.md).
    vfov_deg: float = 100.0
    #: Pitch of every view, positive looking down (0: the ring is level and a
    #: line's azimuth alone says whether it lies inside a view horizontally).
    pitch_deg: float = 0.0

    def __post_init__(self) -> None:
        if isinstance(self.views, bool) or not isinstance(self.views, numbers.Integral) or not 3 <= self.views <= 64:
            raise InputError(f"panorama views must be a whole number from 3 to 64, got {self.views!r}")
        for name, lo, hi in (("hfov_deg", 1.0, 170.0), ("vfov_deg", 1.0, 170.0), ("pitch_deg", -60.0, 60.0)):
            v = getattr(self, name)
            if not _number(v) or not lo <= v <= hi:
                raise InputError(f"panorama {name} must be a number from {lo:g} to {hi:g}, got {v!r}")
        if self.hfov_deg <= 360.0 / self.views:
            raise InputError(f"panorama views of {self.hfov_deg:g} degrees leave gaps between {self.views} sectors of "
                             f"{360.0 / self.views:g} degrees: widen hfov_deg or add views")


#: The default cut of a panorama.
PANORAMA_CUT = PanoramaCut()
