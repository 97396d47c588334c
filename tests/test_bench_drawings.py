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
    assert rows["flat"][1] == "right", rows["flat"]
    assert rows["flat"][6] == "7 / 7"
    assert rows["office_miscounted"][1] == "built wrong", rows["office_miscounted"]
    assert f"{office.doors} of 20 doors found" in rows["office_miscounted"][-1]
    assert rows["no_walls"][1] == "refused" and "--walls" in rows["no_walls"][-1]
    assert "3 drawings: 1 right, 0 built, 1 built wrong, 1 refused, 0 bug" in out
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


def test_the_corpus_is_fetched_checked_and_kept(tmp_path, capsys):
    served = tmp_path / "served" / "someone" / "plans" / "abc123" / "floor plans"
    served.mkdir(parents=True)
    shutil.copy(FLAT, served / "level 1.dxf")
    manifest = tmp_path / "corpus.tsv"
    manifest.write_text("# corpus\nid\trepo\tcommit\tpath\tsha256_12\n"
                        f"level1\tsomeone/plans\tabc123\tfloor plans/level 1.dxf\t{_sha12(FLAT)}\n"
                        "wrong\tsomeone/plans\tabc123\tfloor plans/level 1.dxf\tffffffffffff\n")
    base = (tmp_path / "served").as_uri()
    args = [str(tmp_path / "got"), "--manifest", str(manifest), "--base-url", base]
    assert fetch_drawings.main(args) == 1  # the second row's checksum differs
    out, err = capsys.readouterr()
    assert "level1: fetched" in out and "wrong: failed: SHA-256" in err
    assert (tmp_path / "got" / "level1.dxf").read_bytes() == FLAT.read_bytes()
    assert not (tmp_path / "got" / "wrong.dxf").exists()
    assert fetch_drawings.main([*args, "level1"]) == 0
    assert "level1: kept" in capsys.readouterr().out


def test_the_shipped_corpus_manifest_lists_every_drawing_with_its_source():
    rows = fetch_drawings.corpus(fetch_drawings.MANIFEST)
    assert len(rows) == 14
    for row in rows:
        assert row["repo"].count("/") == 1 and len(row["commit"]) == 40 and row["path"] and len(row["sha256_12"]) == 12
