"""A building of several storeys: the manifest ``building.json`` and its maps.

``mapkit build model.ifc -o DIR`` writes one ``.lmap`` per storey and the
manifest that ties them together (docs/building.md). Both halves read it
here: ``mapkit info`` and the batch builder's skip rule through
:func:`read_manifest`, the matcher through :func:`load_building` (and
``matcher.load_map``, which takes a map or a building: :func:`load_any`).

A :class:`Building` holds its storeys lowest first, each with its name,
floor elevation, height and :class:`~linemap.lmap.LineMap`. The maps are
loaded at once, when the building is: a missing or damaged storey map is
reported then, in one line, not in the middle of a robot's run; and lost
mode searches every storey anyway.
"""

from __future__ import annotations

import json
import math
import os
from dataclasses import dataclass
from pathlib import Path

from linemap.lmap import LineMap, LmapError, load_map

#: The manifest's file name in a building's folder, and its format's name and version.
MANIFEST_NAME = "building.json"
MANIFEST_FORMAT = "mapkit-building"
MANIFEST_VERSION = 1

_REBUILD = "rebuild it with 'mapkit build model.ifc -o DIR'"


class StoreyNeeded(LmapError):
    """A building of several mapped storeys where one storey is needed and
    none was named. Its message names the Python parameter (``storey=NAME``);
    :meth:`naming` gives the same error naming the command line's flag."""

    def __init__(self, before: str, after: str = "", named_by: str = "storey=NAME"):
        self.before, self.after = before, after
        super().__init__(before + named_by + after)

    def naming(self, flag: str) -> "StoreyNeeded":
        """This error naming ``flag`` (``"--storey NAME"``) where the storey goes."""
        return StoreyNeeded(self.before, self.after, flag)


@dataclass(frozen=True)
class Storey:
    """One storey: its ``name`` (the model's), the ``elevation_m`` of its
    floor and its ``height_m`` to the next floor (metres), its ``map``
    (every z measured from this floor), or None with ``why`` it has none
    (no walls, no free space)."""

    name: str
    elevation_m: float
    height_m: float
    map: LineMap | None
    why: str = ""


@dataclass(frozen=True)
class Building:
    """The storeys of a building manifest, lowest first (:class:`Storey`),
    the manifest's ``path`` and its JSON ``manifest`` as read."""

    storeys: tuple[Storey, ...]
    path: Path
    manifest: dict

    @property
    def mapped(self) -> tuple[Storey, ...]:
        """The storeys that have a map, lowest first."""
        return tuple(s for s in self.storeys if s.map is not None)

    def storey(self, name: str | None) -> Storey:
        """The storey called ``name`` (case aside when no name matches
        exactly); with None, the building's only mapped storey. InputError
        (an LmapError) naming the storeys otherwise, or when it has no map."""
        names = ", ".join(repr(s.name) for s in self.storeys)
        if name is None:
            if len(self.mapped) == 1:
                return self.mapped[0]
            raise StoreyNeeded(f"{self.path} is a building of {len(self.mapped)} mapped storeys ({names}): "
                               "give the storey (", ")")
        found = [s for s in self.storeys if s.name == name] or [
            s for s in self.storeys if s.name.casefold() == str(name).casefold()]
        if not found:
            raise LmapError(f"{self.path} has no storey named {name!r}; its storeys: {names}")
        if found[0].map is None:
            raise LmapError(f"storey {found[0].name!r} of {self.path} has no map ({found[0].why}); "
                            "give another storey")
        return found[0]


def manifest_path(path: str | os.PathLike) -> Path:
    """The manifest of ``path``: the file itself, or ``building.json`` in a folder."""
    path = Path(path)
    return path / MANIFEST_NAME if path.is_dir() else path


def is_manifest(doc) -> bool:
    """Is the JSON document ``doc`` a building manifest (by its format)?"""
    return isinstance(doc, dict) and doc.get("format") == MANIFEST_FORMAT


def read_manifest(path: str | os.PathLike) -> dict:
    """The manifest at ``path`` (a ``building.json``, or a folder holding
    one), checked for its format, version and shape (the storeys and their
    map file names); LmapError in one line otherwise, OSError if unreadable."""
    path = manifest_path(path)
    try:
        doc = json.loads(path.read_bytes())
    except (ValueError, RecursionError) as exc:
        why = "nested too deeply" if isinstance(exc, RecursionError) else str(exc).splitlines()[0][:120]
        raise LmapError(f"{path}: not valid JSON ({why})") from None
    if not is_manifest(doc):
        raise LmapError(f"{path}: not a building manifest (a '{MANIFEST_FORMAT}' JSON file 'mapkit build "
                        "model.ifc -o DIR' writes)")
    if doc.get("version") != MANIFEST_VERSION:
        raise LmapError(f"{path}: building manifest version {doc.get('version')!r}; this reader reads version "
                        f"{MANIFEST_VERSION}: upgrade mapkit, or {_REBUILD}")
    _check_shape(doc, path)
    return doc


def _check_shape(doc: dict, path: Path) -> None:
    """LmapError unless ``doc`` has what readers use: a source object with
    its name and SHA-256, storeys (a non-empty list) each with a unique
    name, finite elevation and height, and a map file name beside the
    manifest (or null with the reason), their counts (where given) numbers,
    and a list of connections each with its kind, name, GlobalId and
    storeys."""
    def bad(msg: str) -> LmapError:
        return LmapError(f"{path}: invalid building manifest: {msg}; {_REBUILD}")

    source = doc.get("source")
    if not (isinstance(source, dict) and isinstance(source.get("name"), str)
            and isinstance(source.get("sha256"), str)):
        raise bad("'source' must be an object with the model's 'name' and 'sha256'")
    if not isinstance(doc.get("connections", []), list):
        raise bad("'connections' must be a list")
    storeys = doc.get("storeys")
    if not isinstance(storeys, list) or not storeys:
        raise bad("'storeys' must be a non-empty list")
    seen = set()
    for k, s in enumerate(storeys):
        if not isinstance(s, dict) or not isinstance(s.get("name"), str):
            raise bad(f"storey {k} must be an object with a 'name'")
        for key in ("elevation_m", "height_m"):
            if not _finite_number(s.get(key)):
                raise bad(f"storey {s['name']!r} lacks a finite number '{key}'")
        m = s.get("map")
        if m is not None and not (isinstance(m, str) and m.endswith(".lmap") and Path(m).name == m
                                  and "\\" not in m):
            raise bad(f"storey {s['name']!r}: 'map' must be the file name of a .lmap beside the manifest, "
                      f"got {str(m)[:80]!r}")
        if s["name"] in seen:
            raise bad(f"storey name {s['name']!r} appears twice")
        seen.add(s["name"])
        for key in ("segments", "regions", "wall_height_m"):  # what mapkit info shows; each may be absent
            if s.get(key) is not None and not _finite_number(s[key]):
                raise bad(f"storey {s['name']!r}: '{key}' must be a number")
        if not isinstance(s.get("why", ""), (str, type(None))):
            raise bad(f"storey {s['name']!r}: 'why' must be a text")
    if not any(s.get("map") for s in storeys):
        raise bad("no storey has a map")
    for k, c in enumerate(doc.get("connections", [])):
        if not (isinstance(c, dict) and isinstance(c.get("kind"), str)
                and all(isinstance(c.get(key), (str, type(None))) for key in ("name", "guid"))
                and isinstance(c.get("storeys"), list) and all(isinstance(n, str) for n in c["storeys"])):
            raise bad(f"connection {k} must be an object with its 'kind', 'name', 'guid' and a list of 'storeys' "
                      "names")


def _finite_number(v) -> bool:
    """Is the JSON value ``v`` a finite number (not a boolean, not an integer past a float's range)?"""
    if not isinstance(v, (int, float)) or isinstance(v, bool):
        return False
    try:
        return math.isfinite(float(v))
    except OverflowError:
        return False


def load_building(path: str | os.PathLike) -> Building:
    """The building of the manifest at ``path`` (a ``building.json``, or a
    folder holding one) with every storey's map loaded and checked: each
    map must be the storey's (its META's ``floor_name``) from the model the
    manifest names (its source's SHA-256). LmapError in one line otherwise;
    FileNotFoundError (an OSError) for a missing manifest."""
    path = manifest_path(path)
    doc = read_manifest(path)
    storeys = []
    for s in doc["storeys"]:
        linemap = None
        if s.get("map"):
            map_path = path.parent / s["map"]
            if not map_path.is_file():
                raise LmapError(f"{map_path}: the map of storey {s['name']!r} that {path.name} names is missing; "
                                f"copy the whole folder, or {_REBUILD}")
            linemap = load_map(map_path)
            _check_belongs(linemap, s["name"], doc["source"]["sha256"], map_path)
        storeys.append(Storey(s["name"], float(s["elevation_m"]), float(s["height_m"]), linemap,
                              "" if linemap is not None else str(s.get("why") or "no map")))
    return Building(tuple(storeys), path, doc)


def _check_belongs(linemap: LineMap, name: str, sha256: str, map_path: Path) -> None:
    """LmapError when the map's META says it is another storey's, or was
    built from another model than the manifest's (a folder of mixed builds)."""
    meta = linemap.meta if isinstance(linemap.meta, dict) else {}
    source = meta.get("source") if isinstance(meta.get("source"), dict) else {}
    build = meta.get("build") if isinstance(meta.get("build"), dict) else {}
    if source.get("sha256") not in (None, sha256):
        raise LmapError(f"{map_path}: built from another model (source SHA-256 {str(source['sha256'])[:12]}...) "
                        f"than the manifest names ({sha256[:12]}...); {_REBUILD}")
    if build.get("floor_name") not in (None, name):
        raise LmapError(f"{map_path}: the map of storey {build['floor_name']!r}, not of {name!r} as the manifest "
                        f"says; {_REBUILD}")


def is_building_path(path: str | os.PathLike) -> bool:
    """Does ``path`` name a building: a folder, or a ``.json`` file (a map is a ``.lmap``)?"""
    path = Path(path)
    return path.is_dir() or path.suffix.lower() == ".json"


def load_any(path: str | os.PathLike) -> LineMap | Building:
    """A ``.lmap`` map (:func:`linemap.lmap.load_map`), or the
    :class:`Building` of a manifest (a ``.json`` file, or a folder holding
    ``building.json``). A folder without one is an LmapError."""
    path = Path(path)
    if path.is_dir() and not (path / MANIFEST_NAME).is_file():
        raise LmapError(f"{path} is a directory with no {MANIFEST_NAME}; give a .lmap map or a building manifest")
    return load_building(path) if is_building_path(path) else load_map(path)
