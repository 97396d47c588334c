"""Where the tiles of one floor (:mod:`mapkit.tiles`) run, other than one
after the other in the build's own process.

:class:`ChildTiles`: one after the other, each in a fresh process of its
own (what ``mapkit build`` does when the floor is past
``--memory-budget``): a tile's heap is handed back whole when it ends, so
no tile's peak adds to the next one's, and the build's own process holds
only the floor and the tiles' compact results
(:class:`mapkit.tiles.TileRegions`).

:class:`DaskTiles`: the tiles as Dask tasks,
``mapkit build PLAN -o OUT.lmap --workers N`` (a local cluster of N
processes) or ``--scheduler ADDRESS`` (a running cluster), the options of
the batch builds (:mod:`mapkit.batch`).

The floor (segments, walls, free space, camera, settings) and the tiling
are sent to every worker once; each task builds one tile
(:func:`mapkit.tiles.build_tile`, one thread) and sends back its regions.
The tiles' results are put together in the tiles' order, so the map is the
same byte for byte however the tasks were scheduled, and the same as a
build of the tiles in one process. A tile that fails stops the build, named
with its place. Dask is imported only here.
"""

from __future__ import annotations

import uuid
from dataclasses import dataclass


@dataclass(frozen=True)
class ChildTiles:
    """Each tile built in a fresh process of its own (``spawn``: a new
    interpreter, nothing inherited of this one's heap), one after the other,
    with ``threads`` threads (:mod:`mapkit.parallel`)."""

    threads: int = 1

    def run(self, floor, plan, progress: bool = False) -> list:
        """Every tile of ``plan``: their :class:`~mapkit.tiles.TileRegions`,
        in tile order; a bar over the tiles with ``progress``. MapkitError
        (bad input) or :class:`~mapkit.tiles.TileFailed` naming the first
        tile that failed (a child that died too: e.g. out of memory)."""
        import multiprocessing
        from concurrent.futures import ProcessPoolExecutor

        from tqdm import tqdm

        from mapkit.tiles import build_tile, tile_error

        context = multiprocessing.get_context("spawn")
        out = []
        for tile in tqdm(plan.tiles, desc="tiles", unit="tile", disable=not progress, leave=False):
            try:
                with ProcessPoolExecutor(1, mp_context=context) as child:
                    out.append(child.submit(build_tile, floor, plan, tile, self.threads).result())
            except Exception as exc:
                raise tile_error(tile, len(plan.tiles), exc) from exc
        return out


@dataclass(frozen=True)
class DaskTiles:
    """Where the tiles run: a local cluster of ``workers`` processes (None:
    one per core available, at most one per tile), or the running cluster
    at ``scheduler``."""

    workers: int | None = None
    scheduler: str | None = None

    def run(self, floor, plan, progress: bool = False) -> list:
        """Every tile of ``plan`` built on the cluster: their
        :class:`~mapkit.tiles.TileRegions`, in tile order; a bar over the
        tiles with ``progress``. MapkitError (bad input) or
        :class:`~mapkit.tiles.TileFailed` naming the first tile that failed."""
        from distributed import as_completed
        from tqdm import tqdm

        from mapkit.batch import default_workers, open_client
        from mapkit.tiles import build_tile, tile_error

        n = len(plan.tiles)
        client, cluster = open_client(self.workers or default_workers(n), self.scheduler)
        run = uuid.uuid4().hex[:8]  # keys of this build only, on a cluster that may hold others'
        try:
            with client:
                floor_f, plan_f = client.scatter([floor, plan], broadcast=True)
                futures = {client.submit(build_tile, floor_f, plan_f, tile, 1, pure=False,
                                         key=f"tile-{run}-{tile.index}"): tile for tile in plan.tiles}
                results = [None] * n
                try:
                    with tqdm(total=n, desc="tiles", unit="tile", disable=not progress, leave=False) as bar:
                        for future in as_completed(futures):
                            tile = futures[future]
                            try:
                                results[tile.index] = future.result()
                            except Exception as exc:
                                raise tile_error(tile, n, exc) from exc
                            bar.update(1)
                finally:
                    for future in futures:
                        future.cancel()
        finally:
            if cluster is not None:
                cluster.close()
        return results


__all__ = ["ChildTiles", "DaskTiles"]
