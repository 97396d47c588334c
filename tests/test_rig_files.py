"""Rig files (linemap/rig_files.py): a rig JSON, a Kalibr camchain and a
list of ROS camera_info files read into the same rig; the YAML Kalibr's
files are written in, read by PyYAML bounded (linemap/safe_yaml.py); every
bad input one line that says what to fix."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

import matcher
from linemap.camera import Camera, CameraError, world2cam_rotation
from linemap.rig import Mount, Rig, RigCamera
from linemap.rig_files import CameraPlacement, camera_placement, load_rig, rig_to_dict
from linemap.safe_yaml import YamlError
from linemap.safe_yaml import load as load_yaml
from mapkit_harness.rigs import ring_rig

DATA = Path(__file__).parent / "data" / "cameras"

#: A 4-camera rig whose cameras differ in everything: intrinsics,
#: distortion, mount, height, pitch and roll.
PLACES = [  # name, x, y, yaw_deg, height_m, pitch_deg, roll_deg
    ("front", 0.25, 0.02, 0.0, 1.10, 5.0, 0.0),
    ("left", 0.05, 0.18, 88.0, 1.15, -3.0, 2.5),
    ("back", -0.22, -0.01, 179.0, 0.95, 12.0, -4.0),
    ("right", 0.04, -0.19, -91.5, 1.30, 0.5, 30.0),
]
INTRINSICS = [
    dict(width=640, height=480, fx=457.0, fy=456.5, cx=321.0, cy=239.5, distortion=(-0.28, 0.07, 0.0005, -0.0003)),
    dict(width=752, height=480, fx=458.6, fy=457.3, cx=367.2, cy=248.4, distortion=(-0.2834, 0.0739, 0.0002, 1.7e-5)),
    dict(width=640, height=400, fx=300.0, fy=300.0, cx=320.0, cy=200.0, distortion=()),
    dict(width=1280, height=720, fx=910.0, fy=909.0, cx=640.5, cy=360.5, distortion=(0.01, -0.02, 0.0, 0.0)),
]


def _rig(places=PLACES) -> Rig:
    cams = []
    for (name, x, y, yaw, h, pitch, roll), intr in zip(places, INTRINSICS):
        cam = Camera(**{k: v for k, v in intr.items() if k != "distortion"}, height_m=h, pitch_deg=pitch,
                     roll_deg=roll, distortion=intr["distortion"])
        cams.append(RigCamera(name, cam, Mount(x, y, yaw)))
    return Rig(tuple(cams))


def _robot_to_camera(rc: RigCamera) -> np.ndarray:
    """4x4 transform taking robot-frame points to the camera's frame,
    computed here from the conventions (not with the reader's code)."""
    R = world2cam_rotation(math.radians(rc.mount.yaw_deg), math.radians(rc.camera.pitch_deg),
                           math.radians(rc.camera.roll_deg))
    C = np.array([rc.mount.x, rc.mount.y, rc.camera.height_m])
    T = np.eye(4)
    T[:3, :3], T[:3, 3] = R, -R @ C
    return T


def _yaml_list(v, flow: bool, indent: str) -> str:
    """PyYAML's two styles: flow leaves (PyYAML < 5.1) or all block (>= 5.1)."""
    if flow:
        return "[" + ", ".join(repr(x) if not isinstance(x, list) else _yaml_list(x, True, "") for x in v) + "]"
    out = []
    for x in v:
        if isinstance(x, list):  # "- - a" then "  - b"
            items = [repr(float(y)) for y in x]
            out.append(f"{indent}- - {items[0]}\n" + "".join(f"{indent}  - {y}\n" for y in items[1:]))
        else:
            out.append(f"{indent}- {x!r}\n")
    return "".join(out)


def _camchain(rig: Rig, flow: bool = True, extra: str = "", cam0_extra: dict | None = None) -> str:
    """The Kalibr camchain.yaml of ``rig``, written as Kalibr writes it
    (top-level lists not indented under their key)."""
    text = ""
    for n, rc in enumerate(rig):
        c = rc.camera
        fields = {"camera_model": "pinhole", "distortion_model": "radtan",
                  "distortion_coeffs": list(c.distortion) or [0.0, 0.0, 0.0, 0.0],
                  "intrinsics": [c.fx, c.fy, c.cx, c.cy], "resolution": [c.width, c.height]}
        if n:
            T = _robot_to_camera(rc) @ np.linalg.inv(_robot_to_camera(rig[n - 1]))
            fields["T_cn_cnm1"] = T.tolist()
        fields.update((cam0_extra or {}) if n == 0 else {})
        text += f"cam{n}:\n"
        for k, v in sorted(fields.items()):
            if isinstance(v, list):
                body = _yaml_list(v, flow and k != "T_cn_cnm1", "  ")
                text += f"  {k}: {body}\n" if flow and k != "T_cn_cnm1" else f"  {k}:\n{body}"
            else:
                text += f"  {k}: {v}\n"
        text += f"  rostopic: /{rc.name}/image_raw\n"
        if flow and n:  # T as "- [a, b, c, d]" rows, the older PyYAML's way
            text = text.replace(_yaml_list(fields["T_cn_cnm1"], False, "  "),
                                "".join(f"  - {_yaml_list(row, True, '')}\n" for row in fields["T_cn_cnm1"]))
    return text + extra


def _placement_yaml(rc: RigCamera) -> str:
    return (f"robot:\n  x: {rc.mount.x!r}\n  y: {rc.mount.y!r}\n  yaw_deg: {rc.mount.yaw_deg!r}\n"
            f"  height_m: {rc.camera.height_m!r}\n  pitch_deg: {rc.camera.pitch_deg!r}\n"
            f"  roll_deg: {rc.camera.roll_deg!r}\n")


def _assert_same_rig(got: Rig, want: Rig, angle_tol: float = 1e-6) -> None:
    assert len(got) == len(want)
    for g, w in zip(got, want):
        for k in ("width", "height", "fx", "fy", "cx", "cy"):
            assert getattr(g.camera, k) == pytest.approx(getattr(w.camera, k), abs=1e-9), (g.name, k)
        assert np.allclose(g.camera.distortion, w.camera.distortion, atol=1e-12, rtol=0), g.name
        assert g.mount.x == pytest.approx(w.mount.x, abs=1e-9) and g.mount.y == pytest.approx(w.mount.y, abs=1e-9)
        assert g.camera.height_m == pytest.approx(w.camera.height_m, abs=1e-9), g.name
        dyaw = (g.mount.yaw_deg - w.mount.yaw_deg + 180.0) % 360.0 - 180.0
        assert abs(dyaw) < angle_tol, (g.name, g.mount.yaw_deg, w.mount.yaw_deg)
        assert g.camera.pitch_deg == pytest.approx(w.camera.pitch_deg, abs=angle_tol), g.name
        assert g.camera.roll_deg == pytest.approx(w.camera.roll_deg, abs=angle_tol), g.name


def _write(tmp_path, name: str, text: str) -> Path:
    p = tmp_path / name
    p.write_text(text)
    return p


# ---- the same rig from every kind of file ------------------------------------


def test_rig_json_reads_back_the_rig(tmp_path):
    rig = _rig()
    got = load_rig(_write(tmp_path, "rig.json", json.dumps(rig_to_dict(rig))))
    assert got == rig  # exactly: every field, every number


@pytest.mark.parametrize("flow", [True, False], ids=["pyyaml-flow-leaves", "pyyaml-block"])
def test_kalibr_camchain_is_the_same_rig_as_the_rig_json(tmp_path, flow):
    rig = _rig()
    from_json = load_rig(_write(tmp_path, "rig.json", json.dumps(rig_to_dict(rig))))
    first = rig[0]
    placement = dict(x=first.mount.x, y=first.mount.y, yaw_deg=first.mount.yaw_deg, height_m=first.camera.height_m,
                     pitch_deg=first.camera.pitch_deg, roll_deg=first.camera.roll_deg)
    chain = _write(tmp_path, "camchain.yaml", _camchain(rig, flow))
    from_kalibr = load_rig(chain, first_mount=placement)
    _assert_same_rig(from_kalibr, from_json)
    assert from_kalibr.names == ["cam0", "cam1", "cam2", "cam3"]
    assert [rc.topic for rc in from_kalibr] == [f"/{n}/image_raw" for n in from_json.names]
    # cam0 keeps its placement exactly; the same placement from a dataclass or from the file
    assert from_kalibr[0].mount == first.mount and from_kalibr[0].camera == first.camera
    assert load_rig(chain, CameraPlacement(**placement)) == from_kalibr
    in_file = _write(tmp_path, "camchain_robot.yaml", _camchain(rig, flow, extra=_placement_yaml(first)))
    assert load_rig(in_file) == from_kalibr


def test_kalibr_first_camera_from_t_robot_cam0(tmp_path):
    rig = _rig()
    T = np.linalg.inv(_robot_to_camera(rig[0]))  # cam0 -> robot
    extra = "T_robot_cam0:\n" + "".join(f"- {json.dumps(row)}\n" for row in T.tolist())
    got = load_rig(_write(tmp_path, "camchain.yaml", _camchain(rig, extra=extra)))
    _assert_same_rig(got, rig)


def test_ring_rig_through_kalibr_and_poses_round_trip(tmp_path):
    """A 4-camera ring: the camchain gives its mounts; each camera's pose of
    a robot pose, and the robot pose back from each camera's."""
    rig = ring_rig(4, hfov_deg=80.0, height_m=1.0, pitch_deg=4.0, radius_m=0.15)
    rc0 = rig[0]
    got = load_rig(_write(tmp_path, "camchain.yaml", _camchain(rig)),
                   dict(x=rc0.mount.x, y=rc0.mount.y, yaw_deg=0.0, height_m=1.0, pitch_deg=4.0))
    _assert_same_rig(got, rig)
    robot = np.array([[2.0, -1.0, 0.3], [0.5, 4.0, -2.9]])
    for g, w in zip(got, rig):
        cams = g.mount.camera_poses(robot)
        assert np.allclose(cams, w.mount.camera_poses(robot), atol=1e-9)
        assert np.allclose(g.mount.robot_poses(cams), robot, atol=1e-12)
        # the camera sits radius_m from the robot's centre, heading outwards
        assert np.allclose(np.hypot(*(cams[:, :2] - robot[:, :2]).T), 0.15)
        outwards = np.arctan2(cams[:, 1] - robot[:, 1], cams[:, 0] - robot[:, 0])
        assert np.allclose(np.angle(np.exp(1j * (outwards - cams[:, 2]))), 0.0, atol=1e-9)


def test_a_single_camera_camchain_at_the_centre_is_the_one_camera_rig(tmp_path):
    cam = Camera.from_fov(70.0, 640, 480, 1.2, 0.0)
    text = (f"cam0:\n  camera_model: pinhole\n  intrinsics: [{cam.fx!r}, {cam.fy!r}, 320.0, 240.0]\n"
            "  distortion_model: none\n  resolution: [640, 480]\n")
    got = load_rig(_write(tmp_path, "camchain.yaml", text), dict(x=0, y=0, yaw_deg=0, height_m=1.2))
    assert got == Rig.single(cam) and got.is_single


def test_camera_info_files_listed_in_a_rig_json(tmp_path):
    """Two ROS camera_info files (the same calibration) with their poses; the
    rig entry gives the height a calibration file lacks, and overrides."""
    for name in ("front.yaml", "back.yaml"):
        (tmp_path / "calib").mkdir(exist_ok=True)
        (tmp_path / "calib" / name).write_text((DATA / "ros_camera_info.yaml").read_text())
    doc = {"cameras": [
        {"name": "front", "camera_file": "calib/front.yaml", "x": 0.2, "y": 0.0, "yaw_deg": 0.0, "height_m": 1.1,
         "pitch_deg": 3.0, "topic": "/front/image_raw"},
        {"name": "back", "camera_file": "calib/back.yaml", "x": -0.2, "y": 0.0, "yaw_deg": 180.0, "height_m": 0.9,
         "roll_deg": 1.5, "pitch_std_deg": 1.0}]}
    rig = load_rig(_write(tmp_path, "rig.json", json.dumps(doc)))
    want = Camera.load(DATA / "ros_camera_info.yaml", height_m=1.1, pitch_deg=3.0)
    assert rig[0].camera == want and rig[0].topic == "/front/image_raw"
    assert rig[0].mount == Mount(0.2, 0.0, 0.0)
    back = rig[1].camera
    assert (back.fx, back.height_m, back.pitch_deg, back.roll_deg, back.pitch_std_deg) == (want.fx, 0.9, 0.0, 1.5, 1.0)
    assert rig[1].mount.yaw_deg == 180.0 and not rig.is_single
    # the same rig as YAML, and its cameras inline
    yaml_text = "cameras:\n" + "".join(
        "- " + "\n  ".join(f"{k}: {json.dumps(v)}" for k, v in e.items()) + "\n" for e in doc["cameras"])
    assert load_rig(_write(tmp_path, "rig.yaml", yaml_text)) == rig
    assert load_rig(_write(tmp_path, "inline.json", json.dumps(rig_to_dict(rig)))) == rig


def test_camera_placement_splits_any_orientation_into_yaw_pitch_roll():
    rng = np.random.default_rng(3)
    for _ in range(200):
        yaw, pitch, roll = rng.uniform(-180, 180), rng.uniform(-88, 88), rng.uniform(-45, 45)
        R = world2cam_rotation(math.radians(yaw), math.radians(pitch), math.radians(roll))
        p = camera_placement(R, np.array([1.0, 2.0, 1.5]))
        assert (p.yaw_deg - yaw + 180) % 360 - 180 == pytest.approx(0.0, abs=1e-9)
        assert (p.pitch_deg, p.roll_deg) == pytest.approx((pitch, roll), abs=1e-9)
    with pytest.raises(CameraError, match=r"looks 90.0 deg down: a camera must look within 89 deg"):
        camera_placement(world2cam_rotation(0.3, math.radians(89.99)), np.zeros(3), "cam2")


# ---- every bad input is one line -------------------------------------------


def _one_line_error(path, match, first_mount=None):
    with pytest.raises(CameraError, match=match) as info:
        load_rig(path, first_mount)
    assert "\n" not in str(info.value)
    assert isinstance(info.value, matcher.InputError)


def _entry(**kw):
    e = {"name": "front", "camera": Camera.from_fov(70, 640, 480, 1.2, 0.0).to_dict(), "x": 0.0, "y": 0.0,
         "yaw_deg": 0.0}
    e.update(kw)
    return {k: v for k, v in e.items() if v is not None}


@pytest.mark.parametrize("doc,match", [
    ("{\"cameras\": [", r"is not valid JSON"),
    ("[1, 2]", r"neither a rig file \(a 'cameras' list\) nor a Kalibr camchain"),
    ({"cameras": []}, r"'cameras' must be a non-empty list"),
    ({"cameras": [_entry()], "camera": 1}, r"unknown top-level fields \['camera'\]"),
    ({"cameras": [_entry(), _entry()]}, r"rig camera names must differ"),
    ({"cameras": [_entry(name="")]}, r"camera 0 needs a 'name'"),
    ({"cameras": [_entry(yaw_deg=None)]}, r"camera 'front' lacks yaw_deg \(x, y metres forward"),
    ({"cameras": [_entry(yaw=3.0)]}, r"camera 'front' has unknown fields \['yaw'\]"),
    ({"cameras": [_entry(x="0.2")]}, r"camera 'front': camera mount x must be a finite number"),
    ({"cameras": [_entry(camera_file="front.yaml")]}, r"needs one of 'camera' .* and 'camera_file'"),
    ({"cameras": [_entry(camera=None, camera_file="missing.yaml")]}, r"camera 'front': camera file .* not found"),
    ({"cameras": [_entry(camera=None, camera_file="calib.yaml")]},
     r"calib.yaml is a calibration file without the camera's height: give \"height_m\""),
    ({"cameras": [_entry(height_m=-1.0)]}, r"camera 'front': camera height_m must be above the floor"),
    ({"cameras": [_entry(camera={"width": 640})]}, r"camera 'front': camera description lacks height"),
])
def test_bad_rig_files_are_one_line_errors(tmp_path, doc, match):
    (tmp_path / "calib.yaml").write_text((DATA / "ros_camera_info.yaml").read_text())
    _one_line_error(_write(tmp_path, "rig.json", doc if isinstance(doc, str) else json.dumps(doc)), match)


def test_missing_and_unreadable_rig_files(tmp_path):
    _one_line_error(tmp_path / "nope.json", r"rig file .*nope.json not found")
    _one_line_error(tmp_path, r"is a directory")
    _one_line_error(_write(tmp_path, "rig.json", json.dumps({"cameras": [_entry()]})),
                    r"placement is for Kalibr camchain files only", dict(x=0, y=0, yaw_deg=0, height_m=1))


KALIBR_OK = "cam0:\n  camera_model: pinhole\n  intrinsics: [400, 400, 320, 240]\n  resolution: [640, 480]\n"
PLACE = dict(x=0.0, y=0.0, yaw_deg=0.0, height_m=1.2)
T_OK = "  T_cn_cnm1:\n  - [0, 0, -1, 0]\n  - [0, 1, 0, 0]\n  - [1, 0, 0, 0]\n  - [0, 0, 0, 1]\n"


@pytest.mark.parametrize("text,first,match", [
    (KALIBR_OK, None, r"does not say where cam0 is on the robot: give the first camera's placement"),
    (KALIBR_OK + "robot: {x: 0}\n", None, r"robot \(cam0's placement\) lacks \['y', 'yaw_deg', 'height_m'\]"),
    (KALIBR_OK + "robot:\n  x: 0\n", None, r"robot \(cam0's placement\) lacks \['y', 'yaw_deg', 'height_m'\]"),
    (KALIBR_OK + "robot:\n  x: 0\n  y: 0\n  yaw_deg: 0\n  height_m: .nan\n", None,
     r"camchain .*: camera placement height_m must be a finite number, got nan"),
    (KALIBR_OK, dict(PLACE, z=1.0), r"has unknown fields \['z'\]"),
    (KALIBR_OK, dict(PLACE, height_m="1.2"), r"height_m must be a finite number"),
    (KALIBR_OK + KALIBR_OK.replace("cam0", "cam2"), PLACE, r"has no cam1: cameras must be cam0, cam1, \.\.\."),
    (KALIBR_OK + KALIBR_OK.replace("cam0", "cam1"), PLACE, r"cam1: lacks T_cn_cnm1"),
    (KALIBR_OK + KALIBR_OK.replace("cam0", "cam00"), PLACE, r"names a camera twice"),
    (KALIBR_OK.replace("pinhole", "omni"), PLACE, r"cam0: camera_model 'omni' is not supported \(pinhole is"),
    (KALIBR_OK + "  distortion_model: equidistant\n", PLACE,
     r"cam0: distortion_model 'equidistant' is not supported \(radtan and none are\)"),
    (KALIBR_OK + "  distortion_model: radtan\n  distortion_coeffs: [0.1, 0.2]\n", PLACE,
     r"distortion_coeffs of radtan must be a list of 4 numbers"),
    (KALIBR_OK.replace("[400, 400, 320, 240]", "[400, 320, 240]"), PLACE, r"intrinsics \(\[fu, fv, pu, pv\]\) must"),
    (KALIBR_OK.replace("  resolution: [640, 480]\n", ""), PLACE, r"cam0: lacks resolution"),
    (KALIBR_OK + KALIBR_OK.replace("cam0", "cam1") + T_OK.replace("[1, 0, 0, 0]", "[1, 0, 0.1, 0]"), PLACE,
     r"cam1: T_cn_cnm1 is not a rigid transform .*: off by 0.1"),
    (KALIBR_OK + KALIBR_OK.replace("cam0", "cam1") + T_OK.replace("[0, 1, 0, 0]", "[0, -1, 0, 0]"), PLACE,
     r"T_cn_cnm1 is not a rigid transform .*: its rotation is a reflection"),
    (KALIBR_OK + KALIBR_OK.replace("cam0", "cam1") + T_OK.replace("- [0, 0, 0, 1]", "- [0, 0, 1]"), PLACE,
     r"T_cn_cnm1 must be a 4x4 matrix"),
    # cam1 looks straight down: T turns cam0's forward into cam1's down
    (KALIBR_OK + KALIBR_OK.replace("cam0", "cam1")
     + "  T_cn_cnm1:\n  - [1, 0, 0, 0]\n  - [0, 0, 1, 0]\n  - [0, -1, 0, 0]\n  - [0, 0, 0, 1]\n", PLACE,
     r"cam1: the camera looks 90.0 deg (down|up): a camera must look within 89 deg of the horizon"),
    # cam1 turned about its optical axis by 90 degrees: beyond a camera's roll
    (KALIBR_OK + KALIBR_OK.replace("cam0", "cam1")
     + "  T_cn_cnm1:\n  - [0, 1, 0, 0]\n  - [-1, 0, 0, 0]\n  - [0, 0, 1, 0]\n  - [0, 0, 0, 1]\n", PLACE,
     r"cam1: camera roll_deg must be in \[-45, 45\]"),
    ("cam0:\n\tcamera_model: pinhole\n", PLACE, r"line 2: not valid YAML \(.*found character '\\t'"),
    ("cam0:\n  a: 1\n  a: 2\n", PLACE, r"line 3 repeats the key 'a'"),
    ("cam0: [1, 2\n", PLACE, r"line 2: not valid YAML \(while parsing a flow sequence expected ',' or '\]'"),
    ("cam0: 3\n", PLACE, r"cam0: must be a mapping"),
    ("a: " + "[" * 100 + "]" * 100, PLACE, r"nested deeper than 32 levels"),
    ("image_width: 640\n", PLACE, r"neither a rig file .* nor a Kalibr camchain"),
])
def test_bad_kalibr_files_are_one_line_errors(tmp_path, text, first, match):
    _one_line_error(_write(tmp_path, "camchain.yaml", text), match, first)


def test_kalibr_rig_in_the_file_and_given_twice(tmp_path):
    rig = _rig()
    both = _camchain(rig, extra=_placement_yaml(rig[0]) + "T_robot_cam0:\n" + "- [1, 0, 0, 0]\n" * 4)
    _one_line_error(_write(tmp_path, "camchain.yaml", both), r"gives both robot and T_robot_cam0: keep one")
    # the argument wins over the file's (as a command line's --height-m over a camera.json's)
    inside = _write(tmp_path, "inside.yaml", _camchain(rig, extra=_placement_yaml(rig[0])))
    moved = load_rig(inside, dict(x=0.0, y=0.0, yaw_deg=0.0, height_m=2.0))
    assert moved[0].camera.height_m == 2.0 and moved[0].mount.at_centre


# ---- the YAML reader (PyYAML, bounded) -------------------------------------------


def test_yaml_reads_what_pyyaml_writes():
    text = ("%YAML 1.1\n---\n# a comment\n'quoted key': \"a # b\"  # comment\nlist:\n- - 1\n  - 2.5e-3\n"
            "- [3, [4, .nan],\n   -5]\n- k: v\n  k2: ~\nempty: []\nflag: true\nnothing:\nneg: -.inf\n"
            "nested:\n    deeper:\n        - /cam0/image_raw\nprintf: 1e-05\n")
    doc = load_yaml(text)
    assert math.isnan(doc["list"][1][1][1])
    doc["list"][1][1][1] = 0.0
    assert doc == {"quoted key": "a # b", "list": [[1, 0.0025], [3, [4, 0.0], -5], {"k": "v", "k2": None}],
                   "empty": [], "flag": True, "nothing": None, "neg": -math.inf,
                   "nested": {"deeper": ["/cam0/image_raw"]}, "printf": 1e-05}
    # What PyYAML's dump writes reads back as it was (Kalibr writes with it).
    import yaml

    chain = {"cam0": {"T_cn_cnm1": [[1.0, 0.0, 0.0, 0.1], [0.0, 1.0, 0.0, 0.0]], "intrinsics": [458.654, 457.296],
                      "distortion_coeffs": [-0.28340811, 0.07395907, 0.00019359, 1.76187114e-05],
                      "rostopic": "/cam0/image_raw", "resolution": [752, 480]}}
    assert load_yaml(yaml.dump(chain)) == chain
    assert load_yaml(yaml.dump(chain, default_flow_style=None)) == chain


#: Eight levels of aliases, each naming the one before nine times: 9^8 (43
#: million) strings from 10 lines, were the aliases expanded.
ALIAS_BOMB = "a: &a [lol, lol, lol, lol, lol, lol, lol, lol, lol]\n" + "".join(
    f"{n}: &{n} [{', '.join(['*' + p] * 9)}]\n" for p, n in zip("abcdefgh", "bcdefghi"))


@pytest.mark.parametrize("text,match", [
    ("", r"f.yaml is empty"),
    ("a: 1\n  b: 2\n", r"f.yaml line 2: not valid YAML \(mapping values are not allowed here\)"),
    ("a: 1\n- 2\n", r"f.yaml line 2: not valid YAML"),
    ("a: &x 1\n", r"f.yaml line 1 uses an anchor or alias"),
    ("a: 1\nb: *x\n", r"f.yaml line 2 uses an anchor or alias"),
    (ALIAS_BOMB, r"f.yaml line 1 uses an anchor or alias"),
    ("a: !!python/object:os.system {}\n", r"f.yaml line 1: not valid YAML \(could not determine a constructor"),
    ("a: [1, 2] x\n", r"f.yaml line 1: not valid YAML"),
    ("a: 'open\n", r"f.yaml line 2: not valid YAML \(while scanning a quoted scalar"),
    ("a: 1\na: 2\n", r"f.yaml line 2 repeats the key 'a'"),
    ("a: " + "[" * 40 + "]" * 40, r"f.yaml line 1 is nested deeper than 32 levels"),
    ("a: " + "[" * 100000 + "]" * 100000, r"f.yaml line 1 is nested deeper than 32 levels"),
    ("a: 1 # " + "x" * (1 << 20), r"f.yaml is larger than 1048576 characters"),
    ("a: \x07\n", r"f.yaml: not valid YAML \(.*special characters are not allowed"),
])
def test_yaml_refuses_what_a_calibration_file_never_holds(text, match):
    with pytest.raises(YamlError, match=match) as e:
        load_yaml(text, "f.yaml")
    assert "\n" not in str(e.value) and isinstance(e.value, matcher.InputError)


def test_the_rig_file_example_of_docs_inputs_reads(tmp_path):
    """docs/inputs.md's rig file, with its two camera_info files, and its
    Kalibr 'robot' entry say what the reader reads."""
    import textwrap

    doc = (Path(__file__).resolve().parents[1] / "docs" / "inputs.md").read_text()
    start = doc.index('    {"cameras": [')
    block = textwrap.dedent(doc[start:doc.index("\n\n", start)])
    for name in ("front.yaml", "left.yaml"):
        (tmp_path / name).write_text((DATA / "ros_camera_info.yaml").read_text())
    rig = load_rig(_write(tmp_path, "rig.json", block))
    assert rig.names == ["front", "left", "back"] and rig[0].topic == "/front/image_raw"
    assert [rc.mount.yaw_deg for rc in rig] == [0, 90, 180] and rig[2].camera.height_m == 0.95
    start = doc.index("    robot:\n")
    robot = textwrap.dedent(doc[start:doc.index("\n\n", start)]) + "\n"
    got = load_rig(_write(tmp_path, "camchain.yaml", KALIBR_OK + robot))
    assert got[0].mount == Mount(0.2, 0.0, 0.0) and got[0].camera.pitch_deg == 5


@pytest.mark.parametrize("kind", [pytest.param("camchain-lines", marks=pytest.mark.slow), "camchain-bytes", "rig-json"])
def test_damaged_rig_files_are_a_rig_or_one_line_error(tmp_path, kind):
    """Seeded damage (the fuzz families' mutations) to a Kalibr camchain, in
    both PyYAML styles, and to a rig JSON: each reads into a rig or ends in
    one CameraError line, never another exception."""
    import random

    from mapkit_harness.fuzz.mutations import mutate_bytes, mutate_json_doc, mutate_lines

    rig = _rig()
    chains = [_camchain(rig, flow, extra=_placement_yaml(rig[0])) for flow in (True, False)]
    doc = rig_to_dict(rig)
    outcomes = {"rig": 0, "error": 0}
    for i in range(150):
        rng = random.Random(i)
        if kind == "camchain-lines":
            blob = mutate_lines(chains[i % 2], rng)[0].encode()
        elif kind == "camchain-bytes":
            blob = mutate_bytes(chains[i % 2].encode(), rng)[0]
        else:
            blob = mutate_json_doc(doc, rng)[0].encode()
        path = tmp_path / f"case{i}"
        path.write_bytes(blob)
        try:
            assert isinstance(load_rig(path), Rig)
            outcomes["rig"] += 1
        except CameraError as exc:
            assert "\n" not in str(exc), str(exc)
            outcomes["error"] += 1
    assert outcomes["error"] >= 20 and outcomes["rig"] >= 1, outcomes  # the damage reaches both ends
