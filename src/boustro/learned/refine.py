"""Refinement of candidate layouts, all polygons in one batch: sweep, events, gradient, zoom."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, NamedTuple

from .._torch import torch
from ..objectives import as_plan_objective
from .batch import PlanBatch, batch_objective

__all__ = ["NUDGE", "Candidates", "RefineOptions", "refine", "refine_evaluations"]


def _offset_sweep(
    batch: PlanBatch, theta: torch.Tensor, offset: torch.Tensor, n: int, objective: Any
) -> tuple[torch.Tensor, torch.Tensor]:
    """At each candidate's angle, the best of ``n`` offsets over a whole spacing (exact)."""
    p, k = theta.shape
    u = torch.arange(n, dtype=theta.dtype, device=theta.device) / n
    o = offset[..., None] + u * batch.spacing[:, None, None]
    th = theta[..., None].expand(-1, -1, n)
    values = batch_objective(batch, th.reshape(p, -1), o.reshape(p, -1), objective=objective)
    values = values.reshape(p, k, n)
    best = values.argmax(dim=-1, keepdim=True)
    return values.gather(-1, best)[..., 0], o.gather(-1, best)[..., 0]


def _zoom(
    batch: PlanBatch,
    theta: torch.Tensor,
    offset: torch.Tensor,
    half_angle: float,
    half_offset: float,
    points: int,
    levels: int,
    objective: Any,
) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor]:
    """Coarse-to-fine exact search around every candidate ``(P, c)``: ``points^2`` a level,
    the window shrinking to one cell of the level before; ``half_offset`` in spacings."""
    p, c = theta.shape
    u = torch.linspace(-1.0, 1.0, points, dtype=theta.dtype, device=theta.device)
    s = batch.spacing[:, None, None, None]
    best = batch_objective(batch, theta, offset, objective=objective)
    for _ in range(levels):
        a = theta[..., None, None] + half_angle * u[:, None]
        o = offset[..., None, None] + half_offset * s * u
        a, o = torch.broadcast_tensors(a, o)
        a, o = a.reshape(p, c, -1), o.reshape(p, c, -1)
        values = batch_objective(
            batch, a.reshape(p, -1), o.reshape(p, -1), objective=objective
        ).reshape(p, c, -1)
        top, where = values.max(dim=-1)
        better = top > best
        theta = torch.where(better, a.gather(-1, where[..., None])[..., 0], theta)
        offset = torch.where(better, o.gather(-1, where[..., None])[..., 0], offset)
        best = torch.maximum(top, best)
        half_angle *= 2.0 / (points - 1)
        half_offset *= 2.0 / (points - 1)
    return best, theta, offset


@dataclass(frozen=True)
class RefineOptions:
    """Settings of :func:`refine` (defaults tuned on random polygons, see docs/learned.md).

    Costs per polygon, in exact evaluations: ``k`` (the hypotheses), ``sweep_top * sweep``,
    ``2 N (N - 1)`` with ``events`` (``N`` vertices),
    ``top * steps / check_every`` plus ``steps`` smooth forward and backward passes of ``top``
    layouts, ``zoom_top * zoom_points^2 * zoom_levels``, and 6 for the final nudge.
    """

    sweep: int = 16  # offsets tried over one spacing at each swept hypothesis's angle
    sweep_top: int = 4  # hypotheses swept, best first by the exact model (0: all)
    events: bool = True  # add the layouts with transects through two vertices (m <= 1 apart)
    top: int = 2  # candidates kept for the gradient and zoom stages
    steps: int = 0  # gradient steps (see :meth:`gradient`)
    check_every: int = 2  # exact scoring of the gradient iterates every this many steps
    lr_angle: float = 0.01
    lr_offset: float = 0.05  # fraction of the spacing per Adam step
    smoothing: float = 0.05  # fraction of the spacing
    zoom_top: int = 1
    zoom_points: int = 5
    zoom_levels: int = 3
    zoom_angle: float = 0.02  # radians, first window half-width
    zoom_offset: float = 0.08  # spacings

    @classmethod
    def gradient(cls) -> RefineOptions:
        """A wider, slower preset with 20 Adam steps through the smooth closed form: every
        hypothesis swept, 4 candidates descended, the best 2 zoomed (7 x 7 points a level)."""
        return cls(sweep_top=0, top=4, steps=20, zoom_top=2, zoom_points=7)


def _event_layouts(batch: PlanBatch) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor]:
    """Layouts ``(P, C)`` where one transect passes through vertex ``i`` and a transect
    ``m in {-1, 0, 1}`` spacings away through vertex ``j``, for every pair of vertices, and a
    mask of the real ones (``n(theta) . (v_i - v_j) = m s``: the events of
    :func:`boustro.global_opt.event_angles` with ``|m| <= 1``).

    Eq. 1's optimum often sits exactly there: at a spacing comparable to the polygon's width
    the best layout is one or two long transects, pressed against the angle where a
    neighbouring transect would enter the polygon (or, ``m = 0``, one transect along a
    diagonal). Such optima are needles in the (angle, offset) plane that sampling rarely hits.

    Exactly on an event a transect may graze an extreme vertex and count or not by rounding,
    so the offset is nudged by ``NUDGE`` spacings to the side where it does not: down when the
    lower transect of an ``m = 1`` pair grazes the lowest vertex, up when the upper one grazes
    the highest. ``m = 0`` layouts come on both sides: along an extreme edge, the transect just
    inside and the grid with that transect just outside are different layouts.
    """
    n = batch.vertices.shape[1]
    i, j = torch.triu_indices(n, n, offset=1)
    vi, vj = batch.vertices[:, i], batch.vertices[:, j]
    delta = vi - vj
    dist = torch.linalg.norm(delta, dim=-1)
    real = batch.mask[:, i] & batch.mask[:, j] & (dist > 0)
    dist = torch.where(real, dist, torch.ones_like(dist))
    alpha = torch.atan2(-delta[..., 0], delta[..., 1])  # n(theta) . delta = dist cos(theta - a)
    # m = -1 gives the same grids as m = 1 turned by pi (the offset's sign flips with the turn)
    ratio = batch.spacing[:, None] / dist
    ok = real & (ratio <= 1)
    acos = torch.acos(ratio.clamp(max=1.0))
    theta = torch.cat([alpha + math.pi / 2, alpha + acos, alpha - acos], dim=1)
    mask = torch.cat([real, ok, ok], dim=1)
    vi, vj = vi.repeat(1, 3, 1), vj.repeat(1, 3, 1)
    sin, cos = torch.sin(theta), torch.cos(theta)
    h_i = -sin * vi[..., 0] + cos * vi[..., 1]
    h_j = -sin * vj[..., 0] + cos * vj[..., 1]
    h = (
        -sin[..., None] * batch.vertices[:, None, :, 0]
        + cos[..., None] * batch.vertices[:, None, :, 1]
    )
    lo, hi = h.amin(dim=-1), h.amax(dim=-1)  # padding repeats vertex 0: no effect
    tol = 1e-9 * batch.radius[:, None]
    pair = torch.arange(theta.shape[1], device=theta.device) < i.numel()  # the m = 0 block
    down = torch.where(pair, h_i >= hi - tol, h_j <= lo + tol)
    step = NUDGE * batch.spacing[:, None]
    offset = h_i + torch.where(down, -step, step)
    # m = 0 along an extreme edge: just outside is a layout of its own (the transect leaves)
    c = i.numel()
    return (
        torch.cat([theta, theta[:, :c]], dim=1),
        torch.cat([offset, h_i[:, :c] + torch.where(down[:, :c], step, -step)], dim=1),
        torch.cat([mask, mask[:, :c]], dim=1),
    )


def _keep(k: torch.Tensor, *tensors: torch.Tensor) -> list[torch.Tensor]:
    return [t.gather(1, k) for t in tensors]


class Candidates(NamedTuple):
    """Candidate layouts ``(P, c)`` of a batch and their exact objective values."""

    value: torch.Tensor
    theta: torch.Tensor
    offset: torch.Tensor

    def keep(self, k: torch.Tensor) -> Candidates:
        """The candidates ``k`` ``(P, c')`` of each polygon."""
        return Candidates(*_keep(k, *self))

    def best(self, count: int) -> Candidates:
        """Each polygon's best ``count`` candidates (all if ``count`` is 0 or too large)."""
        if 0 < count < self.theta.shape[1]:
            return self.keep(torch.argsort(self.value, dim=1, descending=True)[:, :count])
        return self

    def join(self, other: Candidates) -> Candidates:
        """Both sets of candidates side by side."""
        return Candidates(*(torch.cat(x, dim=1) for x in zip(self, other, strict=True)))

    def improved(
        self, value: torch.Tensor, theta: torch.Tensor, offset: torch.Tensor
    ) -> Candidates:
        """Each candidate replaced by ``(value, theta, offset)`` where that is better."""
        better = value > self.value
        return Candidates(
            torch.where(better, value, self.value),
            torch.where(better, theta, self.theta),
            torch.where(better, offset, self.offset),
        )


def _sweep_stage(batch: PlanBatch, cand: Candidates, o: RefineOptions, obj: Any) -> Candidates:
    """Stage 1: the best ``sweep_top`` candidates, each at the best of ``sweep`` offsets."""
    if o.sweep <= 1:
        return cand
    cand = cand.best(o.sweep_top)
    v, off = _offset_sweep(batch, cand.theta, cand.offset, o.sweep, obj)
    return cand.improved(v, cand.theta, off)


def _event_stage(batch: PlanBatch, cand: Candidates, obj: Any) -> Candidates:
    """Stage 2: the event layouts (:func:`_event_layouts`) join the candidates."""
    pt, po, real = _event_layouts(batch)
    # 2 N (N - 1) layouts a polygon: scored in chunks so that memory stays bounded for
    # polygons of many vertices (each layout costs about K x E elements)
    n_pairs, n_edges = batch.normals.shape[0], batch.normals.shape[-2]
    k_est = int(2.0 / float(batch.spacing.min()) + 4.0)
    chunk = max(1, _EVENT_CHUNK_ELEMENTS // max(1, n_pairs * n_edges * k_est))
    pv = torch.cat(
        [
            batch_objective(batch, pt[:, i : i + chunk], po[:, i : i + chunk], objective=obj)
            for i in range(0, pt.shape[1], chunk)
        ],
        dim=1,
    )
    return cand.join(Candidates(torch.where(real, pv, -math.inf), pt, po))


def _gradient_stage(batch: PlanBatch, cand: Candidates, o: RefineOptions, obj: Any) -> Candidates:
    """Stage 3: Adam through the smooth closed form, the iterates scored exactly."""
    spacing = batch.spacing[:, None]
    th = cand.theta.clone().requires_grad_(True)
    # the offset in units of the spacing, so that one learning rate fits every polygon
    u = (cand.offset / spacing).clone().requires_grad_(True)
    opt = torch.optim.Adam([{"params": [th], "lr": o.lr_angle}, {"params": [u], "lr": o.lr_offset}])
    every = max(1, o.check_every)
    for step in range(o.steps):
        opt.zero_grad(set_to_none=True)
        value = batch_objective(batch, th, u * spacing, smoothing=o.smoothing, objective=obj)
        (-value.sum()).backward()
        for param in (th, u):
            if param.grad is not None:
                torch.nan_to_num_(param.grad, nan=0.0, posinf=0.0, neginf=0.0)
        opt.step()
        if (step + 1) % every and step + 1 < o.steps:
            continue
        with torch.no_grad():
            cur_t, cur_o = th.detach().clone(), u.detach() * spacing
            cand = cand.improved(batch_objective(batch, cur_t, cur_o, objective=obj), cur_t, cur_o)
    return cand


def _zoom_stage(batch: PlanBatch, cand: Candidates, o: RefineOptions, obj: Any) -> Candidates:
    """Stage 4: exact coarse-to-fine zoom around the best ``zoom_top`` candidates."""
    top = cand.keep(torch.argsort(cand.value, dim=1, descending=True)[:, : o.zoom_top])
    zv, zt, zo = _zoom(
        batch, top.theta, top.offset, o.zoom_angle, o.zoom_offset, o.zoom_points, o.zoom_levels, obj
    )
    return cand.join(Candidates(zv, zt, zo))


def refine(
    batch: PlanBatch,
    theta: torch.Tensor,
    offset: torch.Tensor,
    *,
    objective: Any = None,
    options: RefineOptions | None = None,
) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor]:
    """Improve candidate layouts ``(P, k)`` of a batch of polygons, all in one batch.

    1. the candidates are scored exactly; at the angles of the best ``sweep_top`` of them
       (``0``: all) ``sweep`` offsets over one spacing are tried (exact), each keeping its best;
    2. with ``events``, the layouts with transects through two vertices, at most one spacing
       apart (:func:`_event_layouts`), join the candidates; the best ``top`` go on;
    3. gradient ascent (Adam) of the objective through the smooth closed form (smoothing a
       fraction of each spacing), ``steps`` steps (0 by default, see
       :meth:`RefineOptions.gradient`), the iterates scored exactly;
    4. exact coarse-to-fine zoom around each polygon's best ``zoom_top`` candidates.

    Args:
        batch: the polygons, :func:`make_batch` (float64 for exact answers).
        theta, offset: ``(P, k)`` starting layouts, normalised frame.
        objective: anything :func:`as_plan_objective` accepts (default Eq. 1), maximised.
        options: :class:`RefineOptions` (default: the fast preset of the benchmark).

    Returns ``(value, theta, offset)`` ``(P,)``: each polygon's best layout by the EXACT
    objective over all stages (never worse than the best input candidate).

    >>> import numpy as np
    >>> from boustro.learned import load_planner, make_batch, refine
    >>> batch = make_batch([[(0, 0), (4, 0), (4, 2), (0, 2)]], 0.5)
    >>> start = load_planner()(batch)
    >>> value, theta, offset = refine(batch, start.theta.double(), start.offset.double())
    >>> round(float(value[0]), 4), round(float(theta[0]) % np.pi, 4)
    (0.9505, 3.021)
    """
    o = options or RefineOptions()
    obj = as_plan_objective(objective)
    t, off = theta.detach(), offset.detach()
    cand = _sweep_stage(
        batch, Candidates(batch_objective(batch, t, off, objective=obj), t, off), o, obj
    )
    if o.events:
        cand = _event_stage(batch, cand, obj)
    cand = cand.best(o.top)
    if o.steps > 0:
        cand = _gradient_stage(batch, cand, o, obj)
    if o.zoom_levels > 0 and o.zoom_top > 0:
        cand = _zoom_stage(batch, cand, o, obj)
    k = cand.value.argmax(dim=1, keepdim=True)
    return (
        cand.value.gather(1, k)[:, 0],
        cand.theta.gather(1, k)[:, 0],
        cand.offset.gather(1, k)[:, 0],
    )


def refine_evaluations(k: int, n_vertices: int, o: RefineOptions) -> int:
    """Exact evaluations plus gradient evaluations (one each) of :func:`refine`, per polygon."""
    swept = min(o.sweep_top, k) if o.sweep_top > 0 else k
    count = k + (swept * o.sweep if o.sweep > 1 else 0)
    events = 2 * n_vertices * (n_vertices - 1) if o.events else 0
    m = min(o.top, k + events) if o.top > 0 else k + events
    count += events + m * (o.steps + -(-o.steps // max(1, o.check_every)))
    if o.zoom_levels:
        count += min(o.zoom_top, m) * o.zoom_points**2 * o.zoom_levels
    return count + 6


#: Elements (layouts x transects x edges) of one chunk of event layouts in :func:`refine`.
_EVENT_CHUNK_ELEMENTS = 1 << 23

#: Offset nudge (in spacings) of the event layouts: far above rounding (1e-16), far below any
#: difference that matters (the fitness moves by about this much).
NUDGE = 1e-7
