"""``mapkit query MAP --at X,Y [--radius R] [--json]``: regions met, candidate segments."""

from __future__ import annotations

import json

from mapkit.errors import MapkitError

HELP = "list the regions met by a disk and the segments visible from it"


def parse_xy(text: str) -> tuple[float, float]:
    """'X,Y' in metres -> (x, y); a MapkitError says the expected form."""
    try:
        x, y = (float(v) for v in text.split(","))
    except ValueError:
        raise MapkitError(f"--at expects X,Y in metres (e.g. --at 2.5,1.0), got '{text}'") from None
    if not all(map(lambda v: v == v and abs(v) != float("inf"), (x, y))):
        raise MapkitError(f"--at must be finite, got '{text}'")
    return x, y


def add_arguments(p) -> None:
    p.add_argument("map", metavar="MAP", help=".lmap file")
    p.add_argument("--at", required=True, metavar="X,Y", help="position in metres")
    p.add_argument("--radius", type=float, default=0.0, metavar="R", help="disk radius in metres (default 0)")
    p.add_argument("--json", action="store_true", help='print {"regions": [...], "segments": [...]}')


def run(args) -> int:
    from linemap.lmap import load_map

    x, y = parse_xy(args.at)
    if not args.radius >= 0:
        raise MapkitError(f"--radius must be >= 0 metres, got {args.radius}")
    m = load_map(args.map)
    regions = m.regions_near(x, y, args.radius)
    segments = m.segments_for_regions(regions)
    out = {"regions": [int(r) for r in regions], "segments": [int(s) for s in segments]}
    if args.json:
        print(json.dumps(out))
    else:
        if not out["regions"]:
            print(f"({x}, {y}) r={args.radius}: outside every region of the map")
        else:
            print(f"({x}, {y}) r={args.radius}: {len(out['regions'])} region(s) {out['regions']}")
            print(f"{len(out['segments'])} candidate segment(s): {out['segments']}")
    return 0
