"""Small bounded memos of planning steps keyed by the bytes of their inputs.

>>> cache: dict[bytes, int] = {}
>>> remember(cache, bytes_key([b"a", b"bc"]), 2, lambda: 1)
1
>>> remember(cache, bytes_key([b"a", b"bc"]), 2, lambda: 2)  # remembered
1
"""

from __future__ import annotations

from collections.abc import Callable, Iterable
from typing import TypeVar

T = TypeVar("T")


def bytes_key(parts: Iterable[bytes]) -> bytes:
    """``parts`` joined, each followed by its length (so that no two lists of parts collide)."""
    return b"|".join(p + len(p).to_bytes(8, "little") for p in parts)


def remember(cache: dict[bytes, T], key: bytes, limit: int, make: Callable[[], T]) -> T:
    """``cache[key]``, made by ``make()`` if missing; the oldest entry dropped past ``limit``."""
    hit = cache.get(key)
    if hit is None:
        hit = make()
        if len(cache) >= limit:
            cache.pop(next(iter(cache)))
        cache[key] = hit
    return hit
