"""Importers, keyed by file suffix. Each turns a file into a :class:`~mapkit.scene.Scene`.

An importer module defines ``SUFFIXES`` (lower-case, with the dot) and
``load_scene(path: Path, options: BuildOptions) -> Scene``. It reports what
it decided through ``logging.getLogger("mapkit")`` warnings and in
``scene.info["warnings"]``, and raises :class:`~mapkit.errors.MapkitError`
for anything the user can fix.
"""

from __future__ import annotations

import importlib
from pathlib import Path

from mapkit.errors import MapkitError
from mapkit.options import BuildOptions
from mapkit.scene import Scene

#: suffix -> importer module (imported on first use: ezdxf and trimesh are heavy).
REGISTRY = {
    ".dxf": "mapkit.importers.dxf",
    ".obj": "mapkit.importers.mesh",
    ".ply": "mapkit.importers.mesh",
    ".stl": "mapkit.importers.mesh",
    ".glb": "mapkit.importers.mesh",
    ".gltf": "mapkit.importers.mesh",
    ".off": "mapkit.importers.mesh",
    ".csv": "mapkit.importers.segments",
}


def load_scene(path: str | Path, options: BuildOptions | None = None) -> Scene:
    """Import a floor plan or mesh; the importer is chosen by the file suffix."""
    path = Path(path)
    options = options or BuildOptions()
    if not path.exists():
        raise MapkitError(f"{path}: no such file; check the path")
    if path.is_dir():
        raise MapkitError(f"{path} is a directory; give a .dxf plan or a mesh file")
    suffix = path.suffix.lower()
    if suffix not in REGISTRY:
        known = ", ".join(sorted(REGISTRY))
        raise MapkitError(f"{path}: unsupported file type '{suffix or '(none)'}'; give one of {known}")
    module = importlib.import_module(REGISTRY[suffix])
    return module.load_scene(path, options)
