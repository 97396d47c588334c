"""The fuzz families, by name: each a maker ``(rng, name) -> Case``.

- ``dxf`` (:mod:`.dxf`): damaged DXF plans; ``mapkit build``, ``preview``, ``layers``;
- ``mesh`` (:mod:`.meshes`): every mesh format damaged; ``mapkit build``;
- ``zind`` (:mod:`.zind`): damaged or random ZInD floors; ``mapkit build``, ``preview``;
- ``segments`` (:mod:`.segments`): damaged or random segments files; ``mapkit build``;
- ``lmap`` (:mod:`.lmap_files`): damaged or crafted maps; every command that reads a map;
- ``matcher`` (:mod:`.matcher_inputs`): odd values for every input of the matcher;
- ``building`` (:mod:`.buildings`): damaged building manifests and storey maps; ``mapkit info``,
  ``matcher localize``, ``matcher track``.
"""

from __future__ import annotations

import random

from .buildings import building_case
from .cases import Case
from .dxf import dxf_case
from .lmap_files import lmap_case
from .matcher_inputs import matcher_case
from .meshes import mesh_case
from .segments import segments_case
from .zind import zind_case

FAMILIES = ("dxf", "mesh", "zind", "segments", "lmap", "matcher", "building")

MAKERS = {"dxf": dxf_case, "mesh": mesh_case, "zind": zind_case, "segments": segments_case, "lmap": lmap_case,
          "matcher": matcher_case, "building": building_case}


def make_case(family: str, seed: int, i: int) -> Case:
    """Case ``i`` of ``family`` for ``seed``, drawn from its own
    ``random.Random(f"{family}:{seed}:{i}")``: any case can be drawn again by
    its number."""
    return MAKERS[family](random.Random(f"{family}:{seed}:{i}"), f"{family}-{seed}-{i}")
