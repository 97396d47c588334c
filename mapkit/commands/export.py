"""``mapkit export MAP --geojson OUT.geojson``: regions and segments for GIS tools."""

from __future__ import annotations

import json

from linemap.atomic import check_output_path, write_atomic

HELP = "export regions (Polygons) and segments (3D LineStrings) as GeoJSON"


def add_arguments(p) -> None:
    p.add_argument("map", metavar="MAP", help=".lmap file")
    p.add_argument("--geojson", required=True, metavar="OUT", help="GeoJSON file to write")
    p.add_argument("--drawing-coordinates", action="store_true",
                   help="in the source drawing's coordinates: a georeferenced plan's origin offset "
                        "(mapkit info) added back; default: the map's local frame")


def to_geojson(m, drawing_coordinates: bool = False) -> dict:
    """A FeatureCollection: one Polygon per region (properties id, segments),
    one 3D LineString per segment (properties id, kind). Metres, the map's
    local frame, or with ``drawing_coordinates`` the source drawing's (its
    ``origin_offset_m`` added: a georeferenced plan's national grid)."""
    from linemap.lmap import SegmentKind

    offset = m.meta.get("origin_offset_m") if drawing_coordinates else None
    ox, oy = offset or (0.0, 0.0)

    features = []
    for r in range(m.n_regions):
        rings = m.region_rings(r)
        outer = [p for p, hole in rings if not hole]
        holes = [p for p, hole in rings if hole]
        # RFC 7946: the outer ring counter-clockwise, holes clockwise.
        coords = [_closed(p + (ox, oy), ccw=True) for p in outer[:1]] + [_closed(p + (ox, oy), ccw=False) for p in holes]
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
                "geometry": {"type": "LineString", "coordinates": [[float(p[0] + ox), float(p[1] + oy), float(p[2])]
                                                                  for p in seg]},
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
    write_atomic(out, json.dumps(to_geojson(m, args.drawing_coordinates)))
    print(f"wrote {out}: {m.n_regions} regions, {m.n_segments} segments")
    return 0
