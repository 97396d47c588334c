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


# ---- the order of the tests, for pytest-xdist's workers ---------------------
#
# The suite runs under ``--dist worksteal`` (pyproject.toml's addopts): the
# collection is cut into one run of consecutive tests per worker, and a
# worker that has run out takes the second half of what another still has
# queued. So that the workers end together, each run starts with its share
# of the slow tests (dealt out in turn) and ends with short ones: what is
# taken from a queue's end, and what a worker finishes on, is then short.
# The tests that share a module-scoped fixture of their module (a built map,
# a Dask cluster, a browser) stay together and in their order, so one worker
# makes that fixture once. Without xdist: the slow tests first, which no
# test depends on.

def _shares_a_module_fixture(item: pytest.Item) -> bool:
    """Whether ``item`` uses a module-scoped fixture defined in its own module."""
    module_id = item.nodeid.split("::")[0]
    info = getattr(item, "_fixtureinfo", None)
    if info is None:
        return False
    return any(fixturedef.scope == "module" and fixturedef.baseid == module_id
               for name in info.names_closure for fixturedef in info.name2fixturedefs.get(name, ()))


def _workers(config) -> int:
    """How many xdist workers share the collection (1 without xdist)."""
    workerinput = getattr(config, "workerinput", None)
    return int(workerinput["workercount"]) if workerinput else 1


@pytest.hookimpl(trylast=True)  # after pytest's own reordering by parametrized fixtures
def pytest_collection_modifyitems(config, items):
    units: dict[str, list[pytest.Item]] = {}  # a module's id or a test's id -> its tests, in collection order
    for item in items:
        key = item.nodeid.split("::")[0] if _shares_a_module_fixture(item) else item.nodeid
        units.setdefault(key, []).append(item)
    slow = [u for u in units.values() if any(i.get_closest_marker("slow") for i in u)]
    quick = [u for u in units.values() if not any(i.get_closest_marker("slow") for i in u)]
    workers = _workers(config)
    ordered: list[pytest.Item] = []
    left, run_end = len(items), 0
    for k in range(workers):
        share = left // (workers - k)  # worksteal's first cut: an equal share of what is left
        left, run_end = left - share, run_end + share
        for unit in slow[k::workers]:
            ordered += unit
        while quick and (len(ordered) < run_end or k == workers - 1):
            ordered += quick.pop(0)
    items[:] = ordered
