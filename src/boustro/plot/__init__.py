"""Figures (matplotlib, imported only when a figure is drawn): layouts and plans."""

from __future__ import annotations

from .layout import plot_layout
from .plan import nice_length, plot_plan

__all__ = ["nice_length", "plot_layout", "plot_plan"]
