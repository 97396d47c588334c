"""The matcher's entry points now live in :mod:`matcher.from_prior` (with a
prior) and :mod:`matcher.lost` (without); this module keeps the old import
path."""

from matcher.from_prior import localize  # noqa: F401
from matcher.lost import localize_global  # noqa: F401
