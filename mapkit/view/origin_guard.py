"""Only pages of the inspector itself may open its websocket.

A browser lets any web page open a websocket to any address, the user's
own machine included, and sends the page's ``Origin`` with the request. The
inspector's websocket serves the whole plan and takes control messages, so
a page on another site open in the same browser could read the plan and
drive the controls. viser (1.1) does not check the origin; the websockets
server it runs on can (its ``origins`` option), so the inspector starts
viser's server with that option set: requests without an ``Origin`` header
(not from a browser page: scripts, tests) and from pages served on the
inspector's own port by a loopback name or an IP address are accepted;
pages of any other origin get HTTP 403.
"""

from __future__ import annotations

import contextlib
import re
import socket

import websockets.asyncio.server as ws_server

#: Host part of an acceptable origin: loopback names and IP address literals
#: (a page on a domain name cannot be the inspector's own).
_HOSTS = r"(localhost|127\.\d{1,3}\.\d{1,3}\.\d{1,3}|\d{1,3}\.\d{1,3}\.\d{1,3}\.\d{1,3}|\[[0-9a-fA-F:.]+\])"


def allowed_origins(port: int) -> list:
    """The ``origins`` option for a server on ``port``."""
    return [None, re.compile(rf"https?://{_HOSTS}:{int(port)}")]


def free_port(host: str) -> int:
    """A port free on ``host`` now: the origin check needs the port before
    the server binds it (the operating system's choice for port 0 comes too
    late)."""
    family = socket.AF_INET6 if ":" in host else socket.AF_INET
    with socket.socket(family, socket.SOCK_STREAM) as s:
        s.bind((host.strip("[]"), 0))
        return int(s.getsockname()[1])


@contextlib.contextmanager
def origin_checked_servers():
    """While active, websockets servers started in this process without an
    ``origins`` option get :func:`allowed_origins` for their port (viser
    starts its server this way, trying successive ports)."""
    serve = ws_server.serve

    def guarded(handler, host=None, port=None, *args, **kwargs):
        kwargs.setdefault("origins", allowed_origins(port))
        return serve(handler, host, port, *args, **kwargs)

    ws_server.serve = guarded
    try:
        yield
    finally:
        ws_server.serve = serve
