"""The matcher command line: output forms and every user error."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import cv2
import numpy as np
import pytest

from matcher.cli import main


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    from mapkit_harness.plans import make_small_flat
    from linemap.lmap import save_map
    from mapkit_harness.simulate import make_frame, paper_camera

    d = tmp_path_factory.mktemp("cli")
    m = make_small_flat()
    save_map(d / "flat.lmap", m)
    cam = paper_camera()
    (d / "cam.json").write_text(json.dumps(cam.to_dict()))
    fr = make_frame(m, cam, np.random.default_rng(11), 2)
    (d / "lines.json").write_text(json.dumps({"lines": fr.lines.reshape(-1, 4).tolist()}))
    prior = ",".join(f"{v:.4f}" for v in fr.prior)
    return {"dir": d, "frame": fr, "prior": prior, "dt": str(fr.dt), "dyaw": str(fr.dyaw), "map": m, "camera": cam}


def args(files, *extra, lines=True):
    d = files["dir"]
    a = ["localize", "--map", str(d / "flat.lmap"), "--camera", str(d / "cam.json"),
         "--prior", files["prior"], "--dt", files["dt"], "--dyaw", files["dyaw"]]
    if lines:
        a += ["--lines", str(d / "lines.json")]
    return a + list(extra)


def test_human_output(files, capsys):
    assert main(args(files)) == 0
    out = capsys.readouterr().out
    assert out.startswith("pose x=") and "score E=" in out and "matches [segment, line]" in out


def test_json_output_is_one_object(files, capsys):
    assert main(args(files, "--json")) == 0
    out = capsys.readouterr().out.strip()
    d = json.loads(out)
    assert d["ok"] is True and set(d["pose"]) == {"x", "y", "yaw_deg"}
    x, y, yaw = files["frame"].pose
    assert abs(d["pose"]["x"] - x) < 0.05 and abs(d["pose"]["y"] - y) < 0.05
    assert len(out.splitlines()) == 1


def test_not_localised_exits_1_with_reason(files, capsys):
    a = args(files, "--json")
    a[a.index("--prior") + 1] = "60,60,0"
    assert main(a) == 1
    d = json.loads(capsys.readouterr().out)
    assert d["ok"] is False and "farther than" in d["reason"]


def test_image_input(files, capsys, tmp_path):
    """--image: the frame rendered (tools/render.py), lines found by LSD."""
    from mapkit_harness.render import render_view

    fr = files["frame"]
    p = tmp_path / "frame.png"
    cv2.imwrite(str(p), render_view(files["map"], files["camera"], fr.pose, supersample=2))
    a = args(files, "--json", lines=False) + ["--image", str(p)]
    assert main(a) == 0
    d = json.loads(capsys.readouterr().out)
    x, y, yaw = fr.pose
    assert abs(d["pose"]["x"] - x) < 0.03 and abs(d["pose"]["y"] - y) < 0.03
    assert abs((d["pose"]["yaw_deg"] - yaw + 180) % 360 - 180) < 0.5


@pytest.mark.parametrize(
    "change, message",
    [
        (("--map", "missing.lmap"), "map file missing.lmap not found; build one with 'mapkit build'"),
        (("--camera", "missing.json"), "camera file missing.json not found"),
        (("--lines", "missing.json"), "lines file missing.json not found"),
        (("--prior", "1,2"), "--prior must be X,Y,YAW_DEG"),
        (("--dt", "-1"), r"dt must be in (0, 100] metres"),
        (("--dyaw", "500"), r"dyaw must be in (0, 180] degrees"),
    ],
)
def test_user_errors_one_line(files, capsys, change, message):
    a = args(files)
    a[a.index(change[0]) + 1] = change[1]
    assert main(a) == 2
    err = capsys.readouterr().err
    assert err.startswith("matcher: error: ") and message in err and len(err.strip().splitlines()) == 1


def test_bad_files(files, capsys, tmp_path):
    bad_cam = tmp_path / "cam.json"
    bad_cam.write_text(json.dumps({"width": 640, "height": 480}))
    a = args(files)
    a[a.index("--camera") + 1] = str(bad_cam)
    assert main(a) == 2
    assert "camera description lacks fx" in capsys.readouterr().err
    bad_lines = tmp_path / "lines.json"
    bad_lines.write_text('{"lines": [[1, 2, 3]]}')
    a = args(files)
    a[a.index("--lines") + 1] = str(bad_lines)
    assert main(a) == 2
    assert "Expected shape (M, 2, 2) or (M, 4)" in capsys.readouterr().err
    bad_lines.write_text("not json")
    assert main(a) == 2
    assert "is not valid JSON" in capsys.readouterr().err
    bad_map = tmp_path / "bad.lmap"
    bad_map.write_bytes(b"garbage")
    a = args(files)
    a[a.index("--map") + 1] = str(bad_map)
    assert main(a) == 2
    assert "not a .lmap map" in capsys.readouterr().err


@pytest.mark.parametrize(
    "content, message",
    [
        ('{"lines": [[true, 2, 3, 4], [1, 2, 3, 5], [1, 2, 3, 6]]}', "holds true/false where pixel coordinates"),
        ('{"lines": [[1' + "0" * 400 + ', 2, 3, 4]]}', "lines must be numbers"),
        ('{"lines": ' + "[" * 100_000 + "]" * 100_000 + "}", "is not valid JSON (nested too deeply)"),
        ('{"lines": [[1e308, 1e308, 3, 4]]}', "lies outside the 640x480 image"),
    ],
)
def test_bad_lines_files_one_line(files, capsys, tmp_path, content, message):
    p = tmp_path / "lines.json"
    p.write_text(content)
    a = args(files)
    a[a.index("--lines") + 1] = str(p)
    assert main(a) == 2
    err = capsys.readouterr().err
    assert err.startswith("matcher: error: ") and message in err and len(err.strip().splitlines()) == 1


@pytest.mark.slow
def test_truncated_image_is_one_line_from_a_fresh_process(files, tmp_path):
    """libpng's own complaint on the C stderr is kept quiet: the one line says it."""
    img = np.random.default_rng(0).integers(0, 255, (480, 640)).astype(np.uint8)  # the cut falls in pixel data
    ok, png = cv2.imencode(".png", img)
    p = tmp_path / "cut.png"
    p.write_bytes(png.tobytes()[: len(png) // 2])
    a = args(files, lines=False) + ["--image", str(p)]
    out = subprocess.run([sys.executable, "-m", "matcher", *a], capture_output=True, text=True, timeout=120)
    assert out.returncode == 2 and out.stdout == ""
    assert out.stderr.startswith("matcher: error: image file") and len(out.stderr.strip().splitlines()) == 1, out.stderr


@pytest.mark.parametrize("option", ["--map", "--camera", "--lines"])
def test_a_directory_for_a_file(files, capsys, tmp_path, option):
    a = args(files)
    a[a.index(option) + 1] = str(tmp_path)
    assert main(a) == 2
    err = capsys.readouterr().err
    assert err.startswith("matcher: error: ") and "is a directory" in err


def test_negative_prior_x_without_equals_sign(files, capsys):
    """argparse takes '-0.05,...' for an option; the CLI joins it to --prior."""
    a = args(files, "--json")
    x, y, yaw = (float(v) for v in files["prior"].split(","))
    a[a.index("--prior") + 1] = f"-0.05,{y},{yaw}"
    assert main(a) in (0, 1)
    out, err = capsys.readouterr()
    assert err == "" and "ok" in json.loads(out)


def test_missing_option_and_both_sources(files, capsys):
    assert main(["localize", "--map", "x"]) == 2  # no camera, rig or panorama: one line
    err = capsys.readouterr().err
    assert err.startswith("matcher: error: give one of --camera") and err.count("\n") == 1
    with pytest.raises(SystemExit):
        main(args(files, "--image", "x.png"))
    assert "not allowed with argument" in capsys.readouterr().err


def test_lost_mode_from_the_command_line(files, capsys, tmp_path):
    """--lost: no prior, the voted places then (if need be) every region
    tried (human and JSON forms). The
    frame is one lost mode places in the right room (with few lines it may
    pick another: README, lost mode)."""
    from mapkit_harness.simulate import make_frame

    fr = make_frame(files["map"], files["camera"], np.random.default_rng(3), 1)
    (tmp_path / "lines.json").write_text(json.dumps({"lines": fr.lines.reshape(-1, 4).tolist()}))
    d = files["dir"]
    base = ["localize", "--map", str(d / "flat.lmap"), "--camera", str(d / "cam.json"),
            "--lines", str(tmp_path / "lines.json"), "--lost"]
    assert main(base + ["--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    x, y, _ = fr.pose
    assert abs(out["pose"]["x"] - x) < 0.05 and abs(out["pose"]["y"] - y) < 0.05
    tried = out["time_ms"]["places_tried"], out["time_ms"]["regions_tried"]
    assert tried[0] >= 1 and tried[1] in (0, files["map"].n_regions)
    assert main(base) == 0
    assert f"({tried[0]} voted places, {tried[1]} regions tried)" in capsys.readouterr().out


@pytest.mark.parametrize(
    "drop, add, message",
    [
        (("--prior",), (), "missing --prior: give --prior X,Y,YAW_DEG with --dt and --dyaw, or --lost"),
        (("--dt", "--dyaw"), (), "missing --dt, --dyaw: give"),
        ((), ("--lost",), "--lost takes no prior; drop --prior, --dt, --dyaw or drop --lost"),
    ],
)
def test_prior_or_lost_one_line(files, capsys, drop, add, message):
    a = args(files)
    for opt in drop:
        i = a.index(opt)
        del a[i:i + 2]
    assert main(a + list(add)) == 2
    err = capsys.readouterr().err
    assert err.startswith("matcher: error: ") and message in err and len(err.strip().splitlines()) == 1


def test_reader_gone_is_quiet(files):
    """`matcher localize ... | head -0`: stdout's reader has gone; no error, no traceback."""
    from cli_helpers import run_with_reader_gone

    out = run_with_reader_gone("-m", "matcher", *args(files))
    assert out.returncode == 0 and out.stderr == ""


@pytest.mark.slow
def test_python_dash_m(files):
    out = subprocess.run([sys.executable, "-m", "matcher", *args(files, "--json")], capture_output=True, text=True,
                         timeout=120)
    assert out.returncode == 0, out.stderr
    assert json.loads(out.stdout)["ok"] is True
    assert out.stderr == ""


@pytest.mark.slow
def test_simulated_frame_files_localise_from_the_command_line(tmp_path, capsys):
    """tools/simulate.py --out writes what `matcher localize` reads (the README's example)."""
    import simulate

    root = Path(__file__).resolve().parents[1]
    assert simulate.main(["--peq", "2", "--seed", "4", "--out", str(tmp_path), "--no-images"]) == 0
    assert not (tmp_path / "frame.png").exists()  # the lines only (the README's example renders it too)
    truth = json.loads((tmp_path / "truth.json").read_text())
    x, y, yaw = truth["prior"]
    capsys.readouterr()
    code = main(["localize", "--map", str(root / "maps" / "flat.lmap"), "--camera", str(tmp_path / "camera.json"),
                 "--lines", str(tmp_path / "lines.json"), "--prior", f"{x},{y},{yaw}",
                 "--dt", str(truth["dt"]), "--dyaw", str(truth["dyaw"]), "--json"])
    res = json.loads(capsys.readouterr().out)
    assert code == 0 and res["ok"]
    assert sorted(map(tuple, res["matches"])) == sorted(map(tuple, truth["matches"]))
    assert abs(res["pose"]["x"] - truth["pose"]["x"]) < 0.02 and abs(res["pose"]["y"] - truth["pose"]["y"]) < 0.02


@pytest.mark.parametrize("value", ["0", "-5", "nan", "inf"])
def test_budget_must_be_positive(files, capsys, value):
    assert main(args(files, f"--budget-ms={value}")) == 2
    err = capsys.readouterr().err
    assert err.startswith("matcher: error: --budget-ms must be a positive number of milliseconds")
    assert len(err.strip().splitlines()) == 1


def test_budget_from_the_command_line(files, capsys):
    assert main(args(files, "--budget-ms", "100000", "--json")) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["ok"] is True and out["out_of_time"] is False
    assert main(args(files, "--budget-ms", "1e-9")) == 1
    assert "(time budget of 1e-09 ms spent; --budget-ms" in capsys.readouterr().out
    assert main(args(files, "--budget-ms", "1e-9", "--json")) == 1
    out = json.loads(capsys.readouterr().out)
    assert out["ok"] is False and out["out_of_time"] is True


def test_human_output_says_when_the_budget_cut_the_search():
    from dataclasses import replace

    from matcher.cli import _human
    from matcher.result import LocalizeResult, SearchStats, Timings

    res = LocalizeResult(True, pose=(1.0, 2.0, 30.0), score=1e-4, matches=[[1, 0], [2, 1], [3, 2]],
                         time_ms=Timings(total=50.2), stage1=SearchStats(out_of_time=True))
    assert _human(res, 4).endswith("time ms: total 50.2 (search stopped at the time budget)")
    res = replace(res, stage1=SearchStats(out_of_time=False))
    assert _human(res, 4).endswith("time ms: total 50.2")


@pytest.mark.parametrize("prog", ["matcher", "mapkit"])
def test_version_of_both_commands_is_the_projects(prog, capsys):
    """``--version`` on either command prints the one version (linemap's) and exits 0."""
    import linemap
    from mapkit.cli import main as mapkit_main

    with pytest.raises(SystemExit) as stop:
        (main if prog == "matcher" else mapkit_main)(["--version"])
    assert stop.value.code == 0
    assert capsys.readouterr().out.strip() == f"{prog} {linemap.__version__}"
