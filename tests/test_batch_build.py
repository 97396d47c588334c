"""``mapkit build A B ... -o DIR``: many builds at once on Dask (mapkit/batch.py).

The maps are byte for byte those of one-at-a-time builds, on a real
cluster (a ``dask scheduler`` and two ``dask worker`` processes on
localhost) and on the local cluster ``--workers 2`` starts; a failing input
is one line and the others finish; a rerun skips the unchanged outputs."""

from __future__ import annotations

import json
import os
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from cli_helpers import assert_one_line_error, run
from mapkit_harness.plans import office_grid

ROOT = Path(__file__).resolve().parents[1]
FLAT = ROOT / "maps" / "flat.dxf"
DASK = Path(sys.executable).parent / "dask"


@pytest.fixture(scope="module")
def inputs(tmp_path_factory):
    """Three good plans (the example flat, offices of 2 x 2 rooms and of one room) and one that is no DXF."""
    d = tmp_path_factory.mktemp("inputs")
    shutil.copy(FLAT, d / "flat.dxf")
    office_grid(d / "office2.dxf", n=2)
    office_grid(d / "office1.dxf", n=1)
    (d / "bad.dxf").write_text("this is no drawing\n")
    return d


@pytest.fixture(scope="module")
def one_at_a_time(inputs, tmp_path_factory):
    """Each good input built on its own, ``mapkit build X -o Y``: {stem: map bytes}.
    The flat's is the committed example map (test_build_real checks it is
    flat.dxf's build, and the map does not depend on the plan's folder)."""
    import contextlib
    import io

    from mapkit.cli import main

    out = tmp_path_factory.mktemp("single")
    maps = {"flat": FLAT.with_suffix(".lmap").read_bytes()}
    for stem in ("office2", "office1"):
        with contextlib.redirect_stdout(io.StringIO()):
            assert main(["build", str(inputs / f"{stem}.dxf"), "-o", str(out / f"{stem}.lmap"), "-q"]) == 0
        maps[stem] = (out / f"{stem}.lmap").read_bytes()
    return maps


@pytest.fixture(scope="module")
def cluster(tmp_path_factory):
    """The address of a real Dask cluster: ``dask scheduler`` and two
    ``dask worker`` processes (one thread each) on 127.0.0.1, free ports;
    all of them killed at the end, whatever happened."""
    if not DASK.exists():
        pytest.fail(f"{DASK} missing: install the dask extra (pip install 'mapkit[dask]')")
    d = tmp_path_factory.mktemp("cluster")
    info = d / "scheduler.json"
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH", "")])}
    procs = []

    def start(name, *argv):
        log = open(d / f"{name}.log", "wb")
        procs.append(subprocess.Popen([str(DASK), *argv], stdout=log, stderr=subprocess.STDOUT, env=env, cwd=d,
                                      start_new_session=True))  # its own group: the nanny's child goes with it
        log.close()

    try:
        start("scheduler", "scheduler", "--host", "127.0.0.1", "--port", "0", "--no-dashboard",
              "--scheduler-file", str(info))
        deadline = time.monotonic() + 60
        while not info.exists() and time.monotonic() < deadline:
            assert procs[0].poll() is None, (d / "scheduler.log").read_text()
            time.sleep(0.2)
        address = json.loads(info.read_text())["address"]
        for k in range(2):
            start(f"worker{k}", "worker", address, "--host", "127.0.0.1", "--nworkers", "1", "--nthreads", "1",
                  "--no-dashboard", "--name", f"w{k}")
        from distributed import Client

        with Client(address, timeout="30s") as client:
            client.wait_for_workers(2, timeout=90)
        yield address
    finally:
        for p in procs:
            if p.poll() is None:
                os.killpg(p.pid, signal.SIGTERM)
        for p in procs:
            try:
                p.wait(timeout=20)
            except subprocess.TimeoutExpired:
                os.killpg(p.pid, signal.SIGKILL)
                p.wait()


def _good_maps_equal(out: Path, expected: dict) -> None:
    for stem, data in expected.items():
        assert (out / f"{stem}.lmap").read_bytes() == data, stem


@pytest.mark.slow
def test_scheduler_builds_the_maps_of_one_at_a_time_builds(capsys, inputs, one_at_a_time, cluster, tmp_path):
    plans = [inputs / "flat.dxf", inputs / "bad.dxf", inputs / "office2.dxf", inputs / "office1.dxf"]
    out = tmp_path / "maps"
    code, stdout, stderr = run(capsys, "build", *plans, "-o", out, "--scheduler", cluster)
    assert code == 2, (stdout, stderr)
    errors = [ln for ln in stderr.splitlines() if ln.startswith("mapkit: error:")]
    assert len(errors) == 1 and "bad.dxf" in errors[0] and "not a DXF file" in errors[0], stderr
    assert "Traceback" not in stderr
    assert "built 3, skipped 0 unchanged, failed 1 of 4 inputs" in stdout
    assert sorted(p.name for p in out.iterdir()) == ["flat.lmap", "office1.lmap", "office2.lmap"]
    _good_maps_equal(out, one_at_a_time)

    # A rerun: the unchanged skipped (the bad input still fails); then one input changed is the one rebuilt.
    code, stdout, stderr = run(capsys, "build", *plans, "-o", out, "--scheduler", cluster)
    assert code == 2 and "built 0, skipped 3 unchanged, failed 1 of 4 inputs" in stdout, (stdout, stderr)
    changed = tmp_path / "flat.dxf"
    office_grid(changed, n=2)  # another plan under the name 'flat'
    good = [changed, inputs / "office2.dxf", inputs / "office1.dxf"]
    code, stdout, stderr = run(capsys, "build", *good, "-o", out, "--scheduler", cluster)
    assert code == 0 and "built 1, skipped 2 unchanged, failed 0 of 3 inputs" in stdout, (stdout, stderr)
    assert (out / "flat.lmap").read_bytes() != one_at_a_time["flat"]
    # Other options: another map, so it is not skipped (the smallest input is enough to show it).
    code, stdout, stderr = run(capsys, "build", inputs / "office1.dxf", "-o", out, "--scheduler", cluster,
                               "--wall-height", "2.6")
    assert code == 0 and "built 1, skipped 0 unchanged" in stdout, (stdout, stderr)


@pytest.mark.slow
def test_local_cluster_of_two_workers(capsys, inputs, one_at_a_time, tmp_path):
    """Plans and an IFC model (a folder of storey maps and building.json, as built on its own)."""
    from test_ifc_import import write_model

    model = write_model(tmp_path / "house.ifc")
    assert run(capsys, "build", model, "-o", tmp_path / "alone", "-q")[0] == 0
    out = tmp_path / "new" / "maps"  # made, with its parent
    plans = [inputs / "flat.dxf", inputs / "office2.dxf", inputs / "office1.dxf", model]
    code, stdout, stderr = run(capsys, "build", *plans, "-o", out, "--workers", "2")
    assert code == 0 and "built 4, skipped 0 unchanged, failed 0 of 4 inputs" in stdout, (stdout, stderr)
    assert f"wrote {out / 'flat.lmap'}: " in stdout
    _good_maps_equal(out, one_at_a_time)
    alone = sorted(p.name for p in (tmp_path / "alone").iterdir())
    assert "building.json" in alone and sorted(p.name for p in (out / "house").iterdir()) == alone
    for name in alone:
        assert (out / "house" / name).read_bytes() == (tmp_path / "alone" / name).read_bytes(), name
    code, stdout, stderr = run(capsys, "build", *plans, "-o", out, "--workers", "2")
    assert code == 0 and "built 0, skipped 4 unchanged, failed 0 of 4 inputs" in stdout, (stdout, stderr)


def test_several_inputs_need_a_folder(capsys, inputs, tmp_path):
    code, out, err = run(capsys, "build", inputs / "flat.dxf", inputs / "office2.dxf", "-o", tmp_path / "x.lmap")
    assert_one_line_error(code, out, err, "-o DIR")
    (tmp_path / "file").write_text("")
    code, out, err = run(capsys, "build", inputs / "flat.dxf", inputs / "office2.dxf", "-o", tmp_path / "file")
    assert_one_line_error(code, out, err, "not a folder")


def test_two_inputs_of_one_name_are_refused_before_any_work(capsys, inputs, tmp_path):
    other = tmp_path / "elsewhere"
    other.mkdir()
    shutil.copy(FLAT, other / "FLAT.dxf")
    code, out, err = run(capsys, "build", inputs / "flat.dxf", other / "FLAT.dxf", "-o", tmp_path / "maps")
    assert_one_line_error(code, out, err, "would both write")
    assert not (tmp_path / "maps").exists()


def test_workers_must_be_positive(capsys, inputs, tmp_path):
    code, out, err = run(capsys, "build", inputs / "flat.dxf", "-o", tmp_path / "maps", "--workers", "0")
    assert_one_line_error(code, out, err, "--workers")


@pytest.mark.slow
def test_one_input_to_one_map_does_not_load_dask(inputs, tmp_path):
    plan = inputs / "office1.dxf"  # the smallest plan: any one input takes the same path
    script = ("import sys\nfrom mapkit.cli import main\n"
              f"assert main(['build', {str(plan)!r}, '-o', {str(tmp_path / 'f.lmap')!r}, '-q']) == 0\n"
              "assert not {'dask', 'distributed'} & {m.split('.')[0] for m in sys.modules}, 'dask loaded'\n")
    subprocess.run([sys.executable, "-c", script], check=True, cwd=ROOT, timeout=300,
                   env={**os.environ, "PYTHONPATH": str(ROOT)})


def test_the_skip_rule_compares_source_options_and_version(inputs, one_at_a_time, tmp_path):
    from dataclasses import replace

    from mapkit.batch import is_up_to_date, plan_jobs
    from mapkit.options import BuildOptions

    (job,) = plan_jobs([inputs / "office2.dxf"], tmp_path)
    options = BuildOptions()
    assert not is_up_to_date(job, options)  # no output yet
    job.output.write_bytes(one_at_a_time["office2"])
    assert is_up_to_date(job, options)
    assert is_up_to_date(job, replace(options, jobs=1))  # a limit of work, not recorded in the map
    assert not is_up_to_date(job, replace(options, wall_height=2.6))
    (other,) = plan_jobs([inputs / "office1.dxf"], tmp_path)
    shutil.copy(job.output, other.output)  # another source's map
    assert not is_up_to_date(other, options)
    job.output.write_bytes(b"LMAP damaged")
    assert not is_up_to_date(job, options)


@pytest.mark.slow
def test_the_batch_benchmark_runs_and_checks_the_bytes(capsys):
    import bench_batch

    assert bench_batch.main(["--floors", "2", "--rooms", "1"]) == 0
    out = capsys.readouterr().out
    assert "maps byte-identical: yes" in out and "| at once (`--workers 2`) | 2 |" in out, out


def test_a_task_meeting_a_bug_says_so_in_one_line(monkeypatch, inputs, tmp_path):
    import mapkit.pipeline
    from mapkit.batch import BUG, FAILED, build_job, plan_jobs
    from mapkit.options import BuildOptions

    good, bad = plan_jobs([inputs / "office2.dxf", inputs / "bad.dxf"], tmp_path)
    failed = build_job(bad, BuildOptions())
    assert failed.status == FAILED and "\n" not in failed.error
    assert failed.error.startswith(("bad.dxf", str(bad.source))), failed.error

    def broken(*_args, **_kwargs):
        raise RuntimeError("an invariant broke\nsecond line")

    monkeypatch.setattr(mapkit.pipeline, "build_map", broken)
    result = build_job(good, BuildOptions())
    assert result.status == BUG and result.error == "office2.dxf: RuntimeError: an invariant broke"
    assert not good.output.exists()


def test_the_command_exits_3_on_a_bug_and_2_on_bad_input(monkeypatch, capsys, inputs, tmp_path):
    from mapkit import batch

    def results(status, error):
        def run_jobs(jobs, options, **_kwargs):
            return [batch.JobResult(str(j.source), str(j.output), status, error=error) for j in jobs]
        return run_jobs

    plans = [inputs / "flat.dxf", inputs / "office2.dxf"]
    monkeypatch.setattr(batch, "run_jobs", results(batch.BUG, "flat.dxf: RuntimeError: boom"))
    code, out, err = run(capsys, "build", *plans, "-o", tmp_path / "a")
    assert code == 3 and "mapkit: internal error: flat.dxf: RuntimeError: boom -- this is a bug" in err, err
    assert "Traceback" not in err
    monkeypatch.setattr(batch, "run_jobs", results(batch.FAILED, "flat.dxf: no walls"))
    code, out, err = run(capsys, "build", *plans, "-o", tmp_path / "b")
    assert code == 2 and "failed 2 of 2 inputs" in out


@pytest.mark.slow
def test_tiles_of_one_floor_on_a_real_cluster_give_the_local_build(capsys, inputs, cluster, tmp_path):
    """One floor built in tiles (--tile-side) as tasks on the cluster: the
    map of the tiles built one after the other in this process."""
    from linemap.lmap import load_map

    args = [inputs / "office2.dxf", "--tile-side", "6", "--max-range", "4", "-q"]
    code, _, err = run(capsys, "build", *args, "-o", tmp_path / "here.lmap")
    assert code == 0, err
    code, _, err = run(capsys, "build", *args, "-o", tmp_path / "cluster.lmap", "--scheduler", cluster)
    assert code == 0, err
    assert (tmp_path / "cluster.lmap").read_bytes() == (tmp_path / "here.lmap").read_bytes()
    assert load_map(tmp_path / "here.lmap").meta["stats"]["regions"]["tiles"] == 4
