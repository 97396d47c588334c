"""The inspector: a viser server showing one map, reacting to clicks and the pose tool.

:class:`Inspector` builds the static layers once (:mod:`~mapkit.view.scene_nodes`)
and redraws three small dynamic groups on demand:

- ``/selection/...``: the clicked region (fill, outline) and its visible segments;
- ``/pose/...``: the uncertainty disk, the regions it meets (``regions_near``),
  the candidate segments (``candidate_segments``, optionally reduced to the
  horizontal field of view over ``[yaw - dyaw, yaw + dyaw]``), the heading
  wedge and the camera frustum; the panel shows the synthetic image;
- ``/result/...``: a matcher result's pose, matched segments and the image
  lines back-projected as rays.

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
import viser.transforms as vtf

from mapkit.lmap import LineMap, SegmentKind
from mapkit.view import palette, scene_nodes
from mapkit.view.fov import in_horizontal_view
from mapkit.view.geometry import (disk_mesh, disk_outline, lift, map_bounds, region_adjacency, region_polygons,
                                  ring_edges, triangulate)
from mapkit.view.panel import SELECTION_HINT, build_panel, id_list_markdown
from mapkit.view.result import MatchResult
from mapkit.view.stats import map_camera, map_statistics, statistics_markdown
from mapkit.view.synthetic_image import blank_image, draw_lines, project_segments, render_segments

#: Length of the back-projected image-line rays when no matched segment says how far (metres).
RAY_LENGTH_M = 4.0


def floor_point(origin, direction) -> tuple[float, float] | None:
    """Where a click ray meets the floor plane z = 0, or None if it never does."""
    o, d = np.asarray(origin, dtype=float), np.asarray(direction, dtype=float)
    if d[2] >= -1e-9:
        return None
    t = -o[2] / d[2]
    return (float(o[0] + t * d[0]), float(o[1] + t * d[1])) if t > 0 else None


def camera_wxyz(camera, yaw: float) -> np.ndarray:
    """Quaternion (w, x, y, z) of the camera-to-world rotation at heading ``yaw``.

    viser's frustum follows OpenCV axes (X right, Y down, Z forward), like
    :class:`matcher.camera.Camera`, whose world-to-camera rotation R has the
    camera axes as rows; the camera-to-world rotation is R transposed.
    """
    return vtf.SO3.from_matrix(camera.world2cam(yaw).T).wxyz


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
        self.half_fov = self.camera.horizontal_half_fov()
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
        with contextlib.redirect_stdout(io.StringIO()):
            self.server = viser.ViserServer(host=host, port=port, verbose=False)
        self.host = host
        scene = self.server.scene
        # No shadows (nothing here needs them; they are costly in software
        # WebGL) and a dimmer environment light, which otherwise washes the
        # region colours out towards white.
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
        layer_names = list(self.layers.handles) + (["matcher result"] if result else [])
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
        # default) leaves too little depth precision at building scale under
        # software WebGL, and the highlights z-fight with the fills.
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
        mid = (centres * areas[:, None]).sum(axis=0) / max(areas.sum(), 1e-12)
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
        regions = self.m.regions_near(x, y, dt)
        cands = self.m.segments_for_regions(regions)
        if fov_filter and len(cands):
            keep = in_horizontal_view(self.m.segments[cands], x, y, dt, yaw, dyaw, self.half_fov)
        else:
            keep = np.ones(len(cands), dtype=bool)
        return regions, cands, cands[keep]

    def update_pose(self) -> None:
        """Redraw the pose tool from the panel's inputs."""
        with self._lock:
            scene = self.server.scene
            pc = self.panel.pose
            names = ("/pose/disk", "/pose/disk_fill", "/pose/regions", "/pose/candidates", "/pose/out_of_view",
                     "/pose/heading", "/pose/frustum")
            if not pc.show.value:
                for n in names:
                    scene.remove_by_name(n)
                pc.summary.content = "Pose tool hidden."
                return
            x, y, yaw, dt, dyaw = pc.values()
            regions, cands, in_view = self.pose_sets(x, y, yaw, dt, dyaw, bool(pc.fov_filter.value))
            out = np.setdiff1d(cands, in_view)
            scene.add_line_segments("/pose/disk", disk_outline(x, y, max(dt, 0.01), 0.01), palette.POSE_DISK,
                                    thickness=3.0, thickness_units="screen")
            dv, df = disk_mesh(x, y, max(dt, 0.01), scene_nodes.Z_RETAINED + 0.001)
            scene.add_mesh_simple("/pose/disk_fill", dv, df, color=palette.POSE_DISK, opacity=0.35, side="double",
                                  cast_shadow=False, receive_shadow=False)
            verts, faces = self.triangles.subset(regions)
            if len(faces):
                scene.add_mesh_simple("/pose/regions", np.c_[verts, np.full(len(verts), scene_nodes.Z_RETAINED)],
                                      faces, color=palette.RETAINED_REGION, opacity=0.55, side="double",
                                      cast_shadow=False, receive_shadow=False)
            else:
                scene.remove_by_name("/pose/regions")
            self._segments_node("/pose/candidates", in_view, palette.CANDIDATE, 3.5)
            self._segments_node("/pose/out_of_view", out, palette.CANDIDATE_OUT_OF_VIEW, 3.0)
            scene.add_line_segments("/pose/heading", self._heading_wedge(x, y, yaw, dyaw), palette.FRUSTUM,
                                    thickness=2.0, thickness_units="screen")
            self._frustum("/pose/frustum", x, y, yaw, palette.FRUSTUM)
            img, drawn = render_segments(self.camera, self.m.segments[in_view], self.kind_colours[in_view], x, y, yaw)
            pc.image.image = img
            pc.summary.content = (
                f"**{len(regions)} regions** retained, **{len(cands)} candidate segments**, "
                f"**{len(in_view)}** in view over yaw {math.degrees(yaw):.0f} ± {math.degrees(dyaw):.0f}° "
                f"(half FOV {math.degrees(self.half_fov):.0f}°); {len(drawn)} project into the image at the "
                f"nominal pose."
            )

    def _segments_node(self, name: str, ids: np.ndarray, colour, px: float) -> None:
        if len(ids):
            self.server.scene.add_line_segments(name, self.m.segments[ids].astype(np.float32), colour,
                                                thickness=px, thickness_units="screen")
        else:
            self.server.scene.remove_by_name(name)

    def _heading_wedge(self, x: float, y: float, yaw: float, dyaw: float, length: float = 1.5) -> np.ndarray:
        """Rays on the floor: the nominal heading and the outermost edges of the field of view."""
        reach = dyaw + self.half_fov
        angles = [yaw, yaw - reach, yaw + reach]
        z = 0.02
        return np.array([[[x, y, z], [x + length * math.cos(a), y + length * math.sin(a), z]] for a in angles])

    def _frustum(self, name: str, x: float, y: float, yaw: float, colour):
        cam = self.camera
        fov = 2.0 * math.atan2(cam.height / 2.0, cam.fy)
        return self.server.scene.add_camera_frustum(
            name, fov=fov, aspect=cam.width / cam.height, scale=0.5, color=colour, thickness=2.0,
            thickness_units="screen", wxyz=camera_wxyz(cam, yaw), position=tuple(cam.centre(x, y)),
        )

    # ---- matcher result ---------------------------------------------------------
    def show_result(self, res: MatchResult) -> None:
        """Draw a result: pose frustum, matched segments, image lines as rays and in the image."""
        with self._lock:
            scene = self.server.scene
            handles = []
            matched = np.unique(res.matches[:, 0]) if len(res.matches) else np.zeros(0, dtype=np.int64)
            score = f"{res.score:.3g}" if res.score is not None else "n/a"
            head = f"**{'accepted' if res.ok else 'rejected'}**, score E = {score}, {len(res.matches)} matches"
            if not res.ok and res.reason:
                head += f"; reason: {res.reason}"
            if not res.has_pose:
                self.panel.result_text.content = head + "\n\nNo pose to show."
                self._result_handles = handles
                return
            x, y, yaw = res.x, res.y, res.yaw
            handles.append(self._frustum("/result/frustum", x, y, yaw, palette.RESULT_POSE))
            if len(matched):
                handles.append(scene.add_line_segments(
                    "/result/matched", self.m.segments[matched].astype(np.float32), palette.MATCHED,
                    thickness=scene_nodes.HIGHLIGHT_PX + 1, thickness_units="screen"))
            img = blank_image(self.camera)
            visible = self.m.candidate_segments(x, y, 0.0)
            render_segments(self.camera, self.m.segments[visible], np.full((len(visible), 3), 170), x, y, yaw,
                            image=img, thickness=1)
            if len(matched):
                render_segments(self.camera, self.m.segments[matched], np.array([palette.MATCHED]), x, y, yaw,
                                image=img, thickness=3)
            if res.lines is not None and len(res.lines):
                draw_lines(img, res.lines, palette.RAYS, thickness=2)
                handles.append(scene.add_line_segments("/result/rays", self._rays(res), palette.RAYS,
                                                       thickness=1.5, thickness_units="screen"))
            self.panel.result_image.image = img
            n_lines = "no image lines given" if res.lines is None else f"{len(res.lines)} image lines"
            self.panel.result_text.content = (
                head + f"\n\npose x = {x:.3f} m, y = {y:.3f} m, yaw = {math.degrees(yaw):.1f}°; {n_lines}.\n\n"
                "Image: model at the estimated pose (grey), matched segments (green), image lines (blue)."
            )
            self._result_handles = handles

    def _rays(self, res: MatchResult) -> np.ndarray:
        """(3M, 2, 3) segments: for each image line, the rays through its end points
        from the camera centre and the segment joining their far ends (the
        line's interpretation plane, cut at the matched segment's distance)."""
        cam = self.camera
        c = cam.centre(res.x, res.y)
        R = cam.world2cam(res.yaw)
        dirs = cam.pixel_rays(res.lines.reshape(-1, 2)) @ R  # world directions, (2M, 3)
        dirs /= np.linalg.norm(dirs, axis=1, keepdims=True)
        length = np.full(len(res.lines), RAY_LENGTH_M)
        for seg, line in res.matches:
            if 0 <= line < len(length):
                length[line] = float(np.linalg.norm(self.m.segments[seg].mean(axis=0) - c))
        far = c + dirs * np.repeat(length, 2)[:, None]
        far = far.reshape(-1, 2, 3)
        cc = np.broadcast_to(c, far[:, 0].shape)
        return np.concatenate([np.stack([cc, far[:, 0]], 1), np.stack([cc, far[:, 1]], 1),
                               np.stack([far[:, 0], far[:, 1]], 1)]).astype(np.float32)

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
