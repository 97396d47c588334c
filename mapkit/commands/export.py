"""``mapkit export MAP --geojson OUT.geojson``: regions and segments for GIS tools."""

from __future__ import annotations

import json

from linemap.atomic import check_output_path, write_atomic

HELP = "export regions (Polygons) and segments (3D LineStrings) as GeoJSON"


def add_arguments(p) -> None:
    p.add_argument("map", metavar="MAP", help=".lmap file")
    p.add_argument("--geojson", required=True, metavar="OUT", help="GeoJSON file to write")


def to_geojson(m) -> dict:
    """A FeatureCollection: one Polygon per region (properties id, segments),
    one 3D LineString per segment (properties id, kind). Metres, local frame."""
    from linemap.lmap import SegmentKind

    features = []
    for r in range(m.n_regions):
        rings = m.region_rings(r)
        outer = [p for p, hole in rings if not hole]
        holes = [p for p, hole in rings if hole]
        # RFC 7946: the outer ring counter-clockwise, holes clockwise.
        coords = [_closed(p, ccw=True) for p in outer[:1]] + [_closed(p, ccw=False) for p in holes]
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


def _closed(p, ccw: bool) -> list[list[float]]:
    """Ring ``p`` (K, 2) closed (first point repeated), turning
    counter-clockwise if ``ccw`` else clockwise."""
    pts = [[float(x), float(y)] for x, y in p]
    area2 = sum(x0 * y1 - x1 * y0 for (x0, y0), (x1, y1) in zip(pts, pts[1:] + pts[:1]))  # shoelace
    if (area2 > 0) != ccw:
        pts.reverse()
    return pts + [pts[0]]


def run(args) -> int:
    from linemap.lmap import load_map

    out = check_output_path(args.geojson, [args.map])
    m = load_map(args.map)
    write_atomic(out, json.dumps(to_geojson(m)))
    print(f"wrote {out}: {m.n_regions} regions, {m.n_segments} segments")
    return 0
