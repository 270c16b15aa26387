"""The order of a plan's passes and each pass's driving option, solved: exactly (Held-Karp) for
few passes, by OR-Tools' routing with disjunctions beyond (when installed), else greedy + 2-opt.

A pass is a chain of lanes (a cell's lanes driven back and forth: its 4 options are the first
lane and the end it starts at), a pass around a hole or a boundary pass (:mod:`.tour`). The cost
of a tour is the length of its passes plus the routed moves between them
(:meth:`~boustro.plan.routing.Router.distances`); the number of turns is the same for every
order, so the least length is the least mission time. This is the generalised travelling
salesman problem of Bähnemann et al. (FSR 2019) over the cells' sweep options.
"""

from __future__ import annotations

import itertools
import math
from importlib.util import find_spec
from typing import Literal

import numpy as np
from numpy.typing import NDArray

from ..errors import InvalidParameterError, MissingDependencyError
from .routing import Router
from .tour import _orders, _Pass

__all__ = ["EXACT_PASSES", "ORDER_SOLVERS", "OrderSolver", "solve_order", "tour_cost"]

#: Passes up to which the order is solved exactly (Held-Karp: 2^n x options^2 work).
EXACT_PASSES = 12
#: OR-Tools' search is a greedy descent from the cheapest-arc tour to its local optimum: the same
#: tour on any load. This many seconds is only a safety cap (a note says when it was hit).
ORTOOLS_SECONDS = 60.0
OrderSolver = Literal["exact", "or-tools", "heuristic"]
ORDER_SOLVERS: tuple[OrderSolver, ...] = ("exact", "or-tools", "heuristic")


class _Problem:
    """The flattened problem: every option of every pass a node with an entry and an exit."""

    def __init__(
        self, passes: list[_Pass], start: NDArray[np.float64], router: Router, force_start: bool
    ) -> None:
        pts = [start]
        self.pass_of: list[int] = []
        internal = []
        entry, exit_ = [], []
        for k, p in enumerate(passes):
            for a, b, _, length in p.options:
                self.pass_of.append(k)
                entry.append(len(pts))
                pts.append(a)
                exit_.append(len(pts))
                pts.append(b)
                internal.append(length)
        dist = router.distances(np.asarray(pts))
        self.n = len(passes)
        self.internal = np.asarray(internal, dtype=np.float64)
        # move[a, b]: from option a's exit to option b's entry, plus b's own length
        self.move = dist[np.ix_(exit_, entry)] + self.internal[None, :]
        self.first = self.internal.copy()  # begin anywhere: the tour starts where it is best
        if force_start:  # begin at the start: the approach to the first entry counts
            self.first = dist[0, entry] + self.internal
        self.options = [
            np.flatnonzero(np.asarray(self.pass_of) == k).astype(np.int64) for k in range(self.n)
        ]

    def cost(self, nodes: list[int]) -> float:
        """The cost of driving the options ``nodes`` in this order."""
        total = float(self.first[nodes[0]])
        for a, b in itertools.pairwise(nodes):
            total += float(self.move[a, b])
        return total

    def split(self, nodes: list[int]) -> tuple[list[int], list[int]]:
        """``(pass order, option of each pass within its pass)``."""
        order = [self.pass_of[m] for m in nodes]
        return order, [
            int(np.searchsorted(self.options[k], m)) for k, m in zip(order, nodes, strict=True)
        ]

    def nodes(self, order: list[int], choice: list[int]) -> list[int]:
        return [int(self.options[k][c]) for k, c in zip(order, choice, strict=True)]


def _held_karp(pb: _Problem) -> list[int]:
    """The least-cost sequence of options, one per pass (dynamic programme over subsets)."""
    dp, parent, bit = _tables(pb)
    every = np.arange(len(pb.pass_of))
    for s in range(1, len(dp) - 1):
        row = dp[s]
        live = np.flatnonzero(np.isfinite(row))
        if len(live) == 0:
            continue
        step = row[live, None] + pb.move[live]  # (live, m)
        arg = np.argmin(step, axis=0)
        best = step[arg, every]
        # every option of a pass not in s at once: option o extends s to s | bit[o], and no
        # two options share a cell (t, o), so this is the pass-by-pass update in one step
        opts = every[(s & bit) == 0]
        t = s | bit[opts]
        better = best[opts] < dp[t, opts]
        if better.any():
            sel, t = opts[better], t[better]
            dp[t, sel] = best[sel]
            parent[t, sel] = live[arg[sel]]
    return _backtrack(dp, parent, bit)


def _tables(pb: _Problem) -> tuple[NDArray[np.float64], NDArray[np.int64], NDArray[np.int64]]:
    """Held-Karp's tables over (subset of passes, last option): the least costs (each option
    alone: its first cost), the parents (none), and each option's pass as a bit."""
    m = len(pb.pass_of)
    dp = np.full((1 << pb.n, m), math.inf)
    parent = np.full((1 << pb.n, m), -1, dtype=np.int64)
    bit = np.array([1 << k for k in pb.pass_of], dtype=np.int64)
    dp[bit, np.arange(m)] = pb.first
    return dp, parent, bit


def _backtrack(
    dp: NDArray[np.float64], parent: NDArray[np.int64], bit: NDArray[np.int64]
) -> list[int]:
    """The sequence of options of Held-Karp's tables: from the least cost over every pass back
    through the parents."""
    s = len(dp) - 1
    nodes = [int(np.argmin(dp[s]))]
    while parent[s, nodes[-1]] >= 0:
        prev = int(parent[s, nodes[-1]])
        s ^= int(bit[nodes[-1]])
        nodes.append(prev)
    return nodes[::-1]


def _ortools(pb: _Problem) -> tuple[list[int] | None, bool]:
    """The sequence of options by OR-Tools' routing (one option of each pass: a disjunction),
    or ``None`` when OR-Tools is not installed or finds none; and whether the search stopped at
    :data:`ORTOOLS_SECONDS` before its local optimum."""
    try:
        from ortools.constraint_solver import pywrapcp, routing_enums_pb2
    except ImportError:
        return None, False
    m = len(pb.pass_of)
    finite = np.concatenate([pb.move[np.isfinite(pb.move)], pb.first[np.isfinite(pb.first)]])
    unit = 1e6 / max(float(finite.max(initial=0.0)), 1e-300)
    big = 10**12
    arc = np.zeros((m + 1, m + 1), dtype=np.int64)  # node 0: the depot (start and end)
    arc[0, 1:] = np.where(np.isfinite(pb.first), np.round(pb.first * unit), big)
    arc[1:, 1:] = np.where(np.isfinite(pb.move), np.round(pb.move * unit), big)
    manager = pywrapcp.RoutingIndexManager(m + 1, 1, 0)
    routing = pywrapcp.RoutingModel(manager)
    # the arc costs as a matrix by node, looked up in C++ (a Python callback was asked 2.2
    # million times on a 2000-vertex field: 1.9 s of its 2.0 s); the same costs, the same tour
    routing.SetArcCostEvaluatorOfAllVehicles(routing.RegisterTransitMatrix(arc.tolist()))
    for opts in pb.options:  # exactly one option of every pass is driven
        routing.AddDisjunction([manager.NodeToIndex(int(o) + 1) for o in opts], -1, 1)
    params = pywrapcp.DefaultRoutingSearchParameters()
    params.first_solution_strategy = routing_enums_pb2.FirstSolutionStrategy.PATH_CHEAPEST_ARC
    params.local_search_metaheuristic = routing_enums_pb2.LocalSearchMetaheuristic.GREEDY_DESCENT
    params.time_limit.FromMilliseconds(int(ORTOOLS_SECONDS * 1000))
    solution = routing.SolveWithParameters(params)
    status = routing_enums_pb2.RoutingSearchStatus
    capped = routing.status() in (
        status.ROUTING_PARTIAL_SUCCESS_LOCAL_OPTIMUM_NOT_REACHED,
        status.ROUTING_FAIL_TIMEOUT,
    )
    if solution is None:
        return None, capped
    nodes, index = [], routing.Start(0)
    index = solution.Value(routing.NextVar(index))
    while not routing.IsEnd(index):
        nodes.append(manager.IndexToNode(index) - 1)
        index = solution.Value(routing.NextVar(index))
    return (nodes if len(nodes) == pb.n else None), capped


def solve_order(
    passes: list[_Pass],
    start: NDArray[np.float64],
    router: Router,
    *,
    force_start: bool = False,
    solver: str = "auto",
) -> tuple[list[int], list[int], OrderSolver, list[str]]:
    """Order and driving option of every pass for the shortest tour.

    ``solver``: ``"auto"`` (default) solves exactly up to :data:`EXACT_PASSES` passes, by
    OR-Tools beyond (``pip install 'boustro[order]'``; the better of its tour and the greedy +
    2-opt one is kept), else greedy + 2-opt (:func:`boustro.plan.tour._orders`) with a note;
    ``"exact"``, ``"or-tools"`` or ``"heuristic"`` asks for one (``"exact"`` refuses more than
    :data:`EXACT_PASSES` passes, ``"or-tools"`` needs the extra). With ``force_start`` the tour
    begins at ``start`` (the routed approach to the first entry counted; the greedy order begins
    at the entry nearest it); without, wherever it is shortest. OR-Tools' search is a greedy
    descent to its local optimum (deterministic), capped at :data:`ORTOOLS_SECONDS` for safety
    (a note says when the cap was hit).

    Returns:
        ``(order, choice, solver used, notes)``.
    """
    if solver not in ("auto", *ORDER_SOLVERS):
        raise InvalidParameterError(
            f"order solver must be 'auto', 'exact', 'or-tools' or 'heuristic', got {solver!r}"
        )
    pb = _Problem(passes, start, router, force_start)
    if solver == "exact" and pb.n > EXACT_PASSES:
        raise InvalidParameterError(
            f"the exact order takes at most {EXACT_PASSES} passes, got {pb.n}"
        )
    if solver == "exact" or (solver == "auto" and pb.n <= EXACT_PASSES):
        order, choice = pb.split(_held_karp(pb))
        return order, choice, "exact", []
    notes: list[str] = []
    if solver in ("auto", "or-tools"):
        if solver == "or-tools" and find_spec("ortools") is None:
            raise MissingDependencyError(
                "the or-tools order needs OR-Tools: pip install 'boustro[order]'"
            )
        found, capped = _ortools(pb)
        if capped:
            notes.append(
                f"OR-Tools stopped at its {ORTOOLS_SECONDS:g} s safety cap before its local "
                "optimum: this order may differ on another machine or load"
            )
        if found is not None:
            order, choice = _orders(passes, start, router, force_start=force_start)[0]
            greedy = pb.nodes(order, choice)
            best = found if pb.cost(found) <= pb.cost(greedy) else greedy
            used: OrderSolver = "or-tools" if best is found else "heuristic"
            return *pb.split(best), used, notes
        why = "OR-Tools found no tour" if find_spec("ortools") else "OR-Tools is not installed"
        notes.append(
            f"{pb.n} passes ordered by greedy + 2-opt (more than {EXACT_PASSES} for the exact "
            f"order, and {why}: pip install 'boustro[order]')"
        )
    order, choice = _orders(passes, start, router, force_start=force_start)[0]
    return order, choice, "heuristic", notes


def tour_cost(
    passes: list[_Pass],
    start: NDArray[np.float64],
    router: Router,
    order: list[int],
    choice: list[int],
    *,
    force_start: bool = False,
) -> float:
    """The cost :func:`solve_order` minimises, of a given order and choice (for tests)."""
    pb = _Problem(passes, start, router, force_start)
    return pb.cost(pb.nodes(order, choice))
