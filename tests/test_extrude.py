"""extrude: plan scene -> 3D model, and back through the mesh importer."""

from __future__ import annotations

from pathlib import Path

from dataclasses import replace

import numpy as np
import pytest
import shapely
from shapely.geometry import MultiPolygon, box

from mapkit.cli import main
from mapkit.edges import extract_edges
from mapkit.extrude import SLAB_THICKNESS, scene_to_mesh
from mapkit.importers import load_scene
from linemap.lmap import SegmentKind as K
from mapkit.options import BuildOptions
from mapkit.scene import Opening, Scene

ROOT = Path(__file__).resolve().parents[1]
FLAT = ROOT / "maps" / "flat.dxf"
H, T = 2.5, 0.25  # walls thicker than min_edge_length: no borderline pieces

#: Plan kinds -> what a mesh can tell from geometry alone.
AS_MESH_KIND = {K.JAMB: K.VERTICAL, K.LINTEL: K.HORIZONTAL, K.WINDOW: K.HORIZONTAL}


def two_rooms() -> Scene:
    """Rooms A (0..4 x 0..4) and B (4.25..8 x 0..4) in 0.25 m walls; a door
    (1 m, head 2.1) in the partition, a window (2 m, sill 0.9, head 2.1) in
    the south wall. Walls exclude the opening footprints, as the DXF
    importer gives them."""
    rooms = [box(0, 0, 4, 4), box(4 + T, 0, 8, 4)]
    door = Opening(box(4, 1, 4 + T, 2), "door", 0.0, 2.1)
    window = Opening(box(1, -T, 3, 0), "window", 0.9, 2.1)
    walls = box(-T, -T, 8 + T, 4 + T).difference(shapely.union_all(rooms + [door.footprint, window.footprint]))
    free = shapely.union_all(rooms + [door.footprint]).buffer(-0.2)
    return Scene(walls=MultiPolygon([walls]), openings=[door, window], free_space=MultiPolygon([free]), wall_height=H)


def samples(segments: np.ndarray, step: float = 0.02) -> tuple[np.ndarray, np.ndarray]:
    """Points (P, 3) every ``step`` along segments (N, 2, 3), and their segment ids."""
    n = np.maximum(2, np.ceil(np.linalg.norm(segments[:, 1] - segments[:, 0], axis=1) / step).astype(int) + 1)
    owner = np.repeat(np.arange(len(segments)), n)
    t = np.concatenate([np.linspace(0, 1, k) for k in n])[:, None]
    return segments[owner, 0] + t * (segments[owner, 1] - segments[owner, 0]), owner


def distance_to_segments(points: np.ndarray, segments: np.ndarray) -> np.ndarray:
    """(P,) distance from each point (P, 3) to the nearest segment (N, 2, 3)."""
    a = segments[:, 0]
    d = segments[:, 1] - a
    out = np.full(len(points), np.inf)
    for i in range(0, len(points), 2000):
        p = points[i : i + 2000, None, :]
        t = np.clip(np.einsum("pnj,nj->pn", p - a, d) / np.einsum("nj,nj->n", d, d), 0, 1)
        out[i : i + 2000] = np.linalg.norm(p - (a + t[..., None] * d), axis=2).min(axis=1)
    return out


def uncovered(a_seg, a_kind, b_seg, b_kind, tol=0.01) -> np.ndarray:
    """Sample points of segments ``a`` farther than ``tol`` from every
    segment of ``b`` of the same (mesh-visible) kind: (M, 3)."""
    a_kind = np.array([AS_MESH_KIND.get(K(k), K(k)) for k in a_kind])
    b_kind = np.array([AS_MESH_KIND.get(K(k), K(k)) for k in b_kind])
    bad = []
    for k in np.unique(a_kind):
        pts, _ = samples(a_seg[a_kind == k])
        other = b_seg[b_kind == k]
        d = distance_to_segments(pts, other) if len(other) else np.full(len(pts), np.inf)
        bad.append(pts[d > tol])
    return np.concatenate(bad) if bad else np.zeros((0, 3))


def round_trip(scene: Scene, tmp_path: Path, options: BuildOptions, name="model.glb"):
    """The scene's model written z-up (as it is made; ``mapkit extrude`` turns
    it y-up for glTF) and read back as such."""
    path = tmp_path / name
    path.write_bytes(scene_to_mesh(scene).export(file_type="glb"))
    return load_scene(path, replace(options, up="z"))


def test_volume_is_walls_lintels_parapets_and_slab():
    s = two_rooms()
    mesh = scene_to_mesh(s)
    door, window = s.openings
    expected = (
        s.walls.area * H
        + door.footprint.area * (H - door.head)
        + window.footprint.area * (window.sill + H - window.head)
        + (2 * 16.0 - T * 4 + door.footprint.area) * SLAB_THICKNESS  # rooms + doorway
    )
    assert mesh.volume == pytest.approx(expected, rel=1e-6)
    assert mesh.is_winding_consistent
    ceiling = scene_to_mesh(s, ceiling=True)
    assert ceiling.bounds[1, 2] == pytest.approx(H + SLAB_THICKNESS)


def test_two_rooms_round_trip_gives_the_plan_edges(tmp_path):
    s = two_rooms()
    options = BuildOptions()
    plan_seg, plan_kind = extract_edges(s, options)
    back = round_trip(s, tmp_path, options)
    assert back.wall_height == pytest.approx(H)
    assert len(uncovered(plan_seg, plan_kind, back.segments, back.kinds)) == 0
    assert len(uncovered(back.segments, back.kinds, plan_seg, plan_kind)) == 0
    # Worked out from the plan: floor junctions: outer 4, room A 5 and room B
    # 5 (the door splits the partition's), the door's 2 jamb bottoms; the
    # window's parapet keeps the south junction whole. Ceiling: 4 + 4 + 4.
    # Verticals: 12 corners. Jambs: 4 at the door, 4 at the window. The
    # lintel: 2 faces + 2 across the wall; window sill and head: 4 each.
    counts = {K(k).name: int(c) for k, c in zip(*np.unique(plan_kind, return_counts=True))}
    assert counts == {"FLOOR": 16, "CEILING": 12, "VERTICAL": 12, "JAMB": 8, "LINTEL": 4, "WINDOW": 8}
    # The mesh cannot tell jambs from corners, nor lintels from sills.
    counts = {K(k).name: int(c) for k, c in zip(*np.unique(back.kinds, return_counts=True))}
    assert counts == {"FLOOR": 16, "CEILING": 12, "VERTICAL": 20, "HORIZONTAL": 12}
    # Free space: the rooms and the doorway, shrunk by the robot radius.
    assert back.free_space.symmetric_difference(s.free_space).area < 0.01
    # At camera height both openings are open: the walls are the plan's.
    assert back.walls.symmetric_difference(s.walls).area < 1e-3


def test_ceiling_hides_the_outer_top_edges(tmp_path):
    s = two_rooms()
    path = tmp_path / "c.obj"
    path.write_text(scene_to_mesh(s, ceiling=True).export(file_type="obj"))
    back = load_scene(path, BuildOptions())
    assert back.info["ceiling"] == "ceiling faces"
    assert back.wall_height == pytest.approx(H)
    top = back.segments[back.kinds == K.CEILING]
    # Wall/ceiling junctions inside the two rooms only: 4 + 4; the outer
    # wall faces run on into the slab's edge.
    assert len(top) == 8
    assert np.allclose(top[:, :, 2], H)
    assert top[:, :, 0].min() >= -0.01 and top[:, :, 0].max() <= 8.01


def test_flat_dxf_round_trip_matches_the_plan_edges(tmp_path):
    """The example flat: DXF -> model -> mesh import gives the DXF build's
    edges within 1 cm. Two differences are the model's doing, not errors:
    the floor slab's border shows across doorways in the outer walls (the
    plan's edge model has no floor), and pieces as long as min_edge_length
    (0.2 m) may fall either side of the cut."""
    options = BuildOptions()
    plan = load_scene(FLAT, options)
    plan_seg, plan_kind = extract_edges(plan, options)
    back = round_trip(plan, tmp_path, options)
    # The model is closed solids: its section at camera height is the plan's walls.
    assert back.walls.symmetric_difference(plan.walls).area < 0.01 * plan.walls.area

    def borderline(seg):
        return np.abs(np.linalg.norm(seg[:, 1] - seg[:, 0], axis=1) - options.min_edge_length) < 0.01

    keep = ~borderline(plan_seg)
    assert len(uncovered(plan_seg[keep], plan_kind[keep], back.segments, back.kinds)) == 0
    keep = ~borderline(back.segments)
    extra = uncovered(back.segments[keep], back.kinds[keep], plan_seg, plan_kind)
    doors = shapely.union_all([o.footprint for o in plan.openings if o.kind == "door"]).buffer(0.01)
    at_threshold = np.isclose(extra[:, 2], 0.0) & shapely.contains_xy(doors, extra[:, 0], extra[:, 1])
    assert at_threshold.all(), extra[~at_threshold][:5]


@pytest.mark.slow
def test_flat_dxf_round_trip_gives_the_same_lists(tmp_path):
    """The maps built from the plan and from its extruded model list the same
    segments at random points (segments matched by their end points within
    1 cm). Merging is off: greedy merging reacts to centimetre differences."""
    from mapkit.pipeline import build_map

    options = BuildOptions(merge_growth=0.0)
    plan_map, _ = build_map(FLAT, options)
    model = tmp_path / "flat.glb"
    model.write_bytes(scene_to_mesh(load_scene(FLAT, options)).export(file_type="glb"))  # written z-up
    mesh_map, _ = build_map(model, replace(options, up="z"))
    a, b = plan_map.segments, mesh_map.segments
    dist = np.minimum(
        np.abs(a[:, None] - b[None]).max(axis=(2, 3)), np.abs(a[:, None] - b[None, :, ::-1]).max(axis=(2, 3))
    )
    to_mesh = np.where(dist.min(axis=1) < 0.01, dist.argmin(axis=1), -1)
    rng = np.random.default_rng(3)
    similarity = []
    for _ in range(5000):  # points in both maps' regions, 200 of them
        if len(similarity) == 200:
            break
        x, y = rng.uniform(0, 11), rng.uniform(-0.6, 8.5)
        if not (len(plan_map.regions_at(x, y)) and len(mesh_map.regions_at(x, y))):
            continue
        seen_plan = {int(to_mesh[i]) if to_mesh[i] >= 0 else -1 - int(i) for i in plan_map.candidate_segments(x, y, 0)}
        seen_mesh = set(mesh_map.candidate_segments(x, y, 0).tolist())
        similarity.append(len(seen_plan & seen_mesh) / len(seen_plan | seen_mesh))
    similarity = np.array(similarity)
    assert len(similarity) == 200
    assert np.median(similarity) == 1.0
    assert similarity.mean() > 0.97 and similarity.min() > 0.85


# ---- the command ----------------------------------------------------------------


@pytest.mark.parametrize("suffix", [".glb", ".obj", ".ply", ".stl"])
def test_cli_writes_each_format(tmp_path, capsys, suffix):
    out = tmp_path / f"flat{suffix}"
    assert main(["extrude", str(FLAT), "-o", str(out)]) == 0
    assert "triangles" in capsys.readouterr().out
    back = load_scene(out)  # no --up: glTF's +Y, the others' z, from the file's format and geometry
    assert back.wall_height == pytest.approx(2.5)
    if suffix == ".glb":
        import trimesh

        lo, hi = trimesh.load(out, force="mesh").bounds
        assert hi[1] == pytest.approx(2.5, abs=0.01)  # the walls stand along +Y, up to their 2.5 m
    assert [p.name for p in tmp_path.iterdir()] == [out.name]  # no temporary left


def test_cli_errors_write_nothing(tmp_path, capsys):
    out = tmp_path / "m.glb"
    assert main(["extrude", str(tmp_path / "missing.dxf"), "-o", str(out)]) == 2
    assert "no such file" in capsys.readouterr().err
    assert main(["extrude", str(ROOT / "tests" / "data" / "hospital.stl"), "-o", str(tmp_path / "m.fbx")]) == 2
    assert "output must end in one of" in capsys.readouterr().err
    assert main(["extrude", str(ROOT / "tests" / "data" / "hospital.stl"), "-o", str(tmp_path / "no" / "m.glb")]) == 2
    assert "does not exist" in capsys.readouterr().err
    bad = tmp_path / "bad.stl"
    bad.write_text("solid nothing\nendsolid\n")
    out.write_bytes(b"old")
    assert main(["extrude", str(bad), "-o", str(out)]) == 2
    err = capsys.readouterr().err
    assert err.startswith("mapkit: error:") and len(err.strip().splitlines()) == 1
    assert out.read_bytes() == b"old"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["bad.stl", "m.glb"]


def test_scene_without_walls_is_rejected():
    s = two_rooms()
    s.walls = MultiPolygon()
    s.openings = []
    s.free_space = MultiPolygon()
    with pytest.raises(ValueError, match="no walls"):
        scene_to_mesh(s)


@pytest.mark.slow
def test_extrude_then_build_gives_the_plans_segments_with_no_option(tmp_path):
    """``mapkit extrude flat.dxf -o flat.glb`` then ``mapkit build flat.glb``,
    no --up (glTF is +Y up): the DXF build's segments come back (64 of 264
    did when glTF files were read z-up)."""
    from linemap.lmap import load_map

    glb, from_mesh = tmp_path / "flat.glb", tmp_path / "mesh.lmap"
    assert main(["extrude", str(FLAT), "-o", str(glb)]) == 0
    assert main(["build", str(glb), "-o", str(from_mesh), "-q"]) == 0
    a, b = load_map(FLAT.with_suffix(".lmap")), load_map(from_mesh)  # flat.dxf's build (test_build_real checks it)

    def keys(m):
        return {tuple(sorted(map(tuple, np.round(s, 2)))) for s in m.segments}

    assert abs(b.n_segments - a.n_segments) <= 2
    assert len(keys(a) & keys(b)) >= 0.98 * a.n_segments
