"""Two ways to rank the places a frame may have been taken from, one way to
verify them.

- ``tree``: the paper's interpretation tree (:mod:`matcher.search.tree`, with
  the strategy of :mod:`matcher.search.tree.strategy`): correspondences between image
  lines and map segments, grown into consistent sets inside the prior.
- ``structure`` (:mod:`matcher.search.structure`): every pose the prior
  allows (the whole floor when lost) scored at once from the scene's
  structure (level lines give the yaw, vertical lines the bearings of the
  corners and jambs, floor and ceiling junctions the distance to the walls
  per bearing); the best few places are the seeds.

Either way the seeds go to stage 2 (:mod:`matcher.stage2`, on a rig
:mod:`matcher.rig.verify`) and the one verdict (:mod:`matcher.verdict`).
"""

from __future__ import annotations

from linemap.errors import InputError

#: The searches, by name.
SEARCHES = ("tree", "structure")


def check_search(search) -> str:
    """``search`` if it names a search of :data:`SEARCHES`, else InputError."""
    if search not in SEARCHES:
        raise InputError(f"search must be one of {', '.join(SEARCHES)}, got {search!r}")
    return search


#: The default search per kind of frame: a rig of several cameras (a
#: panorama's views, a ring) from a prior, the same lost, and one camera.
#: Chosen on measurement (docs/benchmarks/real-structure.md): the structure
#: search is right more often on real panoramas and rigs; lost, it ranks
#: the synthetic flat's look-alike rooms above the true one where the
#: tree finds it, so the tree stays there.
DEFAULTS = {"rig": "structure", "rig_lost": "tree", "single": "tree"}


def search_of(tolerances) -> str | None:
    """``tolerances.search`` (None when no tolerances or not a
    :class:`~matcher.tolerances.Tolerances`: the entry point's own check
    says so)."""
    return getattr(tolerances, "search", None)


def default_search(search, rig=None, lost: bool = False) -> str:
    """``search`` checked (:func:`check_search`), or when None the default
    for ``rig`` (:data:`DEFAULTS`; None or a one-camera rig: a single
    camera), ``lost`` or from a prior."""
    if search is not None:
        return check_search(search)
    if rig is None or len(rig) == 1:
        return DEFAULTS["single"]
    return DEFAULTS["rig_lost" if lost else "rig"]
