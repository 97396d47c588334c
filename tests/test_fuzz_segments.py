"""Damaged and random segments files (CSV: the example map's segments with
cells, lines or bytes damaged; JSON: two rooms with an outline and walls,
values made hostile; random segments): ``mapkit build`` ends in a
one-line error (exit 2) or a map, within its bound; never a traceback or
a hang."""

from __future__ import annotations

import json

import pytest
from fuzz_helpers import BUILD_BOUND_S, check_case, fuzz_settings
from hypothesis import given
from hypothesis import strategies as st

from mapkit_harness.fuzz.campaign import preload
from mapkit_harness.fuzz.cases import Case
from mapkit_harness.fuzz.classify import VALID
from mapkit_harness.fuzz.run import run_bounded
from mapkit_harness.fuzz.segments import base_segments, base_segments_csv, mutate_csv, segments_case


@pytest.fixture(scope="module", autouse=True)
def _warm():
    preload()


@fuzz_settings(examples=8)
@given(rng=st.randoms(use_true_random=False))
@pytest.mark.slow
def test_a_damaged_segments_file_ends_in_a_clean_error_or_a_map(tmp_path_factory, rng):
    case = segments_case(rng)
    check_case(case, tmp_path_factory.mktemp("case"), BUILD_BOUND_S)


@pytest.mark.parametrize("name, text", [
    ("segments.json", lambda: json.dumps(base_segments())),
    ("segments.csv", base_segments_csv),
])
@pytest.mark.slow
def test_the_undamaged_files_build(tmp_path, name, text):
    """The bases every mutation starts from build: the cases reach the
    region builder, not only the reader."""
    case = Case("segments", "base", {name: text().encode()}, ["mapkit", "build", name, "-o", "out.lmap"])
    assert run_bounded(case, tmp_path, BUILD_BOUND_S).kind == VALID


def test_the_mutations_change_the_csv():
    import random

    original = base_segments_csv()
    texts = [mutate_csv(original, random.Random(i))[0] for i in range(20)]
    assert sum(t != original for t in texts) >= 18
