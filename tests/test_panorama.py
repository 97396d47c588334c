"""matcher/panorama.py: an equirectangular panorama as a rig of virtual pinhole cameras.

A panorama of maps/flat.lmap rendered by the project
(``mapkit_harness.render.render_panorama``) at a known pose: the lines cut
and detected from it lie on the map segments their virtual camera projects,
no stretch of a map segment is kept by two views, the convention's
directions hold (centre column forward, clockwise, up at the top; a yaw
offset turns the rig), the cut agrees with the ZInD views'
(``mapkit_harness.panorama``), and bad input is refused in one line.
"""

from __future__ import annotations

import math
from pathlib import Path

import cv2
import numpy as np
import pytest

import matcher
from linemap.errors import InputError
from linemap.rig import Rig
from mapkit.importers.zind.annotations import ZindPano
from mapkit_harness.line_support import line_matches
from mapkit_harness.panorama import cut_view, view_directions as zind_view_directions
from mapkit_harness.render import render_panorama
from matcher.tolerances import PANORAMA_CUT
from matcher.panorama import (PanoramaRig, cut_views, direction_pixels, in_own_sector, line_azimuths,
                              panorama_lines, panorama_rig, pixel_directions, view_maps)

ROOT = Path(__file__).resolve().parents[1]
WIDTH = 1024
HEIGHT_M = 1.2
#: Robot poses (x, y, yaw_deg) on maps/flat.lmap: a room's corner, the hall, a far room.
POSES = [(2.0, 1.5, 30.0), (5.0, 4.0, -60.0)]


@pytest.fixture(scope="module")
def flat():
    return matcher.load_map(ROOT / "maps" / "flat.lmap")


@pytest.fixture(scope="module")
def panoramas(flat):
    return {pose: render_panorama(flat, pose, HEIGHT_M, WIDTH) for pose in POSES}


def _camera_pose(rc, pose):
    return rc.mount.camera_poses(np.array([pose[0], pose[1], math.radians(pose[2])]))


def test_the_convention_directions():
    """Forward at the centre column, the robot's left a quarter turn to the
    left of it (columns run clockwise), up at the top row; a yaw offset of
    +90 puts the robot's left at the centre column."""
    w = 2048
    forward, left, right, up, down = np.eye(3)[0], np.eye(3)[1], -np.eye(3)[1], np.eye(3)[2], -np.eye(3)[2]
    uv = direction_pixels(np.stack([forward, left, right, up, down]), w)
    assert np.allclose(uv[0], [(w - 1) / 2, (w / 2 - 1) / 2])
    assert np.allclose(uv[1, 0], w / 4 - 0.5) and np.allclose(uv[2, 0], 3 * w / 4 - 0.5)
    assert np.isclose(uv[3, 1], -0.5) and np.isclose(uv[4, 1], w / 2 - 0.5)
    assert np.allclose(direction_pixels(left, w, yaw_offset_deg=90.0), uv[0])
    # pixel_directions is the inverse.
    pix = np.random.default_rng(0).uniform([0, 1], [w - 1, w / 2 - 2], (50, 2))
    assert np.allclose(direction_pixels(pixel_directions(pix, w, 33.0), w, 33.0), pix)


def test_the_rig_the_cut_makes():
    rig = panorama_rig(WIDTH, HEIGHT_M)
    assert isinstance(rig, PanoramaRig) and isinstance(rig, Rig)
    cut = PANORAMA_CUT
    assert len(rig) == cut.views and rig.names[0] == "pano0"
    step = 360.0 / cut.views
    assert [rc.mount.yaw_deg for rc in rig] == [((-k * step + 180.0) % 360.0) - 180.0 for k in range(cut.views)]
    cam = rig[0].camera
    assert all(rc.camera == cam and (rc.mount.x, rc.mount.y) == (0.0, 0.0) for rc in rig)
    assert cam.height_m == HEIGHT_M and cam.pitch_deg == cut.pitch_deg
    assert math.isclose(cam.fx, WIDTH / (2 * math.pi))  # the panorama's pixels per radian
    assert math.degrees(2 * cam.horizontal_half_fov()) == pytest.approx(cut.hfov_deg, abs=0.5)
    assert math.degrees(2 * math.atan(cam.height / 2 / cam.fy)) == pytest.approx(cut.vfov_deg, abs=0.5)


@pytest.mark.parametrize("pose", POSES)
def test_lines_lie_on_the_map_segments_of_their_view(flat, panoramas, pose):
    rig = panorama_rig(WIDTH, HEIGHT_M)
    per_camera = panorama_lines(panoramas[pose], rig)
    assert len(per_camera) == len(rig)
    dists = []
    for rc, lines in zip(rig, per_camera):
        assert lines.ndim == 3 and lines.shape[1:] == (2, 2)
        _, d = line_matches(rc.camera, _camera_pose(rc, pose), flat.segments, lines)
        dists.append(d)
    d = np.concatenate(dists)
    assert len(d) >= 30
    assert np.mean(d <= 2.0) >= 0.85, np.sort(d)[-10:]
    assert sum(len(x) > 0 for x in per_camera) >= len(rig) // 2  # round the robot, not one side


def _kept_spans(flat, rig, per_camera, pose):
    """(view, segment, azimuth range (radians, robot frame)) of every kept
    line that lies on a map segment whose azimuth span from ``pose`` is
    short enough to be kept whole."""
    whole = math.radians(rig.cut.hfov_deg - rig.sector_deg) - math.radians(5.0)
    seg = flat.segments[:, :, :2] - np.array(pose[:2])
    heading = np.arctan2(seg[..., 1], seg[..., 0]) - math.radians(pose[2])
    span = np.abs(np.angle(np.exp(1j * (heading[:, 1] - heading[:, 0]))))
    out = []
    for k, (rc, lines) in enumerate(zip(rig, per_camera)):
        idx, _ = line_matches(rc.camera, _camera_pose(rc, pose), flat.segments, lines)
        az = line_azimuths(lines, rc)
        for i, a in zip(idx, az):
            if i >= 0 and span[i] <= whole:
                lo = a[0] + min(0.0, np.angle(np.exp(1j * (a[1] - a[0]))))
                out.append((k, int(i), lo, lo + abs(np.angle(np.exp(1j * (a[1] - a[0]))))))
    return out


def _twice(spans) -> list:
    """Pairs of kept lines of different views on one segment whose azimuth ranges overlap by over a degree."""
    bad = []
    for n, (k1, s1, lo1, hi1) in enumerate(spans):
        for k2, s2, lo2, hi2 in spans[n + 1:]:
            shift = np.angle(np.exp(1j * (lo2 - lo1)))  # lo2 seen from lo1, the short way
            overlap = min(hi1 - lo1, shift + hi2 - lo2) - max(0.0, shift)
            if k1 != k2 and s1 == s2 and overlap > math.radians(1.0):
                bad.append((k1, k2, s1, math.degrees(overlap)))
    return bad


@pytest.mark.parametrize("pose", POSES)
def test_no_map_segment_is_kept_by_two_views(flat, panoramas, pose):
    rig = panorama_rig(WIDTH, HEIGHT_M)
    kept = panorama_lines(panoramas[pose], rig)
    assert not _twice(_kept_spans(flat, rig, kept, pose))
    # Without the sector rule the overlapping views do see lines twice (the test can fail).
    every = [matcher.detect_lines(v, rc.camera) for rc, v in zip(rig, cut_views(panoramas[pose], rig))]
    assert _twice(_kept_spans(flat, rig, every, pose))


def test_a_line_is_kept_by_the_one_view_whose_sector_holds_its_middle():
    rig = panorama_rig(WIDTH, HEIGHT_M)
    rng = np.random.default_rng(1)
    # Vertical lines at random headings: each seen by two or three views, kept by one.
    headings = rng.uniform(-math.pi, math.pi, 200)
    keepers = np.zeros(len(headings), dtype=int)
    for rc in rig:
        d = np.stack([np.cos(headings), np.sin(headings)], axis=1)
        ends = np.stack([np.column_stack([d, np.full(len(d), 0.3)]), np.column_stack([d, np.full(len(d), -0.3)])], 1)
        cam_dirs = ends @ rc.camera.world2cam(rc.mount.yaw).T  # robot frame -> camera frame
        in_front = (cam_dirs[..., 2] > 0).all(axis=1)
        uv = cam_dirs[..., :2] / cam_dirs[..., 2:] * rc.camera.fx + [rc.camera.cx, rc.camera.cy]
        seen = in_front & (uv[..., 0] >= 0).all(1) & (uv[..., 0] <= rc.camera.width).all(1)
        keepers += seen & in_own_sector(uv, rc, rig.sector_deg)
    assert (keepers == 1).all()


def test_a_yaw_offset_turns_the_rig_as_rolling_the_image_does(panoramas):
    """Rolling the panorama right by W/4 columns is the same panorama taken
    with a yaw offset 90 degrees larger: the rig's headings turn by 90
    degrees and each view sees what the unrolled panorama's view at the same
    robot-frame heading sees."""
    pano = panoramas[POSES[0]]
    rolled = np.roll(pano, WIDTH // 4, axis=1)
    rig0, rig90 = panorama_rig(WIDTH, HEIGHT_M), panorama_rig(WIDTH, HEIGHT_M, yaw_offset_deg=90.0)
    turn = [((rc.mount.yaw_deg + 90.0 + 180.0) % 360.0) - 180.0 for rc in rig0]
    assert [rc.mount.yaw_deg for rc in rig90] == pytest.approx(turn)
    views0, views90 = cut_views(pano, rig0), cut_views(rolled, rig90)
    by_heading0 = {round(rc.mount.yaw_deg) % 360: v for rc, v in zip(rig0, views0)}
    for rc, v in zip(rig90, views90):
        same = by_heading0[round(rc.mount.yaw_deg) % 360]
        assert np.abs(v.astype(int) - same).max() <= 1
    lines0 = {round(rc.mount.yaw_deg) % 360: x for rc, x in zip(rig0, panorama_lines(pano, rig0))}
    for rc, x in zip(rig90, panorama_lines(rolled, rig90)):
        y = lines0[round(rc.mount.yaw_deg) % 360]
        assert len(x) == len(y) and np.allclose(np.sort(x.reshape(len(x), -1), 0), np.sort(y.reshape(len(y), -1), 0),
                                                atol=0.5)


def test_a_colour_panorama_cuts_to_colour_views(panoramas):
    rig = panorama_rig(WIDTH, HEIGHT_M)
    colour = cv2.cvtColor(panoramas[POSES[0]], cv2.COLOR_GRAY2BGR)
    views = cut_views(colour, rig)
    assert views[0].shape == (rig[0].camera.height, rig[0].camera.width, 3) and views[0].dtype == np.uint8
    assert [len(x) for x in panorama_lines(colour, rig)] == [len(x) for x in panorama_lines(panoramas[POSES[0]], rig)]


@pytest.mark.parametrize("rotation", [0.0, 37.0, -112.0])
def test_the_cut_agrees_with_the_zind_views(rotation):
    """A ZInD panorama of plan rotation r looks along world heading -90 - r
    at its centre column (its local frame is mirrored and turned); views cut
    at the same world heading by mapkit_harness.panorama (ZInD's pixels: the
    full turn over W - 1 columns) and by matcher.panorama (over W columns)
    sample the panorama within half a pixel of each other."""
    w = 1024
    pano = ZindPano("pano_1", "room", "", "", np.array([2.0, 1.5]), rotation, 1.4, True, True)
    robot_heading = -90.0 - rotation
    rig = panorama_rig(w, pano.camera_height)
    u, v = np.meshgrid(np.arange(w) * 2 * math.pi / w, np.arange(w // 2) * 2 * math.pi / w)
    smooth = (128 + 50 * np.sin(4 * u + 1) * np.cos(3 * v) + 30 * np.cos(9 * u - 2 * v)).astype(np.float32)  # seamless
    for rc in rig:
        world_yaw = math.radians(robot_heading + rc.mount.yaw_deg)
        zind_uv = pano.pixel_of(pano.local_directions(zind_view_directions(rc.camera, world_yaw).reshape(-1, 3)), w)
        map_u, map_v = view_maps(rc, w)
        du = np.angle(np.exp(2j * math.pi * (zind_uv[:, 0] - map_u.ravel()) / w)) * w / (2 * math.pi)
        dv = zind_uv[:, 1] - map_v.ravel()
        assert np.abs(du).max() <= 0.5 + 1e-3 and np.abs(dv).max() <= 0.5 + 1e-3
        a = cut_view(smooth, pano, rc.camera, world_yaw)
        b = cut_views(smooth, PanoramaRig((rc,), 0.0, rig.cut))[0]
        assert np.abs(a - b).max() < 3.0  # grey levels of a smooth image half a pixel apart


@pytest.mark.parametrize("bad, says", [
    (np.zeros((100, 150), np.uint8), "twice as wide as high"),
    (np.zeros((0, 0), np.uint8), "empty"),
    (np.zeros((64, 128), np.complex128), "dtype"),
    (np.zeros((64, 128), object), "dtype"),
    (np.zeros((64, 128, 2), np.uint8), "shape"),
    ([[0, 0], [0, 0]], "image array"),
    (np.full((64, 128), np.nan, np.float32), "non-finite"),
])
def test_bad_panoramas_are_refused_in_one_line(bad, says):
    rig = panorama_rig(128, HEIGHT_M)
    for call in (cut_views, panorama_lines):
        with pytest.raises(InputError) as exc:
            call(bad, rig)
        assert says in str(exc.value) and "\n" not in str(exc.value)


@pytest.mark.parametrize("kwargs, says", [
    ({"pano_width": 1001}, "even"), ({"pano_width": 32}, "even"), ({"views": 2}, "views"),
    ({"hfov_deg": 40.0}, "gaps"), ({"height_m": -1.0}, "height_m"), ({"yaw_offset_deg": math.nan}, "yaw offset"),
    ({"vfov_deg": 175.0}, "vfov_deg"),
])
def test_bad_cuts_are_refused_in_one_line(kwargs, says):
    args = {"pano_width": 1024, "height_m": HEIGHT_M, **kwargs}
    with pytest.raises(InputError) as exc:
        panorama_rig(**args)
    assert says in str(exc.value) and "\n" not in str(exc.value)


def test_a_rig_cuts_its_panoramas_with_maps_computed_once():
    # A stream's panoramas share one rig: the views' remap maps are computed
    # for the first and reused, read-only, and every cut equals a fresh one.
    from matcher.panorama import _kept_view_maps

    rng = np.random.default_rng(4)
    rig = panorama_rig(256, 1.2, yaw_offset_deg=30.0)
    first, second = (rng.integers(0, 255, (128, 256), dtype=np.uint8) for _ in range(2))
    cut_views(first, rig)
    before = _kept_view_maps.cache_info()
    kept = cut_views(second, rig)
    after = _kept_view_maps.cache_info()
    assert after.hits - before.hits == len(rig) and after.misses == before.misses
    for rc, view in zip(rig, kept):
        map_u, map_v = view_maps(rc, 256, 30.0)
        fresh = cv2.remap(second, map_u, map_v, interpolation=cv2.INTER_LINEAR, borderMode=cv2.BORDER_WRAP)
        assert np.array_equal(view, fresh)
    assert not _kept_view_maps(rig[0], 256, 30.0)[0].flags.writeable


def test_a_plain_rig_is_refused_by_the_cut(panoramas):
    with pytest.raises(InputError, match="panorama_rig"):
        cut_views(panoramas[POSES[0]], Rig.single(matcher.Camera.from_fov(60, 64, 48, 1.2, 0)))


def test_matcher_exports_the_cut():
    import matcher.panorama as module

    assert {"panorama_rig", "panorama_lines"} <= set(matcher.__all__)
    assert matcher.panorama_rig is module.panorama_rig and matcher.panorama_lines is module.panorama_lines


def test_the_render_command_writes_a_panorama(tmp_path, flat):
    from render import main as render_main  # tools/render.py, the script

    out = tmp_path / "pano.png"
    assert render_main(["--pose", "2.0,1.5,30", "--pano", "256", "--supersample", "1", "--camera-height", "1.2",
                        "--pano-yaw-offset", "-90", "-o", str(out)]) == 0
    image = cv2.imread(str(out), cv2.IMREAD_GRAYSCALE)
    assert image.shape == (128, 256)
    assert (image == render_panorama(flat, (2.0, 1.5, 30.0), 1.2, 256, -90.0, supersample=1)).all()
    assert render_main(["--pose", "2.0,1.5,30", "--pano", "255", "-o", str(out)]) == 2


@pytest.mark.parametrize("argv, says", [
    (["--cuts", "8x90"], "--cuts must be"), (["--cuts", "8x30x110"], "gaps"), ([], "no zind_data.json"),
])
def test_the_cut_benchmark_refuses_bad_arguments_in_one_line(tmp_path, capsys, argv, says):
    import bench_pano_cut  # tools/bench_pano_cut.py

    assert bench_pano_cut.main([str(tmp_path), *argv]) == 2
    err = capsys.readouterr().err
    assert says in err and err.count("\n") == 1
