"""The inspector (``mapkit view``) seen from outside, as its tests and
``tools/bench_view.py`` see it: the scene nodes a websocket client receives,
and the page drawn in headless chromium (:mod:`mapkit_harness.browser`)."""

from __future__ import annotations

import time
from typing import TYPE_CHECKING

import cv2
import numpy as np

from mapkit_harness.browser import Chromium, wait_for

if TYPE_CHECKING:
    from mapkit.view.server import Inspector

#: The page is 1280 x 800; viser's panel covers x > 870, its software-WebGL
#: notice the top-left corner. The 3D view is judged in the rest.
WIDTH, HEIGHT = 1280, 800
VIEW = (slice(160, HEIGHT), slice(0, 860))


def scene_names(port: int, timeout: float = 10.0) -> set[str]:
    """Connect like viser's web client and collect the names of scene nodes received."""
    import msgspec
    import viser
    import zstandard
    from websockets.sync.client import connect

    names: set[str] = set()
    with connect(f"ws://127.0.0.1:{port}", subprotocols=[f"viser-v{viser.__version__}"], max_size=None) as ws:
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            try:
                frame = ws.recv(timeout=0.5)
            except TimeoutError:
                if names:
                    break
                continue
            raw_size = int.from_bytes(frame[:8], "little")
            comp_size = int.from_bytes(frame[8:16], "little")
            inner = zstandard.ZstdDecompressor().decompress(frame[16 : 16 + comp_size], max_output_size=raw_size)
            for msg in msgspec.msgpack.decode(inner)["messages"]:
                if isinstance(msg, dict) and isinstance(msg.get("name"), str):
                    names.add(msg["name"])
    return names


def hue_histogram(img: np.ndarray) -> np.ndarray:
    """Pixels per 15-degree hue bin (OpenCV hue 0-180 in bins of 15), coloured pixels only."""
    hsv = cv2.cvtColor(np.ascontiguousarray(img), cv2.COLOR_RGB2HSV)
    coloured = (hsv[..., 1] > 40) & (hsv[..., 2] > 60)
    return np.bincount(hsv[..., 0][coloured] // 15, minlength=12)


def scene_drawn(img: np.ndarray) -> bool:
    """The map is on screen: region fills of at least five different hues."""
    return int((hue_histogram(img[VIEW]) > 300).sum()) >= 5


def open_and_wait(browser: Chromium, ins: Inspector, timeout: float = 60.0) -> tuple[np.ndarray, float]:
    """Navigate to the inspector; return the first screenshot showing the scene and the seconds it took."""
    t0 = time.perf_counter()
    browser.navigate(ins.url)
    img = wait_for(lambda: (lambda s: s if scene_drawn(s) else None)(browser.screenshot()), timeout,
                   interval=0.1, what="the map to be drawn in chromium")
    return img, time.perf_counter() - t0
