#!/usr/bin/env python3
"""How many map segments a panorama's cut shows: the cuts of matcher.panorama compared on a ZInD tour.

    python tools/bench_pano_cut.py /path/to/zind/000
    python tools/bench_pano_cut.py TOUR --cuts 8x90x110,6x100x110 --report docs/benchmarks/pano-cut.md

The floor's map is built from the tour's annotations (``mapkit build
zind_data.json``, as ``tools/bench_real.py`` does); each panorama is cut by
:func:`matcher.panorama_lines` (every view's lines, each kept by one view)
at its annotated place and heading (a ZInD panorama of plan rotation ``r``
looks along world heading ``-90 - r`` at its centre column), for every cut
of ``--cuts`` (``VIEWSxHFOVxVFOV`` degrees). A map segment is *supported*
when a kept line lies along its projection in some view: within 2 degrees
and 3 px, overlapping half of the segment's part in the image
(:mod:`mapkit_harness.line_support`). Per cut: supported segments per
panorama (median, p10, p90), panoramas with at least 6 and 10, kept lines
per panorama, segments supported by two views (a line kept twice, or a long
one kept as pieces), the views' size and the time to cut and detect.
"""

from __future__ import annotations

import argparse
import math
import os
import sys
import tempfile
import time
from pathlib import Path

import cv2
import numpy as np

import matcher
from mapkit_harness.line_support import supported_segments
from mapkit_harness.tables import Table, add_report_option, reported
from matcher.panorama import panorama_rig

DEFAULT_CUTS = "8x90x100,8x90x90,8x90x110,8x90x130,8x75x90,8x75x110,6x100x110,12x60x90,12x60x110,4x120x110"


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description="Map segments supported by the lines of a panorama's cut, on a ZInD tour.")
    ap.add_argument("tour", help="a ZInD tour folder (zind_data.json and panos/)")
    ap.add_argument("--floor-name", help="the floor to build (default: the tour's first)")
    ap.add_argument("--cuts", default=DEFAULT_CUTS, help=f"VIEWSxHFOVxVFOV,... (default {DEFAULT_CUTS})")
    ap.add_argument("--max-panos", type=int, default=0, help="only the first N panoramas (0: all)")
    add_report_option(ap)
    args = ap.parse_args(argv)
    return reported(args.report, lambda: run(args), __file__, argv)


def parse_cuts(text: str) -> list[tuple[int, float, float]]:
    """``VIEWSxHFOVxVFOV,...`` as tuples; InputError if it is not, or a cut is impossible."""
    try:
        cuts = [(int(v), float(h), float(t)) for v, h, t in (c.lower().split("x") for c in text.split(","))]
    except ValueError:
        raise matcher.InputError(f"--cuts must be VIEWSxHFOVxVFOV,... (e.g. 8x90x110), got {text!r}") from None
    for v, h, t in cuts:
        panorama_rig(2048, 1.0, views=v, hfov_deg=h, vfov_deg=t)  # refuses an impossible cut
    return cuts


def run(args) -> int:
    from linemap.lmap import save_map
    from mapkit.errors import MapkitError
    from mapkit.importers.zind.annotations import read_floor
    from mapkit.options import BuildOptions
    from mapkit.pipeline import build_map

    data = Path(args.tour) / "zind_data.json"
    try:
        cuts = parse_cuts(args.cuts)
        if not data.is_file():
            raise MapkitError(f"{args.tour}: no zind_data.json; give the folder of a ZInD tour (e.g. .../000)")
        floor = read_floor(data, args.floor_name)
        m, _ = build_map(data, BuildOptions(floor_name=floor.name))
    except (MapkitError, matcher.InputError) as e:
        print(f"bench_pano_cut: error: {e}", file=sys.stderr)
        return 2
    path = Path(tempfile.gettempdir()) / f"bench_pano_cut_{os.getpid()}.lmap"
    save_map(path, m)  # the map as the matcher reads it (quantised as in a file)
    try:
        segments = matcher.load_map(path).segments
    finally:
        path.unlink(missing_ok=True)
    panos = floor.panos[: args.max_panos] if args.max_panos else floor.panos
    rows = {c: [] for c in cuts}
    for n, pano in enumerate(panos):
        image = cv2.imread(str(Path(args.tour) / pano.image_path), cv2.IMREAD_GRAYSCALE)
        if image is None:
            print(f"bench_pano_cut: error: {pano.image_path}: panorama missing or unreadable", file=sys.stderr)
            return 2
        heading = math.radians(-90.0 - pano.rotation_deg)
        for cut in cuts:
            rows[cut].append(measure(image, pano, heading, cut, segments))
        print(f"  {n + 1} / {len(panos)} panoramas", file=sys.stderr, flush=True)
    print(f"tour {args.tour}, floor {floor.name}: {len(panos)} panoramas, map {len(segments)} segments, "
          f"camera {floor.panos[0].camera_height:.3f} m; panoramas {image.shape[1]}x{image.shape[0]}")
    table = Table("views x hfov x vfov", "view px", "supported / pano (median, p10, p90)", "panos >= 6", "panos >= 10",
                  "kept lines / pano", "by 2+ views / pano", "s / pano")
    for cut in cuts:
        r = rows[cut]
        sup = np.array([x["supported"] for x in r])
        cam = panorama_rig(image.shape[1], 1.0, views=cut[0], hfov_deg=cut[1], vfov_deg=cut[2])[0].camera
        table.row("x".join(f"{v:g}" for v in cut), f"{cam.width}x{cam.height}",
                  f"{np.median(sup):g}, {np.percentile(sup, 10):g}, {np.percentile(sup, 90):g}",
                  f"{(sup >= 6).sum()} / {len(r)}", f"{(sup >= 10).sum()} / {len(r)}",
                  f"{np.median([x['lines'] for x in r]):g}", f"{np.median([x['twice'] for x in r]):g}",
                  f"{np.median([x['seconds'] for x in r]):.2f}")
    return 0


def measure(image: np.ndarray, pano, heading: float, cut, segments: np.ndarray) -> dict:
    """One panorama through one cut: distinct supported segments, kept lines,
    segments supported by more than one view, seconds to cut and detect."""
    rig = panorama_rig(image.shape[1], pano.camera_height, views=cut[0], hfov_deg=cut[1], vfov_deg=cut[2])
    t0 = time.perf_counter()
    per_camera = matcher.panorama_lines(image, rig)
    seconds = time.perf_counter() - t0
    robot = np.array([pano.position[0], pano.position[1], heading])
    counts: dict[int, int] = {}
    for rc, lines in zip(rig, per_camera):
        for s in supported_segments(rc.camera, rc.mount.camera_poses(robot), segments, lines):
            counts[int(s)] = counts.get(int(s), 0) + 1
    return {"supported": len(counts), "twice": sum(c > 1 for c in counts.values()),
            "lines": sum(len(x) for x in per_camera), "seconds": seconds}


if __name__ == "__main__":
    sys.exit(main())
