"""Serve a viewer folder on 127.0.0.1 with Python's standard library HTTP server."""

from __future__ import annotations

import functools
import http.server
import threading

from ..errors import LfprocError

HOST = "127.0.0.1"  # never another interface: the viewer is for this machine's browser


class _QuietHandler(http.server.SimpleHTTPRequestHandler):
    """Static files from one folder, without a log line per request."""

    def log_message(self, format, *args):  # noqa: A002 (the base class's name)
        pass


class ViewerServer(http.server.ThreadingHTTPServer):
    """A server of one viewer folder on 127.0.0.1 (:func:`make_server`, :func:`serve`)."""

    @property
    def url(self) -> str:
        """The address to open in a browser, ``http://127.0.0.1:PORT/``."""
        return f"http://{HOST}:{self.server_address[1]}/"


def make_server(folder: str, port: int = 8000) -> ViewerServer:
    """A server for ``folder`` on 127.0.0.1:``port`` (0 = any free port); not yet serving.

    Raises
    ------
    LfprocError
        When the port is taken or not allowed.
    """
    if not 0 <= port <= 65535:
        raise LfprocError(f"`port={port}` is not a TCP port; give 1 to 65535, or 0 for any free one")
    handler = functools.partial(_QuietHandler, directory=str(folder))
    try:
        return ViewerServer((HOST, port), handler)
    except OSError as exc:
        raise LfprocError(f"cannot serve on {HOST}:{port} ({exc.strerror or exc}); choose another `port=` "
                          f"(0 picks a free one)") from None


def serve(folder: str, port: int = 8000) -> ViewerServer:
    """Serve ``folder`` on 127.0.0.1:``port`` from a background thread; prints nothing.

    Returns
    -------
    ViewerServer
        Serving already: ``server.url`` is the address to open, ``server.shutdown()`` stops it (and
        ``server.server_close()`` frees the port).

    Raises
    ------
    LfprocError
        When the port is taken or not allowed.
    """
    server = make_server(folder, port)
    threading.Thread(target=server.serve_forever, name="lfproc-viewer-server", daemon=True).start()
    return server
