"""Tests of ``mapkit view``: geometry, field of view, synthetic image, result
files, the viser server (start, stop, scene nodes over a real websocket), the
CLI (Ctrl-C, errors, --html) and the time to open a large map.

The browser itself is exercised in tests/test_view_browser.py.
"""

from __future__ import annotations

import json
import math
import os
import signal
import subprocess
import sys
import urllib.request

import numpy as np
import pytest
from shapely.geometry import Polygon, box

from mapkit.assemble import assemble_map
from mapkit.errors import MapkitError
from linemap.lmap import SegmentKind, save_map
from mapkit.view import geometry, palette
from mapkit.view.result import load_result, parse_result
from mapkit.view.pose_tool import camera_wxyz
from mapkit.view.result_overlay import image_line_rays
from mapkit.view.server import Inspector, floor_point
from mapkit.view.stats import map_camera, map_statistics, statistics_markdown
from mapkit.view.synthetic_image import clip_to_image, project_segments, render_segments
from linemap.camera import Camera
from linemap.geometry import in_field_of_view, wrap
from mapkit_harness.inspector import scene_names
from mapkit_harness.plans import DEMO_CAMERA, grid_flat


# --------------------------------------------------------------------------
# Maps


@pytest.fixture(scope="module")
def flat():
    """A 3 x 2 room flat: ~250 segments, ~340 regions."""
    return grid_flat()


@pytest.fixture(scope="module")
def flat_path(flat, tmp_path_factory):
    path = tmp_path_factory.mktemp("maps") / "flat.lmap"
    save_map(path, flat)
    return path


def holed_map():
    """Two regions: a square with a square hole, and the hole's neighbour strip."""
    outer = Polygon([(0, 0), (4, 0), (4, 4), (0, 4)], [[(1, 1), (3, 1), (3, 3), (1, 3)]])
    strip = box(4, 0, 5, 4)
    segs = np.array([[[0, 0, 0], [4, 0, 0]], [[0, 0, 0], [0, 0, 2.5]]], dtype=float)
    kinds = np.array([SegmentKind.FLOOR, SegmentKind.VERTICAL])
    walls = box(-0.2, -0.2, 5.2, 4.2).difference(box(0, 0, 5, 4))
    return assemble_map(segs, kinds, [outer, strip], [[0, 1], [1]], walls, {"wall_height": 2.5})


# --------------------------------------------------------------------------
# Geometry


def test_ring_edges_close_every_ring():
    pts = np.array([[0, 0], [1, 0], [1, 1], [5, 5], [6, 5], [6, 6], [5, 6]], dtype=float)
    edges, ring = geometry.ring_edges(pts, np.array([0, 3, 7]))
    assert edges.shape == (7, 2, 2)
    assert np.allclose(edges[2], [[1, 1], [0, 0]])  # last edge of ring 0 returns to its start
    assert np.allclose(edges[6], [[5, 6], [5, 5]])
    assert ring.tolist() == [0, 0, 0, 1, 1, 1, 1]


def test_region_polygons_and_triangles_respect_holes():
    m = holed_map()
    polys = geometry.region_polygons(m)
    assert polys[0].area == pytest.approx(16 - 4)
    assert polys[1].area == pytest.approx(4)
    tris = geometry.triangulate(polys)
    v = tris.vertices.reshape(-1, 3, 2)
    e1, e2 = v[:, 1] - v[:, 0], v[:, 2] - v[:, 0]
    area = 0.5 * np.abs(e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0])
    per_region = np.bincount(tris.owner, weights=area)
    assert per_region == pytest.approx([12, 4])
    # No triangle of region 0 lies in its hole.
    centroids = v[tris.owner == 0].mean(axis=1)
    assert not ((centroids > 1) & (centroids < 3)).all(axis=1).any()
    sub_v, sub_f = tris.subset(np.array([1]))
    assert len(sub_f) == tris.start[2] - tris.start[1] and sub_v.shape == (3 * len(sub_f), 2)


def test_extruded_walls_have_the_wall_volume():
    m = holed_map()
    wall = geometry.wall_polygon(m)
    mesh = geometry.extrude(wall, 2.5)
    assert abs(mesh.volume) == pytest.approx(wall.area * 2.5, rel=1e-6)
    assert mesh.vertices[:, 2].min() == 0 and mesh.vertices[:, 2].max() == 2.5


def test_neighbouring_regions_get_different_colours(flat):
    polys = geometry.region_polygons(flat)
    i, j = geometry.region_adjacency(polys)
    assert len(i) > flat.n_regions  # a grid: several neighbours each
    colour = palette.colour_regions(flat.n_regions, i, j)
    assert (colour[i] != colour[j]).all()
    assert len(np.unique(colour)) >= 4


# --------------------------------------------------------------------------
# Field of view


def _camera_with_half_fov(half: float) -> Camera:
    """A level camera whose horizontal field of view is 2 * ``half`` (radians)."""
    return Camera.from_fov(math.degrees(2 * half), 640, 480, 1.2, 0.0)


def test_fov_keeps_ahead_and_drops_behind():
    """The inspector's pose tool uses the matcher's field-of-view test
    (linemap.geometry.in_field_of_view): these are its cases."""
    segs = np.array([
        [[5, -1, 0], [5, 1, 0]],  # ahead (+x)
        [[-5, -1, 0], [-5, 1, 0]],  # behind
        [[0, 5, 0], [0, 5, 2]],  # vertical edge to the left (+y)
    ], dtype=float)
    cam = _camera_with_half_fov(math.radians(35))
    assert cam.horizontal_half_fov() == pytest.approx(math.radians(35))
    assert in_field_of_view(segs, cam, (0, 0, 0.0), 0.0, 0.0).tolist() == [True, False, False]
    # Turning up to 60 degrees brings the left edge (90 degrees) within 35 + 60.
    assert in_field_of_view(segs, cam, (0, 0, 0.0), 0.0, math.radians(60)).tolist() == [True, False, True]
    # Heading range plus half FOV covering the whole turn keeps everything.
    assert in_field_of_view(segs, cam, (0, 0, 0.0), 0.0, math.radians(150)).all()
    # A camera that may stand on a segment sees it whatever the heading.
    assert in_field_of_view(segs, cam, (-4.9, 0, 0.0), 0.2, 0.0)[1]


def test_fov_never_drops_a_segment_some_sampled_pose_sees():
    """Conservative: a sampled pose in the uncertainty set that sees a point
    of a segment inside its horizontal field of view implies the segment is kept."""
    rng = np.random.default_rng(7)
    start = rng.uniform(-6, 6, (300, 2))
    end = start + rng.normal(0, 1.5, (300, 2))
    segs = np.stack([np.c_[start, np.zeros(300)], np.c_[end, rng.uniform(0, 2.5, 300)]], axis=1)
    x, y, dt, yaw, dyaw, half = 0.3, -0.2, 0.8, 0.7, math.radians(20), math.radians(30)
    keep = in_field_of_view(segs, _camera_with_half_fov(half), (x, y, yaw), dt, dyaw)
    assert 0 < keep.sum() < len(segs)  # the test means something
    r, a = dt * np.sqrt(rng.uniform(0, 1, 400)), rng.uniform(0, 2 * math.pi, 400)
    cams = np.c_[x + r * np.cos(a), y + r * np.sin(a)]
    heads = yaw + rng.uniform(-dyaw, dyaw, 400)
    t = np.linspace(0, 1, 25)
    pts = segs[:, None, 0, :2] + t[None, :, None] * (segs[:, None, 1, :2] - segs[:, None, 0, :2])  # (N, 25, 2)
    for c, h in zip(cams, heads):
        d = pts - c
        seen = (np.abs(wrap(np.arctan2(d[..., 1], d[..., 0]) - h)) <= half).any(axis=1)
        assert not (seen & ~keep).any()


def test_pose_tool_shows_the_matchers_field_of_view_set(inspector, flat):
    """The pose tool's in-view set is exactly what the matcher's test keeps."""
    x, y = flat.region_centres()[40]
    _, cands, in_view = inspector.pose_sets(x, y, 0.3, 0.5, math.radians(10))
    keep = in_field_of_view(flat.segments[cands], inspector.camera, (x, y, 0.3), 0.5, math.radians(10))
    assert in_view.tolist() == cands[keep].tolist()


# --------------------------------------------------------------------------
# Synthetic image


def test_projection_of_a_level_edge_at_camera_height_is_the_horizon():
    cam = Camera.from_dict({**DEMO_CAMERA, "pitch_deg": 0.0})
    seg = np.array([[[4.0, -1.0, cam.height_m], [4.0, 1.0, cam.height_m]]])
    lines, idx = project_segments(cam, seg, 0.0, 0.0, 0.0)
    assert idx.tolist() == [0]
    assert np.allclose(lines[0, :, 1], cam.cy)
    # +y is to the left of a camera heading +x: the first end point (y = -1) is on the right.
    assert lines[0, 0, 0] == pytest.approx(cam.cx + cam.fx * 1 / 4)


def test_segments_behind_the_camera_are_cut_at_the_near_plane():
    cam = Camera.from_dict(DEMO_CAMERA)
    seg = np.array([[[-3.0, 0.2, 0.0], [3.0, 0.2, 0.0]], [[-3.0, 0, 0], [-1.0, 0, 0]]])
    lines, idx = project_segments(cam, seg, 0.0, 0.0, 0.0)
    assert idx.tolist() == [0]  # the one wholly behind is dropped
    assert np.isfinite(lines).all()
    assert ((lines >= -1e-9) & (lines <= [cam.width + 1e-9, cam.height + 1e-9])).all()


def test_clip_to_image():
    lines = np.array([[[-10, 50], [110, 50]], [[-10, -10], [-5, -20]], [[10, 10], [20, 20]]], dtype=float)
    out, idx = clip_to_image(lines, 100, 80)
    assert idx.tolist() == [0, 2]
    assert np.allclose(out[0], [[0, 50], [100, 50]])
    assert np.allclose(out[1], lines[2])


def test_render_draws_the_visible_segments(flat):
    cam, source = map_camera(flat)
    assert source == "build parameters"
    x, y = flat.region_centres()[0]
    ids = flat.candidate_segments(x, y, 0.0)
    img, drawn = render_segments(cam, flat.segments[ids], np.full((len(ids), 3), (255, 0, 0)), x, y, math.pi / 4)
    assert img.shape == (cam.height, cam.width, 3)
    assert len(drawn) > 0
    red = (img[:, :, 0] > 200) & (img[:, :, 1] < 100)
    assert red.sum() > 200


# --------------------------------------------------------------------------
# Result files


def test_result_is_parsed_and_validated(tmp_path):
    good = {"ok": True, "pose": {"x": 1, "y": 2, "yaw_deg": 90}, "score": 0.001, "matches": [[3, 0], [5, 1]],
            "lines": [[0, 0, 10, 10], [5, 5, 6, 60]]}
    res = parse_result(good, n_segments=10)
    assert res.ok and res.yaw == pytest.approx(math.pi / 2) and res.lines.shape == (2, 2, 2)
    assert res.matches.tolist() == [[3, 0], [5, 1]]
    with pytest.raises(MapkitError, match="no 'pose'"):
        parse_result({"ok": True})
    with pytest.raises(MapkitError, match="numeric x, y and yaw_deg"):
        parse_result({"ok": True, "pose": {"x": 1}})
    with pytest.raises(MapkitError, match="names segment 12, but the map has 10"):
        parse_result({**good, "matches": [[12, 0]]}, n_segments=10)
    with pytest.raises(MapkitError, match="segment_id, line_index"):
        parse_result({**good, "matches": [["a", 0]]})
    with pytest.raises(MapkitError, match=r"u1, v1, u2, v2"):
        parse_result({**good, "lines": [[1, 2, 3]]})
    failed = parse_result({"ok": False, "reason": "no hypothesis below the threshold"})
    assert not failed.ok and not failed.has_pose and "threshold" in failed.reason
    path = tmp_path / "r.json"
    path.write_text(json.dumps({**good, "lines": None}))
    lines = tmp_path / "l.json"
    lines.write_text(json.dumps({"lines": [[1, 1, 2, 2]]}))
    with pytest.raises(MapkitError, match="names image line 1, but there are 1 lines"):
        load_result(path, 10, lines)
    with pytest.raises(MapkitError, match="not valid JSON"):
        (tmp_path / "bad.json").write_text("{")
        load_result(tmp_path / "bad.json")


# --------------------------------------------------------------------------
# Statistics


def test_statistics(flat, flat_path):
    s = map_statistics(flat, flat_path)
    assert s["segments"] == flat.n_segments and s["regions"] == flat.n_regions
    assert sum(s["segments_per_kind"].values()) == flat.n_segments
    assert s["file_bytes"] == os.path.getsize(flat_path)
    polys = geometry.region_polygons(flat)
    assert s["region_area_m2"]["total"] == pytest.approx(sum(p.area for p in polys), rel=1e-6)
    md = statistics_markdown(s)
    assert f"**Segments** {flat.n_segments}" in md and "max_range" in md


# --------------------------------------------------------------------------
# The inspector (in process)


def test_floor_point_and_frustum_orientation():
    assert floor_point((1, 2, 5), (0, 0, -1)) == pytest.approx((1, 2))
    assert floor_point((0, 0, 5), (1, 0, -1)) == pytest.approx((5, 0))
    assert floor_point((0, 0, 5), (1, 0, 0.1)) is None
    cam = Camera.from_dict({**DEMO_CAMERA, "pitch_deg": 0.0})
    import viser.transforms as vtf

    forward = vtf.SO3(camera_wxyz(cam, math.radians(30))).apply(np.array([0.0, 0.0, 1.0]))
    assert forward == pytest.approx([math.cos(math.radians(30)), math.sin(math.radians(30)), 0.0], abs=1e-9)


@pytest.fixture(scope="module")
def inspector(flat):
    ins = Inspector(flat, port=0)
    yield ins
    ins.stop()


def test_inspector_selects_the_region_under_a_point(inspector, flat):
    x, y = flat.region_centres()[10]
    assert inspector.select_at(x, y) == int(flat.regions_at(x, y)[0])
    assert inspector.server.scene.get_handle_by_name("/selection/fill") is not None
    assert f"**Region {inspector.selected_region}**" in inspector.panel.selection.content
    assert inspector.select_at(-50.0, -50.0) is None
    assert "No region" in inspector.panel.selection.content
    assert inspector.server.scene.get_handle_by_name("/selection/fill") is None


def test_pose_tool_sets(inspector, flat):
    x, y = flat.region_centres()[40]
    regions, cands, in_view = inspector.pose_sets(x, y, 0.3, 0.5, math.radians(10))
    assert regions.tolist() == flat.regions_near(x, y, 0.5).tolist()
    assert cands.tolist() == flat.candidate_segments(x, y, 0.5).tolist()
    assert set(in_view) <= set(cands) and 0 < len(in_view) < len(cands)
    _, _, all_view = inspector.pose_sets(x, y, 0.3, 0.5, math.radians(10), fov_filter=False)
    assert all_view.tolist() == cands.tolist()
    # The panel's inputs drive the drawing.
    pc = inspector.panel.pose
    pc.x.value, pc.y.value, pc.dt.value = float(x), float(y), 0.5
    inspector.update_pose()
    assert f"**{len(regions)} regions**" in pc.summary.content
    for name in ("/pose/disk", "/pose/regions", "/pose/candidates", "/pose/frustum"):
        assert inspector.server.scene.get_handle_by_name(name) is not None, name
    pc.show.value = False
    inspector.update_pose()
    assert inspector.server.scene.get_handle_by_name("/pose/frustum") is None
    pc.show.value = True


def test_inspector_shows_a_result(flat):
    cam, _ = map_camera(flat)
    x, y, yaw = *flat.region_centres()[60], 0.4
    ids = flat.candidate_segments(x, y, 0.0)
    lines, idx = project_segments(cam, flat.segments[ids], x, y, yaw)
    res = parse_result({"ok": True, "pose": {"x": x, "y": y, "yaw_deg": math.degrees(yaw)}, "score": 1e-3,
                        "matches": [[int(ids[idx[k]]), k] for k in range(3)],
                        "lines": lines[:3].reshape(-1, 4).tolist()}, n_segments=flat.n_segments)
    with Inspector(flat, port=0, result=res) as ins:
        for name in ("/result/frustum", "/result/matched", "/result/rays"):
            assert ins.server.scene.get_handle_by_name(name) is not None, name
        assert "accepted" in ins.panel.result_text.content
        rays = image_line_rays(cam, flat, res)
        # A ray through an end point of a matched line passes near the matched segment's line.
        c = cam.centre(x, y)
        seg = flat.segments[ids[idx[0]]]
        d = rays[0, 1] - c
        n = np.cross(d, seg[1] - seg[0])
        assert abs(np.dot(seg[0] - c, n / np.linalg.norm(n))) < 1e-6


# --------------------------------------------------------------------------
# The server over a real websocket


def test_unique_edges_draw_shared_edges_once():
    e = np.array([[[0, 0], [1, 0]], [[1, 0], [0, 0]], [[1, 0], [1, 1]], [[0, 0], [1, 0.00001]]], dtype=float)
    assert geometry.unique_edges(e).tolist() == [[[0, 0], [1, 0]], [[1, 0], [1, 1]]]


def test_server_sends_the_scene_nodes_to_a_websocket_client(inspector):
    names = scene_names(inspector.port)
    for expected in ("/segments/floor", "/segments/ceiling", "/segments/vertical", "/segments/jamb",
                     "/segments/lintel", "/walls", "/regions/fill", "/regions/outlines", "/pose/frustum"):
        assert expected in names, f"{expected} not among {sorted(names)}"


@pytest.mark.parametrize("origin,accepted", [
    (None, True),  # a script, not a browser page
    ("http://127.0.0.1:{port}", True),  # the inspector's own page
    ("http://localhost:{port}", True),
    ("http://evil.example", False),  # another site's page open in the same browser
    ("http://127.0.0.1:9", False),  # another local service's page
])
def test_websocket_accepts_only_the_inspectors_own_pages(inspector, origin, accepted):
    import viser
    from websockets.exceptions import InvalidStatus
    from websockets.sync.client import connect

    port = inspector.port
    headers = {} if origin is None else {"Origin": origin.format(port=port)}
    try:
        with connect(f"ws://127.0.0.1:{port}", subprotocols=[f"viser-v{viser.__version__}"], max_size=None,
                     additional_headers=headers, open_timeout=10):
            got_in = True
    except InvalidStatus as exc:
        assert exc.response.status_code == 403
        got_in = False
    assert got_in == accepted


def test_cli_warns_when_listening_beyond_this_machine():
    from mapkit.commands.view import _loopback

    assert _loopback("127.0.0.1") and _loopback("localhost") and _loopback("::1") and _loopback("[::1]")
    assert not _loopback("0.0.0.0") and not _loopback("192.168.1.5") and not _loopback("myhost")


def test_result_with_a_negative_line_index_or_deep_nesting_is_refused(tmp_path):
    from mapkit.errors import MapkitError
    from mapkit.view.result import load_result

    bad = tmp_path / "neg.json"
    bad.write_text('{"ok": true, "pose": {"x": 0, "y": 0, "yaw_deg": 0}, "matches": [[1, -2]]}')
    with pytest.raises(MapkitError, match="line indices start at 0"):
        load_result(bad, 10)
    deep = tmp_path / "deep.json"
    deep.write_text("[" * 100000 + "]" * 100000)
    with pytest.raises(MapkitError, match="nested too deeply"):
        load_result(deep, 10)


def test_server_page_is_served_and_stops(flat):
    ins = Inspector(flat, port=0)
    port = ins.port
    assert port > 0
    with urllib.request.urlopen(ins.url, timeout=10) as resp:
        page = resp.read().decode("utf-8", "replace")
    assert "<title>Viser</title>" in page
    ins.stop()
    with pytest.raises(OSError):
        urllib.request.urlopen(ins.url, timeout=2)


# --------------------------------------------------------------------------
# The command line


def _mapkit(*args, **kw):
    return subprocess.run([sys.executable, "-m", "mapkit", *args], capture_output=True, text=True, timeout=60, **kw)


def _sigint_default():
    # A shell's background job ('pytest &') starts with SIGINT ignored, and a
    # Python started with it ignored never raises KeyboardInterrupt: the
    # server below must see Ctrl-C as a terminal would send it.
    signal.signal(signal.SIGINT, signal.SIG_DFL)


@pytest.mark.slow
def test_cli_serves_until_ctrl_c(flat_path):
    proc = subprocess.Popen([sys.executable, "-m", "mapkit", "view", str(flat_path), "--port", "0"],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, preexec_fn=_sigint_default)
    try:
        line = proc.stdout.readline()
        assert "http://127.0.0.1:" in line, line + proc.stderr.read()
        url = next(w for w in line.split() if w.startswith("http://"))
        with urllib.request.urlopen(url, timeout=10) as resp:
            assert resp.status == 200
        proc.send_signal(signal.SIGINT)
        out, err = proc.communicate(timeout=30)
    finally:
        if proc.poll() is None:
            proc.kill()
    assert proc.returncode == 0, err
    assert "Traceback" not in err and "stopped" in err


@pytest.mark.slow
def test_cli_errors_are_one_line(tmp_path, flat_path):
    r = _mapkit("view", str(tmp_path / "missing.lmap"), "--port", "0")
    assert r.returncode == 2 and r.stderr.startswith("mapkit: error:") and "Traceback" not in r.stderr
    r = _mapkit("view", str(flat_path), "--lines", "x.json")
    assert r.returncode == 2 and "--lines needs --result" in r.stderr
    bad = tmp_path / "bad.json"
    bad.write_text(json.dumps({"ok": True, "pose": {"x": 0, "y": 0, "yaw_deg": 0}, "matches": [[99999, 0]]}))
    r = _mapkit("view", str(flat_path), "--result", str(bad), "--port", "0")
    assert r.returncode == 2 and "names segment 99999" in r.stderr


def test_a_named_port_that_is_busy_is_refused_not_replaced(flat_path):
    """--port P with P taken: exit 2 naming the port and what to do (a user
    who names a port expects that port); without --port a free one is taken."""
    import socket

    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as s:
        s.bind(("127.0.0.1", 0))
        s.listen(1)
        port = s.getsockname()[1]
        r = _mapkit("view", str(flat_path), "--port", str(port))
    assert r.returncode == 2 and r.stdout == "" and "Traceback" not in r.stderr
    assert f"port {port} on 127.0.0.1 is in use" in r.stderr and "--port" in r.stderr
    assert len(r.stderr.strip().splitlines()) == 1


@pytest.mark.slow
def test_cli_html_snapshot_is_standalone(tmp_path, flat_path):
    out = tmp_path / "flat.html"
    r = _mapkit("view", str(flat_path), "--html", str(out))
    assert r.returncode == 0, r.stderr
    html = out.read_text()
    assert "window.__VISER_EMBED_DATA__=" in html
    assert 'id="mapkit-legend"' in html and "flat.lmap" in html and "floor segments" in html
    # Nothing to fetch: no external scripts, styles or fonts.
    assert "<script src=\"http" not in html and "<link rel=\"stylesheet\" href=\"http" not in html
    assert not list(tmp_path.glob("*.tmp"))


# --------------------------------------------------------------------------
# A large map (timings: tools/bench_view.py; tests assert behaviour, not seconds)


@pytest.mark.slow
def test_a_large_map_opens_and_stays_interactive():
    """A map the size of the Barcelona pavilion's (about 1500 segments, 4600
    regions) is served: a client gets every static node, thousands of
    outlines start hidden behind their toggle, and a click and a pose change
    work on it."""
    big = grid_flat(rooms=(7, 5), room_size=(5.0, 4.5), cell=0.4)
    assert big.n_regions > 4000 and big.n_segments > 1000
    ins = Inspector(big, port=0)
    try:
        names = scene_names(ins.port, timeout=10)
        assert {"/regions/fill", "/regions/outlines", "/walls", "/segments/floor"} <= names
        # Thousands of outlines start hidden (first-frame cost); their toggle shows them.
        outlines = ins.server.scene.get_handle_by_name("/regions/outlines")
        assert not outlines.visible and not ins.panel.toggles["region outlines"].value
        ins.panel.toggles["region outlines"].value = True
        assert outlines.visible
        # A click selects the region under it; a pose change redraws the pose tool.
        x, y = big.region_centres()[2000]
        assert ins.select_at(x, y) == int(big.regions_at(x, y)[0])
        ins.panel.pose.dt.value = 1.0
        ins.update_pose()
        assert ins.server.scene.get_handle_by_name("/pose/disk") is not None
        assert "regions** retained" in ins.panel.pose.summary.content
    finally:
        ins.stop()


# --------------------------------------------------------------------------
# A map built from a real plan, with the plan overlaid


@pytest.fixture(scope="module")
def built_flat():
    """maps/flat.dxf and its map through ``mapkit build``: the committed
    maps/flat.lmap, which test_build_real checks is that build. The
    inspector must take real maps as they come."""
    plan = os.path.join(os.path.dirname(__file__), "..", "maps", "flat.dxf")
    return plan, os.path.join(os.path.dirname(__file__), "..", "maps", "flat.lmap")


@pytest.mark.slow
def test_real_map_with_its_plan_overlaid(built_flat):
    from mapkit.importers import load_scene
    from linemap.lmap import load_map

    plan_path, map_path = built_flat
    m = load_map(map_path)
    with Inspector(m, port=0, map_path=map_path, plan=load_scene(plan_path)) as ins:
        for name in ("/plan/walls", "/plan/free", "/regions/fill", "/walls"):
            assert ins.server.scene.get_handle_by_name(name) is not None, name
        assert "plan overlay" in ins.panel.toggles
        ins.panel.toggles["plan overlay"].value = False
        assert not ins.server.scene.get_handle_by_name("/plan/walls").visible
        x, y = m.region_centres()[0]
        assert ins.select_at(x, y) == int(m.regions_at(x, y)[0])
        assert ins.camera_source in ("build parameters", "map")


@pytest.mark.slow
def test_cli_plan_and_result_on_a_real_map(built_flat, tmp_path):
    plan_path, map_path = built_flat
    res = tmp_path / "result.json"
    res.write_text(json.dumps({"ok": False, "reason": "no hypothesis below the threshold", "matches": []}))
    out = tmp_path / "snap.html"
    r = _mapkit("view", str(map_path), "--plan", plan_path, "--result", str(res), "--html", str(out))
    assert r.returncode == 0, r.stderr
    assert out.stat().st_size > 100_000


def test_degenerate_maps_open():
    """No regions, no walls: the inspector still opens and says so instead of crashing."""
    from shapely.geometry import MultiPolygon

    segs = np.array([[[0, 0, 0], [4, 0, 0]], [[0, 0, 0], [0, 0, 2.5]]], dtype=float)
    empty = assemble_map(segs, [SegmentKind.FLOOR, SegmentKind.VERTICAL], [], [], MultiPolygon(), {})
    with Inspector(empty, port=0) as ins:
        assert ins.select_at(1.0, 1.0) is None
        assert ins.panel.pose.summary.content.startswith("**0 regions**")
        assert ins.camera_source.startswith("default")
    no_walls = assemble_map(segs, [SegmentKind.FLOOR, SegmentKind.VERTICAL], [box(0, 0, 2, 2)], [[0]],
                            MultiPolygon(), {})
    with Inspector(no_walls, port=0) as ins:
        assert ins.select_at(1.0, 1.0) == 0
        assert ins.server.scene.get_handle_by_name("/walls") is None
