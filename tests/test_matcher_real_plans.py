"""Localisation on maps built from the real drawings of tests/data/ (the
plans the README builds), not only on the example flat: frames simulated
from each map at PEQ 3 and 5, within the range its lists were built for."""

from __future__ import annotations
from pathlib import Path

import numpy as np
import pytest

import matcher
from mapkit.cli import main as mapkit_main
from mapkit_harness.simulate import make_frame, pose_error

ROOT = Path(__file__).resolve().parents[1]

PLANS = {
    "thehouse": (ROOT / "tests" / "data" / "thehouse.dxf", ["--walls", "s001-*", "--units", "m"]),
    "hospital": (ROOT / "tests" / "data" / "hospital.stl", []),
}


@pytest.fixture(scope="module", params=sorted(PLANS))
def real_map(request, tmp_path_factory):
    plan, options = PLANS[request.param]
    out = tmp_path_factory.mktemp(request.param) / "map.lmap"
    assert mapkit_main(["build", str(plan), "-o", str(out), "-q", *options]) == 0
    return request.param, matcher.load_map(out)


@pytest.mark.parametrize("peq", [3, 5])
@pytest.mark.slow
def test_recovery_on_real_plans(real_map, cam, peq):
    """tools/bench_paper.py finds the correct match first in 100 % of 40
    frames per PEQ on both maps (docs/matcher.md); 9 of 10 here. The pose
    is looser than in the flat: these frames show five or six segments a
    median 5 to 10 m away, where the 1 degree of noise on a line moves its
    plane by centimetres (median errors of 1 to 7 cm and up to 0.4 degree
    here; 1 cm in the flat, whose lines lie 2.8 m away)."""
    name, linemap = real_map
    rng = np.random.default_rng([13, peq])
    good, errs = 0, []
    for _ in range(10):
        fr = make_frame(linemap, cam, rng, peq)
        res = matcher.localize(linemap, cam, fr.lines, fr.prior, fr.dt, fr.dyaw)
        truth = {tuple(m) for m in fr.true_matches()}
        if res and {tuple(m) for m in res.matches} <= truth:
            good += 1
            errs.append(pose_error(res.pose, fr.pose))
    assert good >= 9, f"{name}, PEQ {peq}: {good} of 10 frames matched correctly"
    pos, yaw = np.median(np.array(errs), axis=0)
    assert pos < 0.12 and yaw < 0.8, f"{name}, PEQ {peq}: median error {pos:.3f} m, {yaw:.2f} deg"
