#!/usr/bin/env python3
"""The matcher on real photographs: perspective views cut from a ZInD tour.

    python tools/bench_real.py /path/to/zind/000              # the tour's first floor
    python tools/bench_real.py TOUR --jobs 2 --overlays /tmp/overlays
    python tools/bench_real.py TOUR --headings 1 --peq 1 5 --lost-every 0 --budget-ms inf   # no time budget at all
    python tools/bench_real.py TOUR --check 6 --overlays /tmp/check   # ground truth only

ZInD (Zillow Indoor Dataset, its own terms of use: download it yourself; no
part of it is in this project) gives upright-corrected 360-degree panoramas
of a home with human-annotated room layouts and each panorama's place on the
floor plan. The floor's map is built from the annotations with
``mapkit build zind_data.json`` (:mod:`mapkit.importers.zind`); from every
panorama, ``--headings`` perspective views are cut (evenly spaced, a seeded
random offset each) with a horizontal field of view in ``--hfov``, a pitch in
``--pitch`` (down) and one of ``--sizes``, drawn per view from the seed.
A view's true pose is the panorama's place and the heading it was cut at.

Per view: lines by :func:`matcher.detect_lines`; the map segments in sight
at the true pose (``mapkit_harness.simulate.visible_lines``); :func:`matcher.localize`
from a prior drawn within each PEQ's bounds (``mapkit_harness.simulate.PEQ``, as in
``tools/bench_paper.py``: dt 0.2 to 1.0 m, dyaw 10 to 50 deg); and
:func:`matcher.localize_global` (lost mode) on every ``--lost-every``-th view;
with ``--oracle``, also from a prior centred on the true pose (PEQ 1's
bounds): what the map allows at best, the cap of the other modes;
each call within ``--budget-ms`` (default 1 s: unbounded, a real view can
take a minute and a whole run hours).
A table per mode: views, views showing at least 6 map lines, within
20 cm / 5 deg and 5 cm / 1 deg, accepted and wrong (over 50 cm or 10 deg),
not localised, time per call median / p95 (wall, and CPU of one thread:
the tool keeps BLAS to one thread), lines per view. ``--overlays DIR``
saves the failing views: the map at the true pose in green, the detected
lines in red, the returned pose's map in blue.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import sys
import tempfile
import time
from concurrent.futures import ProcessPoolExecutor
from dataclasses import replace
from pathlib import Path

# CPU per call is one thread's, as a robot's process would spend it: a BLAS
# library left to start its own threads spins them on the matcher's small
# matrices, and time.process_time counts the spinning (a third of the
# figure on 2 cores). Read when numpy loads, so set before it is imported.
for _threads in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_threads, "1")

import numpy as np

import matcher

from mapkit_harness.panorama import cut_view, view_pose
from mapkit_harness.simulate import PEQ, PEQ_HELP, pose_error, visible_lines
from mapkit_harness.tables import add_report_option, markdown_table, reported


#: Right, tight: within these (metres, degrees) of the true pose.
RIGHT = (0.20, 5.0)
TIGHT = (0.05, 1.0)
#: Accepted and wrong: farther than either of these.
WRONG = (0.50, 10.0)
#: A view "shows the map" when at least this many segments are in sight.
MIN_SHOWN = 6
#: The footprint radius (m) of a tripod, the carrier of ZInD's panoramas
#: (``--robot-radius`` takes it to build the tour's map for it). What keeps a
#: tripod's camera from a wall is its own body, a few centimetres, and the
#: photographers stood it in doorways and by walls (on the sample tour 0.12 m
#: from a wall's face and 0.005 m from a room's open edge at the nearest).
#: With the builder's default (0.2 m, a robot's), 7 of the tour's 32
#: panoramas stand 0.075 to 0.244 m outside the map's regions and stage 2
#: refuses their true poses as outside the free space (``free_space_m``,
#: 0.1 m); at 0.05 m every one is within 0.075 m of them. Measured, it is not
#: the default: docs/benchmarks/real-structure.md, sixth pass.
TRIPOD_RADIUS_M = 0.05


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description="Localise perspective views cut from a ZInD tour's panoramas.")
    ap.add_argument("tour", help="a ZInD tour folder (zind_data.json and panos/)")
    ap.add_argument("--floor-name", help="floor to use (default the tour's first)")
    ap.add_argument("--headings", type=int, default=5, help="views per panorama, evenly spaced (default 5)")
    ap.add_argument("--hfov", default="60,90", help="range of horizontal fields of view, degrees (default 60,90)")
    ap.add_argument("--pitch", default="0,10", help="range of pitches, degrees down (default 0,10)")
    ap.add_argument("--sizes", default="640x480,800x600", help="image sizes to choose from (default 640x480,800x600)")
    ap.add_argument("--rig", type=int, default=0, metavar="N",
                    help="rig mode: N cameras around each panorama's centre (a seeded heading offset, each camera's "
                         "field of view, pitch and size drawn as a single view's), localised together as one robot "
                         "(matcher.localize_rig); one frame per panorama")
    ap.add_argument("--pano", action="store_true",
                    help="panorama mode: each whole panorama cut by matcher.panorama (its default views) and "
                         "localised as one robot (matcher.localize_rig); one frame per panorama")
    ap.add_argument("--peq", type=int, nargs="*", default=sorted(PEQ), choices=sorted(PEQ),
                    help="PEQ levels to run (default 1 to 5). " + PEQ_HELP)
    ap.add_argument("--lost-every", type=int, default=4, help="lost mode on every N-th view (0: none; default 4)")
    ap.add_argument("--oracle", action="store_true",
                    help="also localise from a prior centred on the true pose, with PEQ 1's bounds: the share "
                         "right the map allows at best (ZInD's annotated layout as the map)")
    ap.add_argument("--budget-ms", type=float, default=1000.0,
                    help="time budget per call, ms (default 1000, which keeps a run of the sample tour near 15 min; "
                         "inf: none)")
    ap.add_argument("--robot-radius", type=float, default=None, metavar="M",
                    help=f"footprint radius the tour's map is built with, m (mapkit build --robot-radius; default the "
                         f"builder's, a robot's; a tripod's, which took the panoramas: {TRIPOD_RADIUS_M:g})")
    ap.add_argument("--max-views", type=int, default=0, help="stop after this many views (0: all)")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--search", choices=("tree", "structure"),
                    help="how places are ranked before stage 2 (matcher.search; default: the matcher's default "
                         "per kind of frame)")
    ap.add_argument("--jobs", type=int, default=1, help="worker processes (the views of a panorama stay together)")
    ap.add_argument("--overlays", metavar="DIR", help="save PNGs of the failing views here")
    ap.add_argument("--rows", metavar="FILE.json", help="save every view's results here (for analysis)")
    ap.add_argument("--check", type=int, default=0, metavar="N",
                    help="only save N views with the map at the true pose to --overlays (ground-truth check)")
    add_report_option(ap)
    args = ap.parse_args(argv)
    return reported(args.report, lambda: run(args), __file__, argv)


def run(args) -> int:
    """The benchmark as ``main``'s arguments say; prints the tables."""
    from mapkit.errors import MapkitError
    try:
        views, floor, lmap_path, camera_height = prepare(args)
    except MapkitError as e:
        print(f"bench_real: error: {e}", file=sys.stderr)
        return 2
    if args.check:
        try:
            if not args.overlays:
                print("bench_real: error: --check needs --overlays DIR", file=sys.stderr)
                return 2
            check_views(views[: args.check], args, lmap_path)
            return 0
        finally:
            Path(lmap_path).unlink(missing_ok=True)

    try:
        return run_all(views, floor, lmap_path, camera_height, args)
    finally:
        Path(lmap_path).unlink(missing_ok=True)


def run_all(views, floor, lmap_path, camera_height, args) -> int:
    """Localise every view (in ``--jobs`` processes) and print the tables."""
    tasks = group_by_pano(views)
    t0 = time.perf_counter()
    rows = []
    if args.jobs > 1:
        with ProcessPoolExecutor(args.jobs) as ex:
            for done in ex.map(run_pano, [(t, args, lmap_path) for t in tasks]):
                rows += done
                print(f"  {len(rows)} / {len(views)} views", file=sys.stderr, flush=True)
    else:
        for t in tasks:
            rows += run_pano((t, args, lmap_path))
            print(f"  {len(rows)} / {len(views)} views", file=sys.stderr, flush=True)
    elapsed = time.perf_counter() - t0

    m = matcher.load_map(lmap_path)
    print(f"tour {args.tour}, floor {floor.name}: {len(floor.rooms)} rooms, {len(floor.panos)} panoramas; "
          f"map {len(m.segments)} segments, {len(m.regions) if hasattr(m, 'regions') else m.n_regions} regions; "
          f"camera height {camera_height:.3f} m; built with --robot-radius {m.meta['build']['robot_radius']:g} m")
    print(f"search {args.search or 'default'}; "
          f"{len(rows)} views: hfov {args.hfov} deg, pitch {args.pitch} deg down, sizes {args.sizes}, "
          f"{args.headings} headings per panorama, seed {args.seed}, budget "
          f"{'none' if math.isinf(args.budget_ms) else f'{args.budget_ms:g} ms'}; {elapsed / 60:.1f} min with "
          f"{args.jobs} job(s)")
    print(table(rows, args))
    if args.rows:
        Path(args.rows).write_text(json.dumps(rows, default=float))
    return 0


# --------------------------------------------------------------------------
# Views


def prepare(args):
    """The views to run (dicts), the floor, the built map's path, the camera height."""
    from linemap.lmap import save_map
    from mapkit.importers.zind.annotations import read_floor
    from mapkit.options import BuildOptions
    from mapkit.pipeline import build_map

    from mapkit.errors import MapkitError

    tour = Path(args.tour)
    data = tour / "zind_data.json"
    if not data.is_file():
        raise MapkitError(f"{tour}: no zind_data.json; give the folder of a ZInD tour (e.g. .../000)")
    floor = read_floor(data, args.floor_name)
    options = BuildOptions(floor_name=floor.name)
    if args.robot_radius is not None:
        options = replace(options, robot_radius=args.robot_radius)
    m, _ = build_map(data, options)
    path = Path(tempfile.gettempdir()) / f"bench_real_{os.getpid()}.lmap"
    save_map(path, m)
    camera_height = float(m.meta["camera"]["height_m"])

    rng = np.random.default_rng(args.seed)
    hfov = _range(args.hfov)
    pitch = _range(args.pitch)
    sizes = [tuple(int(v) for v in s.lower().split("x")) for s in args.sizes.split(",")]
    views = []
    per_frame = args.rig or args.headings
    for pano in floor.panos:
        image = tour / pano.image_path
        if not image.is_file():
            raise MapkitError(f"{image}: panorama missing; is the tour complete?")
        offset = rng.uniform(0, 360.0 / per_frame)
        cut = []
        for k in range(per_frame):
            w, h = sizes[int(rng.integers(len(sizes)))]
            cut.append({"yaw_deg": offset + k * 360.0 / per_frame, "hfov": float(rng.uniform(*hfov)),
                        "pitch": float(rng.uniform(*pitch)), "size": (w, h)})
        if args.pano:  # the whole panorama: our convention's robot heading of ZInD's plan rotation
            views.append({"id": len(views), "pano": pano, "image": str(image), "whole": True,
                          "yaw_deg": (-90.0 - pano.rotation_deg + 180.0) % 360.0 - 180.0})
        elif args.rig:  # one frame of N cameras, the robot heading along the first
            views.append({"id": len(views), "pano": pano, "image": str(image), "yaw_deg": offset, "cameras": cut})
        else:
            views += [{"id": len(views) + k, "pano": pano, "image": str(image), **c} for k, c in enumerate(cut)]
    if args.max_views:
        views = views[: args.max_views]
    return views, floor, str(path), camera_height


def _range(text: str) -> tuple[float, float]:
    lo, hi = (float(v) for v in text.split(","))
    return lo, hi


def group_by_pano(views):
    groups: dict[str, list] = {}
    for v in views:
        groups.setdefault(v["image"], []).append(v)
    return list(groups.values())


def view_camera(view, height_m: float) -> matcher.Camera:
    w, h = view["size"]
    return matcher.Camera.from_fov(view["hfov"], w, h, height_m, view["pitch"])


def cut(view, panorama, camera):
    return cut_view(panorama, view["pano"], camera, math.radians(view["yaw_deg"]))


# --------------------------------------------------------------------------
# Localisation


def run_pano(task):
    """Every view of one panorama: cut, detect, localise per PEQ and lost."""
    import cv2

    views, args, lmap_path = task
    m = _loaded(lmap_path, args)
    height_m = float(m.meta["camera"]["height_m"])
    panorama = cv2.imread(views[0]["image"], cv2.IMREAD_GRAYSCALE)
    # inf: no budget at all (the matcher's own default would be 30 s).
    tol = replace(matcher.Tolerances(), time_budget_ms=args.budget_ms, search=args.search)
    rows = []
    for view in views:
        if "cameras" in view or "whole" in view:
            rows.append(run_rig_frame(view, panorama, m, tol, args))
            continue
        camera = view_camera(view, height_m)
        image = cut(view, panorama, camera)
        truth = view_pose(view["pano"], view["yaw_deg"])
        lines = matcher.detect_lines(image, camera)
        shown, _ = visible_lines(m, camera, truth)
        row = {"id": view["id"], "pano": view["pano"].name, "truth": truth, "lines": len(lines),
               "shown": len(shown), "results": {}}
        run_modes(row, args, lambda prior, dt, dyaw: matcher.localize(m, camera, lines, prior, dt, dyaw, tolerances=tol),
                  lambda: matcher.localize_global(m, camera, lines, tolerances=tol))
        if args.overlays:
            save_failures(row, view, image, lines, camera, m, args.overlays)
        rows.append(row)
    return rows


_MAPS: dict = {}


def _loaded(lmap_path: str, args):
    """The map, loaded once per worker process, with what the search
    derives once per map made before any call is timed (as a robot does when
    it loads its map): the structure search's profiles."""
    if lmap_path not in _MAPS:
        m = matcher.load_map(lmap_path)
        if args.search == "structure":
            from matcher.search.structure.profiles import grid_profiles

            c = time.process_time()
            grid_profiles(m, matcher.Tolerances()).make_all()
            print(f"  structure profiles of the map: {time.process_time() - c:.1f} s of CPU, once", file=sys.stderr)
        _MAPS[lmap_path] = m
    return _MAPS[lmap_path]


def draw_prior(truth, rng, peq: int):
    """``(prior, dt, dyaw)``: a prior drawn uniformly within PEQ ``peq``'s
    bounds of the true pose ``truth`` (x, y, yaw_deg)."""
    dt, dyaw = PEQ[peq]
    r, phi = dt * math.sqrt(rng.uniform()), rng.uniform(0, 2 * math.pi)
    return (truth[0] + r * math.cos(phi), truth[1] + r * math.sin(phi), truth[2] + rng.uniform(-dyaw, dyaw)), dt, dyaw


def run_rig_frame(view, panorama, m, tol, args) -> dict:
    """One rig frame of a panorama: its cameras' views cut and their lines
    detected, the robot localised per PEQ and lost (matcher.localize_rig)."""
    height_m = float(m.meta["camera"]["height_m"])
    truth = view_pose(view["pano"], view["yaw_deg"])
    rig, lines = pano_frame(view, panorama, height_m) if "whole" in view else cut_rig(view, panorama, height_m)
    shown = set()
    for rc in rig:
        pose = view_pose(view["pano"], view["yaw_deg"] + rc.mount.yaw_deg)
        shown |= set(visible_lines(m, rc.camera, pose)[1].tolist())
    row = {"id": view["id"], "pano": view["pano"].name, "truth": truth, "lines": sum(len(x) for x in lines),
           "shown": len(shown), "results": {}}
    run_modes(row, args, lambda prior, dt, dyaw: matcher.localize_rig(m, rig, lines, prior, dt, dyaw, tolerances=tol),
              lambda: matcher.localize_rig_global(m, rig, lines, tolerances=tol))
    return row


def run_modes(row: dict, args, from_prior, lost) -> None:
    """``row["results"]`` per PEQ of ``--peq`` (``from_prior(prior, dt,
    dyaw)`` on a prior drawn from the row's seed) and, on every
    ``--lost-every``-th row, lost (``lost()``)."""
    truth = row["truth"]
    rng = np.random.default_rng([args.seed, row["id"]])
    for peq in args.peq:
        prior, dt, dyaw = draw_prior(truth, rng, peq)
        t, c = time.perf_counter(), time.process_time()
        res = from_prior(prior, dt, dyaw)
        row["results"][peq] = _outcome(res, truth, time.perf_counter() - t, time.process_time() - c)
    if args.oracle:
        t, c = time.perf_counter(), time.process_time()
        res = from_prior(truth, *PEQ[1])
        row["results"]["oracle"] = _outcome(res, truth, time.perf_counter() - t, time.process_time() - c)
    if args.lost_every and row["id"] % args.lost_every == 0:
        t, c = time.perf_counter(), time.process_time()
        res = lost()
        row["results"]["lost"] = _outcome(res, truth, time.perf_counter() - t, time.process_time() - c)


def cut_rig(view, panorama, height_m):
    """``(rig, lines per camera)``: the frame's views cut from the ZInD
    panorama (mapkit_harness.panorama, ZInD's pixels) at their headings
    and their lines."""
    cameras, lines = [], []
    for k, c in enumerate(view["cameras"]):
        camera = view_camera(c, height_m)
        cameras.append(matcher.RigCamera(f"cam{k}", camera, matcher.Mount(0.0, 0.0, c["yaw_deg"] - view["yaw_deg"])))
        lines.append(matcher.detect_lines(cut(c | {"pano": view["pano"]}, panorama, camera), camera))
    return matcher.Rig(tuple(cameras)), lines


def pano_frame(view, panorama, height_m):
    """``(rig, lines per camera)`` of the whole panorama through
    matcher.panorama (its default cut), as ``matcher localize --pano``
    makes them."""
    rig = matcher.panorama_rig(panorama.shape[1], height_m)
    return rig, matcher.panorama_lines(panorama, rig)


def _outcome(res, truth, seconds, cpu):
    out = {"ok": bool(res), "seconds": seconds, "cpu": cpu, "reason": "" if res else res.reason, "pose": None,
           "score": res.score, "runner_up": res.runner_up_score, "matches": len(res.matches),
           "candidates": len(res.candidates),
           # The best hypothesis of a refused answer: what accepting it would have given.
           "best_error": pose_error(res.ranked[0][2], truth) if res.ranked else None}
    if res:
        out["pose"] = tuple(res.pose)
        out["error"] = pose_error(res.pose, truth)
        out["pose_std"] = tuple(res.pose_std) if res.pose_std is not None else None
    return out


def classify(o) -> str:
    """'tight', 'right', 'off' (accepted, between right and wrong), 'wrong' or 'none'."""
    if not o["ok"]:
        return "none"
    d, a = o["error"]
    if d <= TIGHT[0] and a <= TIGHT[1]:
        return "tight"
    if d <= RIGHT[0] and a <= RIGHT[1]:
        return "right"
    if d > WRONG[0] or a > WRONG[1]:
        return "wrong"
    return "off"


def table(rows, args) -> str:
    modes = [p for p in args.peq] + (["oracle"] if args.oracle else []) + (["lost"] if args.lost_every else [])
    columns = ["mode", "views", "views showing >= 6 map lines", "within 20 cm / 5 deg (of those showing)",
               "within 5 cm / 1 deg", "accepted and wrong", "not localised", "time ms median / p95",
               "CPU ms median / p95", "lines per view (median)"]
    out = []
    for mode in modes:
        rs = [r for r in rows if mode in r["results"]]
        if not rs:
            continue
        cls = [classify(r["results"][mode]) for r in rs]
        shown = [r["shown"] >= MIN_SHOWN for r in rs]
        n, ns = len(rs), sum(shown)
        right = sum(c in ("tight", "right") for c in cls)
        right_shown = sum(c in ("tight", "right") for c, s in zip(cls, shown) if s)
        ms = np.array([r["results"][mode]["seconds"] * 1000 for r in rs])
        cpu = np.array([r["results"][mode].get("cpu", np.nan) * 1000 for r in rs])
        name = mode if mode in ("lost", "oracle") else f"PEQ {mode}"
        out.append([name, n, ns, f"{_pct(right, n)} ({_pct(right_shown, ns)})", _pct(cls.count("tight"), n),
                    _pct(cls.count("wrong"), n), _pct(cls.count("none"), n),
                    f"{np.median(ms):.0f} / {np.percentile(ms, 95):.0f}",
                    f"{np.median(cpu):.0f} / {np.percentile(cpu, 95):.0f}", f"{np.median([r['lines'] for r in rs]):.0f}"])
    return markdown_table(columns, out)


def _pct(k, n) -> str:
    return f"{100.0 * k / n:.1f}%" if n else "-"


# --------------------------------------------------------------------------
# Overlays


def draw_overlay(image, lines, camera, m, truth, pose=None):
    """BGR image: the map at ``truth`` in green, ``lines`` in red, the map at ``pose`` in blue."""
    import cv2

    canvas = cv2.cvtColor(image, cv2.COLOR_GRAY2BGR) if image.ndim == 2 else image.copy()
    canvas = (canvas * 0.6).astype(np.uint8)
    for seg in visible_lines(m, camera, truth)[0]:
        cv2.line(canvas, _pt(seg[0]), _pt(seg[1]), (0, 220, 0), 3, cv2.LINE_AA)
    for seg in lines:
        cv2.line(canvas, _pt(seg[0]), _pt(seg[1]), (0, 0, 255), 1, cv2.LINE_AA)
    if pose is not None:
        for seg in visible_lines(m, camera, pose)[0]:
            cv2.line(canvas, _pt(seg[0]), _pt(seg[1]), (255, 120, 0), 2, cv2.LINE_AA)
    return canvas


def _pt(p):
    return int(round(float(p[0]))), int(round(float(p[1])))


def save_failures(row, view, image, lines, camera, m, folder):
    import cv2

    Path(folder).mkdir(parents=True, exist_ok=True)
    for mode, o in row["results"].items():
        c = classify(o)
        if c in ("tight", "right"):
            continue
        name = f"view{row['id']:03d}_{row['pano']}_{mode if mode in ('lost', 'oracle') else f'peq{mode}'}_{c}.png"
        cv2.imwrite(str(Path(folder) / name), draw_overlay(image, lines, camera, m, row["truth"], o["pose"]))


def check_views(views, args, lmap_path):
    """Save the map at the true pose over each view: the ground-truth check."""
    import cv2

    m = matcher.load_map(lmap_path)
    height_m = float(m.meta["camera"]["height_m"])
    Path(args.overlays).mkdir(parents=True, exist_ok=True)
    for view in views:
        panorama = cv2.imread(view["image"], cv2.IMREAD_GRAYSCALE)
        camera = view_camera(view, height_m)
        image = cut(view, panorama, camera)
        lines = matcher.detect_lines(image, camera)
        truth = view_pose(view["pano"], view["yaw_deg"])
        path = Path(args.overlays) / f"check_view{view['id']:03d}_{view['pano'].name}.png"
        cv2.imwrite(str(path), draw_overlay(image, lines, camera, m, truth))
        print(f"wrote {path}: pose {truth[0]:.2f}, {truth[1]:.2f}, {truth[2]:.1f} deg; hfov {view['hfov']:.0f}, "
              f"pitch {view['pitch']:.1f}; {len(lines)} lines")


if __name__ == "__main__":
    sys.exit(main())
