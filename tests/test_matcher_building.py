"""The matcher on a building: the two-storey IFC model of test_ifc_import.py
built to a folder of storey maps and its manifest, then frames from its
upper storey localised over the manifest (lost mode, a prior on the
storey, the tracker, the command line); bad manifests in one line.

The storeys are the same 6 x 4 m room with a door and a window, told apart
by their heights only (walls 2.8 and 2.5 m, windows 0.9-2.1 and 1.0-1.8 m):
a view with the ceiling or a window in it belongs to one storey, a view of
the door and the floor to both alike.
"""

from __future__ import annotations

import json
import math
import shutil

import numpy as np
import pytest

import matcher
from linemap.lmap import LineMap, LmapError
from linemap.rig import Mount, Rig, RigCamera
from matcher.cli import main as matcher_main
from mapkit_harness.simulate import PAPER_CAMERA, add_noise, camera_pose, paper_camera, visible_lines
from test_ifc_import import write_model

UPPER, GROUND = "Upper floor", "Ground floor"
#: A pose on the upper storey whose view holds its ceiling and window (9 lines).
POSE = (1.5, 1.2, 60.0)


@pytest.fixture(scope="module")
def built(tmp_path_factory):
    """The model built with ``mapkit build model.ifc -o DIR``: DIR."""
    from mapkit.cli import main

    tmp = tmp_path_factory.mktemp("building")
    model = write_model(tmp / "house.ifc")
    assert main(["build", str(model), "-o", str(tmp / "house"), "-q"]) == 0
    return tmp / "house"


@pytest.fixture(scope="module")
def building(built):
    return matcher.load_map(built / "building.json")


def _frame(building, pose=POSE, camera=None, seed=0, storey=UPPER):
    """Image lines (M, 2, 2) of the storey's map seen from ``pose``, with 0.5 px of seeded noise."""
    camera = camera or paper_camera()
    lines, _ = visible_lines(building.storey(storey).map, camera, pose)
    return add_noise(lines, np.random.default_rng(seed), 0.5, 0.2, 0.5, camera)


def _off(pose, truth) -> tuple[float, float]:
    return math.hypot(pose[0] - truth[0], pose[1] - truth[1]), abs((pose[2] - truth[2] + 180.0) % 360.0 - 180.0)


def test_load_map_of_a_manifest_gives_the_storeys_in_order_with_their_maps(built, building):
    assert isinstance(building, matcher.Building)
    assert [(s.name, s.elevation_m, s.height_m) for s in building.storeys] == [(GROUND, 0.0, 3.0), (UPPER, 3.0, 2.5)]
    for s in building.storeys:
        alone = matcher.load_map(built / f"{s.name.replace(' ', '_')}.lmap")
        assert isinstance(alone, LineMap) and np.array_equal(s.map.segments, alone.segments)
    assert [s.name for s in matcher.load_map(built).storeys] == [GROUND, UPPER]  # the folder will do
    assert building.storey("upper FLOOR").name == UPPER  # case aside, as mapkit build --storey


@pytest.mark.slow
def test_lost_mode_over_the_manifest_finds_the_upper_storey(building):
    lines = _frame(building)
    res = matcher.localize_global(building, paper_camera(), lines)
    assert res, res.reason
    assert res.storey == UPPER
    dist, dyaw = _off(res.pose, POSE)
    assert dist < 0.03 and dyaw < 0.5
    d = res.to_dict()
    assert d["storey"] == UPPER and d["ok"]
    # The ground storey alone explains fewer of the lines, or none.
    alone = matcher.localize_global(building.storey(GROUND).map, paper_camera(), lines)
    assert not alone or len(alone.matches) < len(res.matches)


def test_a_prior_names_its_storey(building):
    lines, cam = _frame(building), paper_camera()
    prior = (POSE[0] + 0.15, POSE[1] - 0.1, POSE[2] + 6.0)
    res = matcher.localize(building, cam, lines, prior, 0.3, 10.0, storey=UPPER)
    assert res and res.storey == UPPER
    assert _off(res.pose, POSE)[0] < 0.03
    # The same search on the storey's map, as a plain map: the same answer, no storey.
    plain = matcher.localize(building.storey(UPPER).map, cam, lines, prior, 0.3, 10.0)
    assert plain.storey is None and "storey" not in plain.to_dict()
    assert (plain.pose, plain.matches, plain.score) == (res.pose, res.matches, res.score)
    with pytest.raises(matcher.InputError, match="give the storey"):
        matcher.localize(building, cam, lines, prior, 0.3, 10.0)
    with pytest.raises(matcher.InputError, match="no storey named 'Cellar'.*Ground floor"):
        matcher.localize(building, cam, lines, prior, 0.3, 10.0, storey="Cellar")
    with pytest.raises(matcher.InputError, match="one floor"):
        matcher.localize(building.storey(UPPER).map, cam, lines, prior, 0.3, 10.0, storey=UPPER)


def test_the_same_view_on_two_storeys_is_ambiguous_naming_both(building):
    """Looking down at the door: jambs and floor edges, alike on both storeys."""
    cam = paper_camera(pitch_deg=20.0)
    res = matcher.localize_global(building, cam, _frame(building, (1.45, 2.6, -90.0), cam))
    assert not res and "2 storeys" in res.reason
    assert sorted(c["storey"] for c in res.candidates) == [GROUND, UPPER]
    assert all(_off((c["x"], c["y"], c["yaw_deg"]), (1.45, 2.6, -90.0))[0] < 0.03 for c in res.candidates)
    assert {c["storey"] for c in res.to_dict()["candidates"]} == {GROUND, UPPER}


def _walk(n=4, start=(1.0, 1.0, 30.0), step=0.08):
    """Poses ``n`` steps of ``step`` metres along the heading from ``start``."""
    x, y, yaw = start
    c, s = math.cos(math.radians(yaw)), math.sin(math.radians(yaw))
    return [(x + k * step * c, y + k * step * s, yaw) for k in range(n)]


def test_the_tracker_keeps_to_its_storey(building):
    cam = paper_camera()
    poses = _walk()
    tracker = matcher.Tracker(building, cam, prior=poses[0], dt=0.2, dyaw=5.0, storey=UPPER)
    for k, pose in enumerate(poses):
        out = tracker.step(float(k), pose, _frame(building, pose, cam, seed=k))
        assert out and out.storey == UPPER and out.to_dict()["storey"] == UPPER
        assert _off(out.estimate, pose)[0] < 0.05
    with pytest.raises(matcher.InputError, match="give the storey"):
        matcher.Tracker(building, cam, prior=poses[0], dt=0.2, dyaw=5.0)


def test_a_lost_tracker_finds_its_storey_and_confirms_it(building):
    cam = paper_camera()
    tracker = matcher.Tracker(building, cam)
    outs = [tracker.step(float(k), pose, _frame(building, pose, cam, seed=k)) for k, pose in enumerate(_walk(5))]
    assert outs[0].storey is None and not outs[0]
    assert outs[0].to_dict()["candidates"][0]["storey"] == UPPER
    assert outs[-1] and outs[-1].storey == UPPER and outs[-1].state == "tracking"
    assert _off(outs[-1].estimate, _walk(5)[-1])[0] < 0.05


def test_the_tracker_keeps_its_storey_until_relocalised_on_another(building):
    """Carried upstairs (the odometry knows nothing of it): the tracker keeps
    to the ground floor while it coasts and searches, then relocalises on
    the upper storey."""
    cam = paper_camera()
    ground, upper = _walk(3), _walk(8, start=POSE, step=0.04)
    tracker = matcher.Tracker(building, cam, prior=ground[0], dt=0.2, dyaw=5.0, storey=GROUND)
    outs = [tracker.step(float(k), p, _frame(building, p, cam, seed=k, storey=GROUND)) for k, p in enumerate(ground)]
    assert all(o and o.storey == GROUND for o in outs)
    jump = (ground[-1][0] - upper[0][0], ground[-1][1] - upper[0][1])
    for k, p in enumerate(upper, len(ground)):
        outs.append(tracker.step(float(k), (p[0] + jump[0], p[1] + jump[1], p[2]), _frame(building, p, cam, seed=k)))
    first_upper = next(k for k, o in enumerate(outs) if o.storey == UPPER)
    assert first_upper > len(ground) + 1  # not on one frame's word
    assert all(o.storey == GROUND for o in outs[:first_upper])
    assert all(o and o.storey == UPPER for o in outs[first_upper:]) and outs[first_upper].state == "tracking"
    assert _off(outs[-1].estimate, upper[-1])[0] < 0.05


def _rig_frame(building, rig, pose, seed: int) -> list:
    """Each rig camera's lines of the upper storey at its own pose, with 0.5 px of seeded noise."""
    rng, out = np.random.default_rng(seed), []
    for rc in rig:
        lines, _ = visible_lines(building.storey(UPPER).map, rc.camera, camera_pose(rc.mount, pose))
        out.append(add_noise(lines, rng, 0.5, 0.2, 0.5, rc.camera) if len(lines) else lines)
    return out


@pytest.mark.slow
def test_a_rig_on_a_building_is_tracked_on_one_storey(building):
    cam = paper_camera()
    rig = Rig((RigCamera("front", cam, Mount(0.1, 0.0, 0.0)), RigCamera("back", cam, Mount(-0.1, 0.0, 180.0))))
    poses = _walk()
    with pytest.raises(matcher.InputError, match="one storey"):
        matcher.Tracker(building, rig, prior=poses[0], dt=0.2, dyaw=5.0)
    tracker = matcher.Tracker(building, rig, prior=poses[0], dt=0.2, dyaw=5.0, storey=UPPER)
    for k, pose in enumerate(poses):
        out = tracker.step(float(k), pose, _rig_frame(building, rig, pose, k))
        assert out and out.storey == UPPER and out.to_dict()["storey"] == UPPER, out.reason
        assert _off(out.estimate, pose)[0] < 0.05
    # With no prior it searches the storey named (a rig's frame is localised on one storey).
    lost = matcher.Tracker(building, rig, storey=UPPER)
    outs = [lost.step(float(k), pose, _rig_frame(building, rig, pose, k)) for k, pose in enumerate(_walk(5))]
    assert not outs[0] and outs[-1] and outs[-1].storey == UPPER and outs[-1].state == "tracking"
    assert _off(outs[-1].estimate, _walk(5)[-1])[0] < 0.05


def _cli_files(tmp_path, building):
    cam = tmp_path / "camera.json"
    cam.write_text(json.dumps(PAPER_CAMERA))
    lines = tmp_path / "lines.json"
    lines.write_text(json.dumps({"lines": _frame(building).reshape(-1, 4).tolist()}))
    return ["--camera", str(cam), "--lines", str(lines)]


@pytest.mark.slow
def test_matcher_localize_on_a_manifest(built, building, tmp_path, capsys):
    files = _cli_files(tmp_path, building)
    assert matcher_main(["localize", "--map", str(built / "building.json"), *files, "--lost"]) == 0
    out = capsys.readouterr().out
    assert out.startswith("storey 'Upper floor'  pose x=1.5")
    prior = ["--prior", "1.6,1.1,65", "--dt", "0.3", "--dyaw", "10"]
    assert matcher_main(["localize", "--map", str(built), *files, *prior, "--storey", UPPER, "--json"]) == 0
    d = json.loads(capsys.readouterr().out)
    assert d["ok"] and d["storey"] == UPPER
    # Lost mode on the named storey only.
    assert matcher_main(["localize", "--map", str(built), *files, "--lost", "--storey", GROUND, "--json"]) == 1
    d = json.loads(capsys.readouterr().out)
    assert not d["ok"] and d.get("storey") in (None, GROUND)


@pytest.mark.parametrize("extra, needle", [
    ([], "give the storey (--storey NAME)"),
    (["--storey", "Cellar"], "no storey named 'Cellar'"),
])
def test_matcher_localize_storey_errors_are_one_line(built, building, tmp_path, capsys, extra, needle):
    files = _cli_files(tmp_path, building)
    prior = ["--prior", "1.6,1.1,65", "--dt", "0.3", "--dyaw", "10"]
    assert matcher_main(["localize", "--map", str(built / "building.json"), *files, *prior, *extra]) == 2
    out, err = capsys.readouterr()
    assert out == "" and len(err.strip().splitlines()) == 1 and err.startswith("matcher: error: ") and needle in err
    assert "storey=" not in err  # the command line's flag, not the Python parameter


def test_a_building_without_a_storey_named_says_storey_from_python(building):
    from linemap.building import StoreyNeeded

    with pytest.raises(StoreyNeeded) as e:
        matcher.localize(building, paper_camera(), _frame(building), (1.6, 1.1, 65.0), 0.3, 10)
    assert str(e.value).endswith("give the storey (storey=NAME)") and "--storey" not in str(e.value)
    assert str(e.value.naming("--storey NAME")).endswith("give the storey (--storey NAME)")


def test_storey_with_a_plain_map_is_a_one_line_error(built, building, tmp_path, capsys):
    files = _cli_files(tmp_path, building)
    assert matcher_main(["localize", "--map", str(built / "Upper_floor.lmap"), *files, "--lost", "--storey",
                         UPPER]) == 2
    out, err = capsys.readouterr()
    assert out == "" and len(err.strip().splitlines()) == 1 and "is for a building" in err


def test_matcher_track_on_a_manifest(built, building, tmp_path, capsys):
    cam = paper_camera()
    run = tmp_path / "run.jsonl"
    run.write_text("".join(json.dumps({"t": float(k), "odom": list(p),
                                       "lines": _frame(building, p, cam, seed=k).reshape(-1, 4).tolist()}) + "\n"
                           for k, p in enumerate(_walk())))
    (tmp_path / "camera.json").write_text(json.dumps(PAPER_CAMERA))
    args = ["track", "--map", str(built), "--camera", str(tmp_path / "camera.json"), "--frames", str(run)]
    assert matcher_main([*args, "--prior", "1,1,30", "--dt", "0.2", "--dyaw", "5", "--storey", UPPER, "--json",
                         "--plot", str(tmp_path / "route.png"), "--out", str(tmp_path / "traj.txt")]) == 0
    frames = [json.loads(ln) for ln in capsys.readouterr().out.splitlines()]
    assert len(frames) == 4 and all(f["ok"] and f["storey"] == UPPER for f in frames)
    assert (tmp_path / "route.png").stat().st_size > 0
    # The trajectory's z: the camera's height above the upper floor (3 m up).
    zs = [float(ln.split()[3]) for ln in (tmp_path / "traj.txt").read_text().splitlines()[1:]]
    assert zs == [pytest.approx(3.0 + PAPER_CAMERA["height_m"])] * 4
    assert matcher_main([*args, "--lost", "--storey", UPPER]) == 2
    assert "--storey names the storey of --prior" in capsys.readouterr().err


def _damaged_copy(built, tmp_path, change):
    """A copy of the building's folder with ``change(folder, manifest dict)`` applied; its manifest path."""
    folder = tmp_path / "copy"
    shutil.copytree(built, folder)
    doc = json.loads((folder / "building.json").read_text())
    change(folder, doc)
    (folder / "building.json").write_text(json.dumps(doc))
    return folder / "building.json"


def _swap_maps(doc):
    a, b = doc["storeys"]
    a["map"], b["map"] = b["map"], a["map"]


def _flip_a_byte(folder):
    data = bytearray((folder / "Upper_floor.lmap").read_bytes())
    data[-5] ^= 0xFF
    (folder / "Upper_floor.lmap").write_bytes(bytes(data))


@pytest.mark.parametrize("change, needle", [
    (lambda f, d: (f / "Upper_floor.lmap").unlink(), "the map of storey 'Upper floor'"),
    (lambda f, d: _flip_a_byte(f), "Upper_floor.lmap"),
    (lambda f, d: _swap_maps(d), "the map of storey 'Upper floor', not of 'Ground floor'"),
    (lambda f, d: d.update(version=2), "building manifest version 2"),
    (lambda f, d: d.update(format="something else"), "not a building manifest"),
    (lambda f, d: d.update(storeys=[]), "'storeys' must be a non-empty list"),
    (lambda f, d: d["storeys"][1].update(map="../Upper_floor.lmap"), "must be the file name of a .lmap"),
    (lambda f, d: d["storeys"][1].update(elevation_m="3"), "lacks a finite number 'elevation_m'"),
    (lambda f, d: d["storeys"][1].update(name=GROUND), "appears twice"),
    (lambda f, d: d["source"].update(sha256="0" * 64), "built from another model"),
    (lambda f, d: d["storeys"][0].update(elevation_m=10 ** 400), "lacks a finite number 'elevation_m'"),
    (lambda f, d: d["storeys"][0].update(segments="many"), "'segments' must be a number"),
    (lambda f, d: d["connections"].append(1), "connection 1 must be an object"),
])
def test_a_bad_manifest_is_a_one_line_error(built, tmp_path, capsys, change, needle):
    path = _damaged_copy(built, tmp_path, change)
    with pytest.raises(LmapError) as info:
        matcher.load_map(path)
    assert needle in str(info.value) and "\n" not in str(info.value)
    files = ["--camera-k", "900,900,320,240", "--image-size", "640x480", "--height-m", "1.2",
             "--lines", str(tmp_path / "lines.json"), "--lost"]
    (tmp_path / "lines.json").write_text('{"lines": [[0, 0, 100, 100]]}')
    assert matcher_main(["localize", "--map", str(path), *files]) == 2
    out, err = capsys.readouterr()
    assert out == "" and len(err.strip().splitlines()) == 1 and needle in err


def test_not_json_and_a_folder_without_a_manifest(tmp_path):
    (tmp_path / "building.json").write_text("{not json")
    with pytest.raises(LmapError, match="not valid JSON"):
        matcher.load_map(tmp_path / "building.json")
    empty = tmp_path / "empty"
    empty.mkdir()
    with pytest.raises(LmapError, match="is a directory with no building.json"):
        matcher.load_map(empty)
