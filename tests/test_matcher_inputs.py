"""Every bad-input branch: a clear error (bad input) or a falsy result with
its reason (a failed estimate), never a crash."""

from __future__ import annotations

import json
import warnings

import numpy as np
import pytest

import matcher
from mapkit_harness.plans import make_box_map
from linemap.camera import Camera, CameraError
from mapkit_harness.simulate import make_frame, paper_camera


@pytest.fixture(scope="module")
def box():
    return make_box_map()


@pytest.fixture(scope="module")
def good_lines(box, cam):
    return make_frame(box, cam, np.random.default_rng(2), 2, min_seen=3).lines


def test_nan_line_is_rejected(box, cam, good_lines):
    lines = good_lines.copy()
    lines[1, 0, 1] = np.nan
    with pytest.raises(ValueError, match=r"lines\[1\] is not finite"):
        matcher.localize(box, cam, lines, (3, 2.5, 0), 0.5, 20)


def test_zero_length_line_is_rejected(box, cam, good_lines):
    lines = good_lines.copy()
    lines[2, 1] = lines[2, 0]
    with pytest.raises(ValueError, match=r"lines\[2\] has zero length"):
        matcher.localize(box, cam, lines, (3, 2.5, 0), 0.5, 20)


def test_out_of_image_line_is_rejected(box, cam, good_lines):
    lines = good_lines.copy()
    lines[0, 1] = [900.0, 100.0]
    with pytest.raises(ValueError, match=r"lines\[0\] .* lies outside the 640x480 image"):
        matcher.localize(box, cam, lines, (3, 2.5, 0), 0.5, 20)


@pytest.mark.parametrize("bad", [np.zeros((3, 3)), np.zeros((2, 3, 2)), "lines", [[1, 2, 3]], np.zeros((5, 0)),
                                 np.zeros((0, 3))])
def test_wrong_shape_is_rejected(box, cam, bad):
    with pytest.raises(ValueError, match=r"Expected shape \(M, 2, 2\) or \(M, 4\)"):
        matcher.localize(box, cam, bad, (3, 2.5, 0), 0.5, 20)


def test_numbers_beyond_float_are_rejected_in_one_line(box, cam):
    with pytest.raises(ValueError, match="lines must be numbers"):
        matcher.localize(box, cam, [[10**400, 1, 2, 3]] * 3, (3, 2.5, 0), 0.5, 20)
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # no overflow warning on the way to the message
        with pytest.raises(ValueError, match=r"lines\[0\] = \[1e\+308, .* lies outside"):
            matcher.localize(box, cam, [[1e308, 1e308, 2, 3]] * 3, (3, 2.5, 0), 0.5, 20)


@pytest.mark.parametrize(
    "prior, dt, dyaw, msg",
    [
        ((1.0, 2.0), 0.5, 20, "prior must be 3 finite numbers"),
        ((1.0, np.nan, 0.0), 0.5, 20, "prior must be 3 finite numbers"),
        ((1.0, 2.0, 0.0), 0.0, 20, r"dt must be in \(0, 100\] metres"),
        ((1.0, 2.0, 0.0), -1.0, 20, r"dt must be in \(0, 100\] metres"),
        ((1.0, 2.0, 0.0), 0.5, 0.0, r"dyaw must be in \(0, 180\] degrees"),
        ((1.0, 2.0, 0.0), 0.5, 270.0, r"dyaw must be in \(0, 180\] degrees"),
        ((1.0, 2.0, 0.0), "far", 20, "dt and dyaw must be numbers"),
    ],
)
def test_bad_prior_is_rejected(box, cam, good_lines, prior, dt, dyaw, msg):
    with pytest.raises(ValueError, match=msg):
        matcher.localize(box, cam, good_lines, prior, dt, dyaw)


def test_prior_beyond_any_map_and_headings_of_many_turns(box, cam, good_lines):
    with pytest.raises(ValueError, match="more than 1000 km out"):
        matcher.localize(box, cam, good_lines, (1e300, 2.0, 0.0), 0.5, 20)
    a = matcher.localize(box, cam, good_lines, (3, 2.5, 10.0), 0.5, 20)
    b = matcher.localize(box, cam, good_lines, (3, 2.5, 10.0 + 360.0 * 10**6), 0.5, 20)
    assert a.pose == pytest.approx(b.pose)


@pytest.mark.parametrize("which, value, msg", [
    ("linemap", "maps/flat.lmap", r"linemap must be a map from matcher.load_map"),
    ("camera", {"width": 640}, r"camera must be a matcher.Camera"),
    ("tolerances", {"line_px": 2}, r"tolerances must be a matcher.Tolerances"),
])
def test_arguments_of_the_wrong_type(box, cam, good_lines, which, value, msg):
    kwargs = {"linemap": box, "camera": cam, "tolerances": None, which: value}
    with pytest.raises(ValueError, match=msg):
        matcher.localize(kwargs["linemap"], kwargs["camera"], good_lines, (3, 2.5, 0), 0.5, 20,
                         tolerances=kwargs["tolerances"])
    with pytest.raises(ValueError, match=msg):
        matcher.localize_global(kwargs["linemap"], kwargs["camera"], good_lines, tolerances=kwargs["tolerances"])


def test_lost_mode_says_when_the_lines_are_too_few(box, cam, good_lines):
    res = matcher.localize_global(box, cam, good_lines[:2])
    assert not res and res.reason.startswith("only 2 usable image lines")
    assert res.to_dict()["time_ms"]["regions_tried"] == 0 and isinstance(res.to_dict()["time_ms"]["regions_tried"], int)


def test_prior_outside_the_map_is_a_falsy_result(box, cam, good_lines):
    res = matcher.localize(box, cam, good_lines, (50.0, 50.0, 0.0), 0.5, 20)
    assert not res and res.pose is None
    assert "farther than dt=0.5 m from every region" in res.reason
    assert res.to_dict()["ok"] is False and res.to_dict()["reason"] == res.reason


def test_no_candidate_segments_is_a_falsy_result(cam, good_lines):
    """A map whose region lists are empty: nothing to match."""
    from shapely.geometry import box as sbox

    from mapkit.assemble import assemble_map

    m = make_box_map()
    empty = assemble_map(m.segments, m.kinds, [sbox(0.2, 0.2, 5.8, 4.8)], [np.zeros(0, dtype=np.int64)],
                         sbox(-1, -1, 7, 6).difference(sbox(0, 0, 6, 5)), {"wall_height": 2.5})
    res = matcher.localize(empty, cam, good_lines, (3.0, 2.5, 0.0), 0.5, 20)
    assert not res and "no model segment is visible" in res.reason


def test_segments_out_of_view_is_a_falsy_result(cam, good_lines):
    """Candidates exist but none can be in view for the prior's headings."""
    from shapely.geometry import box as sbox

    from mapkit.assemble import assemble_map

    seg = np.array([[[-5.0, 2.0, 0.0], [-5.0, 3.0, 0.0]]])  # far behind a camera heading +x
    m = assemble_map(seg, np.array([0]), [sbox(0, 0, 6, 5)], [np.array([0])], sbox(-9, -9, -8, -8), {})
    res = matcher.localize(m, cam, good_lines, (3.0, 2.5, 0.0), 0.3, 10)
    assert not res and "field of view" in res.reason


def test_too_few_lines_is_a_falsy_result(box, cam):
    res = matcher.localize(box, cam, [[10, 10, 300, 20], [5, 5, 9, 9]], (3.0, 2.5, 0.0), 0.5, 20)
    assert not res and "usable image lines" in res.reason


def test_empty_lines_is_a_falsy_result(box, cam):
    res = matcher.localize(box, cam, np.zeros((0, 4)), (3.0, 2.5, 0.0), 0.5, 20)
    assert not res and res.reason


def test_camera_type_is_checked(box, good_lines):
    with pytest.raises(ValueError, match="camera must be a matcher.Camera"):
        matcher.localize(box, {"fx": 900}, good_lines, (3.0, 2.5, 0.0), 0.5, 20)


def test_camera_file_with_missing_fields(tmp_path):
    p = tmp_path / "cam.json"
    p.write_text(json.dumps({"width": 640, "height": 480, "fx": 900}))
    with pytest.raises(CameraError, match="camera description lacks fy, cx, cy, height_m, pitch_deg"):
        Camera.load(p)


@pytest.mark.parametrize(
    "change, msg",
    [
        ({"fx": -1}, "fx and fy must be positive"),
        ({"height_m": 0}, "height_m must be above the floor"),
        ({"pitch_deg": 95}, r"pitch_deg must be in \[-89, 89\]"),
        ({"width": "wide"}, "camera width must be a number, got 'wide'"),
        ({"width": "640"}, "camera width must be a number"),
        ({"width": True}, "camera width must be a number, got True"),
        ({"width": 640.5}, "width and height must be whole pixels"),
        ({"width": float("inf")}, "camera width must be finite"),
        ({"fx": 10**400}, "camera fx is out of range"),
        ({"fy": None}, "camera fy must be a number, got None"),
        ({"distortion": [0.1, 0.2, 0.3]}, "distortion takes 4, 5, 8, 12 or 14"),
        ({"distortion": [0.1, "x", 0.0, 0.0]}, "camera distortion must be a number"),
        ({"distortion": 0.1}, "distortion must be a list of numbers"),
    ],
)
def test_camera_bad_values(change, msg):
    d = {**paper_camera().to_dict(), **change}
    with pytest.raises(CameraError, match=msg):
        Camera.from_dict(d)


def test_camera_round_trip(tmp_path):
    cam = Camera.from_dict({**paper_camera().to_dict(), "distortion": [0.01, -0.002, 0.0, 0.0]})
    p = tmp_path / "c.json"
    p.write_text(json.dumps(cam.to_dict()))
    assert Camera.load(p) == cam


def test_camera_constructor_rejects_wrong_types():
    with pytest.raises(CameraError, match="camera width must be a number"):
        Camera("640", 480, 900.0, 900.0, 320.0, 240.0, 1.2, 0.0)
    with pytest.raises(CameraError, match="whole pixels"):
        Camera(640.5, 480, 900.0, 900.0, 320.0, 240.0, 1.2, 0.0)
    assert Camera(np.int64(640), 480, np.float32(900.0), 900.0, 320.0, 240.0, 1.2, 0.0).width == 640


def test_camera_file_that_is_a_directory_or_too_deep(tmp_path):
    with pytest.raises(CameraError, match="is a directory"):
        Camera.load(tmp_path)
    p = tmp_path / "deep.json"
    p.write_text("[" * 100_000 + "]" * 100_000)
    with pytest.raises(CameraError, match="not valid JSON"):
        Camera.load(p)


def test_tolerances_are_validated():
    with pytest.raises(ValueError, match="yaw_step_deg must be in"):
        matcher.Tolerances(yaw_step_deg=0)
    with pytest.raises(ValueError, match="min_matches must be >= 2"):
        matcher.Tolerances(min_matches=1)


def test_lines_a_little_outside_the_image_are_cut_and_used(cam):
    from matcher.input_validation import check_lines
    from matcher.tolerances import DEFAULT

    lines = np.array([[[600.0, 100.0], [680.0, 100.0]],  # 40 px past the right border: cut at 640 + 5 margin
                      [[10.0, -3.0], [200.0, -3.0]],  # within the 5 px margin: as it is
                      [[100.0, 200.0], [300.0, 400.0]]])
    out = check_lines(lines, cam, DEFAULT)
    assert out.shape == lines.shape
    assert out[0].tolist() == [[600.0, 100.0], [645.0, 100.0]]
    assert (out[1:] == lines[1:]).all()


def test_lines_wholly_outside_or_too_many_are_refused(cam):
    from dataclasses import replace

    from matcher.input_validation import check_lines
    from matcher.tolerances import DEFAULT

    beside = np.array([[[660.0, 100.0], [700.0, 120.0]]])  # near, but no part inside
    with pytest.raises(ValueError, match=r"lines\[0\] .* lies wholly outside the 640x480 image"):
        check_lines(beside, cam, DEFAULT)
    many = np.tile([[[10.0, 10.0], [50.0, 50.0]]], (11, 1, 1))
    with pytest.raises(ValueError, match="11 image lines given, the matcher takes at most 10"):
        check_lines(many, cam, replace(DEFAULT, max_lines=10))
