"""A building of several storeys: one map per storey and the building manifest.

``mapkit build model.ifc -o DIR`` reads the model once, builds every
storey's map through the pipeline (:func:`mapkit.pipeline.build_map_of_scene`,
z measured from that storey's floor) and writes ``DIR/<storey>.lmap`` for
each and ``DIR/building.json``, the manifest (docs/building.md): the
storeys in order with their elevations, heights and map files, the source
and its SHA-256, and the vertical connections (stairs, ramps, lifts) with
their footprint per storey. Nothing is written until every storey is built.
"""

from __future__ import annotations

import json
import re
import time
from dataclasses import dataclass, field
from pathlib import Path

import shapely
from shapely.geometry import mapping

# The manifest's name, format and reader are the shared core's (the matcher
# reads buildings too); kept importable from here.
from linemap.building import MANIFEST_FORMAT, MANIFEST_NAME, MANIFEST_VERSION, read_manifest
from mapkit.errors import MapkitError

#: Decimals of the manifest's coordinates and heights, metres (a millimetre).
_DECIMALS = 3


@dataclass
class StoreyBuild:
    """One storey's outcome: its ``map`` (a LineMap) and build ``report``,
    or ``why`` it has none (no walls, no free space)."""

    name: str
    file_name: str | None
    map: object = None
    report: object = None
    why: str | None = None
    seconds: float = 0.0


@dataclass
class BuildingBuild:
    """Every storey's outcome, the manifest, and the seconds reading the model took."""

    storeys: list[StoreyBuild]
    manifest: dict
    import_seconds: float
    warnings: list[str] = field(default_factory=list)


def build_building(model_path: str | Path, options, progress: bool = False, map_storeys=None) -> BuildingBuild:
    """Build every storey of the IFC model at ``model_path``; nothing is written.

    ``map_storeys``, if given, maps the storeys' scenes in place of a loop
    here: called with a list of ``(scene, path, options)``, it returns
    :func:`map_storey`'s result for each, in order (``mapkit.batch`` runs
    them as Dask tasks); the maps are the same either way."""
    from linemap.lmap import file_sha256

    from mapkit import __version__
    from mapkit.importers.ifc import load_building

    path = Path(model_path)
    options.validate()
    t = time.perf_counter()
    building = load_building(path, options)
    import_seconds = time.perf_counter() - t
    names = storey_file_names([s.name for s in building.storeys])
    outcomes: list[StoreyBuild | None] = [None] * len(building.storeys)
    calls, called, scene_seconds = [], [], []
    for k, storey in enumerate(building.storeys):
        t = time.perf_counter()
        try:
            scene = building.scene(k, options)
        except MapkitError as exc:
            outcomes[k] = StoreyBuild(storey.name, None, why=str(exc), seconds=time.perf_counter() - t)
            continue
        calls.append((scene, path, _storey_options(options, storey.name)))
        called.append(k)
        scene_seconds.append(time.perf_counter() - t)
        if map_storeys is None:  # one storey at a time: one scene in memory at a time
            called.pop()
            _record(outcomes, k, storey.name, names[k], map_storey(*calls.pop(), progress), scene_seconds.pop())
    if map_storeys is not None:
        for k, result, seconds in zip(called, map_storeys(calls), scene_seconds):
            _record(outcomes, k, building.storeys[k].name, names[k], result, seconds)
    if not any(o.map is not None for o in outcomes):
        raise MapkitError(f"{path.name}: no storey could be mapped: " + "; ".join(o.why for o in outcomes))
    source = {"name": path.name, "sha256": file_sha256(path), "bytes": path.stat().st_size,
              "schema": building.info["schema"]}
    manifest = {
        "format": MANIFEST_FORMAT,
        "version": MANIFEST_VERSION,
        "generator": f"mapkit {__version__}",
        "units": "m",
        "source": source,
        "storeys": [_storey_entry(s, o) for s, o in zip(building.storeys, outcomes)],
        "connections": [_connection_entry(c, building.storeys) for c in building.connections],
    }
    warnings = [w for o in outcomes if o.report for w in o.report.warnings]
    return BuildingBuild(outcomes, manifest, import_seconds, warnings)


def map_storey(scene, path: Path, options, progress: bool = False) -> tuple:
    """One storey's map: ``(linemap, report, None, seconds)``, or
    ``(None, None, why, seconds)`` when it has none (a MapkitError: no
    walls, no free space)."""
    from mapkit.pipeline import build_map_of_scene

    t = time.perf_counter()
    try:
        linemap, report = build_map_of_scene(scene, path, options, progress)
        return linemap, report, None, time.perf_counter() - t
    except MapkitError as exc:
        return None, None, str(exc), time.perf_counter() - t


def _record(outcomes: list, k: int, name: str, file_name: str, result: tuple, scene_seconds: float) -> None:
    """Put :func:`map_storey`'s ``result`` as storey ``k``'s outcome (its
    seconds: making the scene and mapping it)."""
    linemap, report, why, seconds = result
    if linemap is None:
        outcomes[k] = StoreyBuild(name, None, why=why, seconds=scene_seconds + seconds)
    else:
        outcomes[k] = StoreyBuild(name, file_name, linemap, report, seconds=scene_seconds + seconds)


def write_building(result: BuildingBuild, out_dir: str | Path) -> Path:
    """Write each storey's map and the manifest into ``out_dir`` (made if
    missing); the manifest last, so a manifest names only written maps."""
    from linemap.atomic import write_atomic
    from linemap.lmap import save_map

    out = Path(out_dir)
    if out.exists() and not out.is_dir():
        raise MapkitError(f"{out}: exists and is not a folder; give a folder for the building's maps (-o DIR)")
    out.mkdir(parents=True, exist_ok=True)
    for o in result.storeys:
        if o.map is not None:
            save_map(out / o.file_name, o.map)
    manifest = out / MANIFEST_NAME
    write_atomic(manifest, json.dumps(result.manifest, indent=1) + "\n")
    return manifest


def storey_file_names(names: list[str]) -> list[str]:
    """A map file name per storey name: letters, digits, ``.``, ``-`` and
    ``_`` kept, any other run of characters one ``_``; unique (``_2``,
    ``_3``, ... added, compared ignoring case, for case-blind file systems)."""
    out, taken = [], set()
    for name in names:
        stem = re.sub(r"[^A-Za-z0-9._-]+", "_", name).strip("._") or "storey"
        candidate, n = stem, 1
        while candidate.casefold() in taken or candidate.casefold() == Path(MANIFEST_NAME).stem:
            n += 1
            candidate = f"{stem}_{n}"
        taken.add(candidate.casefold())
        out.append(f"{candidate}.lmap")
    return out


def load_manifest(path: str | Path) -> dict:
    """A building manifest, checked for its format, version and shape
    (:func:`linemap.building.read_manifest`); LmapError otherwise."""
    return read_manifest(path)


def _storey_options(options, name: str):
    """``options`` with the storey's name recorded (the map's META says which storey it is)."""
    from dataclasses import replace

    return replace(options, floor_name=name)


def _storey_entry(storey, outcome: StoreyBuild) -> dict:
    entry = {
        "name": storey.name,
        "elevation_m": round(storey.elevation, _DECIMALS),
        "height_m": round(storey.height, _DECIMALS),
        "map": outcome.file_name if outcome.map is not None else None,
    }
    if outcome.map is not None:
        entry["wall_height_m"] = round(float(outcome.map.meta["wall_height"]), _DECIMALS)
        entry["segments"] = outcome.report.counts["segments"]
        entry["regions"] = outcome.report.counts["regions"]
    else:
        entry["why"] = outcome.why
    return entry


def _connection_entry(connection, storeys) -> dict:
    return {
        "kind": connection.kind,
        "ifc_class": connection.ifc_class,
        "name": connection.name,
        "guid": connection.guid,
        "storeys": [storeys[k].name for k in sorted(connection.footprints)],
        "footprints": {storeys[k].name: mapping(shapely.set_precision(fp, 10.0**-_DECIMALS))
                       for k, fp in sorted(connection.footprints.items())},
    }
