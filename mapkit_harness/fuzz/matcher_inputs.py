"""The ``matcher`` fuzz family: random values for every input of the
matcher: lines files and arrays of odd shapes and dtypes, camera files
(ours, OpenCV's, ROS's), priors, ``dt``, ``dyaw``, budgets, images of odd
sizes and dtypes, and the JSON Lines frame files of ``matcher track``;
through its command line or its Python API (``["api", ...]`` calls). Also
the frame and run simulated on ``maps/flat.lmap`` the cases start from.
"""

from __future__ import annotations

import io
import json
import math
import random
from functools import lru_cache

from .cases import DATA, FLAT_LMAP, ROOT, Case, source_bytes
from .mutations import mutate_bytes, mutate_lines


def base_camera() -> dict:
    return {"width": 640, "height": 480, "fx": 900.0, "fy": 900.0, "cx": 320.0, "cy": 240.0,
            "height_m": 1.2, "pitch_deg": 0.0}


@lru_cache(maxsize=None)
def base_frame() -> dict:
    """A frame simulated on maps/flat.lmap that localises (seeded)."""
    import numpy as np

    import matcher
    from mapkit_harness import simulate

    m = matcher.load_map(ROOT / "maps" / "flat.lmap")
    f = simulate.make_frame(m, matcher.Camera.from_dict(base_camera()), np.random.default_rng(4), 2)
    return {"lines": np.round(f.lines.reshape(-1, 4), 3).tolist(), "prior": [round(v, 4) for v in f.prior],
            "dt": f.dt, "dyaw": f.dyaw}


@lru_cache(maxsize=None)
def base_run() -> bytes:
    """Five frames of a simulated run on maps/flat.lmap as JSON Lines, and its start."""
    import numpy as np

    import matcher
    from mapkit_harness.runs import simulate_run

    m = matcher.load_map(ROOT / "maps" / "flat.lmap")
    run = simulate_run(m, matcher.Camera.from_dict(base_camera()), np.random.default_rng(3), frames=5)
    rows = [json.dumps({"t": t, "odom": [round(v, 6) for v in o], "lines": np.round(ls.reshape(-1, 4), 3).tolist()})
            for t, o, ls in zip(run.times, run.odom, run.lines)]
    return ("\n".join(rows) + "\n").encode(), [round(v, 4) for v in run.truth[0]]


#: Values any number of a matcher input may become.
ODD_VALUES = (math.nan, math.inf, -math.inf, 1e308, -1e308, 0, -1, 1e-300, 2 ** 70, "7", "x", None, True, [], {},
              [1, 2], [[1, 2, 3, 4]])


def _mutate_json(node, rng: random.Random, depth: int = 0):
    """A copy of a JSON value with some numbers, lists or keys made odd."""
    r = rng.random()
    if isinstance(node, dict):
        out = {k: _mutate_json(v, rng, depth + 1) if rng.random() < 0.3 else v for k, v in node.items()}
        if out and rng.random() < 0.15:
            out.pop(rng.choice(sorted(out)))
        return out
    if isinstance(node, list):
        if r < 0.05:
            return []
        if r < 0.1 and node:
            return node * rng.choice((2, 50, 600))
        out = [_mutate_json(v, rng, depth + 1) if rng.random() < 0.2 else v for v in node]
        if out and rng.random() < 0.1:
            del out[rng.randrange(len(out))]
        return out
    if r < 0.5:
        return rng.choice(ODD_VALUES)
    if isinstance(node, (int, float)) and not isinstance(node, bool):
        return node * rng.choice((-1, 10, 1e3, 1e9, 0.5))
    return node


def _odd_number_text(rng: random.Random, good: float) -> str:
    return rng.choice((str(good), str(good), "nan", "inf", "-1", "0", "1e308", "-1e-300", "1e9", "x", ""))


def _odd_array(rng: random.Random, base):
    """The base lines (or an odd replacement) as an array of odd shape or dtype."""
    import numpy as np

    arr = np.array(base, dtype=np.float64)
    pick = rng.randrange(12)
    if pick == 0:
        return arr.astype(rng.choice((np.float32, np.int64, np.int8, np.uint8, np.complex128, np.float16, bool)))
    if pick == 1:
        return arr.reshape(rng.choice(((-1,), (-1, 2, 2), (1, -1), (-1, 8) if arr.size % 8 == 0 else (-1, 4))))
    if pick == 2:
        return np.zeros(rng.choice(((0,), (0, 4), (0, 2, 2), (1,), (1, 4), (3, 2, 2, 1), (2, 3), ())))
    if pick == 3:
        a = arr.copy()
        a.flat[rng.randrange(a.size)] = rng.choice((np.nan, np.inf, -np.inf, 1e308, -1e308, 1e-320))
        return a
    if pick == 4:
        return arr.astype(object)
    if pick == 5:
        return np.array([str(v) for v in arr.ravel()]).reshape(arr.shape)
    if pick == 6:
        return np.tile(arr, (rng.choice((50, 300, 3000)), 1))
    if pick == 7:
        a = arr.copy()
        a[:, 2:] = a[:, :2]  # zero-length lines
        return a
    if pick == 8:
        return arr * rng.choice((-1.0, 10.0, 1e6, 0.0))
    if pick == 9:
        return arr[: rng.randrange(4)]
    if pick == 10:
        return np.asfortranarray(arr)[:, ::-1]
    return arr


def _odd_image(rng: random.Random):
    """An image array of odd size or dtype."""
    import numpy as np

    shape = rng.choice(((0, 0), (1, 1), (480, 640), (2, 5000), (5000, 2), (480, 640, 3), (480, 640, 4),
                        (480, 640, 1), (480, 640, 2), (10,), (3, 4, 5, 6), (), (64, 64)))
    dtype = rng.choice((np.uint8, np.uint8, np.uint16, np.int64, np.float32, np.float64, bool, np.int8,
                        np.complex64))
    nrng = np.random.default_rng(rng.randrange(2 ** 32))
    with np.errstate(all="ignore"):
        img = (nrng.random(shape) * rng.choice((1.0, 255.0, 65535.0, 1e30))).astype(dtype) if shape else \
            np.array(1, dtype)
    if img.size and rng.random() < 0.3 and img.dtype.kind == "f":
        img.flat[rng.randrange(img.size)] = rng.choice((np.nan, np.inf))
    if img.ndim >= 2 and img.size and rng.random() < 0.5:  # stripes and blocks LSD will find lines in
        img[..., :: max(1, img.shape[1] // 8)] = 0
    return img


def _npy(arr) -> bytes:
    import numpy as np

    buf = io.BytesIO()
    np.save(buf, arr, allow_pickle=True)
    return buf.getvalue()


def matcher_case(rng: random.Random, name: str = "matcher") -> Case:
    """Random values for one of the matcher's inputs, through its CLI or its API."""
    kind = rng.choice(("lines file", "lines file", "camera file", "options", "image file", "lines array",
                       "image array", "frames"))
    return KIND_MAKERS[kind](rng, name)


def _localize_argv(prior=None, dt=None, dyaw=None, extra=()) -> list:
    f = base_frame()
    prior = prior if prior is not None else ",".join(map(str, f["prior"]))
    return ["matcher", "localize", "--map", FLAT_LMAP, "--camera", "camera.json",
            "--prior", prior, "--dt", str(f["dt"] if dt is None else dt),
            "--dyaw", str(f["dyaw"] if dyaw is None else dyaw), *extra]


def _lines_file_case(rng, name):
    f = base_frame()
    if rng.random() < 0.15:
        text, note = mutate_lines(json.dumps({"lines": f["lines"]}, indent=0), rng)
        blob = text.encode()
    else:
        blob, note = json.dumps(_mutate_json({"lines": f["lines"]}, rng)).encode(), "json"
    files = {"camera.json": json.dumps(base_camera()).encode(), "lines.json": blob}
    return Case("matcher", name, files, _localize_argv(extra=["--lines", "lines.json"]), f"lines file: {note}")


#: Camera files of each format the matcher reads.
CAMERA_SOURCES = ("opencv_calibration.yml", "opencv_calibration.xml", "opencv_calibration.json",
                  "ros_camera_info.yaml")


def _camera_file_case(rng, name):
    f = base_frame()
    files = {"lines.json": json.dumps({"lines": f["lines"]}).encode()}
    if rng.random() < 0.5:
        files["camera.json"], note = json.dumps(_mutate_json(base_camera(), rng)).encode(), "json"
        argv = _localize_argv(extra=["--lines", "lines.json"])
    else:
        src = rng.choice(CAMERA_SOURCES)
        raw = source_bytes(DATA / "cameras" / src)
        if rng.random() < 0.7:
            text, note = mutate_lines(raw.decode(), rng)
            raw = text.encode()
        else:
            raw, note = mutate_bytes(raw, rng)
        ext = src.rsplit(".", 1)[1]
        files["camera." + ext] = raw
        argv = _localize_argv(extra=["--lines", "lines.json", "--height-m", _odd_number_text(rng, 1.2)])
        argv[argv.index("camera.json")] = "camera." + ext
        note = f"{src}: {note}"
    return Case("matcher", name, files, argv, f"camera file: {note}")


def _options_case(rng, name):
    f = base_frame()
    files = {"camera.json": json.dumps(base_camera()).encode(), "lines.json": json.dumps({"lines": f["lines"]}).encode()}
    prior = ",".join(_odd_number_text(rng, v) for v in f["prior"]) if rng.random() < 0.5 else \
        rng.choice(("1,2", "1,2,3,4", "a,b,c", "", "1e308,1e308,1e308", "-1e9,5,720", "5,5,nan"))
    extra = ["--lines", "lines.json"]
    if rng.random() < 0.5:
        extra += ["--budget-ms", _odd_number_text(rng, 200.0)]
    if rng.random() < 0.2:  # lost mode, always under a budget (it takes seconds)
        argv = ["matcher", "localize", "--map", FLAT_LMAP, "--camera", "camera.json",
                "--lost", "--lines", "lines.json", "--budget-ms", rng.choice(("100", "300", "0", "nan", "-5"))]
    elif rng.random() < 0.2:  # the camera on the command line
        argv = _localize_argv(prior, extra=extra)
        i = argv.index("--camera")
        argv[i:i + 2] = ["--camera-k", ",".join(_odd_number_text(rng, v) for v in (900, 900, 320, 240)),
                         "--image-size", rng.choice(("640x480", "0x0", "640", "-640x480", "99999999x99999999",
                                                     "axb")), "--height-m", _odd_number_text(rng, 1.2)]
    else:
        argv = _localize_argv(prior, _odd_number_text(rng, f["dt"]), _odd_number_text(rng, f["dyaw"]), extra)
    return Case("matcher", name, files, argv, "options")


def _image_file_case(rng, name):
    import cv2
    import numpy as np

    img = _odd_image(rng)
    ok, enc = False, None
    encodable = img.dtype in (np.uint8, np.uint16) and img.ndim in (2, 3) and img.size and \
        (img.ndim == 2 or img.shape[2] in (1, 3, 4))
    if encodable:  # else random bytes: PNG cannot hold it (and libpng would say so on stderr)
        ok, enc = cv2.imencode(".png", img)
    blob = enc.tobytes() if ok else bytes(rng.randrange(256) for _ in range(64))
    if rng.random() < 0.3:
        blob, _ = mutate_bytes(blob, rng)
    cam = base_camera()
    if img.ndim >= 2 and rng.random() < 0.8:  # a camera of the image's size, so the lines get to the matcher
        cam.update(width=max(int(img.shape[1]), 1), height=max(int(img.shape[0]), 1),
                   cx=img.shape[1] / 2, cy=img.shape[0] / 2)
    files = {"camera.json": json.dumps(cam).encode(), "image.png": blob}
    return Case("matcher", name, files, _localize_argv(extra=["--image", "image.png", "--budget-ms", "2000"]),
                f"image {img.shape} {img.dtype}")


def _lines_array_case(rng, name):
    f = base_frame()
    args = {"lines": "lines.npy", "camera": base_camera(),
            "prior": [rng.choice((v, v, v, math.nan, 1e308, "x")) for v in f["prior"]] if rng.random() < 0.3 else
            f["prior"],
            "dt": rng.choice((f["dt"], f["dt"], -1.0, 0.0, math.nan, math.inf, 1e9, "0.4", None)),
            "dyaw": rng.choice((f["dyaw"], f["dyaw"], -20.0, 0.0, math.nan, 720.0, 1e300, None))}
    return Case("matcher", name, {"lines.npy": _npy(_odd_array(rng, f["lines"]))}, ["api", "localize", args],
                "lines array")


def _image_array_case(rng, name):
    img = _odd_image(rng)
    args = {"image": "image.npy", "camera": base_camera() if rng.random() < 0.5 else None,
            "min_length": rng.choice((None, None, 0.0, -1.0, math.nan, 1e9, "x"))}
    if args["camera"] and img.ndim >= 2 and rng.random() < 0.8:
        args["camera"].update(width=max(int(img.shape[1]), 1), height=max(int(img.shape[0]), 1),
                              cx=img.shape[1] / 2, cy=img.shape[0] / 2)
    return Case("matcher", name, {"image.npy": _npy(img)}, ["api", "detect_lines", args],
                f"image {img.shape} {img.dtype}")


def _frames_case(rng, name):
    run, start = base_run()
    rows = run.decode().splitlines()
    if rng.random() < 0.3:
        text, note = mutate_lines(run.decode(), rng)
    else:
        i = rng.randrange(len(rows))
        rows[i] = json.dumps(_mutate_json(json.loads(rows[i]), rng))
        if rng.random() < 0.2:
            rows[rng.randrange(len(rows))] = json.dumps({"t": 1.0, "odom": [0, 0, 0], "image": rng.choice(
                ("missing.png", "/etc", "..", "camera.json", "", "/dev/zero"))})
        text, note = "\n".join(rows) + "\n", f"frame {i} json"
    files = {"camera.json": json.dumps(base_camera()).encode(), "run.jsonl": text.encode()}
    argv = ["matcher", "track", "--map", FLAT_LMAP, "--camera", "camera.json",
            "--frames", "run.jsonl", "--relocalise-budget-ms", "300", "--budget-ms", "500", "--out", "traj.txt"]
    argv += ["--lost"] if rng.random() < 0.2 else ["--prior", ",".join(map(str, start)), "--dt", "0.3",
                                                    "--dyaw", "15"]
    return Case("matcher", name, files, argv, f"frames: {note}")


#: The maker of each kind of matcher input, by the name ``matcher_case`` draws.
KIND_MAKERS = {"lines file": _lines_file_case, "camera file": _camera_file_case, "options": _options_case,
               "image file": _image_file_case, "lines array": _lines_array_case, "image array": _image_array_case,
               "frames": _frames_case}
