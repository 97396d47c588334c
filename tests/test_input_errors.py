"""Bad input and bugs are told apart (linemap.errors).

Every check of what a user gives raises an InputError (a ValueError); the
command lines print it as one line and exit 2. Any other exception is a bug
of ours: one line asking for a report, exit 3, its traceback with --debug;
and the fuzz campaign counts it as a bug, not as a clean error, even when it
is a one-line ValueError. The injected-bug tests below make an internal
function raise what a numpy slip raises and check all three."""

from __future__ import annotations

import json
import math
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

import linemap
import mapkit
import matcher
from linemap.camera import Camera, CameraError
from linemap.errors import EXIT_BUG, InputError
from linemap.lmap import LmapError, load_map
from mapkit.errors import MapkitError, NoFreeSpaceError, NoWallsError
from mapkit.options import BuildOptions
from mapkit_harness.fuzz.cases import Case
from mapkit_harness.fuzz.classify import BUG, ERROR, VALID, classify_cli
from mapkit_harness.fuzz.matcher_inputs import base_camera, base_frame, base_run
from mapkit_harness.fuzz.run import run_case_here
from mapkit_harness.fuzz.segments import base_segments_csv, segments_case

ROOT = Path(__file__).resolve().parents[1]
#: What numpy says when shapes do not match: a ValueError, and a bug when it escapes.
NUMPY_SLIP = "operands could not be broadcast together with shapes (3,2) (4,2)"


def _numpy_slip(*args, **kwargs):
    raise ValueError(NUMPY_SLIP)


# ---- the error classes -----------------------------------------------------------


def test_every_error_of_bad_input_is_an_input_error():
    from matcher.cli import UsageError
    from matcher.tracking.rosbag import BagError

    for cls in (LmapError, CameraError, MapkitError, NoWallsError, NoFreeSpaceError, BagError, UsageError):
        assert issubclass(cls, InputError), cls
    assert issubclass(InputError, ValueError)  # code that catches ValueError keeps catching bad input
    assert linemap.InputError is mapkit.InputError is matcher.InputError is InputError


def test_the_matchers_input_checks_raise_input_errors():
    from matcher.tolerances import LineDetection, Stage1Constants, Stage2Constants, Tolerances, Tracking

    m = load_map(ROOT / "maps" / "flat.lmap")
    cam = Camera.from_dict(base_camera())
    good = [[10.0, 10.0, 100.0, 100.0], [200.0, 50.0, 200.0, 300.0]]
    bad_calls = [
        lambda: matcher.localize(m, cam, [[1, 2, 3]], (2.0, 6.6, 0.0), 0.3, 10),  # lines of a wrong shape
        lambda: matcher.localize(m, cam, [[np.nan, 1, 2, 3]], (2.0, 6.6, 0.0), 0.3, 10),
        lambda: matcher.localize(m, cam, good, (math.nan, 6.6, 0.0), 0.3, 10),  # the prior
        lambda: matcher.localize(m, cam, good, (2.0, 6.6, 0.0), -1.0, 10),
        lambda: matcher.localize(m, "camera.json", good, (2.0, 6.6, 0.0), 0.3, 10),  # the types
        lambda: matcher.localize(m, cam, good, (2.0, 6.6, 0.0), 0.3, 10, tolerances={"dt": 1}),
        lambda: matcher.detect_lines(np.zeros((0, 0)), cam),
        lambda: Tolerances(yaw_step_deg=0.0),
        lambda: Tolerances(stage1=Stage2Constants()),  # a consumer's constants in another's place
        lambda: Stage1Constants(pinned_m=-0.1),
        lambda: Stage1Constants(grid_sight_samples=(0.5, "1")),
        lambda: Tracking(max_candidates=0),
        lambda: LineDetection(merge_sample_px=0.0),
        lambda: matcher.Tracker(m, cam, (2.0, 6.6, 0.0), None, None),
        lambda: m.regions_near(math.nan, 0.0, 0.0),
    ]
    for call in bad_calls:
        with pytest.raises(InputError):
            call()


def test_the_former_single_class_of_inner_constants_says_where_they_went():
    """Code written for ``Internals`` / ``Tolerances.internals`` fails at
    once, saying the constants kept their names under ``tol.stage1`` and
    the others, not with a bare "cannot import"."""
    import matcher.tolerances as t

    with pytest.raises(ImportError, match="split by consumer"):
        from matcher.tolerances import Internals  # noqa: F401
    with pytest.raises(ImportError, match="split by consumer"):
        t.DEFAULT_INTERNALS
    with pytest.raises(AttributeError, match=r"Tolerances\.map_index, \.shared, \.stage1"):
        t.DEFAULT.internals
    with pytest.raises(TypeError):
        t.Tolerances(internals=None)
    assert t.constants_owner("pinned_m") == "stage1" and t.constants_owner("vote_places") == "lost"
    with pytest.raises(InputError, match="no inner constant is named 'pinned'"):
        t.constants_owner("pinned")


# ---- an injected bug: the command lines --------------------------------------------


def _build(main, tmp_path, *flags):
    return main([*flags, "build", str(ROOT / "maps" / "flat.dxf"), "-o", str(tmp_path / "out.lmap")])


@pytest.mark.slow
def test_a_bug_in_build_map_is_reported_as_a_bug_not_as_bad_input(tmp_path, capsys, monkeypatch):
    """The issue's case: a broadcasting slip inside build_map came out as
    'mapkit: error: operands could not be broadcast together', exit 2."""
    import mapkit.edges
    from mapkit.cli import main

    monkeypatch.setattr(mapkit.edges, "extract_edges", _numpy_slip)
    assert _build(main, tmp_path) == EXIT_BUG
    err = capsys.readouterr().err
    lines = [ln for ln in err.splitlines() if not ln.startswith("mapkit: warning:")]
    assert len(lines) == 1 and lines[0].startswith("mapkit: internal error: ValueError: operands could not")
    assert "please report" in err and "--debug" in err and "Traceback" not in err
    assert not (tmp_path / "out.lmap").exists()

    for flags in (["--debug"], []):  # before the command, or after it
        code = main([*flags, "build", str(ROOT / "maps" / "flat.dxf"), "-o", str(tmp_path / "out.lmap"),
                     *([] if flags else ["--debug"])])
        err = capsys.readouterr().err
        assert code == EXIT_BUG
        assert "Traceback (most recent call last)" in err and "_numpy_slip" in err
        assert err.strip().splitlines()[-1].startswith("mapkit: internal error: ValueError:")


def test_bad_input_still_exits_2_in_one_line(tmp_path, capsys):
    from mapkit.cli import main

    assert main(["build", str(ROOT / "maps" / "flat.dxf"), "-o", str(tmp_path / "out.lmap"),
                 "--robot-radius", "-1"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("mapkit: error: ") and len(err.strip().splitlines()) == 1


# ---- messages name what the user typed, not the code's names behind it ---------


@pytest.mark.parametrize("flags, message", [
    (["--max-range", "0"], "--max-range must be > 0 metres, got 0.0"),
    (["-j", "0"], "-j/--jobs must be >= 1, got 0"),
    (["--camera-height", "-1"], "--camera-height must be above the floor (> 0 m), got -1.0"),
    (["--camera-height", "nan"], "--camera-height must be finite, got nan"),
    (["--pitch", "100"], "--pitch must be in [-89, 89] (positive looks down), got 100.0"),
    (["--hfov", "0"], "--hfov (horizontal field of view) must be in [1, 179) degrees, got 0.0"),
])
def test_mapkit_build_names_the_flag_typed(tmp_path, capsys, flags, message):
    from mapkit.cli import main

    assert main(["build", str(ROOT / "maps" / "flat.dxf"), "-o", str(tmp_path / "out.lmap"), *flags]) == 2
    assert capsys.readouterr().err == f"mapkit: error: {message}\n"
    assert not (tmp_path / "out.lmap").exists()


def test_build_options_from_python_name_the_field_too():
    with pytest.raises(MapkitError) as e:
        BuildOptions(max_range=0.0)
    assert str(e.value) == "--max-range must be > 0 metres, got 0.0 (BuildOptions.max_range)"


def test_a_camera_file_s_own_value_keeps_the_field_s_name():
    from linemap.camera import naming_flags

    with pytest.raises(CameraError, match=r"^camera height_m must be above the floor"):
        with naming_flags({"height_m": None, "pitch_deg": "--pitch-deg"}):
            Camera.from_dict({**base_camera(), "height_m": -1.0})
    with pytest.raises(CameraError, match=r"^--pitch-deg must be in \[-89, 89\]"):
        with naming_flags({"height_m": None, "pitch_deg": "--pitch-deg"}):
            Camera.from_dict({**base_camera(), "pitch_deg": 95.0})


@pytest.mark.parametrize("camera, message", [
    (["--camera", "CAMERA", "--height-m", "-1"], "--height-m must be above the floor (> 0 m), got -1.0"),
    (["--camera", "CAMERA", "--pitch-deg", "95"], "--pitch-deg must be in [-89, 89] (positive looks down), got 95.0"),
    (["--camera-k", "457,457,320,240", "--image-size", "640x480", "--height-m", "-1"],
     "--height-m must be above the floor (> 0 m), got -1.0"),
])
def test_matcher_names_the_camera_flag_typed(localize_files, capsys, camera, message):
    from matcher.cli import main

    d, args = localize_files
    at = args.index("--camera")
    args = args[:at] + [str(d / "camera.json") if a == "CAMERA" else a for a in camera] + args[at + 2:]
    assert main(args) == 2
    assert capsys.readouterr().err == f"matcher: error: {message}\n"


def test_a_panorama_s_height_names_camera_height(tmp_path, capsys):
    import cv2

    from matcher.cli import main

    cv2.imwrite(str(tmp_path / "pano.png"), np.zeros((64, 128), np.uint8))
    assert main(["localize", "--map", str(ROOT / "maps" / "flat.lmap"), "--pano", str(tmp_path / "pano.png"),
                 "--camera-height", "-1", "--lost"]) == 2
    assert capsys.readouterr().err == "matcher: error: --camera-height must be above the floor (> 0 m), got -1.0\n"


@pytest.mark.parametrize("command", [["build", "-o", "OUT"], ["layers"]])
def test_an_empty_ifc_file_is_called_empty(tmp_path, capsys, command):
    from mapkit.cli import main

    (tmp_path / "model.ifc").write_bytes(b"")
    args = [command[0], str(tmp_path / "model.ifc"), *[str(tmp_path / "out") if a == "OUT" else a
                                                        for a in command[1:]]]
    assert main(args) == 2
    err = capsys.readouterr().err
    assert err == ("mapkit: error: model.ifc: the file is empty, not an IFC model; export the model again "
                   "(an IFC file, ISO-10303-21 text)\n")
    assert not (tmp_path / "out").exists()


@pytest.fixture(scope="module")
def localize_files(tmp_path_factory):
    d = tmp_path_factory.mktemp("localize")
    (d / "camera.json").write_text(json.dumps(base_camera()))
    (d / "lines.json").write_text(json.dumps({"lines": base_frame()["lines"]}))
    f = base_frame()
    return d, ["localize", "--map", str(ROOT / "maps" / "flat.lmap"), "--camera", str(d / "camera.json"),
               "--lines", str(d / "lines.json"), "--prior", ",".join(map(str, f["prior"])), "--dt", str(f["dt"]),
               "--dyaw", str(f["dyaw"])]


@pytest.mark.parametrize("lost", [False, True])
def test_a_bug_in_localize_is_reported_as_a_bug(localize_files, capsys, monkeypatch, lost):
    import matcher.from_prior
    from matcher.cli import main

    _, argv = localize_files
    if lost:
        argv = argv[:argv.index("--prior")] + ["--lost", "--budget-ms", "500"]
    monkeypatch.setattr(matcher.from_prior, "select_candidates", _numpy_slip)
    assert main(argv) == EXIT_BUG
    captured = capsys.readouterr()
    assert captured.out == ""
    assert captured.err.startswith("matcher: internal error: ValueError: operands could not")
    assert "please report" in captured.err and "Traceback" not in captured.err
    assert len(captured.err.strip().splitlines()) == 1
    assert main(argv + ["--debug"]) == EXIT_BUG
    assert "Traceback (most recent call last)" in capsys.readouterr().err


def test_a_bug_while_tracking_is_not_a_skipped_frame(localize_files, capsys, monkeypatch):
    """The tracker skips a frame whose lines are bad input; a bug must stop the run instead."""
    import matcher.from_prior
    from matcher.cli import main

    d, _ = localize_files
    run, start = base_run()
    (d / "run.jsonl").write_bytes(run)
    monkeypatch.setattr(matcher.from_prior, "select_candidates", _numpy_slip)
    code = main(["track", "--map", str(ROOT / "maps" / "flat.lmap"), "--camera", str(d / "camera.json"),
                 "--frames", str(d / "run.jsonl"), "--prior", ",".join(map(str, start)), "--dt", "0.3",
                 "--dyaw", "15"])
    assert code == EXIT_BUG
    assert "please report" in capsys.readouterr().err


# ---- an injected bug: the fuzz classifier -------------------------------------------


def test_the_fuzz_classifier_calls_an_injected_bug_a_bug(tmp_path, monkeypatch):
    import mapkit.edges
    import matcher.from_prior

    monkeypatch.chdir(tmp_path)
    build = Case("dxf", "bug", {"plan.dxf": (ROOT / "maps" / "flat.dxf").read_bytes()},
                      ["mapkit", "build", "plan.dxf", "-o", "out.lmap"])
    f = base_frame()
    np.save(tmp_path / "lines.npy", np.array(f["lines"]))
    api = Case("matcher", "bug", {}, ["api", "localize", {"lines": "lines.npy", "camera": base_camera(),
                                                               "prior": f["prior"], "dt": f["dt"], "dyaw": f["dyaw"]}])
    monkeypatch.setattr(mapkit.edges, "extract_edges", _numpy_slip)
    monkeypatch.setattr(matcher.from_prior, "select_candidates", _numpy_slip)
    for case in (build, api):
        kind, detail = run_case_here(case)
        assert kind == BUG and NUMPY_SLIP in detail, (case.call[0], kind, detail)
    # The same call with bad input instead is a clean error: only InputError counts as one.
    api.call[2]["dt"] = -1.0
    assert run_case_here(api)[0] == ERROR


def test_the_fuzz_classifier_reads_exit_codes():
    assert classify_cli("mapkit", 2, "", "mapkit: error: plan.dxf: not a DXF file\n")[0] == ERROR
    assert classify_cli("mapkit", 3, "", "mapkit: internal error: ValueError: x -- this is a bug, please "
                                               "report it\n")[0] == BUG
    assert classify_cli("matcher", 2, "", "matcher: error: a\nmatcher: error: b\n")[0] == BUG


@pytest.mark.slow
def test_a_built_map_is_read_by_every_command_that_reads_maps(tmp_path, monkeypatch):
    """The build families follow a build with info, view --html and export
    on the map it wrote; a bug in one of them is the case's bug, and so is a
    clean error: the builder wrote a map its readers refuse."""
    import mapkit.commands.export

    monkeypatch.chdir(tmp_path)
    case = segments_case(__import__("random").Random(0))
    case = replace(case, files={"segments.csv": base_segments_csv().encode()},
                   call=["mapkit", "build", "segments.csv", "-o", "out.lmap"])
    assert [c[1] for c in case.then] == ["info", "info", "view", "export"]
    assert run_case_here(case) == (VALID, "")
    assert (tmp_path / "out.html").stat().st_size > 0 and json.loads((tmp_path / "out.geojson").read_text())
    # The follow-ups again on the map that build wrote (built once: the build is not what is asked below).
    case = replace(case, files={**case.files, "out.lmap": (tmp_path / "out.lmap").read_bytes()},
                   call=["mapkit", "info", "out.lmap"])
    monkeypatch.setattr(mapkit.commands.export, "to_geojson", _numpy_slip)
    kind, detail = run_case_here(case)
    assert kind == BUG and detail.startswith("then mapkit export out.lmap")

    def refuse(m, *args):
        raise MapkitError("this map is refused")

    monkeypatch.setattr(mapkit.commands.export, "to_geojson", refuse)
    kind, detail = run_case_here(case)
    assert kind == BUG and "a map the case wrote is refused: mapkit: error: this map is refused" in detail


# ---- what the commands read of a map ------------------------------------------------


@pytest.fixture(scope="module")
def crafted():
    from mapkit_harness.crafted_maps import META_SHAPE_CASES, example_chunks

    return [(name, make(example_chunks()), match) for name, make, match in META_SHAPE_CASES]


@pytest.mark.parametrize("command", [["info"], ["info", "--json"], ["view", "--html", "out.html"],
                                     ["export", "--geojson", "out.geojson"]])
def test_meta_entries_of_the_wrong_type_are_refused_by_every_reader(tmp_path, capsys, crafted, command):
    """META entries the commands read, of the wrong type: once a TypeError in
    'mapkit info'; now the loader refuses them, in one line, exit 2."""
    import re

    from mapkit.cli import main

    for name, blob, match in crafted:
        (tmp_path / "m.lmap").write_bytes(blob)
        argv = [command[0], str(tmp_path / "m.lmap"), *[str(tmp_path / a) if a.startswith("out.") else a
                                                        for a in command[1:]]]
        assert main(argv) == 2, name
        err = capsys.readouterr().err
        assert len(err.strip().splitlines()) == 1 and re.search(match, err), (name, err)
        assert not list(tmp_path.glob("out.*")), name


def test_a_map_naming_its_source_by_a_string_is_summarised(tmp_path, capsys):
    """The synthetic buildings of tools/ name their source by a string, mapkit build by an object."""
    from mapkit_harness.crafted_maps import example_chunks, with_meta

    from linemap.lmap import write_chunks
    from mapkit.cli import main

    (tmp_path / "m.lmap").write_bytes(write_chunks(with_meta(example_chunks(),
                                                             lambda m: m.update(source="a plan.dxf"))))
    assert main(["info", str(tmp_path / "m.lmap")]) == 0
    assert "source     a plan.dxf" in capsys.readouterr().out
