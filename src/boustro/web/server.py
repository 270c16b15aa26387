"""Running the web app: uvicorn (the ``boustro[web]`` extra, imported when it runs) on
127.0.0.1 by default, and optionally a browser opened on the page.

Plans run on one torch thread by default (:data:`PLAN_THREADS`), as in a batch worker: one plan
runs at a time and its tensors are small, and a second intra-op thread only adds its wake-ups
(measured in ``docs/web.md``: the embedded field 1.2x and the 1000-vertex boundary 1.4x faster
in wall time on one thread on this project's 2-core machine).
"""

from __future__ import annotations

import sys
import threading
import webbrowser

from .._torch import threads as torch_threads
from ..errors import InvalidParameterError, MissingDependencyError
from .app import create_app

__all__ = ["LOCAL_HOSTS", "PLAN_THREADS", "serve"]

#: Hosts that bind to this machine only.
LOCAL_HOSTS = ("127.0.0.1", "localhost", "::1")

#: torch's intra-op threads while the server runs (``boustro serve --threads``).
PLAN_THREADS = 1


def serve(
    host: str = "127.0.0.1",
    port: int = 8000,
    open_browser: bool = False,
    tiles: str | None = None,
    quiet: bool = False,
    threads: int = PLAN_THREADS,
) -> None:
    """Serve the page and the API until interrupted (Ctrl-C); plans use ``threads`` torch
    threads (restored when the server stops)."""
    try:
        import uvicorn
    except ImportError:
        raise MissingDependencyError(
            "boustro serve needs the web extra: pip install 'boustro[web]'"
        ) from None
    if not 1 <= port <= 65535:
        raise InvalidParameterError(f"--port must be in 1..65535, got {port}")
    if not 1 <= threads <= 256:
        raise InvalidParameterError(f"--threads must be in 1..256, got {threads}")
    hosts: tuple[str, ...] = ("127.0.0.1", "localhost", "[::1]", "::1")
    if host not in LOCAL_HOSTS:
        print(
            f"boustro: warning: serving on {host}: other machines can reach the planner",
            file=sys.stderr,
        )
        hosts = ("*",)  # reached by other names than this machine's: no Host check
    app = create_app(tiles=tiles, allowed_hosts=hosts)
    shown = f"[{host}]" if ":" in host else host
    url = f"http://{shown}:{port}/"
    if not quiet:
        print(f"boustro: serving the planner on {url} (Ctrl-C stops it)", file=sys.stderr)
    if open_browser:
        threading.Timer(1.0, webbrowser.open, args=(url,)).start()
    with torch_threads(threads):  # torch is imported by the plans that need it only
        uvicorn.run(app, host=host, port=port, log_level="warning" if quiet else "info")
