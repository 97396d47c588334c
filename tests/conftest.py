"""Fixtures shared by the matcher's tests: the two-room test map of
tools/synthetic_building.py and the paper's camera of tools/simulate.py."""

from __future__ import annotations

import sys
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tools"))


@pytest.fixture(scope="session")
def small_map():
    from synthetic_building import make_small_flat

    return make_small_flat()


@pytest.fixture(scope="session")
def cam():
    from simulate import paper_camera

    return paper_camera()
