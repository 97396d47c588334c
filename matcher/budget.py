"""A call's time budget as the moments its searches must stop.

The budget (``Tolerances.time_budget_ms``) is split: the searches (the
interpretation tree, the second search, the resection) may take the first
``SharedConstants.search_share`` of it, the final visibility tests of the sets they found
the rest; stage 2 then runs on what passed, at most ``max_hypotheses``
sets (a few milliseconds). The work before the tree (correspondences and
their pairs, a few milliseconds, tens on the largest scenes) is not cut.
"""

from __future__ import annotations

import math
import time
from typing import NamedTuple

class Deadlines(NamedTuple):
    """``time.perf_counter()`` readings: ``search`` ends the searches,
    ``checks`` the final tests of the sets found (inf: no limit)."""

    search: float = math.inf
    checks: float = math.inf

    @classmethod
    def from_budget(cls, t0: float, budget_ms: float, search_share: float) -> Deadlines:
        """The deadlines of a call started at ``t0`` (perf_counter seconds)
        with ``budget_ms`` milliseconds (inf: none), the searches stopping at
        ``search_share`` of it."""
        if not math.isfinite(budget_ms):
            return NO_LIMIT
        return cls(t0 + search_share * budget_ms / 1e3, t0 + budget_ms / 1e3)

    def may_search(self) -> bool:
        """Is there time left to search?"""
        return time.perf_counter() <= self.search

    def may_check(self) -> bool:
        """Is there time left to test the sets found?"""
        return time.perf_counter() <= self.checks


NO_LIMIT = Deadlines()
