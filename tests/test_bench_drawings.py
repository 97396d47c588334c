"""tools/bench_drawings.py judges the builds of a folder of drawings, and
tools/fetch_drawings.py downloads the corpus it is run on."""

from __future__ import annotations

import hashlib
import shutil
from pathlib import Path

import bench_drawings
import fetch_drawings
import pytest

from mapkit_harness.plans import office_grid
from mapkit_harness.tables import markdown_cells

ROOT = Path(__file__).resolve().parent.parent
FLAT = ROOT / "maps" / "flat.dxf"
NO_WALLS = ROOT / "tests" / "data" / "dxf" / "no_walls.dxf"


def _sha12(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()[:12]


@pytest.mark.slow
def test_a_folder_of_drawings_is_built_and_judged(tmp_path, capsys):
    folder = tmp_path / "drawings"
    folder.mkdir()
    shutil.copy(FLAT, folder / "flat.dxf")
    # Any plan with its doors drawn shows a miscount: an office of 2 x 2 rooms builds in a fraction of the flat's time.
    office = office_grid(folder / "office_miscounted.dxf", n=2)
    shutil.copy(NO_WALLS, folder / "no_walls.dxf")
    (folder / "manifest.tsv").write_text(
        "# what a person sees\n"
        "id\tdoors_drawn\trooms\toutline_m2\tsha256_12\n"
        f"flat\t7\t\t100\t{_sha12(FLAT)}\n"
        "office_miscounted\t20\t\t\t000000000000\n")
    assert bench_drawings.main([str(folder)]) == 0
    out, err = capsys.readouterr()
    rows = {cells[0]: cells for cells in (markdown_cells(line) for line in out.splitlines() if line.startswith("| "))}
    assert rows["flat"][2] == "right", rows["flat"]  # [1]: the half (none here)
    assert rows["flat"][7] == "7 / 7"
    assert rows["office_miscounted"][2] == "built wrong", rows["office_miscounted"]
    assert f"{office.doors} of 20 doors found" in rows["office_miscounted"][-1]
    assert rows["no_walls"][2] == "refused" and "--walls" in rows["no_walls"][-1]
    assert "3 drawings (all): 1 right (33 %), 0 built, 1 built wrong, 1 refused, 0 bug" in out
    assert "office_miscounted.dxf: SHA-256" in err and "another version" in err


def test_judging_names_each_failed_fact():
    o = bench_drawings.Outcome("plan", doors=3, free_m2=150.0, free_parts=4, warnings=["using the walls' convex hull"])
    bench_drawings.judge(o, bench_drawings.Expected(doors_drawn=10, outline_m2=100.0))
    assert o.outcome == "built wrong"
    assert o.notes == ["3 of 10 doors found", "free space in 4 parts: rooms not connected",
                       "free space 150 m2 beyond the outline's 100 m2", "free space from the walls' convex hull"]
    o = bench_drawings.Outcome("rooms", doors=0, free_m2=40.0, free_parts=9)
    bench_drawings.judge(o, bench_drawings.Expected(doors_drawn=0, rooms=9))
    assert o.outcome == "right"  # no doors drawn: rooms cannot connect
    o = bench_drawings.Outcome("unjudged", doors=2, free_m2=40.0, free_parts=1)
    bench_drawings.judge(o, bench_drawings.Expected())
    assert o.outcome == "built"
    o = bench_drawings.Outcome("rooms lost", doors=0, free_m2=9.8, free_parts=1)
    bench_drawings.judge(o, bench_drawings.Expected(outline_m2=70.0))
    assert o.outcome == "built wrong" and o.notes == ["free space 10 m2, under 40 % of the outline's 70 m2: rooms lost"]


def test_a_drawing_that_cannot_be_right_with_defaults_is_right_when_refused_naming_its_fix():
    exp = bench_drawings.Expected(expect="refuse:--scale|--units")
    o = bench_drawings.Outcome("traced")
    bench_drawings.judge_refusal(o, exp, "the walls span only 2.4 x 3.2 m: if it is drawn in cm, give --units cm")
    assert o.outcome == "right" and "naming --units" in o.notes[0]
    o = bench_drawings.Outcome("traced")
    bench_drawings.judge_refusal(o, exp, "no recognisable walls: name the wall layers with --walls")
    assert o.outcome == "refused"  # a refusal that does not name the fix
    o = bench_drawings.Outcome("framing")
    bench_drawings.judge_refusal(o, bench_drawings.Expected(expect="refuse"), "no recognisable walls")
    assert o.outcome == "right"  # not a floor plan: any clear refusal
    o = bench_drawings.Outcome("unexpected")
    bench_drawings.judge_refusal(o, bench_drawings.Expected(doors_drawn=3), "no recognisable walls")
    assert o.outcome == "refused"
    o = bench_drawings.Outcome("guessed", doors=0, free_m2=50.0, free_parts=1)
    bench_drawings.judge(o, bench_drawings.Expected(expect="refuse:--scale"))
    assert o.outcome == "built wrong" and "expects refuse:--scale" in o.notes[0]


def _split_manifest(tmp_path, rows):
    """A manifest of (id, repo, split, expect, doors_drawn) rows."""
    path = tmp_path / "corpus.tsv"
    path.write_text("# halves\nid\trepo\tsplit\texpect\tdoors_drawn\n"
                    + "".join("\t".join(r) + "\n" for r in rows), encoding="utf-8")
    return path


def _repo_in(half):
    """A repository name the split rule puts in ``half``."""
    return next(f"someone/plans{i}" for i in range(100) if bench_drawings.split_of(f"someone/plans{i}") == half)


def test_the_split_rule_keeps_forks_together_and_gives_both_halves():
    assert bench_drawings.split_of("alice/house") == bench_drawings.split_of("bob/House")
    halves = {bench_drawings.split_of(f"owner/repo{i}") for i in range(20)}
    assert halves == set(bench_drawings.HALVES)


def test_each_half_is_reported_separately(tmp_path):
    tuning, held = _repo_in("tuning"), _repo_in("held_out")
    exps, _ = bench_drawings.read_manifest(_split_manifest(tmp_path, [
        ("a", tuning, "tuning", "", "2"), ("b", tuning, "tuning", "refuse:--scale", ""),
        ("c", held, "held_out", "", "4"), ("d", held, "held_out", "", "4")]))
    assert exps["b"].split == "tuning" and exps["b"].refusal_options() == ["--scale"]
    rows = [bench_drawings.Outcome("a", outcome="right"), bench_drawings.Outcome("b", outcome="right"),
            bench_drawings.Outcome("c", outcome="built wrong"), bench_drawings.Outcome("d", outcome="refused")]
    text = bench_drawings.table(rows, exps)
    assert "2 drawings (tuning): 2 right (100 %), 0 built, 0 built wrong, 0 refused, 0 bug" in text
    assert "2 drawings (held_out): 0 right (0 %), 0 built, 1 built wrong, 1 refused, 0 bug" in text
    assert "4 drawings (all): 2 right (50 %), 0 built, 1 built wrong, 1 refused, 0 bug" in text
    cells = [markdown_cells(line) for line in text.splitlines() if line.startswith("| c ")]
    assert cells and cells[0][:3] == ["c", "held_out", "built wrong"], cells


def test_a_drawing_moved_to_the_other_half_by_hand_is_an_error(tmp_path, capsys):
    held = _repo_in("held_out")
    manifest = _split_manifest(tmp_path, [("a", held, "tuning", "", "")])
    with pytest.raises(ValueError, match="the rule .* puts"):
        bench_drawings.read_manifest(manifest)
    folder = tmp_path / "drawings"
    folder.mkdir()
    assert bench_drawings.main([str(folder), "--manifest", str(manifest)]) == 2
    assert "bench_drawings: error:" in capsys.readouterr().err


def test_one_half_is_built_alone(tmp_path, monkeypatch, capsys):
    tuning, held = _repo_in("tuning"), _repo_in("held_out")
    manifest = _split_manifest(tmp_path, [("a", tuning, "tuning", "", ""), ("b", held, "held_out", "", "")])
    folder = tmp_path / "drawings"
    folder.mkdir()
    for name in "ab":
        (folder / f"{name}.dxf").write_text("not built in this test")
    built = []
    monkeypatch.setattr(bench_drawings, "bench_one",
                        lambda plan, exp, timeout, previews: built.append(plan.stem) or bench_drawings.Outcome(plan.stem, "built"))
    assert bench_drawings.main([str(folder), "--manifest", str(manifest), "--half", "held_out"]) == 0
    assert built == ["b"]
    assert "1 drawings (held_out): 0 right (0 %), 1 built" in capsys.readouterr().out


def test_the_corpus_is_fetched_checked_and_kept(tmp_path, capsys):
    served = tmp_path / "served" / "someone" / "plans" / "abc123" / "floor plans"
    served.mkdir(parents=True)
    shutil.copy(FLAT, served / "level 1.dxf")
    manifest = tmp_path / "corpus.tsv"
    manifest.write_text("# corpus\nid\trepo\tcommit\tpath\tsha256_12\tsplit\n"
                        f"level1\tsomeone/plans\tabc123\tfloor plans/level 1.dxf\t{_sha12(FLAT)}\ttuning\n"
                        "wrong\tsomeone/plans\tabc123\tfloor plans/level 1.dxf\tffffffffffff\ttuning\n")
    base = (tmp_path / "served").as_uri()
    args = [str(tmp_path / "got"), "--manifest", str(manifest), "--base-url", base]
    assert fetch_drawings.main(args) == 1  # the second row's checksum differs
    out, err = capsys.readouterr()
    assert "level1: fetched" in out and "wrong: failed: SHA-256" in err
    assert (tmp_path / "got" / "level1.dxf").read_bytes() == FLAT.read_bytes()
    assert not (tmp_path / "got" / "wrong.dxf").exists()
    assert fetch_drawings.main([*args, "level1"]) == 0
    assert "level1: kept" in capsys.readouterr().out
    assert fetch_drawings.main([*args, "--half", "held_out"]) == 0  # no drawing of that half
    assert capsys.readouterr().out == ""


def test_the_shipped_corpus_manifest_lists_every_drawing_with_its_source():
    rows = fetch_drawings.corpus(fetch_drawings.MANIFEST)
    assert len(rows) >= 40 and len({r["id"] for r in rows}) == len(rows)
    for row in rows:
        assert row["repo"].count("/") == 1 and len(row["commit"]) == 40 and row["path"] and len(row["sha256_12"]) == 12
        assert row["split"] == bench_drawings.split_of(row["repo"]), row["id"]
        assert not row["expect"] or row["expect"] == "refuse" or row["expect"].startswith("refuse:--"), row["id"]
    exps, _ = bench_drawings.read_manifest(fetch_drawings.MANIFEST)  # the benchmark reads the same columns
    assert set(exps) == {r["id"] for r in rows}
    for half in bench_drawings.HALVES:
        assert sum(r["split"] == half for r in rows) >= len(rows) // 3, half
