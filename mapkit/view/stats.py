"""The numbers the inspector's panel shows about a map."""

from __future__ import annotations

import json
import os

import numpy as np

from linemap.lmap import LineMap, SegmentKind
from linemap.camera import Camera



def map_camera(m: LineMap) -> tuple[Camera, str]:
    """The camera the map was built for and where it came from.

    Looks in ``meta["build"]["camera"]``, then ``meta["camera"]``; falls back
    to the build's default camera (:func:`mapkit.options.default_camera`; the
    returned source says "default").
    """
    build = m.meta.get("build") if isinstance(m.meta.get("build"), dict) else {}
    for source, d in (("build parameters", build.get("camera")), ("map", m.meta.get("camera"))):
        if isinstance(d, dict):
            return Camera.from_dict(d), source
    from mapkit.options import default_camera

    return Camera.from_dict(default_camera()), "default (the map records none)"


def map_statistics(m: LineMap, path: str | os.PathLike | None = None) -> dict:
    """Counts, sizes and build parameters, JSON-able."""
    lens = np.diff(m.list_offsets)
    kinds = np.bincount(m.kinds, minlength=len(SegmentKind)) if m.n_segments else np.zeros(len(SegmentKind), int)
    seg_len = np.linalg.norm(m.segments[:, 1] - m.segments[:, 0], axis=1) if m.n_segments else np.zeros(0)
    areas = _region_areas(m)
    lo = m.segments.reshape(-1, 3).min(axis=0) if m.n_segments else np.zeros(3)
    hi = m.segments.reshape(-1, 3).max(axis=0) if m.n_segments else np.zeros(3)
    return {
        "file": str(path) if path is not None else None,
        "file_bytes": os.path.getsize(path) if path is not None and os.path.exists(path) else None,
        "format_version": f"{m.version[0]}.{m.version[1]}",
        "segments": m.n_segments,
        "segments_per_kind": {k.label: int(kinds[k]) for k in SegmentKind if kinds[k]},
        "segment_length_m": {"total": float(seg_len.sum()), "mean": float(seg_len.mean()) if len(seg_len) else 0.0},
        "regions": m.n_regions,
        "region_rings": int(len(m.ring_region)),
        "region_area_m2": {"total": float(areas.sum()), "mean": float(areas.mean()) if len(areas) else 0.0,
                           "max": float(areas.max()) if len(areas) else 0.0},
        "list_length": {"min": int(lens.min()) if len(lens) else 0, "mean": float(lens.mean()) if len(lens) else 0.0,
                        "max": int(lens.max()) if len(lens) else 0},
        "wall_rings": int(len(m.wall_is_hole)),
        "wall_height_m": m.meta.get("wall_height"),
        "extent_m": [float(v) for v in (hi - lo)],
        "build": m.meta.get("build"),
    }


def _region_areas(m: LineMap) -> np.ndarray:
    """(R,) region areas (even-odd: a hole ring's area is subtracted)."""
    from mapkit.view.geometry import ring_edges

    edges, ring = ring_edges(m.ring_points, m.ring_offsets)
    if len(edges) == 0:
        return np.zeros(m.n_regions)
    a, b = edges[:, 0], edges[:, 1]
    ring_area = np.abs(np.bincount(ring, weights=a[:, 0] * b[:, 1] - b[:, 0] * a[:, 1],
                                   minlength=len(m.ring_region))) / 2
    signed = np.where(m.ring_is_hole, -ring_area, ring_area)
    return np.bincount(m.ring_region, weights=signed, minlength=m.n_regions)


def statistics_markdown(stats: dict) -> str:
    """The statistics as a compact markdown block for the panel."""
    kinds = ", ".join(f"{k} {v}" for k, v in stats["segments_per_kind"].items()) or "none"
    ll = stats["list_length"]
    area = stats["region_area_m2"]
    ext = " x ".join(f"{v:.1f}" for v in stats["extent_m"])
    lines = [
        f"**Segments** {stats['segments']} ({kinds}); total {stats['segment_length_m']['total']:.0f} m",
        f"**Regions** {stats['regions']} ({stats['region_rings']} rings), "
        f"mean {area['mean']:.2f} m², total {area['total']:.0f} m²",
        f"**Lists** min {ll['min']} / mean {ll['mean']:.1f} / max {ll['max']} segments",
        f"**Walls** {stats['wall_rings']} rings, height {stats['wall_height_m']} m; extent {ext} m",
        f"**Format** {stats['format_version']}"
        + (f", {stats['file_bytes'] / 1024:.0f} KiB" if stats.get("file_bytes") else ""),
    ]
    build = stats.get("build")
    if isinstance(build, dict) and build:
        flat = {k: v for k, v in build.items() if k != "camera"}
        lines.append("**Build** `" + json.dumps(flat, sort_keys=True, separators=(", ", "=")) + "`")
    return "\n\n".join(lines)
