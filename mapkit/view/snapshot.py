"""A standalone HTML snapshot of a map's 3D scene (``mapkit view MAP --html OUT``).

viser (1.x) serialises a server's scene messages into its own single-file web
client (``SceneApi.as_html``): the client bundle is inlined and the scene is
embedded as base64, so the file opens from ``file://`` with no server and no
network. Only the 3D scene travels; the GUI panel (pose tool, selection)
needs the live server, so a static legend box is added to the page instead.
The pose tool is hidden first so the snapshot shows the map itself (and a
matcher result, if one is given).
"""

from __future__ import annotations

import os

import html

from linemap.atomic import write_atomic
from linemap.lmap import LineMap
from mapkit.view.palette import legend_html


def legend_box(m: LineMap, title: str) -> str:
    """A fixed box in the page's lower-left corner: title, counts and the legend."""
    return (
        '<div id="mapkit-legend" style="position:fixed;left:10px;bottom:10px;z-index:1000;max-width:420px;'
        "padding:8px 10px;background:rgba(255,255,255,0.92);border-radius:6px;box-shadow:0 1px 4px rgba(0,0,0,.3);"
        'font-family:sans-serif;color:#222">'
        f"<div style=\"font-weight:600;font-size:13px\">{html.escape(title)}</div>"
        f'<div style="font-size:12px">{m.n_segments} segments, {m.n_regions} regions</div>'
        f"{legend_html(interactive=False)}</div>"
    )


def snapshot_html(m: LineMap, plan=None, result=None, camera=None, title: str = "mapkit map") -> str:
    """The HTML text of the snapshot."""
    from mapkit.view.server import Inspector

    inspector = Inspector(m, host="127.0.0.1", port=0, plan=plan, result=result, camera=camera)
    try:
        inspector.panel.pose.show.value = False  # removes the pose tool's nodes
        inspector.update_pose()
        page = inspector.server.scene.as_html()
    finally:
        inspector.stop()
    end = page.rindex("</body>")
    return page[:end] + legend_box(m, title) + page[end:]


def write_snapshot(m: LineMap, path: str | os.PathLike, plan=None, result=None, camera=None,
                   title: str = "mapkit map") -> int:
    """Write the snapshot to ``path`` atomically; returns its size in bytes."""
    text = snapshot_html(m, plan=plan, result=result, camera=camera, title=title).encode("utf-8")
    write_atomic(path, text)
    return len(text)
