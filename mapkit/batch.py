"""Many builds at once: ``mapkit build A.dxf B.dxf model.ifc ... -o DIR`` on Dask.

The job list (:func:`plan_jobs`): each input gives one output in ``DIR``,
``DIR/<stem>.lmap`` for a plan or mesh, ``DIR/<stem>/`` (a map per storey
and ``building.json``, as :mod:`mapkit.building` writes) for an IFC model,
whose task reads the model and runs each storey's map as a task of its own.
The skip rule (:func:`is_up_to_date`): an output whose META records the
same source SHA-256, the same build options and the same mapkit version as
the planned build is left as it is (the map would come out byte for byte
the same). The rest run as ``dask.distributed`` tasks (:func:`run_jobs`),
on a local cluster of ``workers`` processes of one thread each, or on the
running cluster at ``scheduler``; each task builds one input and writes its
output (atomically, through :func:`linemap.lmap.save_map`) on the worker,
and returns a small :class:`JobResult`. A task never raises: bad input
comes back as its one-line error (the others still finish), anything else
as a bug's one line. The map bytes are those of a one-at-a-time build: the
same code on the same input and options.

Workers and the client must share the file system (absolute paths are
sent). Dask is imported only here, and only when several inputs are built.
"""

from __future__ import annotations

import json
import os
import time
from dataclasses import dataclass, replace
from pathlib import Path

from mapkit.errors import MapkitError

#: Outcomes of a task.
BUILT, FAILED, BUG = "built", "failed", "bug"


@dataclass(frozen=True)
class Job:
    """One input to build: ``source`` (absolute path) into ``output`` (a
    ``.lmap`` file, or a folder for an IFC model)."""

    source: Path
    output: Path

    @property
    def is_building(self) -> bool:
        return self.source.suffix.lower() == ".ifc"


@dataclass(frozen=True)
class JobResult:
    """What a task sends back: ``status`` (BUILT, FAILED, BUG), a one-line
    ``summary`` (counts of what was written) or ``error``, the seconds it
    took, and the worker process's id and peak resident memory so far in bytes (0 if unknown)."""

    source: str
    output: str
    status: str
    summary: str = ""
    error: str = ""
    seconds: float = 0.0
    worker_pid: int = 0
    peak_rss_bytes: int = 0


def plan_jobs(sources, out_dir: str | os.PathLike) -> list[Job]:
    """The job per input, in the order given; MapkitError for two inputs
    that would write the same output (same stem, compared ignoring case)."""
    out = Path(out_dir).absolute()
    jobs, taken = [], {}
    for s in sources:
        src = Path(s).absolute()
        job = Job(src, out / src.stem if src.suffix.lower() == ".ifc" else out / f"{src.stem}.lmap")
        key = job.output.name.casefold()
        if key in taken:
            raise MapkitError(f"{taken[key]} and {s} would both write {job.output}; rename one or build them "
                              "into different folders")
        taken[key] = s
        jobs.append(job)
    return jobs


def is_up_to_date(job: Job, options) -> bool:
    """Would building ``job`` with ``options`` rewrite its output byte for
    byte? Yes when the output exists and its META (each storey map's, and
    the manifest's source, for a building) records the source's SHA-256,
    these build options and this mapkit version. Unreadable outputs: no."""
    from linemap.lmap import LmapError, file_sha256

    try:
        sha = file_sha256(job.source)
    except OSError:
        return False  # the task reports the missing input
    try:
        if not job.is_building:
            return _map_matches(job.output, sha, options)
        from mapkit.building import MANIFEST_NAME, load_manifest

        manifest = load_manifest(job.output / MANIFEST_NAME)
        if manifest.get("source", {}).get("sha256") != sha:
            return False
        return all(_map_matches(job.output / s["map"], sha, replace(options, floor_name=s["name"]))
                   for s in manifest["storeys"] if s.get("map"))
    except (OSError, LmapError, MapkitError, KeyError, TypeError, AttributeError):
        return False


def _map_matches(path: Path, sha: str, options) -> bool:
    from linemap.lmap import load_map

    from mapkit import __version__

    if not path.is_file():
        return False
    meta = load_map(path).meta
    planned = json.loads(json.dumps(options.to_meta()))  # the types a META read back has
    return (meta.get("source", {}).get("sha256") == sha and meta.get("build") == planned
            and meta.get("generator") == f"mapkit {__version__}")


def build_job(job: Job, options) -> JobResult:
    """Build ``job`` and write its output: the task a worker runs. Never
    raises; an error is in the result, one line."""
    from linemap.atomic import OutputPathError
    from linemap.errors import OUT_OF_MEMORY, InputError

    t = time.perf_counter()
    try:
        summary = _build_building(job, options) if job.is_building else _build_map(job, options)
        status, error = BUILT, ""
    except InputError as exc:
        status, error, summary = FAILED, str(exc), ""
    except OutputPathError as exc:
        status, error, summary = FAILED, f"{exc.filename}: {exc.strerror}", ""
    except FileNotFoundError as exc:
        status, error, summary = FAILED, f"{exc.filename or exc}: no such file; check the path", ""
    except OSError as exc:
        status, error, summary = FAILED, f"{exc.filename}: {exc.strerror or exc}" if exc.filename else str(exc), ""
    except MemoryError:
        status, error, summary = FAILED, OUT_OF_MEMORY, ""
    except Exception as exc:  # noqa: BLE001 - a bug of ours, reported as one by the client
        lines = str(exc).strip().splitlines()
        status, summary = BUG, ""
        error = f"{type(exc).__name__}: {lines[0][:300]}" if lines else type(exc).__name__
    return JobResult(str(job.source), str(job.output), status, summary, _one_line(error, job.source),
                     time.perf_counter() - t, os.getpid(), _peak_rss_bytes())


def _one_line(error: str, source: Path) -> str:
    """``error`` naming its input (most messages start with the path already)."""
    if not error or error.startswith((str(source), source.name)):
        return error
    return f"{source.name}: {error}"


def _build_map(job: Job, options) -> str:
    from linemap.lmap import save_map

    from mapkit.pipeline import build_map

    if not job.source.is_file():
        raise FileNotFoundError(2, "no such file", str(job.source))
    linemap, report = build_map(job.source, options)
    size = save_map(job.output, linemap)
    c = report.counts
    return (f"{c['segments']} segments, {c['regions']} regions, mean list {c['mean_list_length']:.1f}, "
            f"{size / 1024:.1f} KiB")


def _build_building(job: Job, options) -> str:
    from mapkit.building import build_building, write_building

    if options.floor_name is not None:
        raise MapkitError("--storey builds one storey into one map; build that model on its own with -o OUT.lmap")
    if not job.source.is_file():
        raise FileNotFoundError(2, "no such file", str(job.source))
    result = build_building(job.source, options, map_storeys=_storeys_on_cluster if _on_a_worker() else None)
    write_building(result, job.output)
    built = [o for o in result.storeys if o.map is not None]
    return f"{len(built)} of {len(result.storeys)} storeys mapped"


def _on_a_worker() -> bool:
    """Is this a Dask worker's task (the storeys can be tasks of their own)?"""
    try:
        from distributed import get_worker

        get_worker()
        return True
    except (ImportError, ValueError):
        return False


def _storeys_on_cluster(calls: list[tuple]) -> list[tuple]:
    """A building's storeys mapped as Dask tasks of their own, from the
    model's task (which leaves its worker's thread to them while it waits):
    :func:`mapkit.building.map_storey` per ``(scene, path, options)``, in order."""
    from distributed import worker_client

    from mapkit.building import map_storey

    with worker_client() as client:
        return client.gather([client.submit(map_storey, *call, pure=False) for call in calls])


def _peak_rss_bytes() -> int:
    """This process's peak resident memory so far, bytes (0 where unknown)."""
    try:
        import resource
        import sys

        peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
        return int(peak if sys.platform == "darwin" else peak * 1024)  # bytes on macOS, KiB on Linux
    except (ImportError, OSError):
        return 0


def default_workers(n_jobs: int) -> int:
    """Local workers when ``--workers`` is not given: one per core available, at most one per job."""
    cores = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else (os.cpu_count() or 1)
    return max(1, min(cores, n_jobs))


def run_jobs(jobs: list[Job], options, *, workers: int | None = None, scheduler: str | None = None,
             progress: bool = False, on_result=None) -> list[JobResult]:
    """Run ``build_job`` for every job as Dask tasks: on ``scheduler``'s
    cluster if given, else on a local cluster of ``workers`` processes of
    one thread each (started here and stopped on return). ``on_result``
    is called with each result as it arrives (a bar over the tasks with
    ``progress``). Returns the results in the order of ``jobs``."""
    from distributed import as_completed

    if not jobs:
        return []
    cluster = None
    try:
        client, cluster = open_client(workers or default_workers(len(jobs)), scheduler)
        with client:
            # pure=False: a rerun after a failure builds again, never a result the cluster kept.
            futures = {client.submit(build_job, job, options, pure=False, key=f"build-{k}-{job.source.name}"): k
                       for k, job in enumerate(jobs)}
            results: list[JobResult | None] = [None] * len(jobs)
            bar = _bar(len(jobs), progress)
            try:
                for future in as_completed(futures):
                    result = future.result()
                    results[futures[future]] = result
                    if bar is not None:
                        bar.update(1)
                    if on_result is not None:
                        on_result(result)
            finally:
                if bar is not None:
                    bar.close()
    finally:
        if cluster is not None:
            cluster.close()
    return results  # type: ignore[return-value]


def open_client(workers: int, scheduler: str | None):
    """``(client, cluster)``: a Dask client of the running cluster at
    ``scheduler`` (cluster None), else of a local cluster of ``workers``
    processes of one thread each, started here (the caller closes it).
    MapkitError when the scheduler cannot be reached."""
    import logging

    from distributed import Client, LocalCluster

    if scheduler:
        try:
            return Client(scheduler, timeout="10s"), None
        except (OSError, TimeoutError) as exc:
            raise MapkitError(f"--scheduler {scheduler}: cannot connect ({str(exc).splitlines()[0][:200]}); "
                              "check the address and that 'dask scheduler' runs there") from None
    # No dashboard; the scheduler's HTTP server (health checks) on a free port, not 8787,
    # which another cluster on the machine may hold (distributed then warns on stderr).
    cluster = LocalCluster(n_workers=workers, threads_per_worker=1, processes=True, dashboard_address="127.0.0.1:0",
                           scheduler_kwargs={"dashboard": False}, silence_logs=logging.ERROR)
    return Client(cluster), cluster


def _bar(total: int, enabled: bool):
    if not enabled:
        return None
    from tqdm import tqdm

    return tqdm(total=total, desc="build", unit="input", leave=False)


__all__ = ["BUG", "BUILT", "FAILED", "Job", "JobResult", "build_job", "default_workers", "is_up_to_date",
           "open_client", "plan_jobs", "run_jobs"]
