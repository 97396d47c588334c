"""IFC models: a map per storey at the model's heights, the building manifest, the CLI.

The model is written here with ``ifcopenshell.api``: two storeys (floors at
0 and 3 m, walls 2.8 and 2.5 m high), each a 6 x 4 m room of four 0.2 m
walls with a door (0.9 m wide, 2.1 m high) in the south wall and a window
(1.2 m wide, sill 0.9 m, head 2.1 m on the ground floor, 1.0 to 1.8 m
upstairs) in the north wall, a space, and a stair from the ground floor up.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

import ezdxf
import ifcopenshell  # the ifc extra, which the test extra includes
import ifcopenshell.api

from cli_helpers import assert_one_line_error, run
from linemap.lmap import SegmentKind, load_map
from mapkit.edges import extract_edges
from mapkit.importers import load_scene
from mapkit.options import BuildOptions

#: name, elevation, wall height, window sill and head, metres.
STOREYS = [("Ground floor", 0.0, 2.8, 0.9, 2.1), ("Upper floor", 3.0, 2.5, 1.0, 1.8)]
DOOR = (1.0, 1.9, 2.1)  # x from, x to, head
WINDOW_X = (3.0, 4.2)
SIZE, T = (6.0, 4.0), 0.2


def _box(f, body, product, origin, size):
    """Give ``product`` a box body (x, y, z sizes) placed with its corner at ``origin``."""
    rep = ifcopenshell.api.run("geometry.add_wall_representation", f, context=body, length=size[0],
                               thickness=size[1], height=size[2])
    ifcopenshell.api.run("geometry.assign_representation", f, product=product, representation=rep)
    m = np.eye(4)
    m[:3, 3] = origin
    ifcopenshell.api.run("geometry.edit_object_placement", f, product=product, matrix=m)


def write_model(path: Path, partition_height: float | None = None) -> Path:
    """The module's model; with ``partition_height``, a low wall (x 2.4 to 2.6,
    from the south wall to y 1.4) of that height on the ground floor too."""
    run_api = ifcopenshell.api.run
    f = run_api("project.create_file", version="IFC4")
    project = run_api("root.create_entity", f, ifc_class="IfcProject", name="Test")
    run_api("unit.assign_unit", f)  # metres
    model = run_api("context.add_context", f, context_type="Model")
    body = run_api("context.add_context", f, context_type="Model", context_identifier="Body",
                   target_view="MODEL_VIEW", parent=model)
    site = run_api("root.create_entity", f, ifc_class="IfcSite", name="Site")
    building = run_api("root.create_entity", f, ifc_class="IfcBuilding", name="House")
    run_api("aggregate.assign_object", f, relating_object=project, products=[site])
    run_api("aggregate.assign_object", f, relating_object=site, products=[building])
    w, d = SIZE
    for k, (name, z, height, sill, head) in enumerate(STOREYS):
        storey = run_api("root.create_entity", f, ifc_class="IfcBuildingStorey", name=name)
        storey.Elevation = z
        m = np.eye(4)
        m[2, 3] = z
        run_api("geometry.edit_object_placement", f, product=storey, matrix=m)
        run_api("aggregate.assign_object", f, relating_object=building, products=[storey])
        walls = []
        for origin, size in [((0, 0, z), (w, T, height)), ((0, d - T, z), (w, T, height)),
                             ((0, T, z), (T, d - 2 * T, height)), ((w - T, T, z), (T, d - 2 * T, height))]:
            wall = run_api("root.create_entity", f, ifc_class="IfcWall", name=f"wall {len(walls)}")
            _box(f, body, wall, origin, size)
            walls.append(wall)
        if partition_height is not None and k == 0:
            wall = run_api("root.create_entity", f, ifc_class="IfcWall", name="partition")
            _box(f, body, wall, (2.4, T, z), (0.2, 1.4 - T, partition_height))
            walls.append(wall)
        run_api("spatial.assign_container", f, relating_structure=storey, products=walls)
        for cls, host, origin, size in [("IfcDoor", walls[0], (DOOR[0], -0.1, z), (DOOR[1] - DOOR[0], T + 0.2, DOOR[2])),
                                        ("IfcWindow", walls[1], (WINDOW_X[0], d - T - 0.1, z + sill),
                                         (WINDOW_X[1] - WINDOW_X[0], T + 0.2, head - sill))]:
            opening = run_api("root.create_entity", f, ifc_class="IfcOpeningElement")
            _box(f, body, opening, origin, size)
            run_api("feature.add_feature", f, feature=opening, element=host)
            filling = run_api("root.create_entity", f, ifc_class=cls, name=f"{cls} {k}")
            _box(f, body, filling, (origin[0], origin[1] + 0.15, origin[2]), (size[0], 0.1, size[2]))
            run_api("feature.add_filling", f, opening=opening, element=filling)
            run_api("spatial.assign_container", f, relating_structure=storey, products=[filling])
        space = run_api("root.create_entity", f, ifc_class="IfcSpace", name=f"room {k}")
        _box(f, body, space, (T, T, z), (w - 2 * T, d - 2 * T, height))
        run_api("aggregate.assign_object", f, relating_object=storey, products=[space])
        if k == 0:
            stair = run_api("root.create_entity", f, ifc_class="IfcStair", name="stair")
            _box(f, body, stair, (4.0, 1.0, z), (1.0, 2.0, STOREYS[1][1]))
            run_api("spatial.assign_container", f, relating_structure=storey, products=[stair])
    f.write(str(path))
    return path


@pytest.fixture(scope="module")
def model(tmp_path_factory) -> Path:
    return write_model(tmp_path_factory.mktemp("ifc") / "house.ifc")


@pytest.fixture(scope="module")
def building(model, tmp_path_factory):
    """The model built with ``mapkit build model.ifc -o DIR``: (DIR, manifest)."""
    from mapkit.cli import main

    out = tmp_path_factory.mktemp("built") / "house"
    assert main(["build", str(model), "-o", str(out), "-q"]) == 0
    return out, json.loads((out / "building.json").read_text())


def _expected_edges(height: float, sill: float, head: float) -> list[tuple[str, np.ndarray]]:
    """The room's inner wall edges, the door's and window's jambs, lintel, sill and head, (2, 3) each."""
    w, d = SIZE
    x0, x1, h = DOOR
    a0, a1 = WINDOW_X
    out = []
    inner = [((T, T), (w - T, T)), ((T, d - T), (w - T, d - T)), ((T, T), (T, d - T)), ((w - T, T), (w - T, d - T))]
    for (p, q) in inner[2:]:  # the side walls: whole at floor and ceiling
        for z in (0.0, height):
            out.append(("wall edge", np.array([[*p, z], [*q, z]])))
    for px, py in [(T, T), (w - T, T), (T, d - T), (w - T, d - T)]:  # room corners
        out.append(("wall edge", np.array([[px, py, 0.0], [px, py, height]])))
    out.append(("lintel", np.array([[x0, T, h], [x1, T, h]])))
    out.append(("sill", np.array([[a0, d - T, sill], [a1, d - T, sill]])))
    out.append(("head", np.array([[a0, d - T, head], [a1, d - T, head]])))
    for x in (x0, x1):
        out.append(("door jamb", np.array([[x, T, 0.0], [x, T, h]])))
    for x in (a0, a1):
        out.append(("window jamb", np.array([[x, d - T, sill], [x, d - T, head]])))
    return out


def _holds(segments: np.ndarray, seg: np.ndarray, tol: float = 0.01) -> bool:
    """Whether ``seg`` is among ``segments`` (either direction), endpoints within ``tol``."""
    if len(segments) == 0:
        return False
    fwd = np.abs(segments - seg).max(axis=(1, 2))
    back = np.abs(segments[:, ::-1] - seg).max(axis=(1, 2))
    return bool(min(fwd.min(), back.min()) <= tol)


def test_every_wall_edge_jamb_lintel_and_sill_is_in_its_storeys_map_at_the_models_heights(building):
    out, manifest = building
    for (name, z, height, sill, head), entry in zip(STOREYS, manifest["storeys"]):
        m = load_map(out / entry["map"])
        assert m.meta["wall_height"] == pytest.approx(height, abs=0.01)
        for what, seg in _expected_edges(height, sill, head):
            assert _holds(m.segments, seg), (name, what, seg)
        lintels = m.segments[m.kinds == SegmentKind.LINTEL]
        assert len(lintels) and np.allclose(lintels[:, :, 2], DOOR[2], atol=0.01), name


def test_the_same_building_drawn_as_dxf_gives_the_same_segments_per_storey(model, tmp_path):
    w, d = SIZE
    for name, z, height, sill, head in STOREYS:
        doc = ezdxf.new()
        doc.header["$INSUNITS"] = 6  # metres
        msp = doc.modelspace()
        x0, x1, _ = DOOR
        a0, a1 = WINDOW_X
        rects = [(0, 0, x0, T), (x1, 0, w, T), (0, d - T, a0, d), (a1, d - T, w, d), (0, T, T, d - T),
                 (w - T, T, w, d - T)]
        for ax, ay, bx, by in rects:
            msp.add_lwpolyline([(ax, ay), (bx, ay), (bx, by), (ax, by)], close=True, dxfattribs={"layer": "WALLS"})
        msp.add_lwpolyline([(x0, 0), (x1, 0), (x1, T), (x0, T)], close=True, dxfattribs={"layer": "DOORS"})
        msp.add_lwpolyline([(a0, d - T), (a1, d - T), (a1, d), (a0, d)], close=True, dxfattribs={"layer": "WINDOWS"})
        plan = tmp_path / f"{name}.dxf"
        doc.saveas(plan)
        dxf_options = BuildOptions(walls=["WALLS"], doors=["DOORS"], windows=["WINDOWS"], wall_height=height,
                                   door_height=DOOR[2], window_sill=sill, window_head=head)
        from_dxf, _ = extract_edges(load_scene(plan, dxf_options), dxf_options)
        ifc_options = BuildOptions(floor_name=name)
        from_ifc, _ = extract_edges(load_scene(model, ifc_options), ifc_options)
        assert len(from_dxf) == len(from_ifc), name
        assert all(_holds(from_dxf, s) for s in from_ifc), name


def test_each_wall_rises_to_its_own_height(tmp_path):
    model = write_model(tmp_path / "partition.ifc", partition_height=1.1)
    options = BuildOptions(floor_name="Ground floor")
    scene = load_scene(model, options)
    assert sorted(z.height for z in scene.height_zones) == pytest.approx([1.1, 2.8], abs=0.01)
    segments, _ = extract_edges(scene, options)
    face = np.array([[2.4, T, 1.1], [2.4, 1.4, 1.1]])  # the partition's top, west face
    assert _holds(segments, face)
    on_face = np.isclose(segments[:, :, 0], 2.4, atol=0.01).all(axis=1) & (segments[:, :, 1] < 1.45).all(axis=1)
    assert segments[on_face][:, :, 2].max() == pytest.approx(1.1, abs=0.01)  # nothing of it at the room's 2.8 m
    for what, seg in _expected_edges(2.8, 0.9, 2.1):
        assert _holds(segments, seg), what


def test_the_manifest_lists_storeys_maps_source_and_the_stair(model, building):
    import hashlib

    out, manifest = building
    assert manifest["format"] == "mapkit-building" and manifest["version"] == 1
    assert manifest["source"]["sha256"] == hashlib.sha256(model.read_bytes()).hexdigest()
    assert manifest["source"]["schema"] == "IFC4"
    storeys = manifest["storeys"]
    assert [s["name"] for s in storeys] == ["Ground floor", "Upper floor"]
    assert [s["elevation_m"] for s in storeys] == [0.0, 3.0]
    assert [s["height_m"] for s in storeys] == [3.0, 2.5]
    assert [s["map"] for s in storeys] == ["Ground_floor.lmap", "Upper_floor.lmap"]
    assert all((out / s["map"]).is_file() and s["segments"] > 0 for s in storeys)
    (stair,) = manifest["connections"]
    assert stair["kind"] == "stair" and stair["ifc_class"] == "IfcStair"
    assert stair["storeys"] == ["Ground floor", "Upper floor"]
    from shapely.geometry import shape

    ground = shape(stair["footprints"]["Ground floor"])
    assert ground.area == pytest.approx(2.0, abs=0.01) and ground.bounds == pytest.approx((4, 1, 5, 3), abs=0.01)
    # The robot does not stand on the stair.
    m = load_map(out / storeys[0]["map"])
    assert m.meta["source"]["name"] == model.name and m.meta["build"]["floor_name"] == "Ground floor"


@pytest.mark.slow
def test_storey_builds_one_map_and_layers_info_preview_describe_the_model(model, building, tmp_path, capsys):
    code, out, err = run(capsys, "build", model, "--storey", "upper floor", "-o", tmp_path / "up.lmap", "-q")
    assert code == 0, err
    built_dir, manifest = building
    assert load_map(tmp_path / "up.lmap").segments.tolist() == load_map(built_dir / "Upper_floor.lmap").segments.tolist()
    code, out, err = run(capsys, "layers", model)
    assert code == 0, err
    assert "Ground floor" in out and "IfcWall" in out and "IfcDoor" in out and "IfcStair" in out
    code, out, err = run(capsys, "info", built_dir / "building.json")
    assert code == 0, err
    assert "Ground_floor.lmap" in out and "stair" in out
    code, out, err = run(capsys, "preview", model, "-o", tmp_path / "p.png")
    assert code == 0, err
    assert (tmp_path / "p-Ground_floor.png").is_file() and (tmp_path / "p-Upper_floor.png").is_file()


def test_bad_input_is_a_one_line_error(model, tmp_path, capsys):
    assert_one_line_error(*run(capsys, "build", model, "--storey", "Cellar", "-o", tmp_path / "c.lmap"),
                          "no storey named 'Cellar'", "Ground floor")
    assert_one_line_error(*run(capsys, "build", model, "-o", tmp_path / "one.lmap"), "2 storeys", "--storey")
    bad = tmp_path / "bad.ifc"
    bad.write_text("not a model\n")
    assert_one_line_error(*run(capsys, "build", bad, "-o", tmp_path / "out"), "not a readable IFC model")
    empty = tmp_path / "empty.ifc"
    f = ifcopenshell.api.run("project.create_file", version="IFC4")
    ifcopenshell.api.run("root.create_entity", f, ifc_class="IfcProject", name="Empty")
    f.write(str(empty))
    assert_one_line_error(*run(capsys, "build", empty, "-o", tmp_path / "out"), "no building storey")
    assert not (tmp_path / "out").exists()


def test_without_ifcopenshell_the_error_names_the_extra(model, tmp_path, capsys, monkeypatch):
    import builtins

    real_import = builtins.__import__

    def no_ifcopenshell(name, *args, **kwargs):
        if name.split(".")[0] == "ifcopenshell":
            raise ImportError(name)
        return real_import(name, *args, **kwargs)

    monkeypatch.setattr(builtins, "__import__", no_ifcopenshell)
    assert_one_line_error(*run(capsys, "build", model, "-o", tmp_path / "out"), "pip install 'mapkit[ifc]'")
