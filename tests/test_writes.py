"""Writes never destroy what they read: an output that is an input is
refused before any work, a symbolic link is written through, and the
temporary files a killed run left are cleaned by the next write."""

from __future__ import annotations

import os
import shutil
import time
from pathlib import Path

import pytest
from cli_helpers import assert_one_line_error, run

from linemap.atomic import OutputPathError, check_output_path, write_atomic

ROOT = Path(__file__).resolve().parent.parent


@pytest.fixture
def flat(tmp_path):
    m = tmp_path / "flat.lmap"
    shutil.copy(ROOT / "maps" / "flat.lmap", m)
    return m


@pytest.mark.parametrize("argv", [
    ("export", "{map}", "--geojson", "{map}"),
    ("view", "{map}", "--html", "{map}"),
])
def test_an_output_that_is_the_input_map_is_refused(flat, capsys, argv):
    before = flat.read_bytes()
    code, out, err = run(capsys, *[a.format(map=flat) for a in argv])
    assert_one_line_error(code, out, err, "is also the input", "choose another output path")
    assert flat.read_bytes() == before


def test_an_output_that_is_the_input_plan_is_refused(tmp_path, capsys):
    plan = tmp_path / "room.glb"
    assert run(capsys, "extrude", ROOT / "maps" / "flat.dxf", "-o", plan)[0] == 0
    before = plan.read_bytes()
    code, out, err = run(capsys, "extrude", plan, "-o", plan)
    assert_one_line_error(code, out, err, "is also the input")
    assert plan.read_bytes() == before
    # The same file under another name (a link) is the same input.
    (tmp_path / "link.glb").symlink_to(plan)
    code, out, err = run(capsys, "extrude", tmp_path / "link.glb", "-o", plan)
    assert_one_line_error(code, out, err, "is also the input")


def test_a_symlink_output_is_written_through(tmp_path):
    target = tmp_path / "real" / "out.json"
    target.parent.mkdir()
    target.write_text("old")
    link = tmp_path / "out.json"
    link.symlink_to(target)
    write_atomic(link, "new")
    assert link.is_symlink() and os.readlink(link) == str(target)
    assert target.read_text() == "new"


def test_a_killed_runs_temporary_files_are_removed_by_the_next_write(tmp_path):
    out = tmp_path / "map.json"
    stale = tmp_path / ".map.json.abcd1234.tmp"  # what a killed write leaves
    fresh = tmp_path / ".map.json.efgh5678.tmp"  # a write in progress
    other = tmp_path / ".other.json.abcd1234.tmp"  # another output's
    mine = tmp_path / "notes.tmp"
    for p in (stale, fresh, other, mine):
        p.write_text("x")
    old = time.time() - 3600
    for p in (stale, other, mine):
        os.utime(p, (old, old))
    write_atomic(out, "{}")
    assert out.read_text() == "{}"
    assert not stale.exists()
    assert fresh.exists() and other.exists() and mine.exists()


def test_check_output_path_names_the_input(tmp_path):
    f = tmp_path / "a.lmap"
    f.write_bytes(b"x")
    with pytest.raises(OutputPathError, match="is also the input"):
        check_output_path(tmp_path / "." / "a.lmap", [f])
    assert check_output_path(tmp_path / "b.lmap", [f]) == tmp_path / "b.lmap"
