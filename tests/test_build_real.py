"""`mapkit build` end to end on the bundled example and the real drawings."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from mapkit.cli import main
from linemap.lmap import SegmentKind, load_map

ROOT = Path(__file__).resolve().parent.parent
DATA = ROOT / "tests" / "data"

#: The layer choices the README shows for the real drawings.
BARCELONA = ["--walls", "Walls", "--walls", "Columns", "--windows", "Crystal"]
THEHOUSE = ["--walls", "s001-*", "--units", "m"]


def build(tmp_path, plan, *opts):
    out = tmp_path / (Path(plan).stem + ".lmap")
    assert main(["build", str(plan), "-o", str(out), "-q", *opts]) == 0
    return out


def info(capsys, path):
    capsys.readouterr()
    assert main(["info", str(path), "--json"]) == 0
    return json.loads(capsys.readouterr().out)


@pytest.fixture(scope="module")
def barcelona(tmp_path_factory):
    return build(tmp_path_factory.mktemp("barcelona"), DATA / "barcelona-pavilion.dxf", *BARCELONA)


@pytest.mark.slow
def test_committed_example_map_is_up_to_date(tmp_path):
    # Builds are reproducible, so the committed map must be exactly what the
    # current code makes of the committed plan (rebuild it when this fails:
    # mapkit build maps/flat.dxf -o maps/flat.lmap).
    fresh = build(tmp_path, ROOT / "maps" / "flat.dxf")
    assert fresh.read_bytes() == (ROOT / "maps" / "flat.lmap").read_bytes()


def test_example_map_contents(capsys):
    s = info(capsys, ROOT / "maps" / "flat.lmap")
    kinds = s["segments_per_kind"]
    assert s["units"] == "m" and s["format_version"] == "1.0"
    assert kinds["floor"] > 20 and kinds["ceiling"] > 20 and kinds["vertical"] > 10
    assert kinds["jamb"] >= 2 * 7 and kinds["lintel"] >= 7 and kinds["window"] >= 6
    assert s["file_bytes"] < 100 * 1024
    assert 10.5 < s["bbox"]["max"][0] - s["bbox"]["min"][0] < 11.5
    # Lists are far shorter than the map: visibility, not "everything".
    assert s["list_length"]["mean"] < 0.5 * s["segments"]


def test_example_map_query_in_bedroom_sees_bedroom_walls():
    m = load_map(ROOT / "maps" / "flat.lmap")
    seen = m.candidate_segments(2.0, 6.6, 0.2)  # middle of bedroom 1 (metres)
    mids = m.segments[seen].mean(axis=1)
    # Bedroom 1's interior is x 0.3-3.9, y 5.1-8.2: its own walls are seen...
    inside = (mids[:, 0] > 0.2) & (mids[:, 0] < 4.0) & (mids[:, 1] > 5.0) & (mids[:, 1] < 8.3)
    assert inside.sum() >= 8
    # ...and nothing of bedroom 2 behind two walls (x > 6.4, y > 5.2).
    assert not ((mids[:, 0] > 6.4) & (mids[:, 1] > 5.2)).any()


@pytest.mark.slow
def test_barcelona(barcelona, capsys):
    s = info(capsys, barcelona)
    assert s["segments"] > 150 and s["regions"] > 50
    assert s["segments_per_kind"]["jamb"] > 0 and s["segments_per_kind"]["vertical"] > 20
    assert s["build"]["walls"] == ["Walls", "Columns"] and s["build"]["windows"] == ["Crystal"]
    assert 45 < s["bbox"]["max"][0] - s["bbox"]["min"][0] < 55
    m = load_map(barcelona)
    # The pavilion's central hall, between the onyx wall and the glass.
    assert len(m.candidate_segments(34.0, 9.0, 0.5)) > 10


@pytest.mark.slow
def test_barcelona_guessed_layers_agree(tmp_path, barcelona):
    guessed = load_map(build(tmp_path, DATA / "barcelona-pavilion.dxf"))
    assert guessed.n_segments == load_map(barcelona).n_segments


@pytest.mark.slow
def test_thehouse(tmp_path, capsys):
    s = info(capsys, build(tmp_path, DATA / "thehouse.dxf", *THEHOUSE))
    assert s["segments"] > 50 and s["regions"] > 10
    assert s["segments_per_kind"][SegmentKind.VERTICAL.label] > 20
    assert 40 < s["bbox"]["max"][1] - s["bbox"]["min"][1] < 50  # metres, not millimetres


@pytest.mark.slow
def test_threads_give_the_same_bytes(tmp_path):
    # --jobs splits the region stage's GEOS work among threads; the chunks'
    # results are put back in order, so the map is the one-thread map: the
    # committed one, which test_committed_example_map_is_up_to_date builds
    # with the default number of threads (not built again here).
    from mapkit.parallel import default_jobs

    committed = (ROOT / "maps" / "flat.lmap").read_bytes()
    for jobs in sorted({"1", "2", "3"} - {str(default_jobs())}):
        (tmp_path / jobs).mkdir()
        assert build(tmp_path / jobs, ROOT / "maps" / "flat.dxf", "--jobs", jobs).read_bytes() == committed, jobs


def test_jobs_must_be_positive(tmp_path, capsys):
    assert main(["build", str(ROOT / "maps" / "flat.dxf"), "-o", str(tmp_path / "a.lmap"), "-q", "--jobs", "0"]) != 0
    assert "--jobs" in capsys.readouterr().err
