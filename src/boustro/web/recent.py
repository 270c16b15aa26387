"""The plans the server answered last, kept for their downloads.

The page downloads the plan it shows: ``POST /api/export`` with the request the page has just
planned (the same ``area`` and ``options``, plus ``"format"``). :class:`RecentPlans` keeps the
missions of the last few ``POST /api/plan`` answers under their request, so that such an
export renders the plan already made instead of planning it again (seconds on a large field);
any other request is planned as before. The planner is deterministic, so the file is the same
either way: what changes is only when the work is done.
"""

from __future__ import annotations

import json
import threading
from collections import OrderedDict
from collections.abc import Sequence
from typing import Any

from ..mission import Mission

__all__ = ["RECENT_PLANS", "RecentPlans", "request_key"]

#: How many answered plans are kept (the page needs the last one; a few more cover a second tab).
RECENT_PLANS = 4


def request_key(body: Any) -> str | None:
    """The canonical text of a request's ``area`` and ``options`` (the members that decide the
    plan), or ``None`` for a body that is not a JSON object of them."""
    if not isinstance(body, dict) or "area" not in body:
        return None
    try:
        return json.dumps(
            {"area": body["area"], "options": body.get("options")},
            sort_keys=True,
            separators=(",", ":"),
            allow_nan=False,
        )
    except (TypeError, ValueError):
        return None


class RecentPlans:
    """The missions of the last ``size`` planned requests, by :func:`request_key` (thread-safe).

    Example:
        >>> recent = RecentPlans(size=1)
        >>> recent.put({"area": {"type": "Polygon"}}, [])
        >>> recent.get({"area": {"type": "Polygon"}, "format": "kml"}), recent.get({"area": 1})
        ([], None)
    """

    def __init__(self, size: int = RECENT_PLANS) -> None:
        self.size = size
        self._plans: OrderedDict[str, list[Mission]] = OrderedDict()
        self._lock = threading.Lock()

    def put(self, body: Any, missions: Sequence[Mission]) -> None:
        """Keep ``missions``, the plan of the request ``body``."""
        key = request_key(body)
        if key is None:
            return
        with self._lock:
            self._plans[key] = list(missions)
            self._plans.move_to_end(key)
            while len(self._plans) > self.size:
                self._plans.popitem(last=False)

    def get(self, body: Any) -> list[Mission] | None:
        """The missions kept for a request with ``body``'s area and options, else ``None``."""
        key = request_key(body)
        with self._lock:
            found = None if key is None else self._plans.get(key)
            return None if found is None else list(found)

    def __len__(self) -> int:
        return len(self._plans)
