"""Importers, keyed by file suffix. Each turns a file into a :class:`~mapkit.scene.Scene`.

An importer module defines ``SUFFIXES`` (lower-case, with the dot) and
``load_scene(path: Path, options: BuildOptions) -> Scene``. JSON files are
told apart by content: each module of ``JSON_FORMATS`` also defines
``accepts(doc) -> bool`` (a cheap look at the parsed document's top level)
and ``DESCRIPTION``; the first that accepts a file imports it, and a JSON
file none accepts is a one-line error naming them all. It reports what
it decided through ``logging.getLogger("mapkit")`` warnings and in
``scene.info["warnings"]``, and raises :class:`~mapkit.errors.MapkitError`
for anything the user can fix.
"""

from __future__ import annotations

import importlib
import json
import logging
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
    ".ifc": "mapkit.importers.ifc",
    ".json": "json",  # by content: JSON_FORMATS
}

#: JSON importers, asked in order whether a document is theirs.
JSON_FORMATS = [
    "mapkit.importers.zind",
    "mapkit.importers.segments",
]


def load_scene(path: str | Path, options: BuildOptions | None = None) -> Scene:
    """Import a floor plan or mesh; the importer is chosen by the file suffix."""
    path = Path(path)
    options = options or BuildOptions()
    options.validate()  # again: fields may have been set since construction
    if not path.exists():
        raise MapkitError(f"{path}: no such file; check the path")
    if path.is_dir():
        raise MapkitError(f"{path} is a directory; give a .dxf plan or a mesh file")
    suffix = path.suffix.lower()
    if suffix not in REGISTRY:
        known = ", ".join(sorted(REGISTRY))
        raise MapkitError(f"{path}: unsupported file type '{suffix or '(none)'}'; give one of {known}")
    module = _json_importer(path) if REGISTRY[suffix] == "json" else importlib.import_module(REGISTRY[suffix])
    return module.load_scene(path, options)


def _json_importer(path: Path):
    """The module of ``JSON_FORMATS`` that accepts the file's content."""
    try:
        doc = json.loads(path.read_bytes())
    except (ValueError, RecursionError) as e:  # bad JSON, bad UTF-8, nesting too deep
        raise MapkitError(f"{path}: not valid JSON ({str(e).splitlines()[0][:120]})") from None
    modules = [importlib.import_module(name) for name in JSON_FORMATS]
    for module in modules:
        if module.accepts(doc):
            return module
    known = "; ".join(m.DESCRIPTION for m in modules)
    raise MapkitError(f"{path}: a JSON file of no known kind; accepted: {known}")


def warn_decision(warnings: list[str], message: str) -> None:
    """Report an importer's decision once: to the ``mapkit`` log and in
    ``warnings`` (the list that becomes ``scene.info["warnings"]``)."""
    logging.getLogger("mapkit").warning(message)
    warnings.append(message)
