"""tools/bench_paper.py, tools/bench_images.py, tools/bench_budget.py and
tools/bench_build.py end to end on a few frames: the tables (bench_paper's rig table too), the JSON rows,
the figures and the --report files (the full runs are the README's and
docs/matcher.md's benchmarks)."""

from __future__ import annotations

import json

import pytest

import bench_budget
import bench_images
import bench_paper
from mapkit_harness.tables import markdown_cells, markdown_table


@pytest.mark.slow
def test_bench_paper_writes_table_rows_and_figures(tmp_path, capsys):
    out = tmp_path / "figs"
    js = tmp_path / "rows.json"
    code = bench_paper.main(["--poses", "3", "--peq", "1", "5", "--repeat", "2", "--baseline-poses", "1",
                             "--baseline-limit", "0.2", "--out", str(out), "--json", str(js)])
    assert code == 0
    table = capsys.readouterr().out
    firsts = [markdown_cells(line)[0] for line in table.splitlines() if line.startswith("|")]
    assert "1" in firsts and "5" in firsts
    data = json.loads(js.read_text())
    for peq in ("1", "5"):
        rows = data["rows"][peq]
        assert len(rows) == 3
        assert all(r["ms"] > 0 for r in rows)
        assert "base_ms" in rows[0] and "base_ms" not in rows[1]
        assert data["summary"][peq]["n"] == 3
        # Correct results carry their error over the pose's std, summarised per axis.
        z = [r["err_over_std"] for r in rows if "err_over_std" in r]
        assert z and all(len(v) == 3 for v in z)
        assert len(data["summary"][peq]["err_over_std_rms"]) == 3
    assert sorted(p.name for p in out.iterdir()) == ["paper_fig5.png", "paper_fig6.png"]


@pytest.mark.slow
def test_bench_paper_pools_seeds(tmp_path, capsys):
    js = tmp_path / "rows.json"
    code = bench_paper.main(["--poses", "2", "--peq", "2", "--seed", "0", "1", "--repeat", "1", "--baseline-poses", "0",
                             "--out", str(tmp_path), "--json", str(js)])
    assert code == 0
    assert "4 poses per PEQ; seeds 0, 1;" in capsys.readouterr().out
    pooled = json.loads(js.read_text())["rows"]["2"]
    assert len(pooled) == 4
    # Seed 0's frames are the same pooled or alone.
    assert bench_paper.main(["--poses", "2", "--peq", "2", "--repeat", "1", "--baseline-poses", "0",
                             "--out", str(tmp_path / "alone"), "--json", str(js)]) == 0
    alone = json.loads(js.read_text())["rows"]["2"]
    assert [r["n_lines"] for r in alone] == [r["n_lines"] for r in pooled[:2]]
    assert [r["n_true"] for r in alone] == [r["n_true"] for r in pooled[:2]]
    assert sorted(p.name for p in tmp_path.glob("*.png")) == ["paper_fig5_seed0-1.png", "paper_fig6_seed0-1.png"]


@pytest.mark.slow
def test_bench_paper_rig_table_scores_every_count_by_the_pose(tmp_path, capsys):
    js = tmp_path / "rows.json"
    code = bench_paper.main(["--cameras", "1", "2", "--poses", "2", "--peq", "1", "--repeat", "1",
                             "--baseline-poses", "0", "--budget-ms", "inf", "--out", str(tmp_path), "--json", str(js)])
    assert code == 0
    out = capsys.readouterr().out.splitlines()
    # The one camera's table as without --cameras, then the rig table.
    assert markdown_cells(out[2])[:2] == ["PEQ", "sets found med / max"] and markdown_cells(out[4])[0] == "1"
    assert out[6].startswith("rigs of 2 such cameras, 0.15 m from the robot's centre") and "time budget none" in out[6]
    assert markdown_cells(out[7]) == ["cameras", "PEQ", "frames", "lines (med)", "correct first", "accepted",
                                      "wrong (> 10 cm or 1 deg)", "of which > 20 cm or 5 deg", "pose err (med)",
                                      "cut by budget", "ms med / p95"]
    one, two = (markdown_cells(line) for line in out[9:11])
    assert one[:3] == ["1", "1", "2"] and two[:3] == ["2", "1", "2"]
    assert two[4] == "100%" and two[6] == two[7] == "0%" and two[9] == "0"  # both rig frames right, none cut
    assert out[11].startswith("Correct first: the first ranked pose within 10 cm and 1 deg")
    rows = json.loads(js.read_text())
    assert len(rows["rows"]["1"]) == 2 and len(rows["pose_rows"]["2"]["1"]) == 2
    assert all(r["first_ok"] and r["accepted"] and not r["wrong"] for r in rows["pose_rows"]["2"]["1"])
    # A rig alone prints the map and camera above its table; bad counts are one line.
    assert bench_paper.main(["--cameras", "2", "--poses", "1", "--peq", "1"]) == 0
    alone = capsys.readouterr().out.splitlines()
    assert alone[0].startswith("map ") and alone[1].startswith("camera ") and markdown_cells(alone[4])[0] == "cameras"
    assert "timing best of 1 (rigs) passes" in alone[3]
    assert bench_paper.main(["--cameras", "0"]) == 2
    assert capsys.readouterr().err.startswith("error: --cameras takes distinct counts of at least 1")


@pytest.mark.slow
def test_bench_images_table(capsys):
    assert bench_images.main(["--frames", "1", "--peq", "1", "--supersample", "1"]) == 0
    out = capsys.readouterr().out.splitlines()
    assert out[1].startswith("| PEQ |") and out[3].startswith("| 1 |")
    assert out[3].count("|") == 7
    assert bench_images.main(["--frames", "0"]) == 2
    assert capsys.readouterr().err.strip() == "error: --frames, --supersample and --repeat must be at least 1"


def test_bench_budget_table(capsys):
    assert bench_budget.main(["--poses", "2", "--peq", "2", "--budgets", "0", "1e-9"]) == 0
    out = capsys.readouterr().out.splitlines()
    assert out[1].startswith("| PEQ | budget ms |")
    none, spent = out[3].split(" | "), out[4].split(" | ")
    assert none[1] == "none" and none[5] == "0"  # nothing cut without a budget
    assert spent[1] == "1e-09" and spent[3] == "0%" and spent[5] == "2"  # a spent budget: both cut, none accepted
    assert bench_budget.main(["--poses", "0"]) == 2
    assert capsys.readouterr().err.strip() == "error: --poses must be at least 1 and --budgets at least 0"


@pytest.mark.slow
def test_bench_build_prints_a_row_with_peak_memory(capsys):
    import bench_build

    assert bench_build.main(["simple_room", "--load-repeats", "1"]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert lines[0].startswith("| input | ") and "peak MB" in lines[0]
    row = [c.strip() for c in lines[2].strip("|").split("|")]
    assert row[0] == "simple_room.glb" and float(row[8]) > 10  # a child's peak memory, MB
    assert row[9] == "40" and row[10] == "3"  # segments, regions


def test_bench_build_writes_the_generated_offices(tmp_path):
    import bench_build

    path = bench_build.case_path("office_grid:2", tmp_path)
    assert path.exists() and path.suffix == ".dxf"
    assert bench_build.case_path("open_office", tmp_path).exists()


def test_report_writes_the_table_under_command_commit_and_machine(tmp_path, capsys):
    report = tmp_path / "budget.md"
    assert bench_budget.main(["--poses", "1", "--peq", "2", "--budgets", "0", "--report", str(report)]) == 0
    printed = capsys.readouterr().out
    text = report.read_text()
    assert text.startswith("Command: `python tools/bench_budget.py --poses 1 --peq 2 --budgets 0 --report ")
    assert "\nCommit: " in text and "CPUs (" in text and "load average" in text
    assert text.endswith(printed)  # the table as printed, below the header


def test_report_to_a_missing_folder_is_one_line_before_the_run(tmp_path, capsys):
    assert bench_budget.main(["--poses", "1", "--report", str(tmp_path / "no" / "t.md")]) == 2
    out, err = capsys.readouterr()
    assert out == "" and err.count("\n") == 1 and err.startswith("error: --report ")


def test_markdown_table_keeps_the_cells_as_given_in_aligned_columns():
    text = markdown_table(["PEQ", "ms"], [[1, "1.10"], [5, None], ["007", "12.3"]])
    lines = text.splitlines()
    assert [markdown_cells(line) for line in lines[:1] + lines[2:]] == [
        ["PEQ", "ms"], ["1", "1.10"], ["5", "None"], ["007", "12.3"]]  # no number reformatted
    assert set(lines[1]) <= set("|-: ") and len({len(line) for line in lines}) == 1  # one width a column
