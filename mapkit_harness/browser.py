"""A minimal headless-chromium driver over the Chrome DevTools Protocol.

Used by the inspector's browser test, ``tools/screenshot_view.py`` and
``tools/bench_view.py``.
It needs only Debian's ``chromium`` and the ``websockets`` package (already
a dependency of viser): chromium is started with ``--remote-debugging-port=0``,
writes the port it chose into its profile directory, and we speak CDP (JSON
over a websocket) to the page: navigate, screenshot, click.

WebGL has no GPU here, so chromium renders it with SwiftShader (software):
``--use-angle=swiftshader --enable-unsafe-swiftshader``.
"""

from __future__ import annotations

import base64
import itertools
import json
import os
import shutil
import subprocess
import tempfile
import time
import urllib.request
from pathlib import Path

import numpy as np

#: Executables tried in order; Debian's package installs ``chromium``.
CANDIDATES = ("chromium", "chromium-browser", "google-chrome", "google-chrome-stable")


class BrowserMissing(RuntimeError):
    """No chromium executable on PATH."""


def find_chromium() -> str:
    """Path of a chromium executable; BrowserMissing says how to install one."""
    env = os.environ.get("MAPKIT_CHROMIUM")
    if env:
        return env
    for name in CANDIDATES:
        path = shutil.which(name)
        if path:
            return path
    raise BrowserMissing(
        "chromium is not installed: the inspector's browser test and screenshot need it. "
        "Install Debian's package with `apt-get install -y chromium` (or set MAPKIT_CHROMIUM to a chromium binary)"
    )


def write_profile_preferences(profile: str) -> None:
    """Turn chromium's network prediction off in a fresh profile.

    With it on, chromium opens a spare TCP connection to the page's server
    and never sends a request on it; the websockets server under viser then
    waits for that connection's handshake (10 s) before it can close, so
    every ``Inspector.stop()`` after a page visit waited out viser's joins
    (6 s). There is no command-line switch for this preference."""
    os.makedirs(os.path.join(profile, "Default"), exist_ok=True)
    with open(os.path.join(profile, "Default", "Preferences"), "w") as f:
        json.dump({"net": {"network_prediction_options": 2}}, f)  # 2: never predict


class Chromium:
    """One headless chromium with one page, driven over CDP. Use as a context manager."""

    def __init__(self, width: int = 1280, height: int = 800, timeout: float = 30.0) -> None:
        from websockets.sync.client import connect

        self.width, self.height, self.timeout = width, height, timeout
        self._profile = tempfile.mkdtemp(prefix="mapkit-chromium-")
        write_profile_preferences(self._profile)
        args = [
            find_chromium(),
            "--headless",
            "--no-sandbox",  # we may run as root (CI containers)
            "--disable-gpu",
            "--use-angle=swiftshader",  # software WebGL, no GPU needed
            "--enable-unsafe-swiftshader",
            "--disable-quic",
            "--no-first-run",
            "--disable-background-networking",
            "--disable-component-update",
            "--disable-sync",
            "--disable-dev-shm-usage",
            f"--user-data-dir={self._profile}",
            f"--window-size={width},{height}",
            "--remote-debugging-port=0",
            "about:blank",
        ]
        self._proc = subprocess.Popen(args, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
        try:
            port = self._wait_for_port()
            page = self._page_websocket(port)
            self._ws = connect(page, max_size=None, open_timeout=timeout)
        except BaseException:
            self.close()
            raise
        self._ids = itertools.count(1)
        self.call("Page.enable")
        self.call("Emulation.setDeviceMetricsOverride", width=width, height=height, deviceScaleFactor=1, mobile=False)

    def _wait_for_port(self) -> int:
        port_file = Path(self._profile) / "DevToolsActivePort"
        deadline = time.monotonic() + self.timeout
        while time.monotonic() < deadline:
            if self._proc.poll() is not None:
                err = self._proc.stderr.read().decode(errors="replace")[-2000:] if self._proc.stderr else ""
                raise RuntimeError(f"chromium exited at start (code {self._proc.returncode}): {err}")
            if port_file.exists():
                text = port_file.read_text().split()
                if text:
                    return int(text[0])
            time.sleep(0.05)
        raise TimeoutError("chromium did not open its DevTools port")

    def _page_websocket(self, port: int) -> str:
        deadline = time.monotonic() + self.timeout
        while time.monotonic() < deadline:
            with urllib.request.urlopen(f"http://127.0.0.1:{port}/json/list", timeout=5) as resp:
                targets = json.loads(resp.read())
            pages = [t for t in targets if t.get("type") == "page"]
            if pages:
                return pages[0]["webSocketDebuggerUrl"]
            time.sleep(0.05)
        raise TimeoutError("chromium opened no page")

    # ---- protocol ----------------------------------------------------------
    def call(self, method: str, _until_event: str | None = None, **params) -> dict:
        """Send one CDP command and return its result. Events are dropped, except
        that with ``_until_event`` the call also waits until that event arrives."""
        msg_id = next(self._ids)
        self._ws.send(json.dumps({"id": msg_id, "method": method, "params": params}))
        deadline = time.monotonic() + self.timeout
        result, seen = None, _until_event is None
        while result is None or not seen:
            left = deadline - time.monotonic()
            if left <= 0:
                raise TimeoutError(f"chromium did not answer {method}" + (f" / {_until_event}" if _until_event else ""))
            reply = json.loads(self._ws.recv(timeout=left))
            if reply.get("id") == msg_id:
                if "error" in reply:
                    raise RuntimeError(f"{method} failed: {reply['error']}")
                result = reply.get("result", {})
            elif reply.get("method") == _until_event:
                seen = True
        return result

    def navigate(self, url: str) -> None:
        """Open ``url`` and wait for its load event (scripts loaded, not the scene drawn)."""
        self.call("Page.navigate", _until_event="Page.loadEventFired", url=url)

    def evaluate(self, expression: str):
        """Value of a JavaScript expression in the page."""
        r = self.call("Runtime.evaluate", expression=expression, returnByValue=True)
        return r.get("result", {}).get("value")

    def screenshot(self) -> np.ndarray:
        """(height, width, 3) uint8 RGB of the page as drawn now."""
        import cv2

        data = base64.b64decode(self.call("Page.captureScreenshot", format="png")["data"])
        bgr = cv2.imdecode(np.frombuffer(data, np.uint8), cv2.IMREAD_COLOR)
        return bgr[:, :, ::-1].copy()

    def click(self, x: float, y: float) -> None:
        """A left click at CSS pixel (x, y): move, press, release."""
        self.call("Input.dispatchMouseEvent", type="mouseMoved", x=x, y=y)
        self.call("Input.dispatchMouseEvent", type="mousePressed", x=x, y=y, button="left", clickCount=1)
        self.call("Input.dispatchMouseEvent", type="mouseReleased", x=x, y=y, button="left", clickCount=1)

    def close(self) -> None:
        ws = getattr(self, "_ws", None)
        if ws is not None:
            try:
                ws.close()
            except Exception:  # closing a dead socket is not an error worth reporting
                pass
        if self._proc.poll() is None:
            self._proc.terminate()
            try:
                self._proc.wait(timeout=10)
            except subprocess.TimeoutExpired:
                self._proc.kill()
                self._proc.wait()
        shutil.rmtree(self._profile, ignore_errors=True)

    def __enter__(self) -> "Chromium":
        return self

    def __exit__(self, *exc) -> None:
        self.close()


def wait_for(predicate, timeout: float, interval: float = 0.25, what: str = "condition"):
    """Poll ``predicate()`` until it returns a truthy value (or any array); TimeoutError names ``what``."""
    deadline = time.monotonic() + timeout
    while True:
        value = predicate()
        if isinstance(value, np.ndarray) or value:
            return value
        if time.monotonic() > deadline:
            raise TimeoutError(f"timed out after {timeout:.0f} s waiting for {what}")
        time.sleep(interval)
