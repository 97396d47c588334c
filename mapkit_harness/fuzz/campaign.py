"""The fuzz campaign: many cases of every family, a few at a time, each in
a forked child under a time and memory bound; a failing case saved as a
folder (``cases.save_case``) for ``tools/fuzz.py --replay`` and
``tests/data/fuzz/``.
"""

from __future__ import annotations

import math
import shutil
import sys
import time
from pathlib import Path

from .cases import save_case
from .classify import BUG, OUTCOMES, OVER
from .families import FAMILIES, make_case
from .matcher_inputs import base_frame, base_run
from .run import finish_case, start_case
from .segments import base_segments_csv


def preload() -> None:
    """Import what the cases run before forking, so that each child starts warm."""
    import cv2  # noqa: F401
    import ezdxf  # noqa: F401
    import shapely  # noqa: F401
    import trimesh  # noqa: F401

    import mapkit.assemble  # noqa: F401
    import mapkit.cli  # noqa: F401
    import mapkit.edges  # noqa: F401
    import mapkit.importers.dxf  # noqa: F401
    import mapkit.importers.mesh  # noqa: F401
    import mapkit.importers.segments  # noqa: F401
    import mapkit.importers.zind  # noqa: F401
    import mapkit.pipeline  # noqa: F401
    import mapkit.preview  # noqa: F401
    import mapkit.view.snapshot  # noqa: F401
    import mapkit.vir  # noqa: F401
    import mapkit.visibility  # noqa: F401
    import matcher.cli  # noqa: F401
    import matcher.cli_track  # noqa: F401
    import matcher.lost  # noqa: F401
    import matcher.tracking.tracker  # noqa: F401

    base_frame()
    base_run()
    base_segments_csv()


def campaign(counts: dict[str, int], seed: int, workers: int, bound_s: float, mem_gb: float, save: Path | None,
             scratch: Path, progress: bool = True, minutes: float = math.inf) -> dict[str, dict[str, int]]:
    """Run every case, ``workers`` at a time, the families interleaved in
    proportion to their counts (so that a campaign stopped after ``minutes``
    has run a share of each); returns counts per family and outcome."""
    todo = sorted(((fam, i) for fam in FAMILIES for i in range(counts.get(fam, 0))),
                  key=lambda c: ((c[1] + 0.5) / counts[c[0]], FAMILIES.index(c[0])))
    started = time.monotonic()
    stop_at = started + 60.0 * minutes
    table = {fam: {k: 0 for k in OUTCOMES} for fam in FAMILIES if counts.get(fam)}
    preload()
    for fam in table:  # build the shared inputs once, before forking
        make_case(fam, seed, 0)
    running = []
    done = 0
    while todo or running:
        if time.monotonic() > stop_at and todo:
            print(f"stopping: {minutes:g} minutes are up, {len(todo)} cases not started", file=sys.stderr)
            todo = []
        while todo and len(running) < workers:
            fam, i = todo.pop(0)
            case = make_case(fam, seed, i)
            running.append((case, *start_case(case, scratch / case.name, mem_gb)))
        time.sleep(0.005)
        for entry in list(running):
            case, pid, conn, t0 = entry
            out = finish_case(pid, conn, t0, bound_s, block=False)
            if out is None:
                continue
            running.remove(entry)
            done += 1
            table[case.family][out.kind] += 1
            _clean(scratch / case.name)
            if out.kind in (BUG, OVER):
                where = save_case(case, out, save) if save else None
                print(f"{case.name}: {out.kind} ({case.note}) {out.detail.strip().splitlines()[-1:]}"
                      + (f" -> {where}" if where else ""), file=sys.stderr)
            if progress and done % 100 == 0:
                print(f"{done} cases done, {time.monotonic() - started:.0f} s", file=sys.stderr)
    return table


def _clean(folder: Path) -> None:
    shutil.rmtree(folder, ignore_errors=True)
