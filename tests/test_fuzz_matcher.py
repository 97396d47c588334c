"""Random values for every matcher input: lines files and arrays of odd
shapes and dtypes, camera files of each format, priors, dt, dyaw, budgets,
images of odd sizes and dtypes, and the JSON Lines frame files of
``matcher track``. Each case ends in a one-line error (exit 2, InputError
through the API), a falsy result with its reason, or a valid result."""

from __future__ import annotations

import json

import pytest
from fuzz_helpers import CALL_BOUND_S, check_case, fuzz_settings
from hypothesis import given
from hypothesis import strategies as st

from mapkit_harness.fuzz.campaign import preload
from mapkit_harness.fuzz.classify import VALID
from mapkit_harness.fuzz.matcher_inputs import KIND_MAKERS, base_frame
from mapkit_harness.fuzz.run import run_bounded


@pytest.fixture(scope="module", autouse=True)
def _warm():
    preload()


@pytest.mark.parametrize("kind", sorted(KIND_MAKERS))
@fuzz_settings(examples=5)
@given(rng=st.randoms(use_true_random=False))
@pytest.mark.slow
def test_odd_matcher_inputs_end_in_an_error_a_reason_or_a_pose(tmp_path_factory, kind, rng):
    case = KIND_MAKERS[kind](rng, kind.replace(" ", "_"))
    check_case(case, tmp_path_factory.mktemp("case"), CALL_BOUND_S)


def test_the_undamaged_inputs_localise(tmp_path):
    """The base every mutation starts from is a frame the matcher localises:
    the cases reach the matcher's later stages, not only its input checks."""
    import random

    case = KIND_MAKERS["lines file"](random.Random(0), "base")
    case.files["lines.json"] = json.dumps({"lines": base_frame()["lines"]}).encode()
    assert run_bounded(case, tmp_path, CALL_BOUND_S).kind == VALID
