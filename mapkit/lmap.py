"""The ``.lmap`` format now lives in :mod:`linemap.lmap` (shared by
``mapkit`` and ``matcher``); this module keeps the old import path."""

from linemap.lmap import *  # noqa: F401,F403
from linemap.lmap import (COORD_QUANTUM_M, FORMAT_MAJOR, FORMAT_MINOR, KIND_NAMES, MAGIC, LineMap,  # noqa: F401
                          LmapError, SegmentKind, decode, encode, file_sha256, load_map, save_map, validate)
