"""Camera files users already have: OpenCV calibrations (YAML, XML, JSON as
cv::FileStorage writes them), ROS camera_info YAML, a K on the command line."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

import matcher
from linemap.camera import Camera, CameraError

DATA = Path(__file__).parent / "data" / "cameras"
ROOT = Path(__file__).resolve().parent.parent
WANT = dict(width=640, height=480, fx=457.0, fy=457.0, cx=320.0, cy=240.0,
            distortion=(-0.28, 0.07, 0.0005, -0.0003, 0.0))


@pytest.mark.parametrize("name", ["opencv_calibration.yml", "opencv_calibration.xml", "opencv_calibration.json",
                                  "ros_camera_info.yaml"])
def test_calibration_files_of_each_kind(name):
    cam = Camera.load(DATA / name, height_m=1.2, pitch_deg=3.0)
    for k, v in WANT.items():
        assert getattr(cam, k) == pytest.approx(v), k
    assert cam.height_m == 1.2 and cam.pitch_deg == 3.0


def test_camera_json_still_loads_and_takes_overrides(tmp_path):
    p = tmp_path / "camera.json"
    p.write_text(json.dumps(dict(width=640, height=480, fx=500.0, fy=500.0, cx=320.0, cy=240.0, height_m=1.0,
                                 pitch_deg=0.0)))
    assert Camera.load(p).height_m == 1.0
    assert Camera.load(p, height_m=1.5, pitch_deg=2.0).height_m == 1.5


def test_what_is_missing_or_wrong_is_one_clear_error(tmp_path):
    with pytest.raises(CameraError, match="has no camera height: pass --height-m"):
        Camera.load(DATA / "ros_camera_info.yaml")
    fisheye = tmp_path / "fisheye.yaml"
    fisheye.write_text((DATA / "ros_camera_info.yaml").read_text().replace("plumb_bob", "equidistant"))
    with pytest.raises(CameraError, match="distortion model 'equidistant' is not supported"):
        Camera.load(fisheye, height_m=1.2)
    bad_k = tmp_path / "bad_k.yaml"
    bad_k.write_text("image_width: 640\nimage_height: 480\ncamera_matrix:\n  rows: 2\n  cols: 2\n  data: [1, 0, 0, 1]\n")
    with pytest.raises(CameraError, match="camera matrix must be 3x3"):
        Camera.load(bad_k, height_m=1.2)
    no_size = tmp_path / "no_size.yaml"
    no_size.write_text("camera_matrix:\n  rows: 3\n  cols: 3\n  data: [457, 0, 320, 0, 457, 240, 0, 0, 1]\n")
    with pytest.raises(CameraError, match="has no image size"):
        Camera.load(no_size, height_m=1.2)
    garbage = tmp_path / "garbage.yaml"
    garbage.write_bytes(b"\x00\x01 not : a : [calibration")
    with pytest.raises(CameraError, match="camera file"):
        Camera.load(garbage, height_m=1.2)
    deep = tmp_path / "deep.yaml"
    deep.write_text("a: " + "[" * 10000 + "]" * 10000)
    with pytest.raises(CameraError, match="nested too deeply"):
        Camera.load(deep, height_m=1.2)


def _frame_files(tmp_path):
    from mapkit_harness.simulate import make_frame

    linemap = matcher.load_map(ROOT / "maps" / "flat.lmap")
    cam = Camera.from_dict(dict(width=640, height=480, fx=457.0, fy=457.0, cx=320.0, cy=240.0, height_m=1.2,
                                pitch_deg=0.0))
    fr = make_frame(linemap, cam, np.random.default_rng(4), 1)
    (tmp_path / "lines.json").write_text(json.dumps({"lines": fr.lines.reshape(-1, 4).tolist()}))
    (tmp_path / "camera.json").write_text(json.dumps(cam.to_dict()))
    return fr


def _localize(capsys, *argv):
    from matcher.cli import main

    capsys.readouterr()
    code = main(["localize", *map(str, argv), "--json"])
    return code, capsys.readouterr()


def test_the_command_line_takes_each_kind_alike(tmp_path, capsys):
    """The same frame localised with camera.json, an OpenCV YAML (no
    distortion: the lines are ideal) and a K on the command line."""
    fr = _frame_files(tmp_path)
    ocv = tmp_path / "ocv.yml"
    ocv.write_text((DATA / "opencv_calibration.yml").read_text().replace(
        "-2.8000000000000003e-01, 7.0000000000000007e-02, 5.0000000000000001e-04,\n       -2.9999999999999997e-04, 0.",
        "0., 0., 0., 0., 0."))
    common = ["--map", ROOT / "maps" / "flat.lmap", "--lines", tmp_path / "lines.json",
              "--prior", ",".join(map(str, fr.prior)), "--dt", fr.dt, "--dyaw", fr.dyaw]
    results = []
    for cam_args in (["--camera", tmp_path / "camera.json"], ["--camera", ocv, "--height-m", "1.2"],
                     ["--camera-k", "457,457,320,240", "--image-size", "640x480", "--height-m", "1.2"]):
        code, out = _localize(capsys, *common, *cam_args)
        assert code == 0, out
        results.append(json.loads(out.out))
    assert results[0]["pose"] == results[1]["pose"] == results[2]["pose"]


@pytest.mark.parametrize("extra, msg", [
    (["--camera-k", "457,457,320"], "--camera-k takes FX,FY,CX,CY"),
    (["--camera-k", "457,457,320,240", "--height-m", "1.2"], "needs --image-size"),
    (["--camera-k", "457,457,320,240", "--image-size", "640x480"], "needs --height-m"),
])
def test_the_command_line_says_what_is_missing(tmp_path, capsys, extra, msg):
    fr = _frame_files(tmp_path)
    code, out = _localize(capsys, "--map", ROOT / "maps" / "flat.lmap", "--lines", tmp_path / "lines.json",
                          "--prior", ",".join(map(str, fr.prior)), "--dt", fr.dt, "--dyaw", fr.dyaw, *extra)
    assert code == 2 and msg in out.err and "Traceback" not in out.err
    code, out = _localize(capsys, "--map", ROOT / "maps" / "flat.lmap", "--lines", tmp_path / "lines.json",
                          "--prior", ",".join(map(str, fr.prior)), "--dt", fr.dt, "--dyaw", fr.dyaw,
                          "--camera", DATA / "ros_camera_info.yaml")
    assert code == 2 and "pass --height-m" in out.err


def test_camera_json_takes_roll_and_attitude_stds(tmp_path):
    base = dict(width=640, height=480, fx=500.0, fy=500.0, cx=320.0, cy=240.0, height_m=1.0, pitch_deg=2.0)
    p = tmp_path / "camera.json"
    p.write_text(json.dumps(base))
    cam = Camera.load(p)
    assert (cam.roll_deg, cam.pitch_std_deg, cam.roll_std_deg) == (0.0, 0.0, 0.0) and not cam.attitude_free
    assert cam.to_dict() == base  # a file without them writes back as it was
    p.write_text(json.dumps({**base, "roll_deg": 1.5, "pitch_std_deg": 1.0, "roll_std_deg": 2.0}))
    cam = Camera.load(p)
    assert (cam.roll_deg, cam.pitch_std_deg, cam.roll_std_deg) == (1.5, 1.0, 2.0) and cam.attitude_free
    assert Camera.from_dict(cam.to_dict()) == cam
    assert Camera.load(p, roll_deg=-2.0).roll_deg == -2.0
    # The roll turns the camera about its optical axis: a point right of the
    # axis at the camera's height goes down in the picture (right side down).
    level = Camera.from_dict(base | {"pitch_deg": 0.0})
    rolled = Camera.from_dict(base | {"pitch_deg": 0.0, "roll_deg": 5.0})
    uv0, _ = level.project(np.array([5.0, -1.0, 1.0]), 0.0, 0.0, 0.0)
    uv1, _ = rolled.project(np.array([5.0, -1.0, 1.0]), 0.0, 0.0, 0.0)
    assert uv0[1] == pytest.approx(240.0) and uv1[0] > 320.0 and uv1[1] < uv0[1]


@pytest.mark.parametrize("field, value, msg", [
    ("roll_deg", 60.0, r"camera roll_deg must be in \[-45, 45\]"),
    ("roll_deg", "3", "camera roll_deg must be a number"),
    ("pitch_std_deg", -1.0, r"camera pitch_std_deg must be in \[0, 10\]"),
    ("roll_std_deg", 20.0, r"camera roll_std_deg must be in \[0, 10\]"),
    ("roll_std_deg", float("nan"), "camera roll_std_deg must be finite"),
])
def test_bad_attitude_fields_are_one_line_errors(field, value, msg):
    d = dict(width=640, height=480, fx=500.0, fy=500.0, cx=320.0, cy=240.0, height_m=1.0, pitch_deg=0.0)
    with pytest.raises(CameraError, match=msg) as e:
        Camera.from_dict({**d, field: value})
    assert "\n" not in str(e.value)


def test_calibration_files_carry_the_attitude_and_the_command_line_the_roll(tmp_path, capsys):
    text = (DATA / "ros_camera_info.yaml").read_text() + "\nroll_deg: 1.5\npitch_std_deg: 1.0\nroll_std_deg: 2.0\n"
    p = tmp_path / "ros.yaml"
    p.write_text(text)
    cam = Camera.load(p, height_m=1.2)
    assert (cam.roll_deg, cam.pitch_std_deg, cam.roll_std_deg) == (1.5, 1.0, 2.0)
    assert Camera.load(p, height_m=1.2, roll_deg=0.5).roll_deg == 0.5
    from matcher.cli import _camera, build_parser

    args = build_parser().parse_args(["localize", "--map", "m.lmap", "--camera-k", "457,457,320,240",
                                      "--image-size", "640x480", "--height-m", "1.2", "--roll-deg", "2.5",
                                      "--lines", "l.json", "--lost"])
    assert _camera(args, Camera).roll_deg == 2.5
