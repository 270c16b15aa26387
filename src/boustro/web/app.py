"""The web application of ``boustro serve``: one page, its static files and the JSON API.

Starlette (the ``boustro[web]`` extra) is imported when the app is built, never on
``import boustro``. Routes:

``GET /``                  the page (``static/index.html``)
``GET /static/...``        its script, style and the vendored Leaflet
``GET /api/config``        formats, objectives, options, limits and the tile URL
``GET /api/embedded``      the embedded example field, GeoJSON (longitude/latitude)
``POST /api/plan``         ``{"area", "options"}`` -> the ``boustro plan --json`` object(s), plus
                           ``"geojson"``
``POST /api/estimate``     the same request -> the estimate before planning, no planning
``POST /api/export``       the same request plus ``"format"`` -> the mission file (a request
                           just answered by ``/api/plan`` is not planned again)
``POST /api/read?name=F``  an area file's bytes -> its fields, GeoJSON in longitude/latitude

Bad input is HTTP 400 (413 over a limit) with ``{"error": "<one line>"}``; nothing else ever
reaches the client (an unexpected failure is a 500 with one line and is logged). One plan runs
at a time (the machine's cores are the optimiser's); JSON requests must say
``Content-Type: application/json``, so another site's page cannot post to the server without a
CORS preflight, which it never answers; the ``Host`` header must name this machine.
"""

from __future__ import annotations

import logging
import threading
import time
from importlib import resources
from typing import Any
from urllib.parse import urlsplit

from .._version import __version__
from ..errors import BoustroError, InvalidParameterError, MissingDependencyError
from ..io import embedded_field
from ..io.formats import FORMATS
from .api import estimate_request, export_request, plan_request, plan_response, read_upload
from .limits import (
    MAX_BODY_BYTES,
    MAX_FIELDS,
    MAX_SECONDS,
    MAX_VERTICES,
    RequestTooLargeError,
    parse_strict_json,
)
from .options import OPTIONS, web_objectives
from .recent import RecentPlans

__all__ = ["ALLOWED_HOSTS", "create_app", "static_dir", "web_words"]

log = logging.getLogger("boustro.web")

#: The ``Host`` names the app answers (a DNS-rebinding page gets 400).
ALLOWED_HOSTS = ("127.0.0.1", "localhost", "[::1]", "::1")

#: One plan at a time: the optimiser uses every core, and a queue keeps the answers in order.
#: Plans and exports take it; estimates and file reads (which plan nothing) do not.
_PLAN_LOCK = threading.Lock()


def static_dir() -> str:
    """The folder of the page's files inside the installed package."""
    return str(resources.files("boustro") / "web" / "static")


def _starlette() -> Any:
    try:
        import starlette.applications
        import starlette.middleware
        import starlette.middleware.base
        import starlette.middleware.trustedhost
        import starlette.responses
        import starlette.routing
        import starlette.staticfiles
    except ImportError:
        raise MissingDependencyError(
            "boustro serve needs the web extra: pip install 'boustro[web]'"
        ) from None
    import starlette

    return starlette


#: The command line's flags that the library's messages name, and the API's options for them.
_FLAGS = {"--repair": "options.repair", "--altitude": "options.altitude", "--crs": "options.crs"}


def web_words(message: str) -> str:
    """A library message in the API's words: ``options.repair`` for ``--repair``, etc."""
    for flag, option in _FLAGS.items():
        message = message.replace(flag, option)
    return message


def _tile_origin(tiles: str | None) -> str:
    if not tiles:
        return ""
    parts = urlsplit(tiles.replace("{s}", "a"))
    if parts.scheme not in ("http", "https") or not parts.netloc:
        raise InvalidParameterError(f"--tiles must be an http(s) URL template, got {tiles!r}")
    host = parts.netloc.replace("a.", "*.", 1) if "{s}" in tiles else parts.netloc
    return f"{parts.scheme}://{host}"


def _config(tiles: str | None) -> dict[str, Any]:
    return {
        "version": __version__,
        "tiles": tiles or None,
        "formats": {name: list(exts) for name, (exts, _) in FORMATS.items()},
        "objectives": sorted(web_objectives()),
        "options": OPTIONS,
        "limits": {
            "body_bytes": MAX_BODY_BYTES,
            "vertices": MAX_VERTICES,
            "fields": MAX_FIELDS,
            "seconds": MAX_SECONDS,
        },
    }


def _embedded() -> dict[str, Any]:
    area = embedded_field()
    ring = [[float(x), float(y)] for x, y in area.ring]
    return {
        "type": "FeatureCollection",
        "features": [
            {
                "type": "Feature",
                "properties": {"name": area.name, "crs": area.crs},
                "geometry": {"type": "Polygon", "coordinates": [[*ring, ring[0]]]},
            }
        ],
    }


async def _body(request: Any, json_body: bool) -> bytes:
    """The request's body, at most :data:`MAX_BODY_BYTES` (refused as soon as it is over)."""
    ctype = request.headers.get("content-type", "").split(";")[0].strip().lower()
    if json_body and ctype != "application/json":
        raise InvalidParameterError("send the request as Content-Type: application/json")
    length = request.headers.get("content-length")
    if length is not None and length.isdigit() and int(length) > MAX_BODY_BYTES:
        raise RequestTooLargeError(
            f"request of {length} bytes, over the limit of {MAX_BODY_BYTES} bytes"
        )
    chunks, size = [], 0
    async for chunk in request.stream():
        size += len(chunk)
        if size > MAX_BODY_BYTES:
            raise RequestTooLargeError(f"request over the limit of {MAX_BODY_BYTES} bytes")
        chunks.append(chunk)
    return b"".join(chunks)


def _locked(fn: Any, *args: Any) -> Any:
    with _PLAN_LOCK:
        return fn(*args)


def _error(responses: Any, exc: Exception) -> Any:
    status = 413 if isinstance(exc, RequestTooLargeError) else 400
    return responses.JSONResponse({"error": web_words(str(exc))}, status_code=status)


def _endpoint(responses: Any, work: Any, json_body: bool = True, lock: bool = True) -> Any:
    """An API endpoint: the body within its limit, ``work(responses, request, body)`` in a
    worker thread (under the plan lock if ``lock``), errors as ``{"error": ...}``."""
    from starlette.concurrency import run_in_threadpool

    async def endpoint(request: Any) -> Any:
        try:
            body = await _body(request, json_body)
            if not lock:
                return await run_in_threadpool(work, responses, request, body)
            return await run_in_threadpool(_locked, work, responses, request, body)
        except BoustroError as exc:
            return _error(responses, exc)
        except Exception as exc:  # never a stack trace to the client
            log.exception("boustro web: %s failed", request.url.path)
            return responses.JSONResponse(
                {"error": f"internal error ({type(exc).__name__}); see the server's log"},
                status_code=500,
            )

    return endpoint


class _Laps:
    """Wall-clock laps of a request, for its ``Server-Timing`` header
    (``parse;dur=0.1, plan;dur=95.2, answer;dur=0.6, encode;dur=0.4``, milliseconds)."""

    def __init__(self) -> None:
        self.laps: list[str] = []
        self.last = time.perf_counter()

    def lap(self, name: str) -> None:
        now = time.perf_counter()
        self.laps.append(f"{name};dur={(now - self.last) * 1000:.1f}")
        self.last = now

    def header(self) -> str:
        return ", ".join(self.laps)


def _plan(responses: Any, request: Any, body: bytes) -> Any:
    laps = _Laps()  # the page shows the server's steps apart from its own
    data = parse_strict_json(body)
    laps.lap("parse")
    missions = plan_request(data)
    laps.lap("plan")
    answer = plan_response(missions)
    laps.lap("answer")
    request.app.state.recent.put(data, missions)  # for its downloads
    response = responses.JSONResponse(answer)
    laps.lap("encode")
    response.headers["Server-Timing"] = laps.header()
    return response


def _estimate(responses: Any, request: Any, body: bytes) -> Any:
    return responses.JSONResponse(estimate_request(parse_strict_json(body)))


def _export(responses: Any, request: Any, body: bytes) -> Any:
    data, name, media = export_request(parse_strict_json(body), request.app.state.recent)
    headers = {"Content-Disposition": f'attachment; filename="{name}"'}
    return responses.Response(data, media_type=media, headers=headers)


def _read(responses: Any, request: Any, body: bytes) -> Any:
    name = request.query_params.get("name", "upload")
    crs = request.query_params.get("crs") or None
    return responses.JSONResponse(read_upload(name, body, crs))


def _csp(origin: str) -> str:
    """The page's Content-Security-Policy: everything from this server, images also from the
    tile server's ``origin`` (if any)."""
    return (
        "default-src 'self'; script-src 'self'; style-src 'self' 'unsafe-inline'; "
        f"img-src 'self' data: blob: {origin}".rstrip()
        + "; connect-src 'self'; frame-ancestors 'none'"
    )


def create_app(tiles: str | None = None, allowed_hosts: tuple[str, ...] = ALLOWED_HOSTS) -> Any:
    """The Starlette app; ``tiles`` is an optional tile-server URL template for the map
    (``https://tiles.example/{z}/{x}/{y}.png``); without it the map is a plain background with a
    graticule and needs no network."""
    sl = _starlette()
    responses, routing = sl.responses, sl.routing
    csp = _csp(_tile_origin(tiles))
    config = _config(tiles)

    async def page(request: Any) -> Any:
        return responses.FileResponse(f"{static_dir()}/index.html", media_type="text/html")

    async def get_config(request: Any) -> Any:
        return responses.JSONResponse(config)

    async def embedded(request: Any) -> Any:
        return responses.JSONResponse(_embedded())

    async def headers(request: Any, call_next: Any) -> Any:
        response = await call_next(request)
        response.headers["Content-Security-Policy"] = csp
        response.headers["X-Content-Type-Options"] = "nosniff"
        return response

    post = ["POST"]
    routes = [
        routing.Route("/", page),
        routing.Route("/api/config", get_config),
        routing.Route("/api/embedded", embedded),
        routing.Route("/api/plan", _endpoint(responses, _plan), methods=post),
        routing.Route("/api/estimate", _endpoint(responses, _estimate, lock=False), methods=post),
        routing.Route("/api/export", _endpoint(responses, _export), methods=post),
        routing.Route(  # reading plans nothing: never queued behind a plan
            "/api/read", _endpoint(responses, _read, json_body=False, lock=False), methods=post
        ),
        routing.Mount("/static", app=sl.staticfiles.StaticFiles(directory=static_dir())),
    ]
    middleware = [
        sl.middleware.Middleware(
            sl.middleware.trustedhost.TrustedHostMiddleware, allowed_hosts=list(allowed_hosts)
        ),
        sl.middleware.Middleware(sl.middleware.base.BaseHTTPMiddleware, dispatch=headers),
    ]
    app = sl.applications.Starlette(routes=routes, middleware=middleware)
    app.state.recent = RecentPlans()  # the plans last answered, for their downloads
    return app
