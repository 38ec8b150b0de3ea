"""Serve a viewer folder on 127.0.0.1 with Python's standard library HTTP server."""

from __future__ import annotations

import functools
import http.server
import sys

from ..errors import LfprocError

HOST = "127.0.0.1"  # never another interface: the viewer is for this machine's browser


class _QuietHandler(http.server.SimpleHTTPRequestHandler):
    """Static files from one folder, without a log line per request."""

    def log_message(self, format, *args):  # noqa: A002 (the base class's name)
        pass


def make_server(folder: str, port: int = 8000) -> http.server.ThreadingHTTPServer:
    """A server for ``folder`` on 127.0.0.1:``port`` (0 = any free port); not yet serving.

    Raises
    ------
    LfprocError
        When the port is taken or not allowed.
    """
    if not 0 <= port <= 65535:
        raise LfprocError(f"port={port} is not a TCP port; give 1 to 65535, or 0 for any free one")
    handler = functools.partial(_QuietHandler, directory=str(folder))
    try:
        return http.server.ThreadingHTTPServer((HOST, port), handler)
    except OSError as exc:
        raise LfprocError(f"cannot serve on {HOST}:{port} ({exc.strerror or exc}); choose another port= "
                          f"(0 picks a free one)") from None


def serve(folder: str, port: int = 8000) -> None:
    """Serve ``folder`` until interrupted, printing its URL first."""
    server = make_server(folder, port)
    url = f"http://{HOST}:{server.server_address[1]}/"
    print(f"serving {folder} at {url} (Ctrl-C to stop)", flush=True)
    try:
        server.serve_forever()
    except KeyboardInterrupt:
        print("stopped", file=sys.stderr)
    finally:
        server.server_close()
