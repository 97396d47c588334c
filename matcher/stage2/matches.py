"""Stage 2's matches as one structure: every hypothesis's (segment, line)
pairs in one set of rows, so that a step takes, drops or adds matches
without keeping parallel arrays in step by hand."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class Matches:
    """Matches, one row t each: ``hyp`` (T,) the hypothesis it belongs to,
    ``local`` (T,) its model segment (an index into the candidates'
    ``segments``, or, before stage 2 picks the piece, their collinear
    groups' ``reps``), ``line`` (T,) its image line. All int64."""

    hyp: np.ndarray
    local: np.ndarray
    line: np.ndarray

    def __len__(self) -> int:
        return len(self.hyp)

    def subset(self, sel) -> Matches:
        """The rows ``sel`` (a (T,) bool mask or indices)."""
        return Matches(self.hyp[sel], self.local[sel], self.line[sel])

    def of(self, which: np.ndarray) -> Matches:
        """The rows of the hypotheses ``which`` (W,) (ascending), their
        ``hyp`` renumbered as positions in ``which``."""
        sel = np.isin(self.hyp, which)
        return Matches(np.searchsorted(which, self.hyp[sel]), self.local[sel], self.line[sel])

    def of_one(self, h: int) -> Matches:
        """The rows of hypothesis ``h``, as hypothesis 0."""
        sel = self.hyp == h
        return Matches(np.zeros(int(sel.sum()), dtype=np.int64), self.local[sel], self.line[sel])

    def with_added(self, more: Matches) -> Matches:
        """These rows and ``more``'s, sorted by hypothesis (stable: each
        hypothesis's own first, then those added)."""
        hyp, local, line = (np.concatenate(a).astype(np.int64)
                            for a in ((self.hyp, more.hyp), (self.local, more.local), (self.line, more.line)))
        order = np.argsort(hyp, kind="stable")
        return Matches(hyp[order], local[order], line[order])
