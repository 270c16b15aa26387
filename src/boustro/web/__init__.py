"""A planner in the browser: ``boustro serve``'s web application and its JSON API.

:func:`~boustro.web.app.create_app` builds the app (Starlette, the ``boustro[web]`` extra,
imported when it is built); :mod:`boustro.web.api` does the work with the library's functions
and can be called without a web framework. See ``docs/web.md``.
"""

from __future__ import annotations

from .api import estimate_request, export_request, plan_request, plan_response, read_upload
from .app import create_app
from .limits import MAX_BODY_BYTES, MAX_FIELDS, MAX_SECONDS, MAX_VERTICES
from .server import serve

__all__ = [
    "MAX_BODY_BYTES",
    "MAX_FIELDS",
    "MAX_SECONDS",
    "MAX_VERTICES",
    "create_app",
    "estimate_request",
    "export_request",
    "plan_request",
    "plan_response",
    "read_upload",
    "serve",
]
