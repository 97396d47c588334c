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
# The suite runs under ``--dist worksteal`` (pyproject.toml's addopts): each
# worker is given a run of consecutive tests, and a worker that has run out
# takes the second half of what another still has to run. The slow tests
# come first, so the long ones start early and the many short ones at the
# end even the workers out; the tests that share a module-scoped fixture of
# their module (a built map, a Dask cluster, a browser) stay together and in
# their order, so a worker makes that fixture once, not once per run of them.
# Without xdist the order alone changes, which no test depends on.

def _shares_a_module_fixture(item: pytest.Item) -> bool:
    """Whether ``item`` uses a module-scoped fixture defined in its own module."""
    module_id = item.nodeid.split("::")[0]
    info = getattr(item, "_fixtureinfo", None)
    if info is None:
        return False
    return any(fixturedef.scope == "module" and fixturedef.baseid == module_id
               for name in info.names_closure for fixturedef in info.name2fixturedefs.get(name, ()))


@pytest.hookimpl(trylast=True)  # after pytest's own reordering by parametrized fixtures
def pytest_collection_modifyitems(config, items):
    units: dict[str, list[pytest.Item]] = {}  # a module's id or a test's id -> its tests, in collection order
    for item in items:
        key = item.nodeid.split("::")[0] if _shares_a_module_fixture(item) else item.nodeid
        units.setdefault(key, []).append(item)
    slow_first = sorted(units.values(), key=lambda unit: not any(i.get_closest_marker("slow") for i in unit))
    items[:] = [item for unit in slow_first for item in unit]
