"""The decomposed plan of a plan-level objective (mission time, fewest transects): candidate
decompositions, every cell searched by the same certified search as the one-grid plan (each
carries its certificate: ``certified``, ``gap``), cells merged only where one sweep serves both
at no more cost, the order of the passes solved.

Candidates: at each sweep direction :func:`boustro.plan.choose_sweep` compares (or the one
given), the finest decomposition (every trapezoid of the slab decomposition a cell), Choset's
cells and the merged cells of :func:`boustro.plan.decompose`, each of at most
:data:`MAX_CELLS` cells; each with and without the merges of neighbouring cells (angles within
15 degrees) whose union's modelled cost is no more than the two cells' and the turn between
them. The model (:meth:`_Search.model`: the cell's lines' segments as lanes, no plan) ranks the
candidates; the best :data:`PLANNED` whose model beats the one grid (``beat``) have every cell
optimised by :func:`boustro.optimize.cover.cover_optimum` on the cell as an area (its
certificate is the cell's) and are planned with the order of the passes solved
(:func:`boustro.plan.cell_order.solve_order`): the least flown cost is kept. A candidate's
cells are searched without their spikes thinner than the search's smallest box
(:mod:`.slivers`) and planned whole (so that the plan covers the spikes too).

With ``keep_inside`` each candidate's cells are searched without keep-inside first (cheap
plans, tight bounds) and only then with it (plans with boundary passes, 10-30 times dearer,
loose bounds); both searches stop as soon as the floor of :func:`_cell_optima` (the searched
cells' lower bounds, a turn between cells, the length covering the cells not searched yet)
reaches the one grid's cost, and a candidate the first search drops is not searched keeping
inside. On Fields2Cover's fields (the one grid wins) that skips every keep-inside cell search.
The floor needs the cells' lower bounds only, final once their searches' branch and bound ends:
the plans a search makes after it (:func:`~boustro.optimize.cover.search.cover_optimum`'s
``later``: polish, more offsets, the lanes from the cell's edges) are made only for the cells
of a candidate that passes the floor (:meth:`_Search.finished`): the same optima where a
candidate is planned, none of those plans where it is screened out (issue 21's 2000-vertex
field: 0.7 s; docs/scale.md, eighteenth round). A decomposition of more than
:data:`MAX_CELLS` cells is counted before its cells are traced.
"""

from __future__ import annotations

import dataclasses
import math
import time
from collections.abc import Callable
from typing import Any, NamedTuple

import numpy as np

from ..errors import InvalidParameterError, InvalidPolygonError, NoTransectError
from ..geometry.region import Region
from ..models.region import segment_moments
from ..optimize import OptimizeResult
from ..optimize.cover import CoverCost, centred_offsets, cover_optimum
from ..optimize.cover.plans import rules_out
from ..optimize.result import canonical
from ..plan import Plan, coverage
from ..plan.cells import Decomposition, decompose, slab_decomposition, trapezoids
from ..plan.region import plan_region
from ..plan.region_floor import screen_floor
from ..plan.types import Layout
from .cover import flown_cost
from .project import Frame
from .slivers import cut_slivers
from .steps import Planned, _path_options

__all__ = [
    "CUTOFF_MARGIN",
    "LARGE_EDGES",
    "MAX_CELLS",
    "MAX_SEARCHES",
    "MAX_UNION_EDGES",
    "PLANNED",
    "SLIVER_WIDTH",
    "plan_decomposed",
]

#: Decompositions with more cells are not candidates (the exact order takes 12 passes).
MAX_CELLS = 12
#: Certified cell searches per plan at most (a count, not a time: the same plan on any load).
MAX_SEARCHES = 16
#: Candidate decompositions whose cells are certified and planned in full (their passes
#: ordered), best modelled cost first.
PLANNED = 2
#: Edges of the unions of cells traced to try merges, per plan at most (a count, not a time:
#: the same plan on any load); past it the candidates keep the merges found so far.
MAX_UNION_EDGES = 8000
#: Outer and hole edges of an area beyond which only the best candidate is planned (its cells'
#: searches are the work: a large area's cells have many edges).
LARGE_EDGES = 120
#: Lane directions of the model of a cell's cost (every 5 degrees) and offsets per spacing.
MODEL_ANGLES = 36
MODEL_OFFSETS = 4
#: Edge directions of a cell (longest first) where the lanes laid from its edge are planned.
CENTRED_ANGLES = 8
#: A cell's search stops once its lower bound brings the candidate's floor this share of the
#: one grid's cost above it (:func:`_cell_optima`; rounding: the floor is then above ``beat``).
CUTOFF_MARGIN = 1e-9
#: Neighbouring cells whose angles differ by less than this are tried as one cell.
MERGE_ANGLE = math.radians(15.0)
#: Spikes of a candidate's cells narrower than this share of the spacing are cut before the
#: cells are searched (:mod:`.slivers`; planned whole, their certificate dropped): the cover
#: search's smallest box radius (``RESOLVE_EPS``), below which its bound cannot see them.
SLIVER_WIDTH = 1e-3


class _Candidate(NamedTuple):
    name: str
    cells: list[Region]  # planned: they cover the area
    models: list[tuple[float, float, float]]  # each cell's modelled (cost, angle, offset)
    estimate: float  # the cells' modelled costs and one turn between consecutive cells


class _Search:
    """The certified search of each cell, done once per cell (cached by its vertices)."""

    def __init__(
        self,
        frame: Frame,
        cost: CoverCost,
        layout: str,
        options: dict[str, Any],
        keep_inside: bool = False,
        finish: Callable[[Plan], Plan] | None = None,
    ):
        self.cost, self.layout, self.options = cost, layout, options
        self.keep_inside, self.finish = keep_inside, finish
        self.s = frame.sensor.spacing * frame.proj.scale_min
        self.reach = frame.sensor.reach * frame.proj.scale_min
        self.cache: dict[bytes, OptimizeResult | None] = {}
        # the plans a cell's search left for later (cover_optimum's ``later``) and the cutoff
        # it was given, by cell
        self.later: dict[bytes, tuple[Callable[[], OptimizeResult], float | None]] = {}
        self.models: dict[bytes, tuple[float, float, float]] = {}
        self.searches = 0
        self.union_edges = 0

    def plan(self, cell: Region, angle: float, offset: float) -> Plan:
        lay: Layout = "chords" if self.layout == "chords" else "guaranteed"
        return plan_region(
            cell, self.s, decompose_area=False, angle=angle, offset=offset, layout=lay,
            keep_inside=self.keep_inside, **self.options,
        )  # fmt: skip

    def value(self, cell: Region, angle: float, offset: float) -> float:
        """The cost of the cell's plan as it is flown alone: with ``keep_inside`` as the final
        plan lays it, the vehicle's turns added (``finish``, where given: a cell's own)."""
        plan = self.plan(cell, angle, offset)
        st = (plan if self.finish is None else self.finish(plan)).stats
        return self.cost.of(st.path_length * self.options["ground_scale"], st.n_turns)

    def floor(self, cell: Region, angle: float, offset: float, best: float = math.inf) -> float:
        """A floor of :meth:`value` (without ``finish``), cheaper than the plan: the cell's
        ``keep_inside`` lanes and passes and a floor of its moves, or its lanes alone where
        that already rules it out against ``best`` (without ``keep_inside``: its lanes and a
        floor of its moves)
        (:func:`~boustro.plan.region_floor.screen_floor`), for the search's screen."""
        lay: Layout = "chords" if self.layout == "chords" else "guaranteed"
        return screen_floor(
            cell, self.s, self.cost.of, lambda floor: rules_out(floor, best),
            decompose_area=False, angle=angle, offset=offset, layout=lay,
            keep_inside=self.keep_inside, **self.options,
        )  # fmt: skip

    def model(self, cell: Region) -> tuple[float, float, float]:
        """The least modelled cost of the cell and its layout ``(cost, angle, offset)``: its
        lines' segments (:func:`boustro.models.region.segment_moments`) as lanes, a spacing's
        move and a turn between consecutive ones, over lane directions every 5 degrees and the
        directions of its :data:`CENTRED_ANGLES` longest edges, 4 offsets each. Cheap (no
        plan): it ranks the candidates; what is kept is planned. With the guaranteed layout the
        lanes are counted as the lines whose band meets the cell, the length scaled to match."""
        key = _key(cell)
        if key in self.models:
            return self.models[key]
        v = cell.shell.vertices
        angles = np.concatenate(
            [np.arange(MODEL_ANGLES) * (math.pi / MODEL_ANGLES), _edge_angles(cell)]
        )
        base = centred_offsets(cell, angles, self.s, self.reach)
        a = np.repeat(angles, MODEL_OFFSETS)
        d = (base[:, None] + np.arange(MODEL_OFFSETS) * (self.s / MODEL_OFFSETS)).ravel()
        frame = cell.frame
        n, s1, _ = segment_moments(
            frame.to_normalised(cell.edges), a, d / frame.scale, self.s / frame.scale, tiny=1e-12
        )
        if self.layout != "chords":  # a guaranteed lane on every line whose band meets it
            normal = np.stack([-np.sin(a), np.cos(a)], axis=1)
            across = normal @ (v - cell.centre).T
            tol = 1e-9 * self.s
            lo = np.ceil((across.min(axis=1) - self.reach + tol - d) / self.s)
            hi = np.floor((across.max(axis=1) + self.reach - tol - d) / self.s)
            lanes = np.maximum(hi - lo + 1, n)
            s1 = s1 * lanes / np.maximum(n, 1)
            n = lanes
        turns = np.maximum(n - 1, 0)
        length = s1 * frame.scale + turns * self.s + 2 * n * self.cost.turnaround
        values = self.cost.per_length * length + self.cost.per_turn * turns
        values = np.where(n > 0, values, math.inf)
        i = int(np.argmin(values))
        out = (float(values[i]), float(a[i]), float(d[i]))
        self.models[key] = out
        return out

    def optimum(self, cell: Region, cutoff: float | None = None) -> OptimizeResult | None:
        """The cell's certified optimum (``None`` past :data:`MAX_SEARCHES` or no lane), or
        its search's result before the plans after the branch and bound (``info["plans_later"]``:
        its lower bound final, :meth:`finished` makes them; the floor of :func:`_cell_optima`
        needs only the bound).

        ``cutoff``: the search may stop once no layout of the cell costs less
        (``info["cut_off"]``: then only its lower bound counts, the candidate is screened out);
        such a result is reused only where its lower bound reaches the cutoff asked."""
        key = _key(cell)
        if key in self.cache:
            hit = self.cache[key]
            if hit is None or not hit.info.get("cut_off"):
                return hit
            if cutoff is not None and float(hit.info["lower_bound"]) >= cutoff:
                return hit
        if self.searches >= MAX_SEARCHES:
            return None
        self.searches += 1
        later: list[Callable[[], OptimizeResult]] = []
        try:
            opt = cover_optimum(
                cell, self.s, self.cost, lambda a, d: self.value(cell, a, d),
                reach=self.reach, boustrophedon=False, keep_inside=self.keep_inside,
                centred=False, cutoff=cutoff,
                screen=self._screen(cell) if self.keep_inside else None,  # bound tight without
                moves_on_passes=False,  # its floor decides (below): the decisions of bc75ccd
                later=later,
            )  # fmt: skip
        except (NoTransectError, InvalidPolygonError, InvalidParameterError):
            if cutoff is None:  # a search cut off may have stopped before its first plan
                self.cache[key] = None
            return None
        self.cache[key] = opt
        if later:  # its plans after the branch and bound: once the candidate is planned
            self.later[key] = (later[0], cutoff)
            return opt
        if opt.info.get("cut_off"):  # its candidate is screened out: only the bound counts
            return opt
        return self._completed(cell, opt)

    def finished(self, cell: Region, opt: OptimizeResult) -> OptimizeResult | None:
        """The cell's optimum ``opt`` (:meth:`optimum`'s) with the plans its search left for
        later made (:func:`~boustro.optimize.cover.cover_optimum`'s ``later``): the result
        the search makes without leaving them, ``None`` where those plans raise (as
        :meth:`optimum` returns where the search raises, remembered as it remembers)."""
        key = _key(cell)
        if not opt.info.get("plans_later"):
            return opt
        hit = self.cache.get(key)
        if hit is not None and not hit.info.get("plans_later"):
            return hit
        plans, cutoff = self.later.pop(key)
        try:
            done = plans()
        except (NoTransectError, InvalidPolygonError, InvalidParameterError):
            del self.cache[key]
            if cutoff is None:  # as optimum's search raising
                self.cache[key] = None
            return None
        return self._completed(cell, done)

    def _completed(self, cell: Region, opt: OptimizeResult) -> OptimizeResult:
        """The search's result with the lanes laid from the cell's edges (:meth:`_centred`),
        remembered."""
        opt = self._centred(cell, opt)
        opt = dataclasses.replace(opt, info={**opt.info, "keep_inside": self.keep_inside})
        self.cache[_key(cell)] = opt
        return opt

    def _screen(self, cell: Region) -> Callable[..., float] | None:
        """The screen (:meth:`floor`) of plans not finished, of the guaranteed layout: the
        search's with ``keep_inside``, and :meth:`_centred`'s with and without it (without it
        the search's own bound is within a few percent and rules out what the floor would:
        docs/keep_inside.md, "Eighteenth round")."""
        if self.finish is not None or self.layout == "chords":
            return None
        return lambda a, d, best=math.inf: self.floor(cell, a, d, best)

    def _centred(self, cell: Region, opt: OptimizeResult) -> OptimizeResult:
        """The optimum, or a better plan among the lanes laid from the cell's edge (the first
        half a spacing inside its extreme, as a person lays them) along its longest edges'
        directions: a strip one spacing wide is covered by one lane at one offset only, which
        the search's plans at box centres never hit. The search's lower bound holds for every
        layout, so the certificate stays valid, its gap only shrinks."""
        angles = _edge_angles(cell)
        offsets = centred_offsets(cell, angles, self.s, self.reach)
        best = (opt.fitness, opt.angle, opt.offset)
        screen = self._screen(cell)
        for a, d in zip(angles, offsets, strict=True):
            try:
                if screen is not None and rules_out(screen(float(a), float(d), best[0]), best[0]):
                    continue  # its floor is above the best plan: it cannot replace it
                value = self.value(cell, float(a), float(d))
            except NoTransectError:
                continue
            if value < best[0]:
                best = (value, float(a), float(d))
        if best[0] >= opt.fitness:
            return opt
        value, angle, offset = best
        lower = float(opt.info.get("lower_bound", -math.inf))
        gap = max(0.0, value - lower)
        rtol = float(opt.info.get("rtol", 1e-3))
        info = {**opt.info, "gap": gap, "certified": gap <= rtol * abs(value) + 1e-12}
        angle, offset = canonical(angle, offset, self.s)
        return dataclasses.replace(opt, angle=angle, offset=offset, fitness=value, info=info)


def _key(cell: Region) -> bytes:
    return np.round(cell.shell.vertices, 9).tobytes() + bytes(len(cell.holes))


def _edge_angles(cell: Region) -> np.ndarray:
    """The :data:`CENTRED_ANGLES` distinct directions (mod pi) of the cell's outer edges whose
    longest edge is longest, longest first."""
    v = cell.shell.vertices
    e = np.roll(v, -1, axis=0) - v
    a = np.round(np.arctan2(e[:, 1], e[:, 0]) % math.pi, 12)
    angles, inverse = np.unique(a, return_inverse=True)
    longest = np.zeros(len(angles))
    np.maximum.at(longest, inverse.ravel(), np.hypot(e[:, 0], e[:, 1]))
    return angles[np.argsort(-longest, kind="stable")[:CENTRED_ANGLES]]


def _sweeps(region: Region, sweep: float | None) -> list[float]:
    """The given sweep, or :func:`boustro.plan.choose_sweep`'s candidates: six directions and
    those of the two longest edges."""
    if sweep is not None:
        return [math.radians(float(sweep)) % math.pi]
    e = region.edges
    d = e[:, 1] - e[:, 0]
    longest = np.argsort(-np.linalg.norm(d, axis=1))[:2]
    out: list[float] = []
    for a in [*np.arange(6) * math.pi / 6, *(np.arctan2(d[longest, 1], d[longest, 0]) % math.pi)]:
        if all(abs((a - b + math.pi / 2) % math.pi - math.pi / 2) > 1e-6 for b in out):
            out.append(float(a))
    return out


def _decompositions(
    region: Region, sweeps: list[float], s: float
) -> list[tuple[str, Decomposition]]:
    """The candidate decompositions, distinct, of more than one cell."""
    out: list[tuple[str, Decomposition]] = []
    seen: set[bytes] = set()
    for sw in sweeps:
        for name in ("trapezoids", "choset", "merged"):
            try:
                dec = _decomposition(region, sw, s, name)
            except InvalidPolygonError:
                continue
            if len(dec.cells) < 2:
                continue
            key = np.round(sorted((c.area, *c.centre) for c in dec.cells), 6).tobytes()
            if key not in seen:
                seen.add(key)
                out.append((f"{name} at {math.degrees(sw):.6g} deg", dec))
    return out


def _decomposition(region: Region, sweep: float, s: float, name: str) -> Decomposition:
    """Every trapezoid a cell, Choset's cells, or the merged cells of :func:`decompose`; one of
    more than :data:`MAX_CELLS` cells (no candidate) raises before its cells are traced (a
    traced field's Choset cells: 13-23 of them, 0.2 s of tracing over 8 sweeps)."""
    if name == "trapezoids":
        if len(trapezoids(region, sweep).a) > MAX_CELLS:  # too many cells to search
            raise InvalidPolygonError("too many trapezoids")
        return slab_decomposition(region, sweep)
    merge, min_width = name == "merged", 2 * s
    counted = decompose(region, sweep, merge=merge, min_width=min_width, polygons=False)
    if int(counted.membership.max(initial=-1)) + 1 > MAX_CELLS:
        raise InvalidPolygonError("too many cells")
    return decompose(region, sweep, merge=merge, min_width=min_width)


def _merged(
    dec: Decomposition, diameter: float, search: _Search, models: list[tuple[float, float, float]]
) -> tuple[list[Region], list[tuple[float, float, float]]] | None:
    """Neighbouring cells merged while the union's modelled cost is no more than both cells'
    and one turn (the largest saving first; never into one cell: that is the one-grid plan);
    ``None``: no merge."""
    groups = [[k] for k in range(len(dec.cells))]
    regions, values = list(dec.cells), list(models)
    turn = search.cost.per_turn
    merged = False
    unions: dict[tuple[int, ...], tuple[Region, tuple[float, float, float]] | None] = {}

    def union_of(group: list[int]) -> tuple[Region, tuple[float, float, float]] | None:
        """The union of the cells and its model, once per set of cells (``None``: invalid)."""
        key = tuple(sorted(group))
        if key not in unions:
            if search.union_edges >= MAX_UNION_EDGES:
                return None
            search.union_edges += sum(len(dec.cells[k].edges) for k in key)
            try:
                union = dec.union(group, diameter)
            except InvalidPolygonError:
                unions[key] = None
            else:
                unions[key] = (union, search.model(union))
        return unions[key]

    while len(groups) > 2:
        best: tuple[float, int, int, Region, tuple[float, float, float]] | None = None
        for i in range(len(groups)):
            for j in range(i + 1, len(groups)):
                if float(dec.shared[np.ix_(groups[i], groups[j])].sum()) <= 0:
                    continue
                gap = abs(values[i][1] - values[j][1]) % math.pi
                if min(gap, math.pi - gap) >= MERGE_ANGLE:
                    continue
                found = union_of(groups[i] + groups[j])
                if found is None:
                    continue
                union, model = found
                saving = values[i][0] + values[j][0] + turn - model[0]
                if saving >= 0 and (best is None or saving > best[0]):
                    best = (saving, i, j, union, model)
        if best is None:
            break
        _, i, j, union, model = best
        groups[i], regions[i], values[i] = groups[i] + groups[j], union, model
        del groups[j], regions[j], values[j]
        merged = True
    return (regions, values) if merged else None


def _candidates(region: Region, search: _Search, sweep: float | None) -> list[_Candidate]:
    """Every candidate decomposition with its cells' modelled costs, least estimate first."""
    turn = search.cost.per_turn
    out: list[_Candidate] = []
    for name, dec in _decompositions(region, _sweeps(region, sweep), search.s):
        if len(dec.cells) > MAX_CELLS:
            continue
        models = [search.model(c) for c in dec.cells]
        merged = _merged(dec, region.diameter, search, models)
        for label, cells, values in [(name, list(dec.cells), models)] + (
            [] if merged is None else [(f"{name}, merged", *merged)]
        ):
            estimate = sum(v[0] for v in values) + turn * (len(cells) - 1)
            out.append(_Candidate(label, cells, values, estimate))
    out.sort(key=lambda c: c.estimate)
    return out


def _cell_optima(
    search: _Search, cells: list[Region], beat: float | None
) -> list[OptimizeResult] | None:
    """The cells' certified optima, largest cell first; ``None`` when a cell has none, or when
    (with ``beat``, the one grid's cost) the cells' floor already reaches ``beat``: the whole
    plan flies every cell's lanes, moves and turns, and more (moves between cells, a turn
    each), so it would not win (a screen, not a bound: the solved order may interleave the
    cells' passes). The floor: the searched cells' lower bounds, a turn between consecutive
    cells, and for the cells not searched yet the length that covers their area
    (:func:`_area_floor`), checked before each search (a small cell's search can cost more
    than a large one's)."""
    found: dict[int, OptimizeResult] = {}
    order = sorted(range(len(cells)), key=lambda k: -cells[k].area)
    rest = [_area_floor(search, cells[k]) for k in order]
    floor = search.cost.per_turn * (len(cells) - 1) + sum(rest)
    for i, k in enumerate(order):
        if beat is not None and floor >= beat:
            return None
        # the search may stop once the cell's lower bound alone brings the floor to beat
        cutoff = None if beat is None else beat - (floor - rest[i]) + CUTOFF_MARGIN * abs(beat)
        opt = search.optimum(cells[k], cutoff)
        if opt is None:
            return None
        found[k] = opt
        floor += max(float(opt.info.get("lower_bound") or 0.0), rest[i]) - rest[i]
    if beat is not None and floor >= beat:
        return None
    optima = []
    for k in range(len(cells)):  # a cell whose plans left for later raise: none (as searched)
        done = search.finished(cells[k], found[k])
        if done is None:
            return None
        optima.append(done)
    return optima


def _uncertified_where_cut(
    optima: list[OptimizeResult], cand: _Candidate, searched: list[Region]
) -> list[OptimizeResult]:
    """The optima, those of cells searched without a spike (:mod:`.slivers`) marked: their
    search's certificate is the cut cell's, the plan flies the whole cell (so that it covers the
    spike), hence no certificate there (``certified`` false, ``gap`` and ``lower_bound``
    ``None``, ``spikes_cut`` true)."""
    marks = {"certified": False, "gap": None, "lower_bound": None, "spikes_cut": True}
    return [
        o if cut is cell else dataclasses.replace(o, info={**o.info, **marks})
        for o, cell, cut in zip(optima, cand.cells, searched, strict=True)
    ]


def _area_floor(search: _Search, cell: Region) -> float:
    """The cost of the length a path needs to cover the cell: within ``reach`` of a path of
    length ``L`` lie at most ``2 reach L + pi reach^2`` of area."""
    r = search.reach
    if r <= 0:
        return 0.0
    return search.cost.per_length * max(0.0, cell.area - math.pi * r * r) / (2 * r)


def plan_decomposed(
    frame: Frame,
    cost: CoverCost,
    *,
    layout: str,
    turnaround: float,
    speed: float | None,
    turn_time: float,
    check_coverage: bool,
    keep_inside: bool = False,
    sweep: float | None = None,
    finish: Callable[[Plan], Plan] | None = None,
    cell_finish: Callable[[Plan], Plan] | None = None,
    beat: float | None = None,
    **_: Any,
) -> Planned | None:
    """The decomposed plan of least flown ``cost`` (module docstring), or ``None`` when no
    decomposition has more than one cell (or, with ``beat``, none whose modelled cost is below
    it: the cost of the one-grid plan). Its optimum's ``info``: ``cells``, ``candidates``,
    ``searches``, ``decomposition`` (which candidate), ``cell_order`` (the order's solver),
    ``cells_certified``, ``cells_keep_inside`` (whether the kept cells' searches planned them
    with ``keep_inside``); its cells carry their certificates.

    Each cell's search costs the cell's own plan (``cell_finish``: the vehicle's turns; never
    headland passes). With ``keep_inside`` a cell alone is planned keeping inside the cell (its
    cut edges get boundary passes the whole plan does not fly), so the cells are searched both
    without and with it (in that order: a candidate the first search screens out is dropped)
    and the whole plan (always keeping inside) of least flown cost is kept.
    """
    t0 = time.perf_counter()
    region = frame.region
    assert region is not None
    options = _path_options(frame, turnaround, speed, turn_time)
    # the cells searched without keep_inside first (cheap plans, tight bounds): their floor
    # screens a candidate out before the keep_inside search (dear plans, loose bounds)
    searches = [_Search(frame, cost, layout, options, False, cell_finish)]
    if keep_inside:
        searches.append(_Search(frame, cost, layout, options, True, cell_finish))
        searches[1].models = searches[0].models  # the model does not depend on it
    candidates = _candidates(region, searches[0], sweep)
    if beat is not None:  # the model leaves out moves between cells: hopeless if above
        candidates = [c for c in candidates if c.estimate < beat]
    best: tuple[float, Plan, _Candidate, list[OptimizeResult], bool] | None = None
    lay: Layout = "chords" if layout == "chords" else "guaranteed"
    planned = PLANNED if len(region.edges) <= LARGE_EDGES else 1
    seen: set[tuple[tuple[bytes, ...], ...]] = set()
    for cand in candidates[:planned]:
        key = tuple(tuple(r.vertices.tobytes() for r in (c.shell, *c.holes)) for c in cand.cells)
        if key in seen:  # the same cells under another name: the same plans, not kept (a tie)
            continue
        seen.add(key)
        # the cells less their thin spikes (:mod:`.slivers`): searched (of the planned only)
        searched = [cut_slivers(c, SLIVER_WIDTH * searches[0].s) for c in cand.cells]
        for search in searches:
            optima = _cell_optima(search, searched, beat)
            if optima is None:  # screened out (or no lane): the other search too
                break
            optima = _uncertified_where_cut(optima, cand, searched)
            plan = plan_region(
                region, search.s, layout=lay, cells=list(zip(cand.cells, optima, strict=True)),
                order="auto", keep_inside=keep_inside,
                start=frame.start if frame.given_start else None, **options,
            )  # fmt: skip
            value = flown_cost(cost, plan, frame, finish)
            if best is None or value < best[0]:
                best = (value, plan, cand, optima, search.keep_inside)
    if best is None:
        return None
    value, plan, cand, optima, cells_inside = best
    certified = sum(bool(o.info.get("certified")) for o in optima)
    main = max(range(len(cand.cells)), key=lambda k: cand.cells[k].area)
    optimum = OptimizeResult(
        angle=optima[main].angle,
        offset=optima[main].offset,
        fitness=value,
        spacing=searches[0].s,
        method="decomposed-cover",
        evaluations=int(sum(o.evaluations for o in optima)),
        seconds=time.perf_counter() - t0,
        info={
            "objective": cost.name,
            "certified": False,  # each cell is; the choice of cells is not
            "gap": None,
            "cells": len(cand.cells),
            "cells_certified": certified,
            "decomposition": cand.name,
            "candidates": len(candidates),
            "searches": sum(search.searches for search in searches),
            "cells_keep_inside": cells_inside,
            "cell_order": plan.order_solver,
        },
    )
    cells = tuple(
        dataclasses.replace(c, fitness=o.fitness, optimum=o)
        for c, o in zip(plan.cells, optima, strict=True)
    )
    plan = dataclasses.replace(plan, cells=cells)
    cov = coverage(plan, region) if check_coverage else None
    return Planned(plan, optimum, cov)
