"""Mesh import: the two real meshes, synthetic scenes with known answers, bad input."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import shapely
import trimesh

from mapkit import edges as plan_edges
from mapkit.errors import MapkitError, NoWallsError
from mapkit.importers import load_scene
from mapkit.importers.mesh.load import Y_UP_TO_Z_UP, load_mesh
from mapkit.importers.mesh.section import MeshSections
from linemap.lmap import SegmentKind as K
from mapkit.options import BuildOptions

DATA = Path(__file__).parent / "data"
ROOM = DATA / "simple_room.glb"
HOSPITAL = DATA / "hospital.stl"


def kinds_count(scene) -> dict[str, int]:
    return {K(k).name: int(c) for k, c in zip(*np.unique(scene.kinds, return_counts=True))}


def box(lo, hi) -> trimesh.Trimesh:
    lo, hi = np.asarray(lo, float), np.asarray(hi, float)
    return trimesh.creation.box(extents=hi - lo, transform=trimesh.transformations.translation_matrix((lo + hi) / 2))


def room_walls(w=6.0, d=4.0, h=2.5, t=0.2) -> list[trimesh.Trimesh]:
    """Four wall boxes enclosing a w x d room (inside 0..w, 0..d), no floor."""
    return [
        box([-t, -t, 0], [w + t, 0, h]),
        box([-t, d, 0], [w + t, d + t, h]),
        box([-t, 0, 0], [0, d, h]),
        box([w, 0, 0], [w + t, d, h]),
    ]


def same_segments(a: np.ndarray, b: np.ndarray, tol: float) -> bool:
    """Every segment of ``a`` (N, 2, 3) has one in ``b`` with both ends within ``tol``, and back."""
    fwd = np.abs(a[:, None] - b[None]).max(axis=(2, 3))
    rev = np.abs(a[:, None] - b[None, :, ::-1]).max(axis=(2, 3))
    d = np.minimum(fwd, rev)
    return bool((d.min(axis=1) < tol).all() and (d.min(axis=0) < tol).all())


# ---- the real meshes --------------------------------------------------------


def test_simple_room_glb_scene():
    """Seven cubes placed by node transforms: a floor slab (10.5 x 10.8 m,
    top 0.145 m above the file's origin), a 2 m box standing on it, and a
    table (1.4 m top on four 0.15 m legs). The file is z-up despite glTF."""
    s = load_scene(ROOM)
    assert s.info["floor"] == "floor faces"
    assert s.info["floor_offset_m"] == pytest.approx(0.1455, abs=1e-3)
    assert s.wall_height == pytest.approx(2.008, abs=1e-3)  # the box top
    # Box: 4 corners, 4 floor junctions, 4 top edges. Table legs: 16 corners
    # (their 0.15 m top and bottom edges are under min_edge_length). Table top:
    # 8 edges of 1.4 m (its 0.04 m sides are too short). Slab: its top
    # border at floor level (no wall rises from it); its sides are under the floor.
    assert kinds_count(s) == {"FLOOR": 4, "CEILING": 4, "VERTICAL": 20, "HORIZONTAL": 12}
    assert s.segments[:, :, 2].min() >= -0.02
    floor_border = s.segments[(s.kinds == K.HORIZONTAL) & (np.abs(s.segments[:, :, 2]).max(axis=1) < 0.02)]
    assert sorted(np.round(np.linalg.norm(floor_border[:, 1] - floor_border[:, 0], axis=1), 2)) == [10.53, 10.53, 10.85, 10.85]
    # The box is the only thing at camera height; the legs are obstacles.
    assert s.walls.area == pytest.approx(4.0, rel=1e-3)
    assert s.obstacles.area == pytest.approx(4 * 0.15**2, rel=1e-2)
    assert s.openings == []
    assert s.free_space.contains(shapely.Point(-3, 3))
    assert not s.free_space.contains(shapely.Point(2.37, -1.39))  # inside the box
    assert not s.free_space.contains(shapely.Point(0.5, 0.5))  # a table leg
    assert s.free_space.area == pytest.approx(99.05, abs=0.1)


def test_hospital_stl_walls_only():
    s = load_scene(HOSPITAL)
    assert s.info["floor"].startswith("lowest point")
    assert s.info["faces"] == 482
    assert s.wall_height == pytest.approx(3.0)
    assert kinds_count(s) == {"FLOOR": 74, "CEILING": 20, "VERTICAL": 80, "HORIZONTAL": 65}
    assert s.free_space.area == pytest.approx(234.9, abs=1.0)
    assert s.walls.area == pytest.approx(30.48, abs=0.05)


@pytest.mark.parametrize("z, kind", [(0.01, K.FLOOR), (2.99, K.CEILING)])
def test_hospital_junctions_are_the_outline_of_the_walls(z, kind):
    """The wall/floor (wall/ceiling) junctions are the outline of the wall
    material just above the floor (below the 3 m tops), independently
    derived from a section and the plan edge stage's outline pieces."""
    s = load_scene(HOSPITAL)
    mesh, _ = load_mesh(HOSPITAL, BuildOptions())
    walls, _ = MeshSections(mesh).cut(z)
    outline = [shapely.LineString([a, b]) for a, b in plan_edges._outline_edges(walls, 0.2)]
    seg = s.segments[s.kinds == kind]
    lines = shapely.linestrings(seg[:, :, :2])
    near = 0.005
    assert shapely.union_all(outline).difference(shapely.union_all(lines).buffer(near)).length < 0.05
    assert shapely.union_all(lines).difference(walls.boundary.buffer(near)).length < 0.05
    assert np.abs(seg[:, :, 2] - (0.0 if kind == K.FLOOR else 3.0)).max() < 1e-6


@pytest.mark.slow
def test_hospital_verticals_stand_on_wall_corners_or_openings():
    s = load_scene(HOSPITAL)
    v = s.segments[s.kinds == K.VERTICAL]
    mesh, _ = load_mesh(HOSPITAL, BuildOptions())
    sections = MeshSections(mesh)
    # Each vertical is on the wall outline at its mid-height.
    for seg in v:
        walls, _ = sections.cut(float(seg[:, 2].mean()))
        assert walls.boundary.distance(shapely.Point(seg[0, :2])) < 0.005
    # Full-height corners of the 3 m walls: 20, as many as their top edges.
    assert (np.isclose(v[:, :, 2].min(axis=1), 0) & np.isclose(v[:, :, 2].max(axis=1), 3)).sum() == 20


# ---- synthetic scenes --------------------------------------------------------


def write_scene_glb(path: Path, meshes: list[trimesh.Trimesh], transforms: list[np.ndarray]) -> None:
    scene = trimesh.Scene()
    for i, (m, t) in enumerate(zip(meshes, transforms)):
        scene.add_geometry(m, node_name=f"n{i}", geom_name=f"g{i}", transform=t)
    path.write_bytes(scene.export(file_type="glb"))


def test_node_transforms_and_y_up(tmp_path):
    """The same walls-only room, stored y-up with each wall placed by a node
    transform (unit cubes scaled and moved), gives the same edges as z-up."""
    walls = room_walls()
    z_up = trimesh.util.concatenate(walls)
    (tmp_path / "z.stl").write_bytes(z_up.export(file_type="stl"))
    ref = load_scene(tmp_path / "z.stl")
    to_y_up = np.eye(4)
    to_y_up[:3, :3] = Y_UP_TO_Z_UP.T
    cubes, transforms = [], []
    for w in walls:
        lo, hi = w.bounds
        t = trimesh.transformations.translation_matrix((lo + hi) / 2) @ np.diag([*(hi - lo), 1.0])
        cubes.append(trimesh.creation.box())
        transforms.append(to_y_up @ t)
    write_scene_glb(tmp_path / "y.glb", cubes, transforms)
    got = load_scene(tmp_path / "y.glb", BuildOptions(up="y"))
    assert same_segments(got.segments, ref.segments, 1e-3)
    assert kinds_count(got) == kinds_count(ref) == {"FLOOR": 8, "CEILING": 8, "VERTICAL": 8}


def test_floor_height_units_and_scale(tmp_path):
    """A room modelled 5 m up and in millimetres imports like the original."""
    walls = trimesh.util.concatenate(room_walls())
    (tmp_path / "m.stl").write_bytes(walls.export(file_type="stl"))
    ref = load_scene(tmp_path / "m.stl")
    mm = walls.copy()
    mm.apply_translation([0, 0, 5.0])
    mm.apply_scale(1000.0)
    (tmp_path / "mm.stl").write_bytes(mm.export(file_type="stl"))
    got = load_scene(tmp_path / "mm.stl", BuildOptions(units="mm"))
    assert got.info["floor_offset_m"] == pytest.approx(5.0)
    assert same_segments(got.segments, ref.segments, 1e-3)
    half = load_scene(tmp_path / "mm.stl", BuildOptions(units="mm", scale=0.5))
    assert half.wall_height == pytest.approx(1.25)


def test_floor_faces_give_the_free_space(tmp_path):
    """Walls standing on a floor slab: free space = room shrunk by the robot radius."""
    slab = box([-0.2, -0.2, -0.1], [6.2, 4.2, 0.0])
    mesh = trimesh.util.concatenate([*room_walls(), slab])
    (tmp_path / "r.obj").write_text(mesh.export(file_type="obj"))
    s = load_scene(tmp_path / "r.obj", BuildOptions(robot_radius=0.25))
    assert s.info["floor"] == "floor faces"
    assert s.free_space.area == pytest.approx((6 - 0.5) * (4 - 0.5), rel=1e-3)
    # Inner junctions sit on the slab: still floor edges; the slab's border
    # lies under the outer wall faces, which continue down: no edge there.
    floor = s.segments[s.kinds == K.FLOOR]
    assert len(floor) == 4
    # Buried ends are cut within a few millimetres of the surface they enter.
    assert np.allclose(sorted(np.linalg.norm(floor[:, 1] - floor[:, 0], axis=1)), [4, 4, 6, 6], atol=0.01)


def test_single_surface_walls_are_thickened(tmp_path):
    quads = []
    corners = [(0, 0), (5, 0), (5, 3), (0, 3)]
    for (x0, y0), (x1, y1) in zip(corners, corners[1:] + corners[:1]):
        quads.append(trimesh.Trimesh([[x0, y0, 0], [x1, y1, 0], [x1, y1, 2.4], [x0, y0, 2.4]], [[0, 1, 2], [0, 2, 3]]))
    (tmp_path / "q.ply").write_bytes(trimesh.util.concatenate(quads).export(file_type="ply"))
    s = load_scene(tmp_path / "q.ply", BuildOptions(robot_radius=0.0))
    assert s.walls.area == pytest.approx(16 * 0.05, rel=0.05)  # perimeter x MESH_THIN_WALL
    assert s.free_space.area == pytest.approx((5 - 0.05) * (3 - 0.05), rel=1e-2)
    assert kinds_count(s) == {"FLOOR": 4, "CEILING": 4, "VERTICAL": 4}


# ---- bad input ----------------------------------------------------------------


def test_not_a_mesh(tmp_path):
    bad = tmp_path / "notes.stl"
    bad.write_text("this is not a mesh\n")
    with pytest.raises(MapkitError, match="not a readable .stl mesh|no triangles"):
        load_scene(bad)
    glb = tmp_path / "broken.glb"
    glb.write_bytes(b"glTF\x02\x00\x00\x00garbage")
    with pytest.raises(MapkitError, match="not a readable .glb mesh"):
        load_scene(glb)


def test_empty_mesh(tmp_path):
    empty = tmp_path / "empty.obj"
    empty.write_text("# nothing\nv 0 0 0\nv 1 0 0\n")
    with pytest.raises(MapkitError, match="no triangles"):
        load_scene(empty)


@pytest.mark.parametrize("suffix", [".glb", ".stl", ".ply", ".obj"])
def test_zero_byte_mesh_file(tmp_path, suffix):
    empty = tmp_path / f"empty{suffix}"
    empty.write_bytes(b"")
    with pytest.raises(MapkitError, match="the file is empty; export the model again"):
        load_scene(empty)


def test_gltf_missing_its_buffer(tmp_path):
    files = trimesh.exchange.gltf.export_gltf(trimesh.Scene(room_walls()))
    for name, data in files.items():
        if name.endswith(".gltf"):  # the .bin buffers stay behind
            (tmp_path / name).write_bytes(data)
    gltf = next(tmp_path.glob("*.gltf"))
    with pytest.raises(MapkitError, match=r"refers to is missing \(gltf_buffer_0\.bin\); put it beside"):
        load_scene(gltf)


def test_mesh_without_walls(tmp_path):
    plane = trimesh.Trimesh([[0, 0, 0], [8, 0, 0], [8, 6, 0], [0, 6, 0]], [[0, 1, 2], [0, 2, 3]])
    (tmp_path / "f.obj").write_text(plane.export(file_type="obj"))
    with pytest.raises(NoWallsError, match="flat"):
        load_scene(tmp_path / "f.obj")
    # A slab alone is 10 cm of "wall" around nothing.
    (tmp_path / "s.stl").write_bytes(box([0, 0, -0.1], [8, 6, 0]).export(file_type="stl"))
    with pytest.raises(MapkitError, match="enclose no room"):
        load_scene(tmp_path / "s.stl")


def test_walls_that_enclose_nothing(tmp_path):
    (tmp_path / "w.stl").write_bytes(box([0, 0, 0], [5, 0.2, 2.5]).export(file_type="stl"))
    with pytest.raises(MapkitError, match="enclose no room"):
        load_scene(tmp_path / "w.stl")


@pytest.mark.parametrize(
    "options, message",
    [
        ({"units": "km"}, "not a building"),
        ({"units": "mm"}, "not a building"),
        ({"scale": -1.0}, "--scale must be > 0"),
        ({"units": "furlong"}, "unknown units"),
        ({"up": "x"}, "--up must be"),
    ],
)
def test_absurd_units_and_options(options, message):
    with pytest.raises(MapkitError, match=message):
        load_scene(HOSPITAL, BuildOptions(**options))


def test_options_set_after_construction_are_checked_on_import():
    options = BuildOptions()
    options.up = "x"
    with pytest.raises(MapkitError, match="--up must be one of auto, z, y"):
        load_scene(HOSPITAL, options)


# ---- small edge-case files (tests/data/mesh, each says what it holds) ----------


def test_needle_at_a_t_junction_keeps_the_box_closed():
    from mapkit.importers.mesh.edges import edge_faces, feature_edges

    mesh, _ = load_mesh(DATA / "mesh" / "t_junction_needle.obj", BuildOptions())
    assert set(edge_faces(mesh.faces).counts) == {2}  # no border left where the needle was
    seg, kinds = feature_edges(mesh, 30.0, 0.2)
    assert {K(k).name: int(c) for k, c in zip(*np.unique(kinds, return_counts=True))} == {
        "FLOOR": 4, "CEILING": 4, "VERTICAL": 4
    }


@pytest.mark.parametrize("name", ["sheet_walls.obj", "inside_out_room.obj"])
def test_rooms_without_wall_thickness(name):
    """Single-surface walls, and a closed room box seen from inside (negative
    volume): both have walls of no thickness, given MESH_THIN_WALL."""
    s = load_scene(DATA / "mesh" / name, BuildOptions(robot_radius=0.2))
    assert kinds_count(s) == {"FLOOR": 4, "CEILING": 4, "VERTICAL": 4}
    assert s.walls.area == pytest.approx(16 * 0.05, rel=0.02)
    assert s.free_space.area == pytest.approx((5 - 0.05 - 0.4) * (3 - 0.05 - 0.4), rel=1e-3)


def test_a_hole_in_a_solid_leaves_it_solid(tmp_path):
    """One triangle missing (a scan gap): the walls still read as solids,
    not as sheets (which would make hollow outlines of them)."""
    m = trimesh.load(HOSPITAL, process=False)
    keep = np.ones(len(m.faces), dtype=bool)
    keep[10] = False
    (tmp_path / "holed.stl").write_bytes(trimesh.Trimesh(m.vertices, m.faces[keep], process=False).export(file_type="stl"))
    whole, holed = load_scene(HOSPITAL), load_scene(tmp_path / "holed.stl")
    assert holed.walls.symmetric_difference(whole.walls).area < 1e-3


@pytest.mark.parametrize("seed", [1, 2])
def test_edges_move_with_the_model(tmp_path, seed):
    """A seeded random turn about z and shift: the same edges, turned and shifted."""
    rng = np.random.default_rng(seed)
    walls = trimesh.util.concatenate(room_walls())
    (tmp_path / "a.stl").write_bytes(walls.export(file_type="stl"))
    angle, shift = rng.uniform(0, 2 * np.pi), np.r_[rng.uniform(-50, 50, 2), rng.uniform(-3, 3)]
    move = trimesh.transformations.rotation_matrix(angle, [0, 0, 1])
    move[:3, 3] = shift
    turned = walls.copy()
    turned.apply_transform(move)
    (tmp_path / "b.stl").write_bytes(turned.export(file_type="stl"))
    a, b = load_scene(tmp_path / "a.stl"), load_scene(tmp_path / "b.stl")
    assert b.info["floor_offset_m"] == pytest.approx(shift[2], abs=1e-3)
    expected = a.segments @ move[:3, :3].T + np.r_[shift[:2], 0.0]
    assert kinds_count(a) == kinds_count(b)
    assert len(b.segments) == len(expected)
    assert same_segments(b.segments, expected, 1e-3)


@pytest.mark.slow
def test_build_a_map_from_each_real_mesh(tmp_path):
    """The pipeline takes the mesh scenes through to a .lmap."""
    from mapkit.cli import main
    from linemap.lmap import load_map

    for path in (ROOM, HOSPITAL):
        out = tmp_path / (path.stem + ".lmap")
        assert main(["build", str(path), "-o", str(out), "-q"]) == 0
        m = load_map(out)
        assert 0 < m.n_segments <= len(load_scene(path).segments) and m.n_regions > 0


def test_truncated_binary_stl_says_so(tmp_path):
    cut = tmp_path / "cut.stl"
    cut.write_bytes(HOSPITAL.read_bytes()[:12_000])
    with pytest.raises(MapkitError, match=r"truncated \(its header lists 482 triangles, it holds 238\)"):
        load_scene(cut, BuildOptions())


def test_wall_height_option_on_a_mesh_is_warned(caplog):
    load_scene(HOSPITAL, BuildOptions(wall_height=10.0))
    assert "--wall-height 10 is for DXF plans; a mesh's walls are as high as the model's (3 m)" in caplog.text


@pytest.mark.parametrize("suffix", [".obj", ".off", ".ply"])
def test_truncated_text_meshes_are_refused(tmp_path, suffix):
    """A cut copy of a text mesh used to build the part that was there
    without a word (142 of 187 segments); now it is a one-line error."""
    from mapkit.errors import MapkitError

    mesh = trimesh.util.concatenate(room_walls())
    whole = tmp_path / f"room{suffix}"
    data = mesh.export(file_type=suffix[1:], **({"encoding": "ascii"} if suffix == ".ply" else {}))
    data = data.encode() if isinstance(data, str) else data
    whole.write_bytes(data)
    assert load_scene(whole).segments is not None  # the whole file reads
    cut = tmp_path / f"cut{suffix}"
    lines = data.decode().splitlines()
    cut.write_text("\n".join(lines[: int(len(lines) * 0.7)]) + "\n")
    with pytest.raises(MapkitError, match="truncated"):
        load_scene(cut)
