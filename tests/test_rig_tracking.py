"""Following a robot that carries a camera rig: matcher.Tracker with a Rig,
`matcher track --rig` on JSON Lines runs (``"cameras"``) and on ROS bags
with one image topic per camera (written here with rosbags), the instants
of a rig's bag (matcher.tracking.rig_sync)."""

from __future__ import annotations

import json
import math
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

import matcher
from linemap.rig import Mount, Rig, RigCamera
from linemap.rig_files import rig_to_dict
from matcher.cli import main as matcher_main
from matcher.tolerances import TRACKING
from matcher.tracking.rig_sync import instants, sync_tolerance
from mapkit_harness.rigs import ring_rig
from mapkit_harness.runs import simulate_run, write_run
from mapkit_harness.simulate import camera_pose, pose_error

ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def flat():
    return matcher.load_map(ROOT / "maps" / "flat.lmap")


@pytest.fixture(scope="module")
def rig():
    return ring_rig(2, hfov_deg=90.0, radius_m=0.1)


@pytest.fixture(scope="module")
def rig_run(flat, rig):
    return simulate_run(flat, rig, np.random.default_rng(3), 16)


def _cli(capsys, *argv):
    code = matcher_main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return code, out, err


# ---- the tracker ------------------------------------------------------------------
def test_a_rig_run_is_simulated_with_one_set_of_lines_per_camera(flat, rig, rig_run):
    assert all(isinstance(lines, list) and len(lines) == len(rig) for lines in rig_run.lines)
    assert all(len(ids) == len(rig) for ids in rig_run.ids)
    assert all(len(lines) == len(ids) for frame, per in zip(rig_run.lines, rig_run.ids) for lines, ids in zip(frame, per))


@pytest.mark.slow
def test_a_rig_run_is_tracked_within_a_few_cm_on_every_frame(flat, rig, rig_run):
    tracker = matcher.Tracker(flat, rig, prior=rig_run.truth[0], dt=0.2, dyaw=10)
    for t, odom, lines, truth in zip(rig_run.times, rig_run.odom, rig_run.lines, rig_run.truth):
        out = tracker.step(t, odom, lines)
        assert out and out.state == "tracking", out.reason
        dist, dyaw = pose_error(out.estimate, truth)
        assert dist < 0.03 and dyaw < 0.5, (t, dist, dyaw)
        assert [c["name"] for c in out.to_dict()["cameras"]] == rig.names


@pytest.mark.slow
def test_a_rig_tracker_with_no_prior_searches_then_confirms(flat, rig, rig_run):
    # A budget no machine reaches: the same search, and the same frames, everywhere.
    tracker = matcher.Tracker(flat, rig, settings=replace(TRACKING, relocalise_budget_ms=60000))
    out = [tracker.step(t, odom, lines) for t, odom, lines in zip(rig_run.times[:6], rig_run.odom, rig_run.lines)]
    assert out[0].state == "relocalising" and not out[0] and "map search found" in out[0].reason
    first = next(i for i, o in enumerate(out) if o)
    assert first >= TRACKING.confirm_frames and "confirmed" in out[first].reason
    assert all(o.state == "tracking" for o in out[first:])
    for o, truth in zip(out[first:], rig_run.truth[first:]):
        dist, dyaw = pose_error(o.estimate, truth)
        assert dist < 0.03 and dyaw < 0.5


@pytest.mark.slow
def test_a_rig_frame_with_the_wrong_number_of_cameras_is_skipped_with_its_reason(flat, rig, rig_run):
    tracker = matcher.Tracker(flat, rig, prior=rig_run.truth[0], dt=0.2, dyaw=10)
    assert tracker.step(rig_run.times[0], rig_run.odom[0], rig_run.lines[0])
    before = tracker.estimate
    for lines in (rig_run.lines[1][:1], rig_run.lines[1] + rig_run.lines[1][:1], rig_run.lines[1][0]):
        out = tracker.step(rig_run.times[1], rig_run.odom[1], lines)
        assert out.skipped and not out and out.reason.startswith("frame skipped")
        assert "cam0, cam1" in out.reason and tracker.estimate == before and out.state == "tracking"
        json.dumps(out.to_dict())
    assert tracker.step(rig_run.times[1], rig_run.odom[1], rig_run.lines[1])


def test_a_one_camera_rig_is_tracked_as_its_camera(flat, rig_run):
    camera = matcher.Camera.from_fov(70.0, 640, 480, 1.2, 0.0)
    run = simulate_run(flat, camera, np.random.default_rng(5), 4)
    a = matcher.Tracker(flat, camera, prior=run.truth[0], dt=0.2, dyaw=10)
    b = matcher.Tracker(flat, Rig.single(camera), prior=run.truth[0], dt=0.2, dyaw=10)
    for t, odom, lines in zip(run.times, run.odom, run.lines):
        oa, ob = a.step(t, odom, lines), b.step(t, odom, [lines])
        assert oa.estimate == ob.estimate and oa.result.matches == ob.result.matches and oa.reason == ob.reason


# ---- the command line: JSON Lines ----------------------------------------------------
@pytest.mark.slow
def test_track_a_rig_run_in_json_lines(tmp_path, capsys, rig, rig_run):
    frames, rig_file = tmp_path / "run.jsonl", tmp_path / "rig.json"
    rig_file.write_text(json.dumps(rig_to_dict(rig)))
    write_run(rig_run, frames)
    first = json.loads(frames.read_text().splitlines()[0])
    assert len(first["cameras"]) == 2 and "lines" in first["cameras"][0] and "lines" not in first
    with open(frames, "a") as f:  # a frame of three cameras, one of one camera's lines: skipped, the run goes on
        f.write(json.dumps({"t": 99.0, "odom": [0, 0, 0], "cameras": first["cameras"] + first["cameras"][:1]}) + "\n")
        f.write(json.dumps({"t": 99.5, "odom": [0, 0, 0], "lines": first["cameras"][0]["lines"]}) + "\n")
    x, y, yaw = rig_run.truth[0]
    code, out, err = _cli(capsys, "track", "--map", ROOT / "maps" / "flat.lmap", "--rig", rig_file, "--frames", frames,
                          "--prior", f"{x},{y},{yaw}", "--dt", 0.2, "--dyaw", 10, "--json", "--out", tmp_path / "t.txt",
                          # Budgets no machine reaches: the same search, and the same poses, everywhere.
                          "--budget-ms", 60000, "--relocalise-budget-ms", 60000)
    assert code == 0, err
    rows = [json.loads(line) for line in out.splitlines()]
    assert len(rows) == len(rig_run.times) + 2
    for r, truth in zip(rows, rig_run.truth):
        assert r["ok"], r["reason"]
        assert pose_error((r["pose"]["x"], r["pose"]["y"], r["pose"]["yaw_deg"]), truth)[0] < 0.03
        assert [c["name"] for c in r["cameras"]] == ["cam0", "cam1"]
    assert rows[-2]["skipped"] and "line 17" in rows[-2]["reason"] and "the frame has 3 cameras, the rig has 2" \
        in rows[-2]["reason"]
    assert rows[-1]["skipped"] and 'needs "cameras"' in rows[-1]["reason"]
    tum = [line.split() for line in (tmp_path / "t.txt").read_text().splitlines() if not line.startswith("#")]
    assert len(tum) == len(rig_run.times) and all(float(r[3]) == 0.0 for r in tum)  # the robot's pose: z 0


def test_track_rig_usage_errors_are_one_line(tmp_path, capsys, rig, rig_run):
    frames, rig_file, cam = tmp_path / "run.jsonl", tmp_path / "rig.json", tmp_path / "cam.json"
    rig_file.write_text(json.dumps(rig_to_dict(rig)))
    cam.write_text(json.dumps(rig[0].camera.to_dict()))
    write_run(rig_run, frames)
    lmap = ROOT / "maps" / "flat.lmap"
    bad = [
        (["--rig", rig_file, "--camera", cam], "describe one camera"),
        (["--rig", rig_file, "--height-m", "1.2"], "--height-m"),
        (["--rig", rig_file, "--topics", "/a,/b"], "for bags"),
        (["--rig", tmp_path / "none.json"], "not found"),
        (["--camera", cam, "--cam0-pose", "0,0,0,1"], "goes with --rig"),
    ]
    for extra, why in bad:
        code, out, err = _cli(capsys, "track", "--map", lmap, "--frames", frames, "--lost", *extra)
        assert code == 2 and why in err and out == "" and len(err.strip().splitlines()) == 1, (extra, err)
    # One camera's frames given a rig's file, and a rig's frames given one camera: each frame says why.
    code, out, err = _cli(capsys, "track", "--map", lmap, "--frames", frames, "--lost", "--camera", cam, "--json")
    rows = [json.loads(line) for line in out.splitlines()]
    assert code == 1 and all(r["skipped"] and "track it with --rig" in r["reason"] for r in rows)


# ---- the command line: ROS bags -------------------------------------------------------
@pytest.fixture(scope="module")
def bag_rig_run():
    """Eight frames of a small flat seen by a front and a back camera (320x240), rendered."""
    from mapkit_harness.plans import make_small_flat
    from mapkit_harness.render import render_view

    m = make_small_flat()
    cam = matcher.Camera.from_fov(80.0, 320, 240, 1.2, 0.0)
    rig = Rig((RigCamera("front", cam, Mount(0.1, 0.0, 0.0), topic="/front/image_raw"),
               RigCamera("back", cam, Mount(-0.1, 0.0, 180.0), topic="/back/image_raw")))
    run = simulate_run(m, rig, np.random.default_rng(2), 8)
    images = [[render_view(m, rc.camera, camera_pose(rc.mount, p), supersample=1, rng=np.random.default_rng([i, k]))
               for k, rc in enumerate(rig)] for i, p in enumerate(run.truth)]
    return m, rig, run, images


def _header(T, t: float):
    stamp = T["builtin_interfaces/msg/Time"](sec=int(t), nanosec=int(round((t % 1) * 1e9)))
    return T["std_msgs/msg/Header"](seq=0, stamp=stamp, frame_id="base")


def _odometry(T, run) -> list:
    """Odometry at twice the frame rate (interpolated by the reader)."""
    P, Q, V3 = T["geometry_msgs/msg/Point"], T["geometry_msgs/msg/Quaternion"], T["geometry_msgs/msg/Vector3"]
    odo = np.array(run.odom)
    yaw = np.unwrap(np.radians(odo[:, 2]))
    out = []
    for t in np.arange(run.times[0] - 0.1, run.times[-1] + 0.15, 0.1):
        x, y, a = (np.interp(t, run.times, v) for v in (odo[:, 0], odo[:, 1], yaw))
        pose = T["geometry_msgs/msg/Pose"](position=P(x=x, y=y, z=0.0),
                                           orientation=Q(x=0.0, y=0.0, z=math.sin(a / 2), w=math.cos(a / 2)))
        twist = T["geometry_msgs/msg/Twist"](linear=V3(x=0.0, y=0.0, z=0.0), angular=V3(x=0.0, y=0.0, z=0.0))
        msg = T["nav_msgs/msg/Odometry"](
            header=_header(T, 100.0 + t), child_frame_id="base",
            pose=T["geometry_msgs/msg/PoseWithCovariance"](pose=pose, covariance=np.zeros(36)),
            twist=T["geometry_msgs/msg/TwistWithCovariance"](twist=twist, covariance=np.zeros(36)))
        out.append(("/odom", "nav_msgs/msg/Odometry", msg))
    return out


def write_rig_bag(path: Path, rig, run, images, skew_s: float = 0.0, drop: tuple = ()) -> None:
    """A ROS 1 bag: odometry and one mono8 image topic per camera (each
    camera's topic), camera k's stamps ``k * skew_s`` late; the images of
    ``drop`` ``(frame, camera)`` pairs left out."""
    from rosbags.typesys import Stores, get_typestore

    from test_tracking import write_ros1

    ts = get_typestore(Stores.ROS1_NOETIC)
    T = ts.types
    msgs = _odometry(T, run)
    for i, (t, views) in enumerate(zip(run.times, images)):
        for k, (rc, img) in enumerate(zip(rig, views)):
            if (i, k) in drop:
                continue
            msg = T["sensor_msgs/msg/Image"](header=_header(T, 100.0 + t + k * skew_s), height=img.shape[0],
                                             width=img.shape[1], encoding="mono8", is_bigendian=0,
                                             step=img.shape[1], data=img.ravel().copy())
            msgs.append((rc.topic, "sensor_msgs/msg/Image", msg))
    msgs.sort(key=lambda m: (m[2].header.stamp.sec, m[2].header.stamp.nanosec))
    write_ros1(path, ts, msgs)


@pytest.mark.slow
def test_track_a_rig_bag_with_one_image_topic_per_camera(tmp_path, capsys, bag_rig_run):
    from linemap.lmap import save_map

    m, rig, run, images = bag_rig_run
    lmap, rig_file, bag = tmp_path / "small.lmap", tmp_path / "rig.json", tmp_path / "run.bag"
    save_map(lmap, m)
    rig_file.write_text(json.dumps(rig_to_dict(rig)))
    # The back camera 30 ms late (frames every 200 ms: one instant within 100 ms), its image of frame 3 lost.
    write_rig_bag(bag, rig, run, images, skew_s=0.03, drop=((3, 1),))
    x, y, yaw = run.truth[0]
    prior = ("--prior", f"{x},{y},{yaw}", "--dt", 0.2, "--dyaw", 10)
    code, out, err = _cli(capsys, "track", "--map", lmap, "--rig", rig_file, "--frames", bag, "--json", *prior)
    assert code == 0, err
    rows = [json.loads(line) for line in out.splitlines()]
    assert len(rows) == len(run.times)
    # An instant's time is the mean of its images' (frame 3: the front camera's alone).
    assert [r["t"] for r in rows] == pytest.approx([100.0 + t + (0.015 if i != 3 else 0.0)
                                                    for i, t in enumerate(run.times)])
    assert rows[3]["skipped"] and "no image from /back/image_raw" in rows[3]["reason"]
    assert all(r["ok"] for k, r in enumerate(rows) if k != 3), [r["reason"] for r in rows]
    for r, truth in zip(rows, run.truth):
        if r["ok"]:
            e = pose_error((r["pose"]["x"], r["pose"]["y"], r["pose"]["yaw_deg"]), truth)
            assert e[0] < 0.1 and e[1] < 2.0
    # --topics in the rig's order gives the same frames; a topic the bag lacks and a camera with none are errors.
    code, out2, err = _cli(capsys, "track", "--map", lmap, "--rig", rig_file, "--frames", bag, "--json", *prior,
                           "--topics", "/front/image_raw,/back/image_raw")
    assert code == 0 and [json.loads(line)["ok"] for line in out2.splitlines()] == [r["ok"] for r in rows]
    code, out, err = _cli(capsys, "track", "--map", lmap, "--rig", rig_file, "--frames", bag, *prior,
                          "--topics", "/front/image_raw,/left/image_raw")
    assert code == 2 and "no topic /left/image_raw" in err and out == ""
    bare = tmp_path / "bare.json"
    bare.write_text(json.dumps({"cameras": [{k: v for k, v in c.items() if k != "topic"}
                                            for c in rig_to_dict(rig)["cameras"]]}))
    code, out, err = _cli(capsys, "track", "--map", lmap, "--rig", bare, "--frames", bag, *prior)
    assert code == 2 and "--topics" in err and "/back/image_raw, /front/image_raw" in err and out == ""


# ---- the instants of a rig's bag ---------------------------------------------------------
def test_images_are_grouped_into_instants_by_time():
    assert sync_tolerance([[0.0, 0.1, 0.2], [0.0, 0.2, 0.4]]) == pytest.approx(0.1)  # half the slowest period
    assert sync_tolerance([[1.0], []]) == math.inf
    stream = [(0, 0.00, "a0"), (1, 0.02, "b0"), (0, 0.20, "a1"), (0, 0.40, "a2"), (1, 0.41, "b2")]
    assert list(instants(stream, 2, 0.1)) == [(0.01, ["a0", "b0"]), (0.2, ["a1", None]), (0.405, ["a2", "b2"])]
    # A camera that stopped holds nothing back past Tracking.rig_sync_wait_s: instants come as the others' do.
    got = []
    for item in instants(((0, 0.2 * i, i) for i in range(30)), 2, 0.1):
        got.append(item)
        if len(got) == 3:
            break
    assert got == [(0.0, [0, None]), (0.2, [1, None]), (0.4, [2, None])]
