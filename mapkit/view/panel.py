"""The inspector's GUI panel: legend, layer toggles, selection, pose tool,
matcher result and statistics, as viser GUI elements.

The panel only builds elements and holds their handles; what happens when
one changes is wired by :class:`mapkit.view.server.Inspector`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from mapkit.view import palette

SELECTION_HINT = "Click on the floor to pick a region: its outline, id and visible segments show here."


@dataclass
class PoseControls:
    """The pose tool's inputs (x, y in metres, yaw and dyaw in degrees, dt in metres)."""

    x: object
    y: object
    yaw: object
    dt: object
    dyaw: object
    fov_filter: object
    show: object
    summary: object
    image: object

    def values(self) -> tuple[float, float, float, float, float]:
        """(x, y, yaw radians, dt, dyaw radians)."""
        return (float(self.x.value), float(self.y.value), math.radians(float(self.yaw.value)),
                float(self.dt.value), math.radians(float(self.dyaw.value)))

    def inputs(self) -> list:
        return [self.x, self.y, self.yaw, self.dt, self.dyaw, self.fov_filter, self.show]


@dataclass
class Panel:
    toggles: dict[str, object] = field(default_factory=dict)
    selection: object = None
    click_moves_pose: object = None
    pose: PoseControls | None = None
    result_text: object = None
    result_image: object = None
    pose_from_result: object = None
    stats: object = None


def build_panel(gui, layer_names: dict[str, bool], bounds: tuple[np.ndarray, np.ndarray], start: tuple[float, float],
                blank: np.ndarray, stats_md: str, camera_note: str, has_result: bool) -> Panel:
    """Create every GUI element. ``layer_names`` maps each toggle to its initial
    state, ``bounds`` are the map's (min, max) corners,
    ``start`` the initial pose position, ``blank`` the empty synthetic image."""
    panel = Panel()
    gui.configure_theme(control_width="large")
    with gui.add_folder("Legend", expand_by_default=True):
        gui.add_html(palette.legend_html())
    lo, hi = bounds
    with gui.add_folder("Pose", expand_by_default=True):
        show = gui.add_checkbox("Show pose tool", initial_value=True)
        x = gui.add_slider("x (m)", float(np.floor(lo[0])), float(np.ceil(hi[0])), 0.05, float(start[0]))
        y = gui.add_slider("y (m)", float(np.floor(lo[1])), float(np.ceil(hi[1])), 0.05, float(start[1]))
        yaw = gui.add_slider("yaw (deg)", -180.0, 180.0, 1.0, 0.0)
        dt = gui.add_slider("dt (m)", 0.0, 3.0, 0.05, 0.5)
        dyaw = gui.add_slider("dyaw (deg)", 0.0, 90.0, 1.0, 20.0)
        fov = gui.add_checkbox("Drop out-of-view", initial_value=True,
                               hint="Keep only candidates inside the horizontal field of view for some heading "
                                    "in [yaw - dyaw, yaw + dyaw]")
        summary = gui.add_markdown("")
        image = gui.add_image(blank, label=f"Synthetic image ({camera_note})", format="png")
        panel.pose = PoseControls(x, y, yaw, dt, dyaw, fov, show, summary, image)
    with gui.add_folder("Selection", expand_by_default=True):
        panel.selection = gui.add_markdown(SELECTION_HINT)
        panel.click_moves_pose = gui.add_checkbox("Click moves the pose", initial_value=False,
                                                  hint="A click on the floor also moves the pose tool there")
    if has_result:
        with gui.add_folder("Matcher result", expand_by_default=True):
            panel.result_text = gui.add_markdown("")
            panel.result_image = gui.add_image(blank, label="Model at the estimated pose, image lines over it",
                                               format="png")
            panel.pose_from_result = gui.add_button("Move the pose tool to the result")
    with gui.add_folder("Layers", expand_by_default=False):
        for name, shown in layer_names.items():
            panel.toggles[name] = gui.add_checkbox(name, initial_value=shown)
    with gui.add_folder("Statistics", expand_by_default=False):
        panel.stats = gui.add_markdown(stats_md)
    return panel


def id_list_markdown(ids: np.ndarray, limit: int = 80) -> str:
    """Segment ids as a compact comma list, cut after ``limit`` with a count."""
    ids = [int(i) for i in ids]
    head = ", ".join(str(i) for i in ids[:limit])
    return head + (f", ... ({len(ids)} in all)" if len(ids) > limit else "")
