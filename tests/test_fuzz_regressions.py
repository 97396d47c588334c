"""Every input the fuzz campaign found failing (tests/data/fuzz/*/) ends as
its case.json now expects: a one-line error naming the problem, within the
bound, where it was a traceback, a hang or a blow-up."""

from __future__ import annotations

import json
from pathlib import Path

import fuzz
import pytest
from fuzz_helpers import BUILD_BOUND_S

CASES = sorted(p for p in (Path(__file__).parent / "data" / "fuzz").iterdir() if (p / "case.json").is_file())


@pytest.mark.parametrize("folder", CASES, ids=[p.name for p in CASES])
def test_a_found_failure_stays_fixed(tmp_path, folder):
    expect = json.loads((folder / "case.json").read_text())
    out = fuzz.run_bounded(fuzz.load_case(folder), tmp_path, BUILD_BOUND_S)
    assert out.kind == expect["expect"], (out.kind, out.detail)
    assert expect["contains"].lower() in out.detail.lower(), out.detail
    assert "\n" not in out.detail.strip()
