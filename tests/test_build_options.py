"""BuildOptions: each field's flag, default and allowed values written once
(mapkit/options.py), the commands' flags generated from them, the values
checked on construction."""

from __future__ import annotations

import math
from dataclasses import fields

import pytest

from mapkit.cli import build_parser
from mapkit.commands import build as build_command
from mapkit.commands._import_args import import_options_from_args
from mapkit.errors import MapkitError
from mapkit.parallel import default_jobs
from mapkit.options import (
    DEFAULT_HFOV_DEG,
    DEFAULT_IMAGE_SIZE,
    IMPORT_GROUPS,
    BuildOptions,
    Range,
    default_camera,
    flags_of,
)

#: A valid value other than the default, per field type (as typed on the
#: command line, and as the field then holds it).
ARGV_VALUE = {"bool": (None, True), "float": ("0.35", 0.35), "int": ("3", 3), "int | None": ("2", 2), "float | None": ("12.5", 12.5), "str | None": ("cm", "cm"), "list[str]": ("A*", ["A*"])}
#: Fields whose sample value the generic one does not fit.
SPECIAL = {"floor_name": ("floor_02", "floor_02"), "up": ("y", "y"), "max_entities": ("500", 500),
           "wall_height": ("3.5", 3.5), "window_sill": ("0.5", 0.5), "window_head": ("2.2", 2.2),
           "jobs": (str(default_jobs() + 1), default_jobs() + 1)}


def _parse(command: str, *argv: str):
    return build_parser().parse_args([command, "plan.dxf", *(["-o", "o.lmap"] if command != "layers" else []), *argv])


def _flagged():
    return [f for f in fields(BuildOptions) if flags_of(f)]


@pytest.mark.parametrize("f", _flagged(), ids=lambda f: f.name)
def test_every_flag_parses_to_its_field(f):
    text, value = SPECIAL.get(f.name) or ARGV_VALUE[f.type]
    args = _parse("build", flags_of(f)[-1], *([] if text is None else [text]))  # a switch takes no value
    options = build_command.options_from_args(args)
    assert getattr(options, f.name) == value
    assert getattr(options, f.name) != getattr(BuildOptions(), f.name)
    for other in fields(BuildOptions):  # and nothing else moved
        if other.name not in (f.name, "camera", "camera_from_source"):
            assert getattr(options, other.name) == getattr(BuildOptions(), other.name), other.name


def test_fields_without_a_flag_say_what_sets_them():
    unflagged = {f.name: f.metadata["help"] for f in fields(BuildOptions) if not flags_of(f)}
    assert set(unflagged) == {"camera", "camera_from_source"}
    assert all("--camera" in text for text in unflagged.values())


@pytest.mark.parametrize("command", ["build", "preview", "extrude", "layers"])
def test_defaults_on_the_command_line_are_the_fields_defaults(command):
    args = _parse(command)
    parsed = build_command.options_from_args(args) if command == "build" else import_options_from_args(args)
    assert parsed == BuildOptions()
    # Every import flag is on every command that reads a plan; its help shows the default.
    p = build_parser()._subparsers._group_actions[0].choices[command]
    by_flag = {s: a for a in p._actions for s in a.option_strings}
    for f in fields(BuildOptions):
        if f.metadata["group"] in IMPORT_GROUPS:
            action = by_flag[flags_of(f)[0]]
            assert action.dest == f.name
            default = getattr(BuildOptions(), f.name)
            if isinstance(default, float):
                assert f"default {default:g}" in action.help


def test_the_default_camera_is_the_default_field_of_view():
    cam = default_camera()
    assert (cam["width"], cam["height"]) == DEFAULT_IMAGE_SIZE
    assert cam["fx"] == cam["fy"] == 457.0  # 70 degrees over 640 pixels, to the pixel
    assert math.degrees(2 * math.atan(cam["width"] / 2 / cam["fx"])) == pytest.approx(DEFAULT_HFOV_DEG, abs=0.01)
    assert BuildOptions().camera == cam
    args = _parse("build", "--hfov", str(DEFAULT_HFOV_DEG))
    assert build_command.options_from_args(args).camera["fx"] == pytest.approx(457.0, abs=0.05)


@pytest.mark.parametrize("kwargs, message", [
    ({"eps": 0.0}, "--eps must be in (0, 0.5] metres, got 0.0 (BuildOptions.eps)"),
    ({"eps": 0.7}, "--eps must be in (0, 0.5] metres"),
    ({"scale": -2.0}, "--scale must be > 0, got -2.0 (BuildOptions.scale)"),
    ({"max_range": float("nan")}, "--max-range must be > 0 metres"),
    ({"robot_radius": -0.1}, "--robot-radius must be >= 0 metres"),
    ({"crease_deg": 180.0}, "--crease-deg must be in (0, 180) degrees"),
    ({"merge_growth": 11.0}, "--merge-growth must be in [0, 10]"),
    ({"jobs": 0}, "-j/--jobs must be >= 1, got 0 (BuildOptions.jobs)"),
    ({"jobs": 1.5}, "-j/--jobs must be an integer, got 1.5 (BuildOptions.jobs)"),
    ({"max_entities": True}, "--max-entities must be an integer"),
    ({"wall_height": "2"}, "--wall-height must be a number, got '2' (BuildOptions.wall_height)"),
    ({"walls": "Walls"}, "--walls must be a list of layer names"),
    ({"up": "x"}, "--up must be one of auto, z, y, got 'x' (BuildOptions.up)"),
    ({"units": "furlong"}, "unknown units 'furlong'"),
    ({"camera_from_source": 1}, "camera_from_source must be True or False, got 1 (BuildOptions.camera_from_source)"),
    ({"camera": {"width": 640}}, "BuildOptions.camera (set by --camera"),
    ({"door_height": 3.0}, "--door-height 3 must be in (0, --wall-height 2.5]"),
    ({"window_sill": 2.2}, "0 <= --window-sill < --window-head <= --wall-height"),
])
def test_invalid_values_are_refused_in_one_line(kwargs, message):
    with pytest.raises(MapkitError) as e:
        BuildOptions(**kwargs)
    assert message in str(e.value) and "\n" not in str(e.value)


def test_values_set_after_construction_are_checked_by_the_build(tmp_path):
    from mapkit.pipeline import build_map

    options = BuildOptions()
    options.eps = -1.0
    with pytest.raises(MapkitError, match="--eps must be"):
        build_map(tmp_path / "never-read.dxf", options)


def test_ranges_read_as_they_check():
    r = Range(0.0, 0.5, lo_open=True, unit="metres")
    assert str(r) == "in (0, 0.5] metres" and not r.holds(0.0) and r.holds(0.5) and not r.holds(math.inf)
    assert str(Range(1)) == ">= 1" and Range(1).holds(1) and not Range(1).holds(0)
