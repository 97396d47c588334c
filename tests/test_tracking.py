"""Following a moving robot: matcher.Tracker, `matcher track`, runs as JSON
Lines and as ROS bags (written here with rosbags), simulated runs."""

from __future__ import annotations

import json
import math
from pathlib import Path

import cv2
import numpy as np
import pytest

import matcher
from matcher.cli import main as matcher_main
from matcher.tolerances import TRACKING
from matcher.tracking.odometry import Spread, compose, increment
from mapkit_harness.simulate import pose_error
from mapkit_harness.runs import run_camera, simulate_run, write_run

ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def flat():
    return matcher.load_map(ROOT / "maps" / "flat.lmap")


@pytest.fixture(scope="module")
def camera(flat):
    return run_camera(flat)


@pytest.fixture(scope="module")
def run(flat, camera):
    return simulate_run(flat, camera, np.random.default_rng(3), 40)


def follow(tracker, run, start: int = 0):
    return [tracker.step(run.times[i], run.odom[i], run.lines[i]) for i in range(start, len(run.times))]


# ---- odometry ---------------------------------------------------------------
def test_increment_and_compose_undo_each_other():
    rng = np.random.default_rng(0)
    for _ in range(100):
        a = tuple(rng.uniform([-5, -5, -180], [5, 5, 180]))
        b = tuple(rng.uniform([-5, -5, -180], [5, 5, 180]))
        c = compose(a, increment(a, b))
        assert pose_error(c, b)[0] < 1e-9 and pose_error(c, b)[1] < 1e-9


def test_the_increment_does_not_depend_on_the_odometry_frame():
    rng = np.random.default_rng(1)
    a, b, frame = (tuple(rng.uniform([-5, -5, -180], [5, 5, 180])) for _ in range(3))
    moved = increment(compose(frame, a), compose(frame, b))
    assert np.allclose(moved, increment(a, b))


def test_spread_grows_with_distance_and_turn_and_bounds_have_floors():
    s = Spread(0.02, 0.3)
    assert s.bounds(TRACKING) == (TRACKING.min_dt_m, TRACKING.min_dyaw_deg)
    far = s.grown((1.0, 0.0, 0.0), TRACKING)
    turned = s.grown((0.0, 0.0, 90.0), TRACKING)
    assert far.position_m > 0.02 + TRACKING.odom_distance_fraction - 1e-12 and far.yaw_deg > 0.3
    assert turned.position_m == 0.02 and turned.yaw_deg == pytest.approx(0.3 + 90 * TRACKING.odom_deg_per_deg)
    assert not s.lost(TRACKING) and Spread(1.0, 1.0).lost(TRACKING)


# ---- the tracker --------------------------------------------------------------
@pytest.mark.slow
def test_tracker_follows_a_seeded_run(flat, camera, run):
    out = follow(matcher.Tracker(flat, camera, prior=run.truth[0], dt=0.2, dyaw=10), run)
    errors = [pose_error(o.estimate, g) for o, g in zip(out, run.truth)]
    close = [e[0] <= 0.05 and e[1] <= 1.0 for e in errors]
    assert sum(close) >= 0.85 * len(run.times)
    assert all(e[0] < 0.5 and e[1] < 10 for o, e in zip(out, errors) if o)  # never confidently wrong
    assert {o.state for o in out} <= {"tracking", "coasting"}
    assert all(o.state == "tracking" for o in out if o)
    assert all(o.bounds[0] >= TRACKING.min_dt_m for o in out)


@pytest.mark.slow
def test_a_kidnapped_robot_is_found_again_and_only_after_confirmation(flat, camera):
    run = simulate_run(flat, camera, np.random.default_rng(11), 60, kidnap=25)
    out = follow(matcher.Tracker(flat, camera, prior=run.truth[0], dt=0.2, dyaw=10), run)
    errors = [pose_error(o.estimate, g) if o.estimate else (math.inf, math.inf) for o, g in zip(out, run.truth)]
    assert not [i for i, (o, e) in enumerate(zip(out, errors)) if o and (e[0] > 0.5 or e[1] > 10)]
    back = next(i for i in range(25, 60) if out[i] and errors[i][0] <= 0.05 and errors[i][1] <= 1.0)
    assert back - 25 <= 10
    assert any(o.state == "relocalising" for o in out[25:back])
    # The first trusted pose after the map search came after a confirmation.
    first_search = next(i for i in range(25, 60) if "map search found" in out[i].reason)
    assert not out[first_search] and back > first_search


@pytest.mark.slow
def test_a_tracker_with_no_prior_searches_then_confirms(flat, camera, run):
    tracker = matcher.Tracker(flat, camera)
    out = follow(tracker, run, start=5)
    assert out[0].state == "relocalising" and not out[0]
    first = next(i for i, o in enumerate(out) if o)
    assert first >= TRACKING.confirm_frames
    assert "confirmed" in out[first].reason
    e = pose_error(out[first].estimate, run.truth[5 + first])
    assert e[0] <= 0.05 and e[1] <= 1.0


def test_frames_that_cannot_be_used_are_skipped_with_their_reason(flat, camera, run):
    tracker = matcher.Tracker(flat, camera, prior=run.truth[0], dt=0.2, dyaw=10)
    k = next(i for i in range(1, 20) if tracker.step(run.times[i], run.odom[i], run.lines[i]))
    est = tracker.estimate
    cases = [
        ((run.times[0], run.odom[0], run.lines[0]), "time goes backwards"),
        ((run.times[k + 1], None, run.lines[k + 1]), "no odometry"),
        ((run.times[k + 1], [1.0, float("nan"), 0.0], run.lines[k + 1]), "odometry must be three finite numbers"),
        ((float("nan"), run.odom[k + 1], run.lines[k + 1]), "not finite"),
        ((run.times[k + 1], run.odom[k + 1], [[1.0, 2.0, 3.0]]), "frame skipped"),
    ]
    for args, why in cases:
        out = tracker.step(*args)
        assert not out and why in out.reason and out.reason.startswith("frame skipped")
        assert tracker.estimate == pytest.approx(est) or why == "frame skipped"
        json.dumps(out.to_dict())
    assert tracker.step(run.times[k + 2], run.odom[k + 2], run.lines[k + 2]).estimate is not None


def test_bad_tracker_arguments_are_refused(flat, camera):
    with pytest.raises(ValueError, match="bounds"):
        matcher.Tracker(flat, camera, prior=(1, 2, 3))
    with pytest.raises(ValueError, match="finite"):
        matcher.Tracker(flat, camera, prior=(1, 2, 3), dt=-1, dyaw=5)
    with pytest.raises(ValueError, match="tracking setting"):
        matcher.Tracking(odom_deg_per_m=float("nan"))


# ---- the command line: JSON Lines ---------------------------------------------
def _cli(capsys, *argv):
    code = matcher_main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return code, out, err


@pytest.mark.slow
def test_track_a_json_lines_run(tmp_path, capsys, flat, camera, run):
    frames, cam = tmp_path / "run.jsonl", tmp_path / "cam.json"
    write_run(run, frames)
    cam.write_text(json.dumps(camera.to_dict()))
    with open(frames, "a") as f:  # a damaged line and a blank one: the run goes on
        f.write('{"t": 99.0, "odom": [0, 0]\n\n')
    x, y, yaw = run.truth[0]
    code, out, err = _cli(capsys, "track", "--map", ROOT / "maps" / "flat.lmap", "--camera", cam, "--frames", frames,
                          "--prior", f"{x},{y},{yaw}", "--dt", 0.2, "--dyaw", 10, "--json",
                          "--out", tmp_path / "traj.txt", "--plot", tmp_path / "route.png")
    assert code == 0, err
    rows = [json.loads(line) for line in out.splitlines()]
    assert len(rows) == len(run.times) + 1
    assert {"t", "state", "ok", "pose", "estimate", "matches", "reason"} <= set(rows[0])
    assert sum(r["ok"] for r in rows) >= 0.8 * len(run.times)
    assert rows[-1]["ok"] is False and "not valid JSON" in rows[-1]["reason"] and "line 41" in rows[-1]["reason"]
    tum = [line.split() for line in (tmp_path / "traj.txt").read_text().splitlines() if not line.startswith("#")]
    assert len(tum) == len(run.times) and all(len(r) == 8 for r in tum)
    t, px, py, _, _, _, qz, qw = (float(v) for v in tum[10])
    assert t == pytest.approx(run.times[10])
    assert pose_error((px, py, math.degrees(2 * math.atan2(qz, qw))), run.truth[10])[0] < 0.1
    img = cv2.imread(str(tmp_path / "route.png"))
    assert img is not None and img.shape[0] > 200 and len(np.unique(img.reshape(-1, 3), axis=0)) > 4


@pytest.mark.slow
def test_track_human_output_and_usage_errors(tmp_path, capsys, run, camera):
    frames, cam = tmp_path / "run.jsonl", tmp_path / "cam.json"
    write_run(run, frames)
    cam.write_text(json.dumps(camera.to_dict()))
    lmap = ROOT / "maps" / "flat.lmap"
    code, out, err = _cli(capsys, "track", "--map", lmap, "--camera", cam, "--frames", frames, "--lost")
    assert code == 0 and "frames localised" in out.splitlines()[-1] and "relocalising" in out
    bad = [
        (["--frames", frames], "missing --prior"),
        (["--frames", tmp_path / "none.jsonl", "--lost"], "not found"),
        (["--frames", frames, "--lost", "--odom-topic", "/odom"], "for bags"),
        (["--frames", frames, "--lost", "--out", frames], "input"),
        (["--frames", frames, "--lost", "--plot", tmp_path / "route.svg"], ".png"),
        (["--frames", frames, "--lost", "--odom-deg-per-m", "-1"], "odom-deg-per-m"),
    ]
    for extra, why in bad:
        code, out, err = _cli(capsys, "track", "--map", lmap, "--camera", cam, *extra)
        assert code == 2 and why in err and out == "" and len(err.strip().splitlines()) == 1, (extra, err)
    code, out, err = _cli(capsys, "track", "--map", lmap, "--frames", frames, "--lost")
    assert code == 2 and "--camera" in err


def test_a_file_with_no_frame_of_a_run_is_a_usage_error(tmp_path, capsys, camera):
    """A lines file, a camera file or a pretty-printed JSON given as --frames
    is the wrong file (exit 2, one line naming what it is), not a run whose
    every frame is skipped (exit 1)."""
    cam = tmp_path / "cam.json"
    cam.write_text(json.dumps(camera.to_dict()))
    lines = tmp_path / "lines.json"
    lines.write_text(json.dumps({"lines": [[1, 2, 3, 4]] * 3}, indent=1))
    lmap = ROOT / "maps" / "flat.lmap"
    for frames, why in ((lines, "lines file"), (cam, 'without "t"'), (tmp_path / "empty.jsonl", "empty")):
        if not frames.exists():
            frames.write_text("\n")
        code, out, err = _cli(capsys, "track", "--map", lmap, "--camera", cam, "--frames", frames, "--lost")
        assert code == 2 and out == "" and why in err and len(err.strip().splitlines()) == 1, err


def test_a_skipped_frame_says_skipped_in_the_state_column():
    from matcher.cli_track import _human

    row = {"t": 1.0, "state": "relocalising", "skipped": True, "ok": False, "estimate": None,
           "reason": "frame skipped (run.jsonl line 3): not valid JSON"}
    assert _human(row).split()[1] == "skipped"
    assert _human({**row, "skipped": False}).split()[1] == "relocalising"


# ---- the command line: ROS bags -------------------------------------------------
@pytest.fixture(scope="module")
def bag_run():
    """Eight frames of a small flat, rendered at 320x240, for bags."""
    from mapkit_harness.render import render_view
    from mapkit_harness.plans import make_small_flat

    m = make_small_flat()
    cam = matcher.Camera.from_fov(70.0, 320, 240, 1.2, 0.0)
    run = simulate_run(m, cam, np.random.default_rng(2), 8)
    images = [render_view(m, cam, p, supersample=1, rng=np.random.default_rng(i)) for i, p in enumerate(run.truth)]
    return m, cam, run, images


def _ros_messages(ts, ros1: bool, cam, run, images, compressed: bool):
    """(topic, msgtype, time ns, message) of a run: camera_info and an image per
    frame, odometry at twice the frame rate (interpolated by the reader)."""
    T = ts.types
    Time, Header = T["builtin_interfaces/msg/Time"], T["std_msgs/msg/Header"]

    def header(t):
        stamp = Time(sec=int(t), nanosec=int(round((t % 1) * 1e9)))
        return Header(seq=0, stamp=stamp, frame_id="cam") if ros1 else Header(stamp=stamp, frame_id="cam")

    out = []
    roi = T["sensor_msgs/msg/RegionOfInterest"](x_offset=0, y_offset=0, height=0, width=0, do_rectify=False)
    k = np.array([cam.fx, 0, cam.cx, 0, cam.fy, cam.cy, 0, 0, 1], float)
    info = dict(header=header(100.0), height=cam.height, width=cam.width, distortion_model="plumb_bob",
                binning_x=0, binning_y=0, roi=roi)
    arrays = {"D": np.zeros(5), "K": k, "R": np.eye(3).ravel(), "P": np.zeros(12)}
    info.update({(n if ros1 else n.lower()): v for n, v in arrays.items()})
    out.append(("/camera/camera_info", "sensor_msgs/msg/CameraInfo", T["sensor_msgs/msg/CameraInfo"](**info)))
    P, Q = T["geometry_msgs/msg/Point"], T["geometry_msgs/msg/Quaternion"]
    V3 = T["geometry_msgs/msg/Vector3"]
    t_odom = np.arange(run.times[0] - 0.1, run.times[-1] + 0.15, 0.1)
    odo = np.array(run.odom)
    yaw = np.unwrap(np.radians(odo[:, 2]))
    for t in t_odom:
        x, y, a = (np.interp(t, run.times, v) for v in (odo[:, 0], odo[:, 1], yaw))
        pose = T["geometry_msgs/msg/Pose"](position=P(x=x, y=y, z=0.0), orientation=Q(x=0.0, y=0.0, z=math.sin(a / 2),
                                                                                          w=math.cos(a / 2)))
        twist = T["geometry_msgs/msg/Twist"](linear=V3(x=0.0, y=0.0, z=0.0), angular=V3(x=0.0, y=0.0, z=0.0))
        msg = T["nav_msgs/msg/Odometry"](header=header(100.0 + t), child_frame_id="base",
                                          pose=T["geometry_msgs/msg/PoseWithCovariance"](pose=pose, covariance=np.zeros(36)),
                                          twist=T["geometry_msgs/msg/TwistWithCovariance"](twist=twist, covariance=np.zeros(36)))
        out.append(("/odom", "nav_msgs/msg/Odometry", msg))
    for t, img in zip(run.times, images):
        if compressed:
            data = np.frombuffer(cv2.imencode(".png", img)[1].tobytes(), np.uint8)
            msg = T["sensor_msgs/msg/CompressedImage"](header=header(100.0 + t), format="png", data=data)
            out.append(("/camera/image/compressed", "sensor_msgs/msg/CompressedImage", msg))
        else:
            msg = T["sensor_msgs/msg/Image"](header=header(100.0 + t), height=img.shape[0], width=img.shape[1],
                                             encoding="mono8", is_bigendian=0, step=img.shape[1],
                                             data=img.ravel().copy())
            out.append(("/camera/image_raw", "sensor_msgs/msg/Image", msg))
    return sorted(out, key=lambda m: (m[2].header.stamp.sec, m[2].header.stamp.nanosec))


def write_ros1(path: Path, ts, msgs: list) -> None:
    """A ROS 1 bag at ``path`` of ``msgs`` ``(topic, type, message)``
    serialised with the typestore ``ts``, in the order given."""
    from rosbags.rosbag1 import Writer

    with Writer(path) as w:
        conns = {}
        for topic, mtype, msg in msgs:
            if topic not in conns:
                conns[topic] = w.add_connection(topic, mtype, typestore=ts)
            stamp = msg.header.stamp
            w.write(conns[topic], stamp.sec * 10**9 + stamp.nanosec, ts.serialize_ros1(msg, mtype))


def write_bag(path: Path, kind: str, cam, run, images) -> None:
    from rosbags.typesys import Stores, get_typestore

    if kind == "ros1":
        ts = get_typestore(Stores.ROS1_NOETIC)
        write_ros1(path, ts, _ros_messages(ts, True, cam, run, images, compressed=False))
        return
    from rosbags.rosbag2 import StoragePlugin, Writer

    ts = get_typestore(Stores.ROS2_HUMBLE)
    msgs = _ros_messages(ts, False, cam, run, images, compressed=True)
    with Writer(path, version=9, storage_plugin=StoragePlugin.MCAP) as w:
        conns = {}
        for topic, mtype, msg in msgs:
            if topic not in conns:
                conns[topic] = w.add_connection(topic, mtype, typestore=ts)
            stamp = msg.header.stamp
            w.write(conns[topic], stamp.sec * 10**9 + stamp.nanosec, ts.serialize_cdr(msg, mtype))


@pytest.mark.parametrize("kind", ["ros1", "ros2-mcap"])
def test_track_a_bag(tmp_path, capsys, bag_run, kind):
    from linemap.lmap import save_map

    m, cam, run, images = bag_run
    lmap = tmp_path / "small.lmap"
    save_map(lmap, m)
    bag = tmp_path / ("run.bag" if kind == "ros1" else "run2")
    write_bag(bag, kind, cam, run, images)
    x, y, yaw = run.truth[0]
    code, out, err = _cli(capsys, "track", "--map", lmap, "--frames", bag, "--height-m", 1.2, "--json",
                          "--prior", f"{x},{y},{yaw}", "--dt", 0.2, "--dyaw", 10)
    assert code == 0, err
    rows = [json.loads(line) for line in out.splitlines()]
    assert len(rows) == len(run.times)
    assert [r["t"] for r in rows] == pytest.approx([100.0 + t for t in run.times])
    assert sum(r["ok"] for r in rows) >= len(rows) // 2
    for r, truth in zip(rows, run.truth):
        if r["ok"]:
            e = pose_error((r["pose"]["x"], r["pose"]["y"], r["pose"]["yaw_deg"]), truth)
            assert e[0] < 0.1 and e[1] < 2.0
    # A topic the bag does not have, and a bag with no intrinsics for the camera.
    code, out, err = _cli(capsys, "track", "--map", lmap, "--frames", bag, "--height-m", 1.2, "--lost",
                          "--odom-topic", "/wheels")
    assert code == 2 and "no topic /wheels" in err and "/odom" in err and out == ""
    code, out, err = _cli(capsys, "track", "--map", lmap, "--frames", bag, "--lost")
    assert code == 2 and "--height-m" in err and out == ""


def test_a_damaged_bag_is_a_one_line_error(tmp_path, capsys):
    bag = tmp_path / "broken.bag"
    bag.write_bytes(b"#ROSBAG V2.0\n" + b"\x00" * 50)
    code, out, err = _cli(capsys, "track", "--map", ROOT / "maps" / "flat.lmap", "--frames", bag, "--lost",
                          "--height-m", "1.2")
    assert code == 2 and "could not read the bag" in err and len(err.strip().splitlines()) == 1
