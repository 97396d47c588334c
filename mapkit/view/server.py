"""The inspector: a viser server showing one map, reacting to clicks and the pose tool.

:class:`Inspector` builds the static layers once (:mod:`~mapkit.view.scene_nodes`)
and redraws three small dynamic groups on demand:

- ``/selection/...``: the clicked region (fill, outline) and its visible
  segments, drawn here;
- ``/pose/...``: the pose tool (:mod:`~mapkit.view.pose_tool`);
- ``/result/...``: a matcher result (:mod:`~mapkit.view.result_overlay`).

viser runs GUI and click callbacks on a thread pool; one lock serialises the
redraws so that two quick slider moves cannot interleave their scene updates.
"""

from __future__ import annotations

import contextlib
import io
import math
import threading
import time

import numpy as np
import viser

from linemap.lmap import LineMap, SegmentKind
from mapkit.tolerances import ZERO
from mapkit.view import palette, pose_tool, scene_nodes
from mapkit.view.geometry import lift, map_bounds, region_adjacency, region_polygons, ring_edges, triangulate
from mapkit.view.origin_guard import free_port, origin_checked_servers
from mapkit.view.panel import SELECTION_HINT, build_panel, id_list_markdown
from mapkit.view.result import MatchResult
from mapkit.view.result_overlay import draw_result
from mapkit.view.stats import map_camera, map_statistics, statistics_markdown
from mapkit.view.synthetic_image import blank_image

def floor_point(origin, direction) -> tuple[float, float] | None:
    """Where a click ray meets the floor plane z = 0, or None if it never does."""
    o, d = np.asarray(origin, dtype=float), np.asarray(direction, dtype=float)
    if d[2] >= -ZERO.direction:
        return None
    t = -o[2] / d[2]
    return (float(o[0] + t * d[0]), float(o[1] + t * d[1])) if t > 0 else None


class Inspector:
    """A running inspector for map ``m``. ``stop()`` it (or use it as a context manager).

    ``port=0`` takes any free port; :attr:`url` says which. ``plan`` is an
    imported :class:`mapkit.scene.Scene` to overlay, ``result`` a
    :class:`~mapkit.view.result.MatchResult`, ``camera`` overrides the map's.
    """

    def __init__(self, m: LineMap, *, host: str = "127.0.0.1", port: int = 8080, map_path=None, plan=None,
                 result: MatchResult | None = None, camera=None) -> None:
        t0 = time.perf_counter()
        self.m = m
        self.result = result
        self._lock = threading.RLock()
        if camera is not None:
            self.camera, self.camera_source = camera, "given"
        else:
            self.camera, self.camera_source = map_camera(m)
        self.polygons = region_polygons(m)
        self.triangles = triangulate(self.polygons)
        self.region_colour = palette.colour_regions(m.n_regions, *region_adjacency(self.polygons))
        self.ring_edges, self.ring_of_edge = ring_edges(m.ring_points, m.ring_offsets)
        self.kind_colours = np.array([palette.KIND_COLOURS[SegmentKind(k)] for k in m.kinds], dtype=np.uint8
                                     ).reshape(-1, 3)
        self.selected_region: int | None = None
        self.selection_count = 0  # clicks handled: the browser test waits on it
        self._result_handles: list = []

        # viser prints its own banner; the command prints one line with the URL instead.
        # Its websocket accepts pages of the inspector only (origin_guard).
        with contextlib.redirect_stdout(io.StringIO()), origin_checked_servers():
            self.server = viser.ViserServer(host=host, port=port or free_port(host), verbose=False)
        self.host = host
        scene = self.server.scene
        # No shadows (nothing here needs them; they are costly in software
        # WebGL) and no environment map: its image-based light washed the
        # region colours out towards white and took seconds to prepare in
        # software WebGL. Ambient plus the default lights keep colours true.
        scene.configure_default_lights(enabled=True, cast_shadow=False)
        scene.configure_environment_map(None)
        scene.add_light_ambient("/lights/ambient", intensity=1.2)
        self.layers = scene_nodes.add_map_layers(scene, m, self.triangles, self.region_colour, plan)
        lo, hi = map_bounds(m)
        self.bounds = (lo, hi)
        self._set_initial_camera(lo, hi)

        start = self._start_position()
        stats_md = statistics_markdown(map_statistics(m, map_path))
        cam_note = f"{self.camera.width}x{self.camera.height}, camera from {self.camera_source}"
        layer_names = {name: self.layers.visible(name) for name in self.layers.handles}
        if result is not None:
            layer_names["matcher result"] = True
        self.panel = build_panel(self.server.gui, layer_names, (lo, hi), start, blank_image(self.camera), stats_md,
                                 cam_note, result is not None)
        self._wire()
        self.update_pose()
        if result is not None:
            self.show_result(result)
        self.build_seconds = time.perf_counter() - t0

    # ---- set-up ------------------------------------------------------------
    def _set_initial_camera(self, lo: np.ndarray, hi: np.ndarray) -> None:
        centre = (lo + hi) / 2
        span = float(max(hi[0] - lo[0], hi[1] - lo[1], 1.0))
        # Look a little right of the map's centre: the panel covers the right of the page.
        ax = float(centre[0] + 0.12 * span)
        self.server.initial_camera.look_at = (ax, float(centre[1]), 0.0)
        self.server.initial_camera.position = (ax, float(centre[1] - 0.7 * span), 0.8 * span)
        self.server.initial_camera.up = (0.0, 0.0, 1.0)
        # The floor layers are millimetres apart; a near plane at 1 cm (viser's
        # default) wastes depth precision at building scale.
        self.server.initial_camera.near = max(0.05, 0.005 * span)
        self.server.initial_camera.far = 50.0 * span

    def _start_position(self) -> tuple[float, float]:
        """The pose tool starts at the region nearest the middle of the free space
        (area-weighted mean of the region centres), so it is inside the map."""
        if self.m.n_regions == 0:
            lo, hi = self.bounds
            return float((lo[0] + hi[0]) / 2), float((lo[1] + hi[1]) / 2)
        centres = self.m.region_centres()
        areas = np.bincount(self.triangles.owner, weights=self._triangle_areas(), minlength=self.m.n_regions)
        mid = (centres * areas[:, None]).sum(axis=0) / max(areas.sum(), ZERO.divisor)
        r = int(np.argmin(np.linalg.norm(centres - mid, axis=1)))
        return float(centres[r, 0]), float(centres[r, 1])

    def _triangle_areas(self) -> np.ndarray:
        v = self.triangles.vertices.reshape(-1, 3, 2)
        if len(v) == 0:
            return np.zeros(0)
        e1, e2 = v[:, 1] - v[:, 0], v[:, 2] - v[:, 0]
        return 0.5 * np.abs(e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0])

    def _wire(self) -> None:
        p = self.panel
        for name, box in p.toggles.items():
            box.on_update(lambda _e, name=name, box=box: self._toggle(name, bool(box.value)))
        for h in p.pose.inputs():
            h.on_update(lambda _e: self.update_pose())
        if p.pose_from_result is not None:
            p.pose_from_result.on_click(lambda _e: self._pose_from_result())

        @self.server.scene.on_click()
        def _(event) -> None:
            xy = floor_point(event.ray_origin, event.ray_direction)
            if xy is not None:
                self.select_at(*xy)

    def _toggle(self, name: str, visible: bool) -> None:
        if name == "matcher result":
            for h in self._result_handles:
                h.visible = visible
        else:
            self.layers.set_visible(name, visible)

    # ---- selection ------------------------------------------------------------
    def select_at(self, x: float, y: float) -> int | None:
        """Highlight the region under (x, y); returns its id (None off the map)."""
        regions = self.m.regions_at(x, y)
        with self._lock:
            if self.panel.click_moves_pose.value:
                self.panel.pose.x.value, self.panel.pose.y.value = x, y
            if len(regions) == 0:
                self._clear_selection(f"No region at ({x:.2f}, {y:.2f}): outside the free space.")
            else:
                self.select_region(int(regions[0]), (x, y))
            self.selection_count += 1
        return self.selected_region

    def _clear_selection(self, message: str = SELECTION_HINT) -> None:
        for name in ("/selection/fill", "/selection/outline", "/selection/visible"):
            self.server.scene.remove_by_name(name)
        self.selected_region = None
        self.panel.selection.content = message

    def select_region(self, r: int, at: tuple[float, float] | None = None) -> None:
        """Highlight region ``r``, its outline and visible segments; list them in the panel."""
        with self._lock:
            scene = self.server.scene
            verts, faces = self.triangles.subset(np.array([r]))
            scene.add_mesh_simple("/selection/fill", np.c_[verts, np.full(len(verts), scene_nodes.Z_SELECTED)],
                                  faces, color=palette.SELECTED_REGION, opacity=0.85, side="double",
                                  cast_shadow=False, receive_shadow=False)
            edges = self.ring_edges[self.m.ring_region[self.ring_of_edge] == r]
            scene.add_line_segments("/selection/outline", lift(edges, scene_nodes.Z_SELECTED + 0.002),
                                    palette.SELECTED_REGION, thickness=3.0, thickness_units="screen")
            ids = self.m.region_list(r)
            if len(ids):
                scene.add_line_segments("/selection/visible", self.m.segments[ids].astype(np.float32),
                                        palette.SELECTED_SEGMENTS, thickness=scene_nodes.HIGHLIGHT_PX,
                                        thickness_units="screen")
            else:
                scene.remove_by_name("/selection/visible")
            kinds = np.bincount(self.m.kinds[ids], minlength=len(SegmentKind)) if len(ids) else []
            by_kind = ", ".join(f"{SegmentKind(k).label} {int(n)}" for k, n in enumerate(kinds) if n)
            where = f" at ({at[0]:.2f}, {at[1]:.2f})" if at else ""
            c = self.m.region_centres()[r]
            self.panel.selection.content = (
                f"**Region {r}**{where}; centre ({c[0]:.2f}, {c[1]:.2f}), "
                f"{len(self.m.region_rings(r))} ring(s)\n\n"
                f"**{len(ids)} visible segments** ({by_kind or 'none'}):\n\n{id_list_markdown(ids)}"
            )
            self.selected_region = r

    # ---- pose tool ------------------------------------------------------------
    def pose_sets(self, x: float, y: float, yaw: float, dt: float, dyaw: float, fov_filter: bool = True):
        """(retained regions, candidate segments, the candidates kept in view) for a pose."""
        sets = pose_tool.pose_sets(self.m, self.camera, x, y, yaw, dt, dyaw, fov_filter)
        return sets.regions, sets.candidates, sets.in_view

    def update_pose(self) -> None:
        """Redraw the pose tool from the panel's inputs."""
        with self._lock:
            pc = self.panel.pose
            if not pc.show.value:
                pose_tool.remove_pose(self.server.scene)
                pc.summary.content = "Pose tool hidden."
                return
            img, summary = pose_tool.draw_pose(self.server.scene, self.m, self.triangles, self.camera,
                                               self.kind_colours, pose_tool.PoseEstimate(*pc.values()),
                                               fov_filter=bool(pc.fov_filter.value))
            pc.image.image = img
            pc.summary.content = summary

    # ---- matcher result ---------------------------------------------------------
    def show_result(self, res: MatchResult) -> None:
        """Draw a result: pose frustum, matched segments, image lines as rays and in the image."""
        with self._lock:
            handles, img, text = draw_result(self.server.scene, self.m, self.camera, res)
            if img is not None:
                self.panel.result_image.image = img
            self.panel.result_text.content = text
            self._result_handles = handles

    def _pose_from_result(self) -> None:
        res = self.result
        if res is None or not res.has_pose:
            return
        pc = self.panel.pose
        pc.x.value, pc.y.value, pc.yaw.value = res.x, res.y, math.degrees(res.yaw)

    # ---- life cycle ------------------------------------------------------------
    @property
    def port(self) -> int:
        return self.server.get_port()

    @property
    def url(self) -> str:
        host = "localhost" if self.host in ("0.0.0.0", "::", "") else self.host
        return f"http://{host}:{self.port}"

    def stop(self) -> None:
        with contextlib.redirect_stdout(io.StringIO()):
            self.server.stop()

    def __enter__(self) -> "Inspector":
        return self

    def __exit__(self, *exc) -> None:
        self.stop()
