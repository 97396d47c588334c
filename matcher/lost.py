"""Lost mode (method.md section 3): localisation with no prior.

One prior per region of the map (its centre, ``dt`` its radius, any
heading, the region's own visible list), each searched as
:func:`matcher.from_prior.localize_prepared` searches a prior.
"""

from __future__ import annotations

import math
import time
from dataclasses import replace

import numpy as np

from linemap.camera import Camera
from matcher import from_prior
from matcher.budget import Deadlines
from matcher.frame import too_few_lines
from matcher.result import LocalizeResult
from matcher.tolerances import Tolerances


def localize_global(linemap, camera: Camera, lines, tolerances: Tolerances | None = None,
                    first_accepted: bool = False, progress=None):
    """Lost mode (method.md section 3): one prior per region (its centre,
    ``dt`` its radius, any heading, the region's own visible list).

    Regions are tried largest first. With ``first_accepted`` the search
    stops at the first region that gives an accepted hypothesis (the
    paper's loop).
    Otherwise every region is tried and the accepted result that explains
    the most lines wins, then the smallest E: a wrong room can hold a few
    lines that fit well, the right one explains more of the image.
    ``time_ms['total']`` covers all tries (the other entries are the winning
    region's); ``time_ms['regions_tried']`` counts them. ``progress``, if
    given, is called as ``progress(done, total)`` as the regions are done,
    last with ``done == total``. The tolerances' ``time_budget_ms`` bounds
    the whole call: regions are tried until it is spent. Returns a falsy
    result if no region gives one."""
    t0 = time.perf_counter()
    tol, img = from_prior.checked_inputs(linemap, camera, lines, tolerances)
    deadlines = Deadlines.from_budget(t0, tol.time_budget_ms, tol.internals.search_share)
    if linemap.n_regions == 0:
        return LocalizeResult(False, "the map has no regions", time_ms={"total": 0.0, "regions_tried": 0})
    too_few = too_few_lines(img, tol)
    if too_few:  # the same for every region
        return LocalizeResult(False, too_few, time_ms={"total": (time.perf_counter() - t0) * 1e3, "regions_tried": 0})
    # The robot is stopped: a larger search budget per region.
    factor = tol.internals.lost_budget_factor
    tol = replace(tol, max_nodes=tol.max_nodes * factor, max_sets=tol.max_sets * factor)
    centres, radii = linemap.region_centres(), linemap.region_radii()
    # Largest region first: with no estimate, the robot stands most likely
    # on the most floor, and a budget spent early has searched the most.
    order = np.argsort(-linemap.region_areas(), kind="stable")
    tried, best, out_of_time = 0, None, False
    for done, r in enumerate(order.tolist()):
        if progress is not None and done:
            progress(done, linemap.n_regions)
        if not deadlines.may_search():
            out_of_time = True
            break
        cx, cy = (float(v) for v in centres[r])
        dt = float(radii[r])
        if not (math.isfinite(cx) and math.isfinite(cy) and dt > 0):
            continue
        tried += 1
        res = from_prior.localize_prepared(linemap, camera, img, (cx, cy, 0.0, min(dt, 100.0), math.pi), tol,
                                         time.perf_counter(), deadlines, candidate_ids=linemap.region_list(r))
        out_of_time |= bool(res.stage1.get("out_of_time"))
        if res and (best is None or (len(res.matches), -res.score) > (len(best.matches), -best.score)):
            best = res
            if first_accepted:
                break
    if progress is not None:
        progress(linemap.n_regions, linemap.n_regions)
    total = (time.perf_counter() - t0) * 1e3
    if best is None:
        spent = f"; the time budget of {tol.time_budget_ms:g} ms ran out" if out_of_time else ""
        return LocalizeResult(False, f"no region gave an accepted hypothesis ({tried} of {linemap.n_regions} "
                              f"tried{spent})",
                              time_ms={"total": total, "regions_tried": tried})
    best.time_ms["total"] = total
    best.time_ms["regions_tried"] = tried
    # The best of the regions searched, not of all: the result says so.
    best.stage1["out_of_time"] = out_of_time
    return best
