"""Synthetic rig frames (mapkit_harness/simulate.py make_rig_frame, the
rigs of mapkit_harness/rigs.py, tools/simulate.py --rig): one robot pose,
each camera's lines at its own pose."""

from __future__ import annotations

import json
import math
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

import matcher
from linemap.rig import Rig
from linemap.rig_files import load_rig, rig_to_dict
from mapkit_harness.rigs import ring_rig
from mapkit_harness.simulate import PEQ, camera_pose, make_frame, make_rig_frame, paper_camera, visible_lines

ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def flat():
    return matcher.load_map(ROOT / "maps" / "flat.lmap")


def _wrap_deg(a: float) -> float:
    return (a + 180.0) % 360.0 - 180.0


def test_ring_rig_cameras_look_outwards_evenly():
    rig = ring_rig(4, hfov_deg=80.0, width=320, height=240, height_m=1.1, pitch_deg=5.0, radius_m=0.2)
    assert rig.names == ["cam0", "cam1", "cam2", "cam3"] and rig.reach_m == pytest.approx(0.2)
    assert [rc.mount.yaw_deg for rc in rig] == [0.0, 90.0, 180.0, -90.0]
    for rc in rig:
        assert abs(_wrap_deg(math.degrees(math.atan2(rc.mount.y, rc.mount.x)) - rc.mount.yaw_deg)) < 1e-9
        cam = rc.camera
        assert (cam.width, cam.height, cam.height_m, cam.pitch_deg) == (320, 240, 1.1, 5.0)
        assert math.degrees(2 * math.atan(cam.cx / cam.fx)) == pytest.approx(80.0)
    assert ring_rig(1, radius_m=0.0).is_single


def test_each_camera_sees_the_map_from_its_own_pose(flat):
    """Noise-free, clutter-free: camera k of a 4-ring at the robot's pose
    moved 0.2 m along heading + k * 90 deg, looking that way; its lines are
    the visible lines at that pose; the prior is one robot prior within the
    PEQ's bounds, each camera's the same through its mount."""
    rig = ring_rig(4, radius_m=0.2)
    fr = make_rig_frame(flat, rig, np.random.default_rng(7), 3, noise_px=0.0, noise_deg=0.0, end_px=0.0, clutter=0)
    X, Y, th = fr.pose
    seen = 0
    for k, (rc, cf) in enumerate(zip(rig, fr.cameras)):
        heading = math.radians(th + 90.0 * k)
        assert cf.pose[:2] == pytest.approx((X + 0.2 * math.cos(heading), Y + 0.2 * math.sin(heading)), abs=1e-12)
        assert _wrap_deg(cf.pose[2] - th - 90.0 * k) == pytest.approx(0.0, abs=1e-9)
        px, py, pth = fr.prior
        ph = math.radians(pth + 90.0 * k)
        assert cf.prior[:2] == pytest.approx((px + 0.2 * math.cos(ph), py + 0.2 * math.sin(ph)), abs=1e-12)
        ideal, ids = visible_lines(flat, rc.camera, cf.pose)
        order = np.argsort(cf.truth, kind="stable")
        assert (cf.truth >= 0).all() and sorted(cf.truth.tolist()) == sorted(ids.tolist())
        assert np.allclose(cf.lines[order], ideal[np.argsort(ids, kind="stable")], atol=1e-9)
        seen += len(ids)
    assert seen >= 5
    dt, dyaw = PEQ[3]
    assert (fr.dt, fr.dyaw) == (dt, dyaw)
    assert math.hypot(fr.prior[0] - X, fr.prior[1] - Y) <= dt and abs(_wrap_deg(fr.prior[2] - th)) <= dyaw
    assert [len(x) for x in fr.lines] == [len(cf.lines) for cf in fr.cameras]


def test_cameras_around_see_more_than_one_ahead(flat):
    """The same robot poses: four cameras around see what the front one
    sees and much more (over a dozen frames, the point of a rig; one
    camera's share varies from frame to frame)."""
    rig = ring_rig(4, hfov_deg=60.0, radius_m=0.0)
    front, around = 0, 0
    for seed in range(10, 22):
        fr = make_rig_frame(flat, rig, np.random.default_rng(seed), 2, clutter=0, min_seen=1)
        counts = [int((cf.truth >= 0).sum()) for cf in fr.cameras]
        front += counts[0]
        around += sum(counts)
    assert around > 2 * front > 0


def test_one_camera_rig_frame_is_the_single_cameras_frame(flat):
    cam = paper_camera()
    for seed in (3,):
        a = make_frame(flat, cam, np.random.default_rng(seed), 2, roll_deg=2.0, pitch_error_deg=1.0)
        rf = make_rig_frame(flat, Rig.single(cam), np.random.default_rng(seed), 2, min_seen=5, max_seen=9,
                            roll_deg=2.0, pitch_error_deg=1.0)
        b = rf.cameras[0]
        assert (a.pose, a.prior, a.pitch_deg, a.roll_deg) == (b.pose, b.prior, b.pitch_deg, b.roll_deg)
        assert (rf.pose, rf.prior) == (a.pose, a.prior)
        assert np.array_equal(a.lines, b.lines) and np.array_equal(a.truth, b.truth)
        assert camera_pose(Rig.single(cam)[0].mount, a.pose) is a.pose


def test_each_cameras_attitude_is_drawn_within_its_bounds(flat):
    rig = ring_rig(3, pitch_deg=4.0)
    fr = make_rig_frame(flat, rig, np.random.default_rng(2), 1, roll_deg=3.0, pitch_error_deg=2.0)
    pitches = [cf.pitch_deg for cf in fr.cameras]
    rolls = [cf.roll_deg for cf in fr.cameras]
    assert all(abs(p - 4.0) <= 2.0 for p in pitches) and all(abs(r) <= 3.0 for r in rolls)
    assert len(set(pitches)) == 3 and len(set(rolls)) == 3  # each camera its own


@pytest.mark.parametrize("kind", ["rig.json", "camchain.yaml"])
def test_tools_simulate_writes_one_lines_file_per_camera(flat, tmp_path, capsys, kind):
    """tools/simulate.py --rig (a rig file, or a Kalibr camchain placing
    cam0 in the file): rig.json reads back as the rig, each camera's lines
    file holds its frame, the truth names each camera's pose and matches,
    each camera's view is rendered at its own size."""
    import simulate

    rig = ring_rig(2, hfov_deg=90.0, width=160, height=120, radius_m=0.15)
    if kind == "rig.json":  # a camera with distortion: the frame is the ideal pinhole's, and so is rig.json
        distorted = replace(rig[1], camera=replace(rig[1].camera, distortion=(-0.1, 0.01, 0.0, 0.0)))
        (tmp_path / kind).write_text(json.dumps(rig_to_dict(Rig((rig[0], distorted)))))
    else:
        f = rig[0].camera
        cam = (f"  camera_model: pinhole\n  intrinsics: [{f.fx!r}, {f.fy!r}, {f.cx!r}, {f.cy!r}]\n"
               "  resolution: [160, 120]\n  distortion_model: none\n")
        flip = "  T_cn_cnm1:\n  - [-1, 0, 0, 0]\n  - [0, 1, 0, 0]\n  - [0, 0, -1, -0.3]\n  - [0, 0, 0, 1]\n"
        (tmp_path / kind).write_text(f"cam0:\n{cam}cam1:\n{cam}{flip}"
                                     "robot:\n  x: 0.15\n  y: 0.0\n  yaw_deg: 0.0\n  height_m: 1.2\n")
    out = tmp_path / "out"
    assert simulate.main(["--rig", str(tmp_path / kind), "--peq", "2", "--seed", "5", "--out", str(out)]) == 0
    printed = capsys.readouterr().out
    assert "cam0:" in printed and "cam1:" in printed
    got = load_rig(out / "rig.json")
    assert got.names == rig.names and not any(rc.camera.distortion for rc in got)
    for g, w in zip(got, rig):
        assert g.camera == w.camera or np.allclose([g.camera.fx, g.camera.height_m, g.camera.pitch_deg],
                                                   [w.camera.fx, w.camera.height_m, w.camera.pitch_deg])
        assert g.mount.x == pytest.approx(w.mount.x) and _wrap_deg(g.mount.yaw_deg - w.mount.yaw_deg) == 0.0
    truth = json.loads((out / "truth.json").read_text())
    want = make_rig_frame(flat, got, np.random.default_rng(5), 2)
    assert truth["prior"] == list(want.prior) and truth["dt"] == want.dt
    for entry, cf, rc in zip(truth["cameras"], want.cameras, got):
        assert entry["name"] == rc.name and entry["pose"] == list(cf.pose)
        assert entry["matches"] == cf.true_matches()
        lines = np.array(json.loads((out / entry["lines"]).read_text())["lines"]).reshape(-1, 2, 2)
        assert np.allclose(lines, cf.lines, atol=0.005)
        import cv2

        image = cv2.imread(str(out / entry["lines"].replace("lines_", "frame_").replace(".json", ".png")), 0)
        assert image.shape == (120, 160) and image.std() > 5  # walls, floor and ceiling, not a blank


def test_tools_simulate_refuses_a_bad_rig_in_one_line(tmp_path, capsys):
    import simulate

    (tmp_path / "camchain.yaml").write_text("cam0:\n  camera_model: pinhole\n")
    assert simulate.main(["--rig", str(tmp_path / "camchain.yaml")]) == 2
    out = capsys.readouterr().out
    assert out.startswith("error: Kalibr camchain") and "does not say where cam0 is on the robot" in out
    assert len(out.strip().splitlines()) == 1
