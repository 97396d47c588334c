"""``mapkit info MAP [--json]``: what a map holds."""

from __future__ import annotations

import json

HELP = "summarise a .lmap map (counts, kinds, extent, build parameters)"


def add_arguments(p) -> None:
    p.add_argument("map", metavar="MAP", help=".lmap file, or a building manifest (building.json)")
    p.add_argument("--json", action="store_true", help="print one JSON object for scripts")


def summary(path) -> dict:
    """The ``info --json`` object: format version, counts, kinds, bbox, parameters, size."""
    import os

    import numpy as np

    from linemap.lmap import load_map
    from mapkit.pipeline import kind_counts

    m = load_map(path)
    pts = m.segments.reshape(-1, 3)
    if len(m.ring_points):
        xy = np.concatenate([pts[:, :2], m.ring_points]) if len(pts) else m.ring_points
    else:
        xy = pts[:, :2]
    lens = np.diff(m.list_offsets)
    bbox = (
        {"min": [float(v) for v in xy.min(0)] + [float(pts[:, 2].min()) if len(pts) else 0.0],
         "max": [float(v) for v in xy.max(0)] + [float(pts[:, 2].max()) if len(pts) else 0.0]}
        if len(xy) else None
    )
    return {
        "path": str(path),
        "format_version": f"{m.version[0]}.{m.version[1]}",
        "file_bytes": os.path.getsize(path),
        "units": m.meta.get("units", "m"),
        "segments": m.n_segments,
        "regions": m.n_regions,
        "segments_per_kind": kind_counts(m),
        "list_length": {
            "mean": float(lens.mean()) if len(lens) else 0.0,
            "max": int(lens.max()) if len(lens) else 0,
        },
        "bbox": bbox,
        "wall_height": m.meta.get("wall_height"),
        "camera": m.meta.get("camera"),
        "build": m.meta.get("build"),
        "source": m.meta.get("source"),
        "generator": m.meta.get("generator"),
        "stats": m.meta.get("stats"),
        "origin_offset_m": m.meta.get("origin_offset_m"),
    }


def run(args) -> int:
    if str(args.map).lower().endswith(".json"):
        return _building_info(args)
    s = summary(args.map)
    if args.json:
        print(json.dumps(s))
        return 0
    kinds = ", ".join(f"{k} {v}" for k, v in s["segments_per_kind"].items() if v)
    b = s["bbox"]
    source = s["source"]["name"] if isinstance(s["source"], dict) else s["source"]  # build writes an object
    lines = [
        f"{s['path']}: .lmap format {s['format_version']}, {s['file_bytes'] / 1024:.1f} KiB",
        f"  source     {source or '?'}  ({s['generator']})",
        f"  segments   {s['segments']}  ({kinds})",
        f"  regions    {s['regions']}  (visible list length: mean {s['list_length']['mean']:.1f}, max {s['list_length']['max']})",
    ]
    if b:
        size = [hi - lo for lo, hi in zip(b["min"], b["max"])]
        wh = s["wall_height"]
        wh = f"{wh:.3g}" if isinstance(wh, (int, float)) else wh
        lines.append(f"  extent     {size[0]:.2f} x {size[1]:.2f} m, walls {wh} m high")
    if s["origin_offset_m"]:
        ox, oy = s["origin_offset_m"]
        lines.append(f"  origin     the drawing's ({ox:.3f}, {oy:.3f}) m (georeferenced; the map's coordinates are "
                     f"relative to it: 'mapkit export --drawing-coordinates' adds it back)")
    cam = s["camera"] or {}
    if cam:
        lines.append(
            f"  camera     {cam['width']}x{cam['height']} fx {cam['fx']:.0f}, height {cam['height_m']} m, pitch {cam['pitch_deg']} deg"
        )
    build = s["build"] or {}
    if build:
        lines.append(
            f"  visibility range {build.get('max_range')} m, min visible length {build.get('min_visible_length')} m, eps {build.get('eps')} m"
        )
    print("\n".join(lines))
    return 0


def _building_info(args) -> int:
    """Summary of a building manifest: its source, storeys and their maps, connections."""
    from mapkit.building import load_manifest

    doc = load_manifest(args.map)
    if args.json:
        print(json.dumps(doc))
        return 0
    src = doc["source"]
    lines = [f"{args.map}: building of {len(doc['storeys'])} storeys from {src['name']} ({src.get('schema', '?')}, "
             f"sha256 {src['sha256'][:12]}...)"]
    for s in doc["storeys"]:
        walls = "?" if s.get("wall_height_m") is None else f"{s['wall_height_m']:g}"
        what = (f"{s['map']}: {s.get('segments', '?')} segments, {s.get('regions', '?')} regions, walls {walls} m"
                if s.get("map") else f"no map ({s['why']})" if s.get("why") else "no map")
        lines.append(f"  {s['name']:<16} floor {s['elevation_m']:>7.3f} m, height {s['height_m']:.3f} m  {what}")
    for c in doc.get("connections", []):
        lines.append(f"  {c['kind']:<6} {c['name'] or c['guid']}: {' <-> '.join(c['storeys'])}")
    print("\n".join(lines))
    return 0
