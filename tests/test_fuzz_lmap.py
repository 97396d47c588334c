"""Damaged and crafted maps (bytes flipped, cut, appended; or chunks with
valid checksums around a damaged payload or hostile META values): every
command that loads a map ends in a one-line error or works, within its
bound."""

from __future__ import annotations

import pytest
from fuzz_helpers import CALL_BOUND_S, check_case, fuzz_settings
from hypothesis import given
from hypothesis import strategies as st

from mapkit_harness.fuzz.campaign import preload
from mapkit_harness.fuzz.cases import ROOT
from mapkit_harness.fuzz.lmap_files import lmap_case, lmap_chunks, lmap_encode


@pytest.fixture(scope="module", autouse=True)
def _warm():
    preload()


@pytest.mark.slow
@fuzz_settings(examples=25)
@given(rng=st.randoms(use_true_random=False))
def test_a_damaged_map_is_refused_in_one_line_or_read(tmp_path_factory, rng):
    case = lmap_case(rng)
    check_case(case, tmp_path_factory.mktemp("case"), CALL_BOUND_S)


def test_crafted_maps_keep_valid_checksums():
    """Half the cases re-encode the chunks: the loader must meet them past
    its checksum test, where hostile content matters."""
    import random

    from linemap.lmap import decode

    original = (ROOT / "maps" / "flat.lmap").read_bytes()
    assert lmap_encode(lmap_chunks(original)) == original
    decode(lmap_encode(lmap_chunks(original)))
