"""``mapkit view MAP``: the map in the browser (viser), or a standalone HTML snapshot."""

from __future__ import annotations

#: The port tried first when none is named (then the next free ones, as viser does).
DEFAULT_PORT = 8080

HELP = "inspect a .lmap map in the browser (segments, walls, regions, pose tool, matcher results)"


def add_arguments(p) -> None:
    p.add_argument("map", metavar="MAP", help=".lmap file")
    p.add_argument("--plan", metavar="PLAN", help="overlay the source plan (DXF or mesh) the map was built from")
    p.add_argument("--result", metavar="RESULT.json", help="overlay a matcher result (matcher localize --json)")
    p.add_argument("--lines", metavar="LINES.json", help="image lines of the result, if the result holds none")
    p.add_argument("--camera", metavar="CAM.json", help="camera to use instead of the one recorded in the map")
    p.add_argument("--host", default="127.0.0.1", help="address to listen on (default 127.0.0.1; 0.0.0.0 for all)")
    p.add_argument("--port", type=int, default=None,
                   help=f"port to serve on; a port named here is used or refused when busy (0 takes any free port); "
                        f"without --port, {DEFAULT_PORT} or the next free one after it")
    p.add_argument("--html", metavar="OUT.html",
                   help="write a standalone HTML snapshot of the 3D scene (opens from file://, no server) and exit")


def _loopback(host: str) -> bool:
    """Is ``host`` an address only this machine reaches?"""
    import ipaddress

    if host == "localhost":
        return True
    try:
        return ipaddress.ip_address(host.strip("[]")).is_loopback
    except ValueError:
        return False


def _busy(host: str, port: int) -> str:
    return (f"port {port} on {host} is in use; name another with --port, or leave --port out to take "
            f"{DEFAULT_PORT} or the next free port")


def _check_port_free(host: str, port: int) -> None:
    """MapkitError when ``port`` is taken on ``host``: a port the user named
    is served on or refused, never silently replaced by another."""
    import errno
    import socket

    from mapkit.errors import MapkitError

    family = socket.AF_INET6 if ":" in host else socket.AF_INET
    with socket.socket(family, socket.SOCK_STREAM) as s:
        s.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)  # as servers bind: a closing port is free
        try:
            s.bind((host.strip("[]"), port))
        except OSError as exc:
            if exc.errno == errno.EADDRINUSE:
                raise MapkitError(_busy(host, port)) from None
            raise MapkitError(f"cannot listen on {host}:{port} ({exc.strerror or exc}); try --port 0") from None


def run(args) -> int:
    import sys
    import time

    from mapkit.errors import MapkitError
    from linemap.lmap import load_map

    if args.lines and not args.result:
        raise MapkitError("--lines needs --result (the lines are drawn at the result's pose)")
    if args.port is not None and not 0 <= args.port <= 65535:
        raise MapkitError(f"--port must be in [0, 65535], got {args.port}")
    if args.port and not args.html:
        _check_port_free(args.host, args.port)
    if not _loopback(args.host) and not args.html:
        print(f"mapkit view: warning: listening on {args.host}: anyone who can reach this machine can see the "
              "plan and use the inspector (there is no password); use the default 127.0.0.1 to keep it local",
              file=sys.stderr)
    if args.html:
        from linemap.atomic import check_output_path

        check_output_path(args.html, [args.map, args.plan, args.result, args.lines, args.camera])
    m = load_map(args.map)
    camera = None
    if args.camera:
        from linemap.camera import Camera

        camera = Camera.load(args.camera)
    result = None
    if args.result:
        from mapkit.view.result import load_result

        result = load_result(args.result, m.n_segments, args.lines)
    plan = None
    if args.plan:
        from mapkit.importers import load_scene

        plan = load_scene(args.plan)

    if args.html:
        from mapkit.view.snapshot import write_snapshot

        from pathlib import Path

        size = write_snapshot(m, args.html, plan=plan, result=result, camera=camera, title=Path(args.map).name)
        print(f"mapkit view: wrote {args.html} ({size / 1e6:.1f} MB); open it in a browser, no server needed")
        return 0

    from mapkit.view.server import Inspector

    try:
        inspector = Inspector(m, host=args.host, port=DEFAULT_PORT if args.port is None else args.port,
                              map_path=args.map, plan=plan, result=result, camera=camera)
    except OSError as exc:
        raise MapkitError(f"cannot listen on {args.host}:{args.port} ({exc.strerror or exc}); try --port 0") from None
    if args.port and inspector.port != args.port:  # taken between the check and the server's start
        inspector.stop()
        raise MapkitError(_busy(args.host, args.port))
    try:
        # Inside the try: a Ctrl-C right after the address is shown must stop
        # the server too (its threads would keep the process alive).
        print(f"mapkit view: {args.map} at {inspector.url}  (Ctrl-C to stop)", flush=True)
        # The server runs on its own threads; wait for Ctrl-C. In short
        # sleeps: the kernel may deliver SIGINT to one of the server's
        # threads, and a main thread blocked for good would never run
        # Python's handler.
        while True:
            time.sleep(0.2)
    except KeyboardInterrupt:
        pass
    finally:
        inspector.stop()
    print("mapkit view: stopped", file=sys.stderr)
    return 0
