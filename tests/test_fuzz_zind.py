"""Damaged and random ZInD annotations (mapkit_harness.fuzz's mutations of a
ZInD-shaped floor, and floors of random rooms): ``mapkit build`` ends in a
one-line error (exit 2) or a map, within its bound; never a traceback or a
hang."""

from __future__ import annotations

import pytest
from fuzz_helpers import BUILD_BOUND_S, check_case, fuzz_settings
from hypothesis import given
from hypothesis import strategies as st

from mapkit_harness.fuzz.campaign import preload
from mapkit_harness.fuzz.cases import Case
from mapkit_harness.fuzz.classify import VALID
from mapkit_harness.fuzz.mutations import mutate_json_doc
from mapkit_harness.fuzz.run import run_bounded
from mapkit_harness.fuzz.zind import base_zind, zind_case


@pytest.fixture(scope="module", autouse=True)
def _warm():
    preload()


@pytest.mark.slow
@fuzz_settings(examples=8)
@given(rng=st.randoms(use_true_random=False))
def test_damaged_zind_ends_in_a_clean_error_or_a_map(tmp_path_factory, rng):
    case = zind_case(rng)
    check_case(case, tmp_path_factory.mktemp("case"), BUILD_BOUND_S)


def test_the_undamaged_floor_builds_with_its_rooms_and_gaps(tmp_path):
    """The base every mutation starts from builds: the cases reach the
    reconstruction and the region builder, not only the reader."""
    import json

    from mapkit.importers import load_scene

    path = tmp_path / "zind_data.json"
    path.write_text(json.dumps(base_zind()))
    scene = load_scene(path)
    assert scene.info["counts"] == {"rooms": 3, "panoramas": 5, "doors": 2, "windows": 1, "openings": 1}
    assert scene.camera_height == pytest.approx(1.25)
    case = Case("zind", "base", {"zind_data.json": path.read_bytes()},
                     ["mapkit", "build", "zind_data.json", "-o", "out.lmap"])
    assert run_bounded(case, tmp_path / "run", BUILD_BOUND_S).kind == VALID


def test_the_mutations_change_the_document():
    import json
    import random

    original = json.dumps(base_zind())
    texts = [mutate_json_doc(base_zind(), random.Random(i))[0] for i in range(20)]
    assert sum(t != original for t in texts) >= 18
    nested = [mutate_json_doc({"a": [1, 2], "b": {"c": 3}}, random.Random(i)) for i in range(200)]
    deep = [text for text, note in nested if "nest@" in note]
    assert deep and any("[" * 50 in text for text in deep)  # nested past what json.dumps could write


@pytest.mark.slow
def test_the_mutations_draw_the_same_document_for_the_same_seed():
    """A hostile value put into one document and then edited by a later
    mutation must not edit the table it came from: the same seed would then
    draw another document, and hypothesis stops the family as flaky."""
    import random

    from mapkit_harness.fuzz.mutations import HOSTILE_JSON_VALUES

    table = repr(HOSTILE_JSON_VALUES)
    first = [mutate_json_doc(base_zind(), random.Random(i)) for i in range(300)]
    assert repr(HOSTILE_JSON_VALUES) == table
    assert [mutate_json_doc(base_zind(), random.Random(i)) for i in range(300)] == first
