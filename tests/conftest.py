"""Fixtures shared by the matcher's tests: the two-room test map and the
paper's camera of the harness (mapkit_harness.plans, mapkit_harness.simulate)."""

from __future__ import annotations

import pytest


@pytest.fixture(scope="session")
def small_map():
    from mapkit_harness.plans import make_small_flat

    return make_small_flat()


@pytest.fixture(scope="session")
def cam():
    from mapkit_harness.simulate import paper_camera

    return paper_camera()
