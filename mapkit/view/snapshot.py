"""A standalone HTML snapshot of a map's 3D scene (``mapkit view MAP --html OUT``).

viser (1.x) serialises a server's scene messages into its own single-file web
client (``SceneApi.as_html``): the client bundle is inlined and the scene is
embedded as base64, so the file opens from ``file://`` with no server and no
network. Only the 3D scene travels; the GUI panel (legend, pose tool) needs
the live server. The pose tool is hidden first so the snapshot shows the map
itself (and a matcher result, if one is given).
"""

from __future__ import annotations

import os
import tempfile
from pathlib import Path

from mapkit.lmap import LineMap


def snapshot_html(m: LineMap, plan=None, result=None, camera=None) -> str:
    """The HTML text of the snapshot."""
    from mapkit.view.server import Inspector

    inspector = Inspector(m, host="127.0.0.1", port=0, plan=plan, result=result, camera=camera)
    try:
        inspector.panel.pose.show.value = False  # removes the pose tool's nodes
        inspector.update_pose()
        return inspector.server.scene.as_html()
    finally:
        inspector.stop()


def write_snapshot(m: LineMap, path: str | os.PathLike, plan=None, result=None, camera=None) -> int:
    """Write the snapshot to ``path`` atomically; returns its size in bytes."""
    text = snapshot_html(m, plan=plan, result=result, camera=camera).encode("utf-8")
    path = Path(path)
    fd, tmp = tempfile.mkstemp(prefix=path.name + ".", suffix=".tmp", dir=path.parent if str(path.parent) else ".")
    try:
        with os.fdopen(fd, "wb") as fh:
            fh.write(text)
        os.replace(tmp, path)
    except BaseException:
        if os.path.exists(tmp):
            os.unlink(tmp)
        raise
    return len(text)
