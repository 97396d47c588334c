"""Damaged and random segments files (CSV: the example map's segments with
cells, lines or bytes damaged; JSON: two rooms with an outline and walls,
values made hostile; random segments): ``mapkit build`` ends in a
one-line error (exit 2) or a map, within its bound; never a traceback or
a hang."""

from __future__ import annotations

import fuzz
import pytest
from fuzz_helpers import BUILD_BOUND_S, check_case, fuzz_settings
from hypothesis import given
from hypothesis import strategies as st


@pytest.fixture(scope="module", autouse=True)
def _warm():
    fuzz.preload()


@fuzz_settings(examples=8)
@given(rng=st.randoms(use_true_random=False))
@pytest.mark.slow
def test_a_damaged_segments_file_ends_in_a_clean_error_or_a_map(tmp_path_factory, rng):
    case = fuzz.segments_case(rng)
    check_case(case, tmp_path_factory.mktemp("case"), BUILD_BOUND_S)


@pytest.mark.parametrize("name, text", [
    ("segments.json", lambda: fuzz.json.dumps(fuzz.base_segments())),
    ("segments.csv", fuzz.base_segments_csv),
])
def test_the_undamaged_files_build(tmp_path, name, text):
    """The bases every mutation starts from build: the cases reach the
    region builder, not only the reader."""
    case = fuzz.Case("segments", "base", {name: text().encode()}, ["mapkit", "build", name, "-o", "out.lmap"])
    assert fuzz.run_bounded(case, tmp_path, BUILD_BOUND_S).kind == fuzz.VALID


def test_the_mutations_change_the_csv():
    import random

    original = fuzz.base_segments_csv()
    texts = [fuzz._mutate_csv(original, random.Random(i))[0] for i in range(20)]
    assert sum(t != original for t in texts) >= 18
