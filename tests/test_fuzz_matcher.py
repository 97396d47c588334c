"""Random values for every matcher input: lines files and arrays of odd
shapes and dtypes, camera files of each format, priors, dt, dyaw, budgets,
images of odd sizes and dtypes, and the JSON Lines frame files of
``matcher track``. Each case ends in a one-line error (exit 2, InputError
through the API), a falsy result with its reason, or a valid result."""

from __future__ import annotations

import fuzz
import pytest
from fuzz_helpers import CALL_BOUND_S, check_case, fuzz_settings
from hypothesis import given
from hypothesis import strategies as st


@pytest.fixture(scope="module", autouse=True)
def _warm():
    fuzz.preload()


KINDS = {"lines file": fuzz._lines_file_case, "camera file": fuzz._camera_file_case,
         "options": fuzz._options_case, "image file": fuzz._image_file_case,
         "lines array": fuzz._lines_array_case, "image array": fuzz._image_array_case,
         "frames": fuzz._frames_case}


@pytest.mark.parametrize("kind", sorted(KINDS))
@fuzz_settings(examples=5)
@given(rng=st.randoms(use_true_random=False))
@pytest.mark.slow
def test_odd_matcher_inputs_end_in_an_error_a_reason_or_a_pose(tmp_path_factory, kind, rng):
    case = KINDS[kind](rng, kind.replace(" ", "_"))
    check_case(case, tmp_path_factory.mktemp("case"), CALL_BOUND_S)


def test_the_undamaged_inputs_localise(tmp_path):
    """The base every mutation starts from is a frame the matcher localises:
    the cases reach the matcher's later stages, not only its input checks."""
    import random

    case = fuzz._lines_file_case(random.Random(0), "base")
    case.files["lines.json"] = fuzz.json.dumps({"lines": fuzz.base_frame()["lines"]}).encode()
    assert fuzz.run_bounded(case, tmp_path, CALL_BOUND_S).kind == fuzz.VALID
