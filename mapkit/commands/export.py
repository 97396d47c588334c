"""``mapkit export MAP --geojson OUT.geojson``: regions and segments for GIS tools."""

from __future__ import annotations

import json
from pathlib import Path

from mapkit.atomic import write_atomic

HELP = "export regions (Polygons) and segments (3D LineStrings) as GeoJSON"


def add_arguments(p) -> None:
    p.add_argument("map", metavar="MAP", help=".lmap file")
    p.add_argument("--geojson", required=True, metavar="OUT", help="GeoJSON file to write")


def to_geojson(m) -> dict:
    """A FeatureCollection: one Polygon per region (properties id, segments),
    one 3D LineString per segment (properties id, kind). Metres, local frame."""
    from mapkit.lmap import SegmentKind

    features = []
    for r in range(m.n_regions):
        rings = m.region_rings(r)
        outer = [p for p, hole in rings if not hole]
        holes = [p for p, hole in rings if hole]
        coords = [_closed(p) for p in outer[:1]] + [_closed(p) for p in holes]
        features.append(
            {
                "type": "Feature",
                "geometry": {"type": "Polygon", "coordinates": coords},
                "properties": {"id": r, "segments": [int(s) for s in m.region_list(r)]},
            }
        )
    for i, (seg, kind) in enumerate(zip(m.segments, m.kinds)):
        features.append(
            {
                "type": "Feature",
                "geometry": {"type": "LineString", "coordinates": [[float(v) for v in p] for p in seg]},
                "properties": {"id": i, "kind": SegmentKind(int(kind)).label},
            }
        )
    return {"type": "FeatureCollection", "features": features}


def _closed(p) -> list[list[float]]:
    pts = [[float(x), float(y)] for x, y in p]
    return pts + [pts[0]]


def run(args) -> int:
    from mapkit.lmap import load_map

    m = load_map(args.map)
    out = Path(args.geojson)
    write_atomic(out, json.dumps(to_geojson(m)))
    print(f"wrote {out}: {m.n_regions} regions, {m.n_segments} segments")
    return 0
