"""Benchmark mesh feature-edge extraction and the whole mesh import.

    python tools/bench_mesh_edges.py [--rooms N] [--subdivide K] [--repeat R]

Prints one row per mesh: faces, edges found (per kind), the time of
:func:`mapkit.importers.mesh.edges.feature_edges` alone (best of R) and of the whole
import (:func:`mapkit.importers.load_scene`: weld, sections, free space,
hidden-edge test). The generated mesh is an N x N grid of 4 x 3 m rooms,
each wall a separate box subdivided K times (x4 faces each time), so the
edges must be found through coplanar triangles and merged back into long
segments; the expected count is printed beside what was found.
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))


def room_grid(n: int, subdivide: int, height: float = 2.5, thick: float = 0.2):
    """An n x n grid of 4 x 3 m rooms; walls are separate subdivided boxes.

    Walls along x span the whole grid width, walls along y sit between them,
    so every wall/wall junction is a T or an L of touching boxes.
    """
    import trimesh

    def box(lo, hi):
        lo, hi = np.asarray(lo, float), np.asarray(hi, float)
        m = trimesh.creation.box(extents=hi - lo, transform=trimesh.transformations.translation_matrix((lo + hi) / 2))
        for _ in range(subdivide):
            m = m.subdivide()
        return m

    w, d = 4.0, 3.0
    span_x = n * w + thick
    parts = [box([0, j * d, 0], [span_x, j * d + thick, height]) for j in range(n + 1)]
    for j in range(n):
        for i in range(n + 1):
            parts.append(box([i * w, j * d + thick, 0], [i * w + thick, (j + 1) * d, height]))
    return trimesh.util.concatenate(parts)


def expected_grid_edges(n: int) -> int:
    """Edges of the grid's union seen from inside and outside, worked out by hand.

    Per room: 4 floor, 4 ceiling junctions, 4 vertical corners (16 n^2 in all
    over 4 kinds... 12 n^2). Outside: 4 floor, 4 top and 4 vertical corners of
    the outline. The tops of the walls between rooms: each x-wall top is one
    strip with long edges on both sides (the rooms' ceiling junctions, already
    counted) and its 0.2 m ends (too short). So 12 n^2 + 12.
    """
    return 12 * n * n + 12


def best_of(fn, repeat: int) -> tuple[float, object]:
    best, out = np.inf, None
    for _ in range(repeat):
        t = time.perf_counter()
        out = fn()
        best = min(best, time.perf_counter() - t)
    return best, out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rooms", type=int, default=8, help="rooms per side of the generated grid (default 8)")
    ap.add_argument("--subdivide", type=int, default=4, help="subdivisions per wall box (default 4: x256 faces, 249k faces in all)")
    ap.add_argument("--repeat", type=int, default=3, help="timing repeats, best kept (default 3)")
    args = ap.parse_args(argv)

    from mapkit.importers import load_scene
    from mapkit.importers.mesh.load import load_mesh
    from linemap.lmap import KIND_NAMES
    from mapkit.importers.mesh.edges import feature_edges
    from mapkit.options import BuildOptions

    options = BuildOptions()
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        grid = Path(tmp) / f"grid_{args.rooms}x{args.rooms}.stl"
        grid.write_bytes(room_grid(args.rooms, args.subdivide).export(file_type="stl"))
        meshes = [
            (grid, f"expected {expected_grid_edges(args.rooms)} (union, by hand)"),
            (ROOT / "tests" / "data" / "hospital.stl", ""),
            (ROOT / "tests" / "data" / "simple_room.glb", ""),
        ]
        for path, note in meshes:
            mesh, info = load_mesh(path, options)
            top = info["wall_height_m"]
            t_edges, (seg, kinds) = best_of(
                lambda: feature_edges(mesh, options.crease_deg, options.min_edge_length, 0.0, top), args.repeat
            )
            t_import, scene = best_of(lambda: load_scene(path, options), 1)
            per_kind = " ".join(f"{KIND_NAMES[k]}={c}" for k, c in zip(*np.unique(scene.kinds, return_counts=True)))
            rows.append((path.name, len(mesh.faces), len(seg), t_edges, len(scene.segments), t_import, per_kind, note))

    print(f"{'mesh':<22} {'faces':>8} {'edges':>6} {'edges s':>8} {'kept':>6} {'import s':>9}  kinds / note")
    for name, faces, n_edges, t_e, kept, t_i, per_kind, note in rows:
        print(f"{name:<22} {faces:>8} {n_edges:>6} {t_e:>8.3f} {kept:>6} {t_i:>9.2f}  {per_kind} {note}")
    print("edges: feature_edges alone; kept: after the hidden-edge test and overlap merge (the map's segments)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
