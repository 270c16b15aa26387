"""The paper's experiments (an edge of the system): Table I, the optimisers, the figures.

By deliverable: :mod:`~boustro.experiments.samples` (samples and protocols),
:mod:`~boustro.experiments.layouts` (their transects, the exact fitness),
:mod:`~boustro.experiments.paper_batched` (the paper's model, batched),
:mod:`~boustro.experiments.table1`, :mod:`~boustro.experiments.optimizers`,
:mod:`~boustro.experiments.figures`, :mod:`~boustro.experiments.report`.
``boustro reproduce`` (:mod:`boustro.cli.reproduce`) runs them and writes the report.
"""

from __future__ import annotations

from .figures import (
    FIGURES,
    PARALLELOGRAM,
    PARALLELOGRAM_SPACING,
    fig_fitness_vs_angle,
    fig_indicator,
    fig_surface_angle_offset,
    fig_surface_angle_temperature,
    figure_data,
)
from .layouts import exact_fitness_batch, protocol_groups
from .optimizers import (
    PAPER_GRID_MINUS_GRADIENT,
    OptimizerSpec,
    compare_optimizers,
    optimizer_specs,
)
from .paper_batched import BAND_Z, paper_model_fitness
from .paper_batched import Method as Method  # the type aliases, defined here before
from .report import JSON_KEYS, PROTOCOL_NOTES, render_report
from .samples import (
    POINTS_PER_TRANSECT,
    PROTOCOLS,
    TEMPERATURES,
    Protocol,
    Samples,
    draw_samples,
    polygenerator_convex_polygon,
)
from .samples import Eq2 as Eq2
from .samples import Statistics as Statistics
from .samples import Trapezoid as Trapezoid
from .samples import Window as Window
from .table1 import PAPER_TABLE1, Table1, smooth_model_fitness, smooth_table1, table1

__all__ = [
    "BAND_Z",
    "FIGURES",
    "JSON_KEYS",
    "PAPER_GRID_MINUS_GRADIENT",
    "PAPER_TABLE1",
    "PARALLELOGRAM",
    "PARALLELOGRAM_SPACING",
    "POINTS_PER_TRANSECT",
    "PROTOCOLS",
    "PROTOCOL_NOTES",
    "TEMPERATURES",
    "OptimizerSpec",
    "Protocol",
    "Samples",
    "Table1",
    "compare_optimizers",
    "draw_samples",
    "exact_fitness_batch",
    "fig_fitness_vs_angle",
    "fig_indicator",
    "fig_surface_angle_offset",
    "fig_surface_angle_temperature",
    "figure_data",
    "optimizer_specs",
    "paper_model_fitness",
    "polygenerator_convex_polygon",
    "protocol_groups",
    "render_report",
    "smooth_model_fitness",
    "smooth_table1",
    "table1",
]
