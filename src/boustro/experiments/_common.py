"""Helpers the experiments share: a progress bar, JSON numbers."""

from __future__ import annotations

import math
import sys
from typing import Any

__all__ = ["json_number", "progress_bar"]


def progress_bar(total: float, desc: str, progress: bool, unit: str = "it") -> Any:
    """A tqdm bar on stderr (a no-op one when ``progress`` is false)."""
    from tqdm.auto import tqdm

    return tqdm(
        total=total,
        desc=desc,
        file=sys.stderr,
        disable=not progress,
        unit=unit,
        unit_scale=True,
        leave=True,
        dynamic_ncols=True,
    )


def json_number(v: Any) -> Any:
    if isinstance(v, float) and not math.isfinite(v):
        return None
    return v
