"""Camera files users already have, read into a :class:`~linemap.camera.Camera`.

- our ``camera.json`` (docs/architecture.md);
- OpenCV's calibration files, as ``cv::FileStorage`` writes them (YAML, XML
  or JSON; ``camera_matrix`` / ``cameraMatrix`` / ``K``, ``distortion_coefficients``
  / ``dist_coeffs`` / ``distCoeffs`` / ``D``, ``image_width`` and ``image_height``
  or ``image_size``);
- ROS ``camera_info`` YAML, as ``camera_calibration_parsers`` writes it
  (``image_width``, ``image_height``, ``camera_matrix: {rows, cols, data}``,
  ``distortion_model``, ``distortion_coefficients``).

The camera's height above the floor and its pitch are in none of the
calibration files: they come from the caller (``height_m``, ``pitch_deg``;
the command lines' ``--height-m`` and ``--pitch-deg``), which may also
override those of a camera.json; so does the roll (``roll_deg``,
``--roll-deg``). A calibration file that carries ``height_m``,
``pitch_deg``, ``roll_deg``, ``pitch_std_deg`` or ``roll_std_deg`` as
numbers at its top level gives them too. Whatever is missing or wrong is a one-line
:class:`~linemap.camera.CameraError` saying what to give. OpenCV (already a
dependency of the matcher) parses the calibration formats; it is imported
only for them.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np

from linemap.camera import ATTITUDE_FIELDS, REQUIRED_FIELDS, Camera, CameraError

#: Names the camera matrix and the distortion coefficients go by in OpenCV's
#: samples and in ROS files, in the order they are looked for.
_K_NAMES = ("camera_matrix", "cameraMatrix", "K", "intrinsic_matrix", "intrinsics")
_D_NAMES = ("distortion_coefficients", "dist_coeffs", "distCoeffs", "distortion_coeffs", "D")
#: A calibration file is a few kilobytes and a few levels deep; larger or
#: deeper text is not one (and OpenCV's parsers are not made for it).
_MAX_CALIBRATION_CHARS = 1 << 20
_MAX_CALIBRATION_DEPTH = 32
#: ROS distortion models the pinhole model with OpenCV's coefficients covers.
_PINHOLE_MODELS = ("", "plumb_bob", "rational_polynomial")


def load_camera(path: str | Path, height_m: float | None = None, pitch_deg: float | None = None,
                roll_deg: float | None = None) -> Camera:
    """The camera of ``path`` (any of the formats above), its height, pitch
    and roll from ``height_m``, ``pitch_deg`` and ``roll_deg`` when given
    (else from the file: a camera.json has them, calibration files do not)."""
    path = Path(path)
    text = read_text(path, "camera file")
    ours = _our_json(text, path)
    if ours is not None:
        d = dict(ours)
        if height_m is not None:
            d["height_m"] = height_m
        if pitch_deg is not None:
            d["pitch_deg"] = pitch_deg
        if roll_deg is not None:
            d["roll_deg"] = roll_deg
        return Camera.from_dict(d)
    return _from_calibration(path, text, height_m, pitch_deg, roll_deg)


def read_text(path: Path, what: str) -> str:
    """The text of ``path`` (UTF-8, a byte-order mark dropped), or a
    one-line CameraError naming it as ``what`` ("camera file", "rig file")."""
    try:
        raw = path.read_bytes()
    except FileNotFoundError:
        raise CameraError(f"{what} {path} not found") from None
    except IsADirectoryError:
        raise CameraError(f"{what} {path} is a directory; give the {what} in it") from None
    except OSError as exc:
        raise CameraError(f"{what} {path} could not be read ({exc.strerror or exc})") from None
    return raw.decode("utf-8", errors="replace").lstrip("\ufeff")


def camera_from_k(k: tuple[float, float, float, float], size: tuple[int, int], height_m: float,
                  pitch_deg: float = 0.0, distortion=(), **attitude) -> Camera:
    """A camera from ``k`` = (fx, fy, cx, cy) pixels, ``size`` = (width, height);
    ``attitude``: ``roll_deg``, ``pitch_std_deg``, ``roll_std_deg`` (None: 0)."""
    fx, fy, cx, cy = k
    return Camera.from_dict({"width": size[0], "height": size[1], "fx": fx, "fy": fy, "cx": cx, "cy": cy,
                             "height_m": height_m, "pitch_deg": pitch_deg, "distortion": list(distortion),
                             **attitude})


def _our_json(text: str, path: Path) -> dict | None:
    """The camera.json object of ``text``, or None when it is not one (a
    calibration file); CameraError for JSON that does not parse or is not
    an object."""
    if not text.lstrip().startswith(("{", "[")):
        return None
    try:
        d = json.loads(text)
    except json.JSONDecodeError as exc:
        raise CameraError(f"camera file {path} is not valid JSON ({exc})") from None
    except RecursionError:
        raise CameraError(f"camera file {path} is not valid JSON (nested too deeply)") from None
    if not isinstance(d, dict):
        raise CameraError(f"camera file {path} must hold a JSON object (a camera.json or an OpenCV calibration)")
    if any(k in d for k in _K_NAMES):
        return None
    return d


def _from_calibration(path: Path, text: str, height_m, pitch_deg, roll_deg=None) -> Camera:
    """A camera from an OpenCV or ROS calibration file's ``text``."""
    import cv2

    stripped = text.lstrip()
    if stripped.startswith("<"):
        fmt = cv2.FILE_STORAGE_FORMAT_XML
    elif stripped.startswith("{"):
        fmt = cv2.FILE_STORAGE_FORMAT_JSON
    else:
        fmt = cv2.FILE_STORAGE_FORMAT_YAML
    what = f"camera file {path}"
    # OpenCV's parsers are not made for hostile input (deep nesting crashes
    # them): a calibration file is small and flat.
    if len(text) > _MAX_CALIBRATION_CHARS or _bracket_depth(text) > _MAX_CALIBRATION_DEPTH:
        raise CameraError(f"{what} is neither a camera.json nor an OpenCV or ROS calibration file "
                          "(too large or nested too deeply)")
    try:
        fs = cv2.FileStorage(text, cv2.FILE_STORAGE_READ | cv2.FILE_STORAGE_MEMORY | fmt)
    except (cv2.error, SystemError):  # (SystemError: the binding's way to fail on some garbage)
        raise CameraError(f"{what} is neither a camera.json nor an OpenCV or ROS calibration file "
                          "(YAML, XML or JSON)") from None
    try:
        K = _matrix(fs, _K_NAMES)
        if K is None:
            raise CameraError(f"{what} has no camera matrix (looked for {', '.join(_K_NAMES)})")
        K = np.asarray(K, dtype=float)
        if K.size != 9:
            raise CameraError(f"{what}: the camera matrix must be 3x3, got {K.shape[0]}x{K.shape[1]}")
        K = K.reshape(3, 3)
        model = _string(fs, "distortion_model")
        if model not in _PINHOLE_MODELS:
            raise CameraError(f"{what}: distortion model '{model}' is not supported (plumb_bob and "
                              "rational_polynomial are); calibrate with the pinhole model")
        D = _matrix(fs, _D_NAMES)
        dist = () if D is None else tuple(float(v) for v in np.asarray(D, dtype=float).ravel())
        if dist and not any(dist):
            dist = ()
        size = _image_size(fs)
        if size is None:
            raise CameraError(f"{what} has no image size (image_width and image_height, or image_size)")
        height_m = _number(fs, "height_m") if height_m is None else height_m
        pitch_deg = _number(fs, "pitch_deg") if pitch_deg is None else pitch_deg
        attitude = {k: _number(fs, k) for k in ATTITUDE_FIELDS}
        if roll_deg is not None:
            attitude["roll_deg"] = roll_deg
    except (cv2.error, SystemError):  # a damaged matrix node ("dt" missing, data not a map, ...)
        raise CameraError(f"{what} is damaged: OpenCV cannot read its matrices; calibrate again or fix the "
                          "file") from None
    finally:
        fs.release()
    if height_m is None:
        raise CameraError(f"{what} (a calibration file) has no camera height: pass --height-m "
                          "(metres above the floor)")
    if pitch_deg is None:
        pitch_deg = 0.0
    if abs(K[0, 1]) > 1e-9 * abs(K[0, 0]) or np.abs(K[2] - [0.0, 0.0, 1.0]).max() > 1e-9:
        raise CameraError(f"{what}: the camera matrix must be [[fx, 0, cx], [0, fy, cy], [0, 0, 1]], got "
                          f"{K.round(6).tolist()}")
    if not np.isfinite(K).all():
        raise CameraError(f"{what}: the camera matrix holds a non-finite number")
    return camera_from_k((K[0, 0], K[1, 1], K[0, 2], K[1, 2]), size, height_m, pitch_deg, dist, **attitude)


def _bracket_depth(text: str) -> int:
    """The deepest nesting of brackets, braces and XML elements in ``text``
    (an upper bound: brackets in strings count too)."""
    depth = best = 0
    for c in text:
        if c in "[{<":
            depth += 1
            best = max(best, depth)
        elif c in "]}>" and depth:
            depth -= 1
    return best


def _matrix(fs, names) -> np.ndarray | None:
    """The first of ``names`` in ``fs`` as an array: an OpenCV matrix, a ROS
    ``{rows, cols, data}`` map, or a plain list."""
    for name in names:
        node = fs.getNode(name)
        if node.empty():
            continue
        if node.isMap() and not node.getNode("data").empty():
            data = _sequence(node.getNode("data"))
            rows = node.getNode("rows")
            if not rows.empty() and rows.real() > 0 and len(data) % int(rows.real()) == 0:
                return np.array(data).reshape(int(rows.real()), -1)
            return np.array(data)[None]
        m = node.mat()
        if m is not None:
            return m
        if node.isSeq():
            return np.array(_sequence(node))[None]
    return None


def _sequence(node) -> list[float]:
    """The numbers of a sequence node (nested ones flattened)."""
    out = []
    for i in range(node.size()):
        item = node.at(i)
        out.extend(_sequence(item) if item.isSeq() else [item.real()])
    return out


def _string(fs, name: str) -> str:
    node = fs.getNode(name)
    return "" if node.empty() else (node.string() or "").strip().lower()


def _number(fs, name: str) -> float | None:
    node = fs.getNode(name)
    if node.empty() or not (node.isReal() or node.isInt()):
        return None
    v = float(node.real())
    return v if math.isfinite(v) else None


def _image_size(fs) -> tuple[int, int] | None:
    """``(width, height)`` from ``image_width``/``image_height`` (ROS, OpenCV's
    samples), ``image_size`` / ``imageSize`` ([w, h]) or ``width``/``height``."""
    for w, h in (("image_width", "image_height"), ("width", "height")):
        wv, hv = _number(fs, w), _number(fs, h)
        if wv is not None and hv is not None:
            return int(wv), int(hv)
    for name in ("image_size", "imageSize"):
        node = fs.getNode(name)
        if not node.empty():
            seq = _sequence(node) if node.isSeq() else list(np.asarray(node.mat()).ravel())
            if len(seq) == 2:
                return int(seq[0]), int(seq[1])
    return None


__all__ = ["REQUIRED_FIELDS", "camera_from_k", "load_camera"]
