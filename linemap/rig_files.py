"""Rig files users write or already have, read into a :class:`~linemap.rig.Rig`.

**A rig file** (JSON; the same shape in YAML is read too): a list of
cameras, each a name, a camera (inline, the camera.json fields, or
``camera_file``: a camera.json, an OpenCV calibration or a ROS camera_info
YAML, its path relative to the rig file, read by
:func:`linemap.camera_files.load_camera`) and where it sits on the robot::

    {"cameras": [
      {"name": "front", "camera_file": "front.yaml", "x": 0.20, "y": 0.0, "yaw_deg": 0,
       "height_m": 1.1, "pitch_deg": 5},
      {"name": "back", "camera": {"width": 640, ...}, "x": -0.20, "y": 0.0, "yaw_deg": 180}]}

``x``, ``y`` (metres, forward and left of the robot's centre) and
``yaw_deg`` (relative to the robot's heading, counter-clockwise) are
required; ``height_m``, ``pitch_deg``, ``roll_deg``, ``pitch_std_deg`` and
``roll_std_deg`` override the camera's (a calibration file has no height:
the entry must give it); ``topic`` (optional) names the camera's image topic.

**A Kalibr camchain** (``camchain.yaml``, ``camchain-imucam.yaml``):
``cam0``, ``cam1``, ... each with ``camera_model: pinhole``, ``intrinsics:
[fu, fv, pu, pv]``, ``distortion_model`` (``radtan``: OpenCV's k1 k2 p1 p2;
or ``none``), ``distortion_coeffs``, ``resolution: [w, h]``, and from cam1 on
``T_cn_cnm1``, the 4x4 transform taking points from camera n-1's frame to
camera n's (both OpenCV's: x right, y down, z forward); ``rostopic``
becomes the camera's topic. Kalibr does not know where cam0 is on the
robot: ``first_mount`` gives it (:class:`CameraPlacement`, or a dict of its
fields), else the file at its top level, as either

- ``robot: {x: 0.2, y: 0.0, yaw_deg: 0, height_m: 1.1, pitch_deg: 5, roll_deg: 0}``
  (cam0's placement), or
- ``T_robot_cam0``: the 4x4 transform taking points from cam0's frame to the
  robot's (origin on the floor under the robot's centre, x forward, y left,
  z up).

Each camera's orientation on the robot is split into the project's yaw,
pitch and roll (``world2cam_rotation``); a camera looking more than 89
degrees up or down has no heading to split out, and is refused.

Every bad input is a one-line :class:`~linemap.camera.CameraError` saying
what to fix. Standard library and numpy; the YAML is read by PyYAML
(:mod:`linemap.safe_yaml`, imported when a YAML file is read: OpenCV's
parser refuses the files Kalibr writes).
"""

from __future__ import annotations

import json
import math
import numbers
import re
from contextlib import contextmanager
from dataclasses import dataclass, fields
from pathlib import Path

import numpy as np

from linemap.camera import ATTITUDE_FIELDS, Camera, CameraError, world2cam_rotation
from linemap.camera_files import load_camera, read_text
from linemap.rig import Mount, Rig, RigCamera

#: Fields of a rig file's camera entry that override its camera's.
OVERRIDE_FIELDS = ("height_m", "pitch_deg", *ATTITUDE_FIELDS)
MOUNT_FIELDS = ("x", "y", "yaw_deg")
ENTRY_FIELDS = ("name", "camera", "camera_file", "topic", *MOUNT_FIELDS, *OVERRIDE_FIELDS)
#: How far a transform's rotation may be from a rotation (max |R R^T - I|):
#: Kalibr writes 16 digits; a hand-copied matrix of 6 is still rigid.
RIGID_TOLERANCE = 1e-4
#: A camera looking steeper than this, degrees, up or down, has no heading
#: on the floor (the same bound as a camera file's pitch_deg).
MAX_PITCH_DEG = 89.0
#: Kalibr's pinhole distortion models and the OpenCV coefficients each gives.
_KALIBR_DISTORTIONS = {"radtan": 4, "none": 0}
_CAM_KEY = re.compile(r"cam([0-9]+)$")


@dataclass(frozen=True)
class CameraPlacement:
    """Where one camera is on the robot, in full: ``x``, ``y`` metres forward
    and left of the robot's centre, ``yaw_deg`` relative to its heading
    (the :class:`~linemap.rig.Mount`), ``height_m`` above the floor,
    ``pitch_deg`` (positive looking down) and ``roll_deg`` (the right side
    down) as a :class:`~linemap.camera.Camera` has them."""

    x: float
    y: float
    yaw_deg: float
    height_m: float
    pitch_deg: float = 0.0
    roll_deg: float = 0.0

    def __post_init__(self) -> None:
        for f in fields(self):
            v = getattr(self, f.name)
            if isinstance(v, bool) or not isinstance(v, numbers.Real) or not math.isfinite(v):
                raise CameraError(f"camera placement {f.name} must be a finite number, got {v!r}")

    @classmethod
    def from_dict(cls, d, what: str = "camera placement") -> "CameraPlacement":
        """From a dict of the fields (``pitch_deg``, ``roll_deg`` optional)."""
        if isinstance(d, cls):
            return d
        if not isinstance(d, dict):
            raise CameraError(f"{what} must be a mapping of x, y, yaw_deg, height_m[, pitch_deg, roll_deg]")
        names = [f.name for f in fields(cls)]
        unknown = sorted(set(d) - set(names))
        missing = [k for k in names[:4] if k not in d]
        if unknown or missing:
            raise CameraError(f"{what} " + (f"has unknown fields {unknown}" if unknown else f"lacks {missing}")
                              + f" (fields: {', '.join(names)})")
        return cls(**d)

    def robot_to_camera(self) -> tuple[np.ndarray, np.ndarray]:
        """``(R (3, 3), C (3,))``: the rotation taking robot-frame directions to
        the camera's (rows r, d, f) and the camera centre in the robot frame."""
        R = world2cam_rotation(math.radians(self.yaw_deg), math.radians(self.pitch_deg), math.radians(self.roll_deg))
        return R, np.array([self.x, self.y, self.height_m])


def load_rig(path: str | Path, first_mount: CameraPlacement | dict | None = None) -> Rig:
    """The rig of ``path``: a rig file (JSON or YAML) or a Kalibr camchain,
    whose cam0 is placed on the robot by ``first_mount`` (else by the file's
    ``robot`` or ``T_robot_cam0``)."""
    path = Path(path)
    text = read_text(path, "rig file")
    doc = _parse(text, path)
    if isinstance(doc, dict) and "cameras" in doc:
        if first_mount is not None:
            raise CameraError(f"rig file {path} gives each camera's place on the robot; the first camera's "
                              "placement is for Kalibr camchain files only")
        return _rig_from_entries(doc, path)
    if isinstance(doc, dict) and "cam0" in doc:
        return _rig_from_kalibr(doc, path, first_mount)
    raise CameraError(f"rig file {path} is neither a rig file (a 'cameras' list) nor a Kalibr camchain "
                      "(cam0, cam1, ...)")


def rig_to_dict(rig: Rig) -> dict:
    """The rig file of ``rig`` (cameras inline): :func:`load_rig` reads it
    back into an equal rig."""
    out = []
    for rc in rig:
        entry = {"name": rc.name, "camera": rc.camera.to_dict(), "x": rc.mount.x, "y": rc.mount.y,
                 "yaw_deg": rc.mount.yaw_deg}
        if rc.topic:
            entry["topic"] = rc.topic
        out.append(entry)
    return {"cameras": out}


def camera_placement(R: np.ndarray, C: np.ndarray, what: str = "camera") -> CameraPlacement:
    """The placement of a camera whose rotation robot-to-camera is ``R``
    (3, 3; rows r, d, f) and whose centre is ``C`` (3,) in the robot frame:
    ``R = world2cam_rotation(yaw, pitch, roll)``. CameraError when the
    camera looks more than :data:`MAX_PITCH_DEG` up or down."""
    f = R[2]
    pitch = math.degrees(math.atan2(-f[2], math.hypot(f[0], f[1])))
    if abs(pitch) > MAX_PITCH_DEG:
        raise CameraError(f"{what} looks {abs(pitch):.1f} deg {'down' if pitch > 0 else 'up'}: a camera must "
                          f"look within {MAX_PITCH_DEG:g} deg of the horizon (its heading is undefined beyond); "
                          "check the transforms")
    yaw = math.atan2(f[1], f[0])
    M = R @ world2cam_rotation(yaw, math.radians(pitch)).T  # roll_rotation(roll)
    roll = math.degrees(math.atan2(M[0, 1], M[0, 0]))
    return CameraPlacement(float(C[0]), float(C[1]), math.degrees(yaw), float(C[2]), pitch, roll)


# ---- parsing ---------------------------------------------------------------


def _parse(text: str, path: Path):
    if text.lstrip().startswith(("{", "[")):
        try:
            return json.loads(text)
        except json.JSONDecodeError as exc:
            raise CameraError(f"rig file {path} is not valid JSON ({exc})") from None
        except RecursionError:
            raise CameraError(f"rig file {path} is not valid JSON (nested too deeply)") from None
    from linemap.safe_yaml import YamlError, load  # PyYAML, loaded only for a YAML file

    try:
        return load(text, f"rig file {path}")
    except YamlError as exc:
        raise CameraError(str(exc)) from None


@contextmanager
def _context(prefix: str):
    """CameraErrors raised inside say where: ``prefix: message``."""
    try:
        yield
    except CameraError as exc:
        raise CameraError(f"{prefix}: {exc}") from None


def _number(v, what: str) -> float:
    if isinstance(v, bool) or not isinstance(v, numbers.Real) or not math.isfinite(v):
        raise CameraError(f"{what} must be a finite number, got {v!r}")
    return float(v)


def _numbers(v, n: int, what: str) -> np.ndarray:
    """``v`` as a list of ``n`` finite numbers (n None: any length)."""
    if not isinstance(v, list) or (n is not None and len(v) != n):
        raise CameraError(f"{what} must be a list of {n if n is not None else 'some'} numbers, got {v!r}"[:200])
    return np.array([_number(x, what) for x in v], dtype=float)


# ---- rig files ---------------------------------------------------------------


def _rig_from_entries(doc: dict, path: Path) -> Rig:
    what = f"rig file {path}"
    unknown = sorted(set(doc) - {"cameras"})
    if unknown:
        raise CameraError(f"{what} has unknown top-level fields {unknown} (a rig file holds 'cameras')")
    entries = doc["cameras"]
    if not isinstance(entries, list) or not entries:
        raise CameraError(f"{what}: 'cameras' must be a non-empty list of cameras")
    cameras = tuple(_rig_camera(e, i, path) for i, e in enumerate(entries))
    with _context(what):
        return Rig(cameras)


def _rig_camera(entry, i: int, path: Path) -> RigCamera:
    """Camera ``i`` of a rig file."""
    what = f"rig file {path} camera {i}"
    if not isinstance(entry, dict):
        raise CameraError(f"{what} must be an object with name, camera or camera_file, x, y, yaw_deg")
    name = entry.get("name")
    if not isinstance(name, str) or not name.strip():
        raise CameraError(f"{what} needs a 'name' (a non-empty string)")
    what = f"rig file {path} camera '{name}'"
    unknown = sorted(set(entry) - set(ENTRY_FIELDS))
    if unknown:
        raise CameraError(f"{what} has unknown fields {unknown} (fields: {', '.join(ENTRY_FIELDS)})")
    missing = [k for k in MOUNT_FIELDS if k not in entry]
    if missing:
        raise CameraError(f"{what} lacks {', '.join(missing)} (x, y metres forward and left of the robot's "
                          "centre, yaw_deg its heading relative to the robot's, counter-clockwise)")
    if ("camera" in entry) == ("camera_file" in entry):
        raise CameraError(f"{what} needs one of 'camera' (the camera.json fields) and 'camera_file'")
    topic = entry.get("topic", "")
    if not isinstance(topic, str):
        raise CameraError(f"{what}: topic must be a string, got {topic!r}")
    overrides = {k: entry[k] for k in OVERRIDE_FIELDS if k in entry}
    with _context(what):
        camera = _entry_camera(entry, overrides, path)
        mount = Mount(*(entry[k] for k in MOUNT_FIELDS))
    return RigCamera(name, camera, mount, topic)


def _entry_camera(entry: dict, overrides: dict, path: Path) -> Camera:
    """The camera of a rig file's entry, its overrides applied."""
    if "camera" in entry:
        if not isinstance(entry["camera"], dict):
            raise CameraError("'camera' must be an object with the camera.json fields")
        return Camera.from_dict({**entry["camera"], **overrides})
    name = entry["camera_file"]
    if not isinstance(name, str) or not name:
        raise CameraError(f"camera_file must be a path (relative to the rig file), got {name!r}")
    try:
        camera = load_camera(path.parent / name, overrides.get("height_m"), overrides.get("pitch_deg"),
                             overrides.get("roll_deg"))
    except CameraError as exc:
        if "has no camera height" not in str(exc):
            raise
        raise CameraError(f"{name} is a calibration file without the camera's height: give \"height_m\" "
                          "(metres above the floor) in this entry") from None
    return Camera.from_dict({**camera.to_dict(), **overrides}) if overrides else camera


# ---- Kalibr ------------------------------------------------------------------


def _rig_from_kalibr(doc: dict, path: Path, first_mount) -> Rig:
    what = f"Kalibr camchain {path}"
    keys = {int(m.group(1)): k for k in doc if (m := _CAM_KEY.match(k))}
    if len(keys) != sum(1 for k in doc if _CAM_KEY.match(k)):
        raise CameraError(f"{what} names a camera twice (cam1 and cam01?): cameras must be cam0, cam1, ...")
    indices = sorted(keys)
    if indices != list(range(len(indices))):
        gap = next(i for i in range(len(indices) + 1) if i not in indices)
        raise CameraError(f"{what} has no cam{gap}: cameras must be cam0, cam1, ... without a gap")
    first = _first_placement(doc, what, first_mount)
    R, C = first.robot_to_camera()
    T = np.eye(4)  # the transform robot -> camera n
    T[:3, :3], T[:3, 3] = R, -R @ C
    cameras = []
    for n in indices:
        name = keys[n]
        entry = doc[name]
        with _context(f"{what} {name}"):
            if not isinstance(entry, dict):
                raise CameraError("must be a mapping of camera_model, intrinsics, distortion_model, ...")
            if n:
                if "T_cn_cnm1" not in entry:
                    raise CameraError(f"lacks T_cn_cnm1 (the 4x4 transform from cam{n - 1}'s frame to its own)")
                T = _rigid(entry["T_cn_cnm1"], "T_cn_cnm1") @ T
            # cam0 keeps its placement as given (a camera at the robot's centre stays exactly there).
            placement = camera_placement(T[:3, :3], -T[:3, :3].T @ T[:3, 3], "the camera") if n else first
            camera = _kalibr_camera(entry, placement)
            topic = entry.get("rostopic", "")
            if not isinstance(topic, str):
                raise CameraError(f"rostopic must be a string, got {topic!r}")
            cameras.append(RigCamera(name, camera, Mount(placement.x, placement.y, placement.yaw_deg), topic))
    return Rig(tuple(cameras))


def _first_placement(doc: dict, what: str, first_mount) -> CameraPlacement:
    """cam0's placement on the robot: ``first_mount``, else the file's
    ``robot`` or ``T_robot_cam0``."""
    if first_mount is not None:
        return CameraPlacement.from_dict(first_mount, "the first camera's placement")
    if "robot" in doc and "T_robot_cam0" in doc:
        raise CameraError(f"{what} gives both robot and T_robot_cam0: keep one")
    if "robot" in doc:
        with _context(what):
            return CameraPlacement.from_dict(doc["robot"], "robot (cam0's placement)")
    if "T_robot_cam0" in doc:
        with _context(what):
            T = _rigid(doc["T_robot_cam0"], "T_robot_cam0")
            R = T[:3, :3].T
            return camera_placement(R, T[:3, 3], "cam0")
    raise CameraError(f"{what} does not say where cam0 is on the robot: give the first camera's placement "
                      "(x, y, yaw_deg, height_m, pitch_deg, roll_deg), or add 'robot: {x: .., y: .., yaw_deg: .., "
                      "height_m: .., pitch_deg: .., roll_deg: ..}' or T_robot_cam0 to the file")


def _rigid(v, what: str) -> np.ndarray:
    """A 4x4 rigid transform (rotation and translation) from nested lists."""
    if not isinstance(v, list) or len(v) != 4 or not all(isinstance(r, list) and len(r) == 4 for r in v):
        raise CameraError(f"{what} must be a 4x4 matrix (four rows of four numbers)")
    T = np.array([[_number(x, what) for x in row] for row in v])
    R = T[:3, :3]
    err = max(float(np.abs(R @ R.T - np.eye(3)).max()), float(np.abs(T[3] - [0.0, 0.0, 0.0, 1.0]).max()))
    if err > RIGID_TOLERANCE or np.linalg.det(R) < 0:
        raise CameraError(f"{what} is not a rigid transform (a rotation and a translation, last row 0 0 0 1): "
                          + ("its rotation is a reflection" if np.linalg.det(R) < 0 else f"off by {err:.2g}"))
    U, _, Vt = np.linalg.svd(R)  # the nearest rotation: the decomposition assumes one
    T[:3, :3] = U @ Vt
    return T


def _kalibr_camera(entry: dict, placement: CameraPlacement) -> Camera:
    """The pinhole camera of a Kalibr camchain entry at ``placement``."""
    model = entry.get("camera_model")
    if model != "pinhole":
        raise CameraError(f"camera_model {model!r} is not supported (pinhole is, with distortion_model radtan "
                          "or none)")
    dmodel = entry.get("distortion_model", "none")
    if dmodel not in _KALIBR_DISTORTIONS:
        raise CameraError(f"distortion_model {dmodel!r} is not supported (radtan and none are); calibrate with "
                          "the pinhole-radtan model")
    for k in ("intrinsics", "resolution"):
        if k not in entry:
            raise CameraError(f"lacks {k}")
    fu, fv, pu, pv = _numbers(entry["intrinsics"], 4, "intrinsics ([fu, fv, pu, pv])")
    w, h = _numbers(entry["resolution"], 2, "resolution ([width, height])")
    n = _KALIBR_DISTORTIONS[dmodel]
    dist = _numbers(entry.get("distortion_coeffs", [0.0] * n), n, f"distortion_coeffs of {dmodel}")
    return Camera.from_dict({"width": w, "height": h, "fx": fu, "fy": fv, "cx": pu, "cy": pv,
                             "height_m": placement.height_m, "pitch_deg": placement.pitch_deg,
                             "roll_deg": placement.roll_deg, "distortion": list(dist) if dist.any() else []})


__all__ = ["CameraPlacement", "camera_placement", "load_rig", "rig_to_dict"]
