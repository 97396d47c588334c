"""Benchmark ``mapkit build`` on real IFC models: time, memory and counts per storey,
and whether every door and window of the model is in its storey's map.

    python tools/bench_ifc.py /path/to/AC20-FZK-Haus.ifc /path/to/duplex.ifc [--report docs/benchmarks/ifc.md]

The models are not in the repository (see docs/building.md for where to get
them). Each storey is built on its own (``--storey NAME``, a fresh process:
its wall time and peak resident memory are the storey's), then the whole
building once (``-o DIR``). A door or window is in its storey's map when a
jamb, lintel or window edge of that map lies within ``NEAR_M`` of its body
seen from above. Prints markdown tables.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from mapkit_harness.tables import add_report_option, markdown_table, reported

ROOT = Path(__file__).resolve().parent.parent

#: A door or window is found when an opening edge of its storey's map is this close to it, metres.
NEAR_M = 0.05


def timed(argv: list[str]) -> tuple[float, float]:
    """Run ``argv``; its wall seconds and peak resident memory, MiB. Exit on failure."""
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    t = time.perf_counter()
    proc = subprocess.Popen(argv, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    _, status, usage = os.wait4(proc.pid, 0)
    seconds = time.perf_counter() - t
    err = proc.stderr.read().decode()
    proc.returncode = os.waitstatus_to_exitcode(status)
    if proc.returncode != 0:
        sys.exit(f"{' '.join(argv)} failed: {err.strip()}")
    return seconds, usage.ru_maxrss / 1024.0


def openings_in_maps(model: Path, out: Path, manifest: dict) -> list[list]:
    """Per storey: doors and windows of the model, and how many its map shows."""
    import numpy as np
    import shapely

    from linemap.lmap import SegmentKind, load_map
    from mapkit.importers.ifc.geometry import element_meshes
    from mapkit.importers.ifc.read import open_model

    m = open_model(model)
    rows = []
    for storey, entry in zip(m.storeys, manifest["storeys"]):
        elements = storey.of("door") + storey.of("window")
        if not elements:
            continue
        meshes = element_meshes(m.file, elements)
        found, missing = 0, []
        if entry["map"]:
            lmap = load_map(out / entry["map"])
            near = np.isin(lmap.kinds, [SegmentKind.JAMB, SegmentKind.LINTEL, SegmentKind.WINDOW])
            lines = shapely.linestrings(lmap.segments[near][:, :, :2])
        else:
            lines = np.array([])
        for e in elements:
            fp = meshes[e.id()].footprint() if e.id() in meshes else None
            if fp is not None and len(lines) and shapely.distance(lines, fp).min() <= NEAR_M:
                found += 1
            else:
                missing.append(e.Name or e.GlobalId)
        rows.append([storey.name, len(storey.of("door")), len(storey.of("window")), f"{found}/{len(elements)}",
                     ", ".join(missing) or "-"])
    return rows


def bench(model: Path, work: Path) -> None:
    mapkit = [sys.executable, "-m", "mapkit"]
    out = work / model.stem
    seconds, mib = timed(mapkit + ["build", str(model), "-o", str(out), "-q"])
    manifest = json.loads((out / "building.json").read_text())
    rows = []
    for s in manifest["storeys"]:
        if not s["map"]:
            rows.append([s["name"], f"{s['elevation_m']:g}", "-", "-", "-", "-", "-", s.get("why", "")])
            continue
        t, peak = timed(mapkit + ["build", str(model), "--storey", s["name"], "-o", str(work / "one.lmap"), "-q"])
        rows.append([s["name"], f"{s['elevation_m']:g}", f"{s['height_m']:g}", f"{s['wall_height_m']:g}",
                     s["segments"], s["regions"], f"{t:.1f}", f"{peak:.0f}"])
    rows.append(["whole building (-o DIR)", "", "", "", sum(s.get("segments", 0) for s in manifest["storeys"]),
                 sum(s.get("regions", 0) for s in manifest["storeys"]), f"{seconds:.1f}", f"{mib:.0f}"])
    print(f"\n### {model.name} ({manifest['source']['schema']})\n")
    print(markdown_table(["storey", "floor (m)", "height (m)", "walls (m)", "segments", "regions", "time (s)",
                 "peak RSS (MiB)"], rows))
    print("\nconnections: " + ("; ".join(f"{c['kind']} '{c['name']}' {' <-> '.join(c['storeys'])}"
                                          for c in manifest["connections"]) or "none"))
    print()
    print(markdown_table(["storey", "doors", "windows", "in the map", "missing"], openings_in_maps(model, out, manifest)))


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("models", nargs="+", type=Path, help="IFC models")
    add_report_option(p)
    args = p.parse_args(argv)

    def run() -> int:
        with tempfile.TemporaryDirectory() as tmp:
            for model in args.models:
                bench(model, Path(tmp))
        return 0

    return reported(args.report, run, __file__, argv)


if __name__ == "__main__":
    raise SystemExit(main())
