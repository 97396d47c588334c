"""Helpers for CLI tests: run ``mapkit`` in-process and check its error contract."""

from __future__ import annotations

from mapkit.cli import main


def run(capsys, *argv):
    """Run ``mapkit ARGV`` (any path-like arguments allowed); return (code, stdout, stderr)."""
    capsys.readouterr()
    code = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return code, out, err


def assert_one_line_error(code, out, err, *needles):
    """Exit 2, nothing on stdout, one 'mapkit: error:' line (warnings aside) naming each needle."""
    assert code == 2, (code, out, err)
    lines = [ln for ln in err.splitlines() if not ln.startswith("mapkit: warning:")]
    assert len(lines) == 1 and lines[0].startswith("mapkit: error: "), err
    assert "Traceback" not in err and out == ""
    for n in needles:
        assert n.lower() in lines[0].lower(), lines[0]


def run_with_reader_gone(*argv):
    """Run ``python ARGV`` with stdout a pipe whose reader has already gone
    (``... | head -0``); return the CompletedProcess (stderr as text)."""
    import os
    import subprocess
    import sys

    read_end, write_end = os.pipe()
    os.close(read_end)
    try:
        return subprocess.run([sys.executable, *map(str, argv)], stdout=write_end, stderr=subprocess.PIPE,
                              text=True, timeout=120)
    finally:
        os.close(write_end)


def simulated_rig_frame(tmp_path, rig, peq: int, seed: int) -> tuple:
    """A frame of ``rig`` written by ``tools/simulate.py --rig`` under
    ``tmp_path``: (its folder, its truth.json as a dict, the cameras' lines
    files in order)."""
    import json
    import subprocess
    import sys

    from linemap.rig_files import rig_to_dict

    rig_file = tmp_path / "ring.json"
    rig_file.write_text(json.dumps(rig_to_dict(rig)))
    out = tmp_path / "frame"
    subprocess.run([sys.executable, "tools/simulate.py", "--rig", str(rig_file), "--peq", str(peq), "--seed",
                    str(seed), "--no-images", "--out", str(out)], check=True, capture_output=True)
    truth = json.loads((out / "truth.json").read_text())
    return out, truth, [str(out / c["lines"]) for c in truth["cameras"]]


def localize_rig_frame(out, truth: dict, lines: list, *extra: str):
    """``matcher localize --rig`` on a :func:`simulated_rig_frame` from its
    prior, with ``extra`` arguments; the CompletedProcess (text)."""
    import subprocess
    import sys

    prior = ",".join(f"{v:.4f}" for v in truth["prior"])
    return subprocess.run([sys.executable, "-m", "matcher", "localize", "--map", "maps/flat.lmap", "--rig",
                           str(out / "rig.json"), "--lines", *lines, "--prior", prior, "--dt", str(truth["dt"]),
                           "--dyaw", str(truth["dyaw"]), *extra], capture_output=True, text=True)
