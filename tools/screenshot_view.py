"""Make the README screenshot of ``mapkit view`` (docs/images/inspector.png).

    python tools/screenshot_view.py [MAP] [-o docs/images/inspector.png]

Opens the inspector on MAP (default: maps/flat.lmap if it has been built,
else the grid flat of mapkit_harness.plans) in Debian's headless chromium,
clicks a region, sets the pose tool, overlays a simulated matcher result
(the model's own lines at a nearby pose, so no camera image is needed) and
saves the page as PNG. Needs ``apt-get install -y chromium``.
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]


def simulated_result(m, camera, x: float, y: float, yaw: float) -> dict:
    """A matcher result as the matcher would write it for a camera at (x, y, yaw):
    the visible model segments projected (up to 8 matched), a small pose error."""
    from mapkit.view.synthetic_image import project_segments

    ids = m.candidate_segments(x, y, 0.0)
    lines, idx = project_segments(camera, m.segments[ids], x, y, yaw)
    length = np.linalg.norm(lines[:, 1] - lines[:, 0], axis=1)
    keep = np.argsort(-length)[:8]
    return {
        "ok": True,
        "pose": {"x": x + 0.04, "y": y - 0.03, "yaw_deg": math.degrees(yaw) + 1.0},
        "score": 0.0011,
        "matches": [[int(ids[idx[k]]), i] for i, k in enumerate(keep)],
        "lines": lines[keep].reshape(-1, 4).tolist(),
    }


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("map", nargs="?", help=".lmap file (default: maps/flat.lmap or a synthetic flat)")
    ap.add_argument("-o", "--out", default=str(ROOT / "docs" / "images" / "inspector.png"))
    ap.add_argument("--size", default="1600x1000", help="page size in CSS pixels, WxH")
    args = ap.parse_args(argv)

    import cv2

    from linemap.lmap import load_map
    from mapkit_harness.browser import Chromium, wait_for
    from mapkit_harness.plans import grid_flat
    from mapkit.view.result import parse_result
    from mapkit.view.server import Inspector
    from mapkit.view.stats import map_camera

    default = ROOT / "maps" / "flat.lmap"
    path = Path(args.map) if args.map else (default if default.exists() else None)
    m = load_map(path) if path else grid_flat()
    print(f"map: {path or 'synthetic flat'} ({m.n_segments} segments, {m.n_regions} regions)")
    width, height = (int(v) for v in args.size.lower().split("x"))

    camera, _ = map_camera(m)
    centres = m.region_centres()
    mid = centres.mean(axis=0)
    # The result: a camera in the region nearest a point left of the middle, looking right.
    rx, ry = centres[np.argmin(np.linalg.norm(centres - (mid - [0.25 * np.ptp(centres[:, 0]), 0]), axis=1))]
    result = parse_result(simulated_result(m, camera, float(rx), float(ry), 0.3), n_segments=m.n_segments)

    with Inspector(m, port=0, map_path=path, result=result) as ins:
        pc = ins.panel.pose
        px, py = centres[np.argmin(np.linalg.norm(centres - (mid + [0.2 * np.ptp(centres[:, 0]), 0]), axis=1))]
        pc.x.value, pc.y.value, pc.yaw.value, pc.dt.value, pc.dyaw.value = float(px), float(py), 120.0, 0.6, 20.0
        ins.update_pose()
        sel = centres[np.argmin(np.linalg.norm(centres - mid, axis=1))]
        ins.select_at(float(sel[0]), float(sel[1]))
        with Chromium(width, height) as browser:
            browser.navigate(ins.url)
            wait_for(lambda: ins.server.get_clients(), 30, what="the page to connect")
            time.sleep(3.0)
            # viser warns about software WebGL in a toast; it is about this headless run, not the map.
            browser.evaluate("document.querySelectorAll('[role=alert]').forEach(e => e.remove())")
            time.sleep(1.0)
            img = browser.screenshot()
    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    cv2.imwrite(str(out), img[:, :, ::-1], [cv2.IMWRITE_PNG_COMPRESSION, 9])
    print(f"wrote {out} ({img.shape[1]}x{img.shape[0]})")
    return 0


if __name__ == "__main__":
    sys.exit(main())
