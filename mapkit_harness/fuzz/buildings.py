"""The ``building`` fuzz family: a building manifest (``building.json``)
of two storeys whose maps are ``maps/flat.lmap``, damaged: the manifest's
JSON mutated, a storey's map damaged or missing; then every command that
reads a building (``mapkit info``, ``matcher localize`` with a prior on a
storey and in lost mode over every storey, ``matcher track``).
"""

from __future__ import annotations

import json
import random

from .cases import ROOT, Case, source_bytes
from .matcher_inputs import base_camera, base_frame
from .mutations import mutate_bytes, mutate_json_doc

STOREYS = ("Ground", "Upper")


def base_manifest() -> dict:
    """The manifest of two storeys, each a copy of ``maps/flat.lmap`` (the
    source it names is that map's), as ``mapkit build model.ifc -o DIR`` writes one."""
    from linemap.lmap import decode

    source = decode(source_bytes(ROOT / "maps" / "flat.lmap")).meta["source"]
    storeys = [{"name": name, "elevation_m": 3.0 * k, "height_m": 3.0, "map": f"{name}.lmap",
                "wall_height_m": 2.5, "segments": 0, "regions": 0} for k, name in enumerate(STOREYS)]
    stair = {"kind": "stair", "ifc_class": "IfcStair", "name": "stair", "guid": "0" * 22, "storeys": list(STOREYS),
             "footprints": {name: {"type": "Polygon", "coordinates": [[[1, 1], [2, 1], [2, 2], [1, 1]]]}
                            for name in STOREYS}}
    return {"format": "mapkit-building", "version": 1, "generator": "mapkit 0.1.0", "units": "m",
            "source": {"name": source["name"], "sha256": source["sha256"], "bytes": source["bytes"],
                       "schema": "IFC4"}, "storeys": storeys, "connections": [stair]}


def building_case(rng: random.Random, name: str = "building") -> Case:
    """A damaged building and the commands that read it."""
    blob = source_bytes(ROOT / "maps" / "flat.lmap")
    files = {f"{s}.lmap": blob for s in STOREYS}
    manifest = json.dumps(base_manifest(), indent=1)
    r = rng.random()
    if r < 0.6:
        manifest, note = mutate_json_doc(base_manifest(), rng)
    elif r < 0.85:
        victim = rng.choice(STOREYS)
        files[f"{victim}.lmap"], note = mutate_bytes(blob, rng)
        note = f"{victim}.lmap {note}"
    else:
        victim = rng.choice(STOREYS)
        del files[f"{victim}.lmap"]
        note = f"{victim}.lmap missing"
    f = base_frame()
    files.update({"building.json": manifest.encode(), "camera.json": json.dumps(base_camera()).encode(),
                  "lines.json": json.dumps({"lines": f["lines"]}).encode(),
                  "run.jsonl": (json.dumps({"t": 0.0, "odom": f["prior"], "lines": f["lines"]}) + "\n").encode()})
    common = ["--camera", "camera.json"]
    prior = ["--prior", ",".join(map(str, f["prior"])), "--dt", str(f["dt"]), "--dyaw", str(f["dyaw"]),
             "--storey", rng.choice(STOREYS)]
    readers = [["mapkit", "info", "building.json"],
               ["matcher", "localize", "--map", "building.json", *common, "--lines", "lines.json", *prior],
               ["matcher", "localize", "--map", "building.json", *common, "--lines", "lines.json", "--lost",
                "--budget-ms", "300"],
               ["matcher", "track", "--map", "building.json", *common, "--frames", "run.jsonl", *prior]]
    rng.shuffle(readers)
    return Case("building", name, files, readers[0], note, readers[1:])
