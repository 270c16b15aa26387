"""Plan data types: :class:`Plan`, :class:`PlanStats`, :class:`PlanCell`, :data:`KINDS`."""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Literal

import numpy as np
from numpy.typing import NDArray

from ..geometry import Polygon

if TYPE_CHECKING:
    from ..geometry.region import Region


__all__ = [
    "KINDS",
    "Layout",
    "Plan",
    "PlanCell",
    "PlanStats",
]


#: What each waypoint is: run-in point before a transect, its start, its end, the run-out point;
#: for areas with holes or cells also ``via`` (a corner of a connecting move that goes around an
#: obstacle) and ``loop`` (a corner of a pass around a hole); with a vehicle model ``turn`` (a
#: point of a turn's curve, :func:`boustro.plan.drive_vehicle`); with headlands ``headland`` (a
#: point of a pass around the field inside its headland, :func:`boustro.plan.plan_headland`); with
#: ``keep_inside`` ``contour`` (every point of a boundary pass: the contour half a spacing inside
#: the edge, or a patch over a corner or a thin part).
KINDS = ("run_in", "start", "end", "run_out", "via", "loop", "turn", "headland", "contour")
Layout = Literal["guaranteed", "chords"]


# -- plans ------------------------------------------------------------------------------------
@dataclass(frozen=True)
class PlanStats:
    """Statistics of a plan, in ground units (plan units divided by ``ground_scale``).

    Attributes:
        n_transects: transects driven.
        n_turns: turns between transects (``n_transects - 1``).
        transect_length: total length of the transects (survey segments, without run-ins).
        path_length: total length of the path through all waypoints (transects, run-ins and
            run-outs, connecting moves).
        area: area of the polygon planned (units squared).
        speed: speed used for the duration, or ``None``.
        turn_time: time added per turn (seconds).
        duration: ``path_length / speed + n_turns * turn_time`` (seconds), ``None`` without speed.
        n_cells: cells of a decomposed plan (1 otherwise).
        hole_pass_length: length of the passes around holes (included in ``path_length``).
        outside_length: length of the path (lanes, run-ins and run-outs, connecting moves)
            outside the area or inside a hole, measured with shapely segment by segment
            (:func:`boustro.plan.outside.outside_length`; included in ``path_length``); 0 with
            ``keep_inside``.
        boundary_pass_length: length of the boundary passes of a ``keep_inside`` plan
            (included in ``path_length``).
        turn_length: with a vehicle model, the length of the turns' curves (exact, included in
            ``path_length``); 0 otherwise.
        headland_length: the length of the headland passes (included in ``path_length``).

    For a plan over an area with holes or a decomposed plan, ``n_transects`` counts the lane
    segments driven and ``n_turns`` the connecting moves between consecutive passes (a lane
    segment, or a pass around a hole): ``passes - 1``.
    """

    n_transects: int
    n_turns: int
    transect_length: float
    path_length: float
    area: float
    speed: float | None = None
    turn_time: float = 0.0
    duration: float | None = None
    n_cells: int = 1
    hole_pass_length: float = 0.0
    outside_length: float = 0.0
    turn_length: float = 0.0
    headland_length: float = 0.0
    boundary_pass_length: float = 0.0


@dataclass(frozen=True)
class PlanCell:
    """One cell of a decomposed plan (or the whole area of a single-angle plan).

    Attributes:
        region: the cell (plan units), a :class:`~boustro.regions.Region` (it has holes where
            it surrounds one of the area's).
        angle, offset: its lanes (radians; plan units from the cell's shell's vertex mean).
        fitness: the optimiser's value for the cell (Eq. 1 over segments by default), or NaN.
        n_transects: lane segments planned in the cell.
        optimum: the optimiser's result for the cell, if it was optimised.
    """

    region: Region
    angle: float
    offset: float
    fitness: float
    n_transects: int
    optimum: Any = None

    @property
    def polygon(self) -> Polygon:
        """The cell's outer boundary."""
        return self.region.shell


@dataclass(frozen=True)
class Plan:
    """An ordered boustrophedon path over a convex polygon, in the plan frame.

    Attributes:
        polygon: the convex polygon planned (plan units).
        spacing, angle, offset: the transect grid (plan units, radians; see the module
            docstring).
        layout: ``"guaranteed"`` (segments cover the projection of polygon ∩ band) or
            ``"chords"`` (segments are the chords of the lines).
        reach: half-width of the band each transect covers (``spacing / 2`` by default).
        nadir_gap: width of a blind strip centred under the vehicle (0 for most sensors).
        turnaround: run-in / run-out distance beyond each transect end (plan units).
        positions: ``(T,)`` position of each transect, in driving order.
        transects: ``(T, 2, 2)`` survey segments ``[start, end]`` in driving order and direction.
        waypoints: ``(W, 2)`` the path, in order.
        kinds: ``(W,)`` what each waypoint is, one of :data:`KINDS`.
        lane: ``(W,)`` index (into ``transects``) of the transect each waypoint belongs to.
        ground_scale: plan units per ground unit (1 for a planar frame; a projection's scale
            factor for a map projection); statistics are divided by it.
        stats: :class:`PlanStats`.
        region: for an area with a concave boundary or holes
            (:func:`boustro.plan.plan_region`), the area planned; ``polygon`` is its shell.
        cells: the cells of a decomposed plan (:class:`PlanCell`), or the whole area as one cell.
        transect_angles: ``(T,)`` lane direction of each transect where they differ (cells,
            passes around holes), else ``None`` (all at ``angle``).
        roles: ``"lane"``, ``"hole"`` or ``"boundary"`` (an edge of a boundary pass of a
            ``keep_inside`` plan) per transect (empty: all lanes).
        transect_cells: ``(T,)`` the cell of each transect (-1 for passes around holes).
        notes: what the plan could not do as asked (e.g. moves that leave the area).
        vehicle: the :class:`~boustro.vehicle.Vehicle` whose turns the path drives (plan
            units), or ``None`` (straight connecting moves).
        headland: headland passes around the field (0: none).
        keep_inside: planned so that no part of the path leaves the area or enters a hole
            (:mod:`boustro.plan.inside`).
        order_solver: how the order of the passes was solved (``"exact"``, ``"or-tools"``,
            ``"heuristic"``: :func:`boustro.plan.cell_order.solve_order`), or ``None``: the
            default greedy + 2-opt of :func:`boustro.plan.plan_region` and the convex planner.
        routed_moves: with a vehicle, the connecting moves kept straight or routed instead of
            the vehicle's turn, because the turn would leave the field or enter a hole
            (:func:`boustro.plan.drive_vehicle`).
    """

    polygon: Polygon
    spacing: float
    angle: float
    offset: float
    layout: str
    reach: float
    nadir_gap: float
    turnaround: float
    positions: NDArray[np.float64]
    transects: NDArray[np.float64]
    waypoints: NDArray[np.float64]
    kinds: tuple[str, ...]
    lane: NDArray[np.int64]
    ground_scale: float
    stats: PlanStats
    region: Region | None = None
    cells: tuple[PlanCell, ...] = ()
    transect_angles: NDArray[np.float64] | None = None
    roles: tuple[str, ...] = ()
    transect_cells: NDArray[np.int64] | None = None
    notes: tuple[str, ...] = ()
    vehicle: Any = None
    headland: int = 0
    keep_inside: bool = False
    order_solver: str | None = None
    routed_moves: int = 0

    @property
    def n_transects(self) -> int:
        return len(self.transects)

    def transect_angle(self) -> NDArray[np.float64]:
        """``(T,)`` the lane direction of every transect (the plan's angle unless it has many)."""
        if self.transect_angles is None:
            return np.full(len(self.transects), self.angle)
        return self.transect_angles

    def transect_lengths(self) -> NDArray[np.float64]:
        """``(T,)`` the ground length of every transect (its plan length / ``ground_scale``)."""
        d = self.transects[:, 1] - self.transects[:, 0]
        return np.hypot(d[:, 0], d[:, 1]) / self.ground_scale

    def role(self) -> tuple[str, ...]:
        """What each transect is: ``"lane"`` (a survey lane), ``"hole"`` (an edge of a pass
        around a hole) or ``"boundary"`` (an edge of a boundary pass)."""
        return self.roles or ("lane",) * len(self.transects)

    @property
    def start(self) -> NDArray[np.float64]:
        """The first waypoint."""
        return self.waypoints[0]
