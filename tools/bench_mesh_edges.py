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
import tempfile
import time
from pathlib import Path

import numpy as np

from mapkit_harness.plans import expected_grid_edges, room_grid
from mapkit_harness.tables import Table, add_report_option, reported

ROOT = Path(__file__).resolve().parents[1]


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
    add_report_option(ap)
    args = ap.parse_args(argv)
    return reported(args.report, lambda: run(args), __file__, argv)


def run(args) -> int:
    """The benchmark as ``main``'s arguments say; prints the table."""
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

    table = Table("mesh", "faces", "edges", "edges s", "kept", "import s", "kinds / note")
    for name, faces, n_edges, t_e, kept, t_i, per_kind, note in rows:
        table.row(name, faces, n_edges, f"{t_e:.3f}", kept, f"{t_i:.2f}", f"{per_kind} {note}".strip())
    print()
    print("edges: feature_edges alone; kept: after the hidden-edge test and overlap merge (the map's segments)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
