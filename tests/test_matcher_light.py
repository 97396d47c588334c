"""The runtime package stays light: a full localisation on a loaded map
imports none of the authoring stack."""

from __future__ import annotations

import subprocess
import sys
import textwrap

import numpy as np
import pytest

AUTHORING = ("ezdxf", "trimesh", "shapely", "viser")


@pytest.mark.slow
def test_no_authoring_module_after_a_localisation(tmp_path):
    from mapkit_harness.plans import make_small_flat
    from linemap.lmap import save_map
    from mapkit_harness.simulate import make_frame, paper_camera

    m = make_small_flat()
    save_map(tmp_path / "flat.lmap", m)
    fr = make_frame(m, paper_camera(), np.random.default_rng(1), 2)
    np.save(tmp_path / "lines.npy", fr.lines)
    script = textwrap.dedent(
        f"""
        import sys, json
        import numpy as np
        import matcher
        m = matcher.load_map({str(tmp_path / 'flat.lmap')!r})
        cam = matcher.Camera.from_dict({paper_camera().to_dict()!r})
        res = matcher.localize(m, cam, np.load({str(tmp_path / 'lines.npy')!r}), {fr.prior!r}, {fr.dt}, {fr.dyaw})
        img = np.zeros((480, 640), np.uint8)
        matcher.detect_lines(img, cam)
        bad = sorted(n for n in sys.modules if n.split('.')[0] in {AUTHORING!r})
        print(json.dumps({{"ok": bool(res), "bad": bad}}))
        """
    )
    out = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=120)
    assert out.returncode == 0, out.stderr
    import json

    report = json.loads(out.stdout.strip().splitlines()[-1])
    assert report["ok"], "the localisation itself should succeed on this frame"
    assert report["bad"] == []
