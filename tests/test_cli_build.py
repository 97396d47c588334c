"""`mapkit build`: user errors are one line, exit 2, and nothing is written."""

from __future__ import annotations

import json
import os
from pathlib import Path

import ezdxf
import pytest
from cli_helpers import assert_one_line_error, run

ROOT = Path(__file__).resolve().parent.parent




def assert_nothing_written(folder: Path):
    assert [p.name for p in folder.iterdir() if p.suffix in (".lmap", ".tmp")] == []


def test_missing_plan(tmp_path, capsys):
    assert_one_line_error(*run(capsys, "build", tmp_path / "nope.dxf", "-o", tmp_path / "o.lmap"), "no such file")
    assert_nothing_written(tmp_path)


def test_unsupported_suffix(tmp_path, capsys):
    f = tmp_path / "plan.pdf"
    f.write_bytes(b"%PDF-1.4")
    assert_one_line_error(*run(capsys, "build", f, "-o", tmp_path / "o.lmap"), "unsupported file type")
    assert_nothing_written(tmp_path)


def test_not_a_dxf(tmp_path, capsys):
    f = tmp_path / "plan.dxf"
    f.write_bytes(b"\x89PNG\r\n\x1a\n" + bytes(range(256)) * 4)
    assert_one_line_error(*run(capsys, "build", f, "-o", tmp_path / "o.lmap"), "dxf")
    assert_nothing_written(tmp_path)


def test_truncated_dxf(tmp_path, capsys):
    text = (ROOT / "maps" / "flat.dxf").read_text(errors="replace")
    f = tmp_path / "cut.dxf"
    f.write_text(text[: len(text) // 40])
    assert_one_line_error(*run(capsys, "build", f, "-o", tmp_path / "o.lmap"))
    assert_nothing_written(tmp_path)


def _drawing(tmp_path, layers):
    doc = ezdxf.new()
    msp = doc.modelspace()
    for i, name in enumerate(layers):
        doc.layers.add(name)
        msp.add_line((0, i), (1, i), dxfattribs={"layer": name})
        msp.add_circle((2, 2 + i), 0.3, dxfattribs={"layer": name})
    f = tmp_path / "nowalls.dxf"
    doc.saveas(f)
    return f


def test_no_recognisable_walls_lists_layers(tmp_path, capsys):
    f = _drawing(tmp_path, ["Furniture", "Kitchen stuff", "Misc"])
    assert_one_line_error(*run(capsys, "build", f, "-o", tmp_path / "o.lmap"), "--walls", "Kitchen stuff", "Misc")
    assert_nothing_written(tmp_path)


def test_missing_output_folder(tmp_path, capsys):
    assert_one_line_error(*run(capsys, "build", ROOT / "maps" / "flat.dxf", "-o", tmp_path / "no" / "o.lmap"), "does not exist")


def test_unusable_output_paths_fail_before_the_build(tmp_path, capsys, monkeypatch):
    import mapkit.pipeline

    def no_build(*a, **k):
        raise AssertionError("the build ran")

    monkeypatch.setattr(mapkit.pipeline, "build_map", no_build)
    (tmp_path / "d.lmap").mkdir()
    (tmp_path / "file").write_text("")
    plan = ROOT / "maps" / "flat.dxf"
    assert_one_line_error(*run(capsys, "build", plan, "-o", tmp_path / "d.lmap"), "d.lmap: is a directory")
    assert_one_line_error(*run(capsys, "build", plan, "-o", tmp_path / "file" / "o.lmap"), "file: is a file, not a folder")
    assert not list(tmp_path.glob("*.tmp")) and not list(tmp_path.glob(".*"))
    # A file its owner made read-only is not replaced (the rename would allow it).
    kept = tmp_path / "kept.lmap"
    kept.write_bytes(b"the user's map")
    kept.chmod(0o444)
    assert_one_line_error(*run(capsys, "build", plan, "-o", kept), "kept.lmap: is read-only; make it writable")
    assert kept.read_bytes() == b"the user's map"
    # Nor is a pipe (or a device: -o /dev/null as root would replace it).
    pipe = tmp_path / "pipe.lmap"
    os.mkfifo(pipe)
    assert_one_line_error(*run(capsys, "build", plan, "-o", pipe), "pipe.lmap: is not a regular file")
    assert pipe.is_fifo()


def test_output_must_be_lmap(tmp_path, capsys):
    assert_one_line_error(*run(capsys, "build", ROOT / "maps" / "flat.dxf", "-o", tmp_path / "o.txt"), ".lmap")


@pytest.mark.parametrize(
    "opts, needle",
    [
        (["--eps", "0"], "--eps"),
        (["--merge-growth", "-0.5"], "--merge-growth"),
        (["--max-range", "-1"], "--max-range"),
        (["--wall-height", "0"], "--wall-height"),
        (["--door-height", "9"], "--door-height"),
        (["--pitch", "120"], "pitch"),
        (["--image-size", "big"], "--image-size"),
        (["--hfov", "500"], "field of view"),
        (["--window-sill", "-1"], "--window-sill must be >= 0"),
        (["--min-edge-length", "-1"], "--min-edge-length must be >= 0"),
        (["--wall-height", "1.5"], "--door-height 2.1 must be in (0, --wall-height 1.5]"),
        (["--window-sill", "1.5", "--window-head", "1.0"], "0 <= --window-sill < --window-head <= --wall-height"),
        (["--units", "m"], ("plan is 11 km across, not a building", "in mm it is 11 m across")),
        (["--crease-deg", "200"], "--crease-deg must be in (0, 180) degrees"),
    ],
)
def test_bad_options(tmp_path, capsys, opts, needle):
    needles = needle if isinstance(needle, tuple) else (needle,)
    assert_one_line_error(*run(capsys, "build", ROOT / "maps" / "flat.dxf", "-o", tmp_path / "o.lmap", *opts), *needles)
    assert_nothing_written(tmp_path)


def test_camera_file_missing_field(tmp_path, capsys):
    cam = tmp_path / "cam.json"
    cam.write_text(json.dumps({"width": 640, "height": 480, "fx": 500}))
    assert_one_line_error(*run(capsys, "build", ROOT / "maps" / "flat.dxf", "-o", tmp_path / "o.lmap", "--camera", cam), "lacks")
    assert_nothing_written(tmp_path)


def test_existing_map_survives_a_failed_build(tmp_path, capsys):
    out = tmp_path / "o.lmap"
    out.write_bytes(b"previous map")
    bad = tmp_path / "bad.dxf"
    bad.write_text("0\nSECTION\n2\nENTITIES\n0\nLINE\n")
    code, _, _ = run(capsys, "build", bad, "-o", out)
    assert code == 2 and out.read_bytes() == b"previous map"


@pytest.mark.slow
def test_camera_above_the_walls_is_warned(tmp_path, capsys):
    code, out, err = run(capsys, "build", ROOT / "maps" / "flat.dxf", "-o", tmp_path / "o.lmap", "--camera-height", "3")
    assert code == 0 and "camera height 3 m is not below the walls' 2.5 m" in err


def test_named_wall_layer_without_linework(tmp_path, capsys):
    doc = ezdxf.new()
    doc.layers.add("Walls")
    doc.modelspace().add_text("kitchen", dxfattribs={"layer": "Walls"}).set_placement((1, 1))
    doc.modelspace().add_line((0, 0), (5, 0), dxfattribs={"layer": "Other"})
    plan = tmp_path / "text.dxf"
    doc.saveas(plan)
    assert_one_line_error(*run(capsys, "build", plan, "-o", tmp_path / "o.lmap", "--walls", "Walls"),
                          "the wall layers given ('Walls') hold no lines or outlines, only TEXT")
    assert_nothing_written(tmp_path)
