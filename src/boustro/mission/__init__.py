"""The mission facade: a survey area planned end to end (project, plan, map back).

>>> from boustro.io import embedded_field
>>> plan_area(embedded_field(), 10.0).stats.n_transects
19
"""

from __future__ import annotations

from .defaults import (
    DEFAULT_HULL_TOLERANCE,
    DEFAULT_METHOD,
    FALLBACK_METHOD,
    METHOD_OPTIONS,
    REGION_OPTIONS,
    log,
)
from .estimate import WorkEstimate
from .map_back import _bearing
from .map_back import map_back as _map_back
from .pipeline import estimate_work, plan_area
from .project import Frame as _Frame
from .project import Sensor as _Sensor
from .project import _project_holes, _warn_far_start
from .project import as_area as _as_area
from .project import project as _project
from .project import sensor_spacing as _sensor_spacing
from .steps import Planned as _Planned
from .steps import _path_options
from .steps import main_cell as _main_cell
from .steps import plan_concave as _plan_concave
from .steps import plan_convex as _plan_convex
from .steps import region_optimum as _region_optimum
from .types import Mission

__all__ = [
    "DEFAULT_HULL_TOLERANCE",
    "DEFAULT_METHOD",
    "FALLBACK_METHOD",
    "METHOD_OPTIONS",
    "REGION_OPTIONS",
    "Mission",
    "WorkEstimate",
    "estimate_work",
    "plan_area",
]

# The steps of plan_area, importable by their names of the former single module.
_STEPS = (
    _Frame,
    _Planned,
    _Sensor,
    _as_area,
    _bearing,
    _path_options,
    _project_holes,
    _warn_far_start,
    _main_cell,
    _map_back,
    _plan_concave,
    _plan_convex,
    _project,
    _region_optimum,
    _sensor_spacing,
    log,
)
