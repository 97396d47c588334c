"""Damaged DXF plans (mapkit_harness.fuzz's mutations of maps/flat.dxf and the
real plans of tests/data): every case ends in a one-line error (exit 2), a
build or a listing, within its bound; never a traceback or a hang."""

from __future__ import annotations

import pytest
from fuzz_helpers import BUILD_BOUND_S, check_case, fuzz_settings
from hypothesis import given
from hypothesis import strategies as st

from mapkit_harness.fuzz.campaign import preload
from mapkit_harness.fuzz.dxf import DXF_SOURCES, dxf_case


@pytest.fixture(scope="module", autouse=True)
def _warm():
    preload()  # children fork from a process with everything imported


@pytest.mark.parametrize("source", ["flat", "thehouse", "nested_blocks", "bulge_apse"])
@fuzz_settings(examples=3)
@given(rng=st.randoms(use_true_random=False))
@pytest.mark.slow
def test_a_damaged_plan_ends_in_a_clean_error_or_a_map(tmp_path_factory, source, rng):
    case = dxf_case(rng, sources=[source])
    check_case(case, tmp_path_factory.mktemp("case"), BUILD_BOUND_S)


def test_the_mutations_change_the_plan():
    """The generator damages what it says (a case that changes nothing tests nothing)."""
    import random

    original = DXF_SOURCES["flat"].read_bytes()
    cases = [dxf_case(random.Random(i), sources=["flat"]) for i in range(20)]
    assert sum(c.files["plan.dxf"] != original for c in cases) >= 18
