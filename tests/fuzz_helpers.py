"""Shared by the fuzz tests: hypothesis settings and the bounded run of a
case of mapkit_harness.fuzz.

Each case runs in a forked child under a time bound and an address-space
limit; the bound catches hangs (a case that would run for minutes), it is
not a performance assertion: builds of these plans take a few seconds, the
bound is many times that. Hypothesis is derandomized (the same examples on
every run) with no example database, and its own per-example deadline is
off for the same reason: a slow machine must not make the suite red.
"""

from __future__ import annotations

from hypothesis import HealthCheck, settings

from mapkit_harness.fuzz.cases import Case, Outcome
from mapkit_harness.fuzz.classify import ACCEPTED
from mapkit_harness.fuzz.run import run_bounded

#: Hang bound of a case that builds a map, and of one that does not, seconds.
BUILD_BOUND_S = 120.0
CALL_BOUND_S = 60.0


def fuzz_settings(examples: int):
    return settings(max_examples=examples, derandomize=True, database=None, deadline=None,
                    suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture,
                                           HealthCheck.data_too_large])


def check_case(case: Case, folder, bound_s: float) -> Outcome:
    """Run ``case`` bounded; fail with its note and detail unless it ended
    in a clean error, a falsy result with its reason or a valid result."""
    out = run_bounded(case, folder, bound_s)
    assert out.kind in ACCEPTED, f"{case.name} ({case.note}) call {case.call}: {out.kind}: {out.detail}"
    return out
