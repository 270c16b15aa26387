"""Table I: mean ``|differentiable - discrete|`` fitness per temperature x points per transect."""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import torch
from numpy.typing import NDArray

from ..errors import InvalidParameterError
from ..geometry import halfplanes
from ..models.smooth import SmoothModel
from ..objectives.smith import smith_fitness
from ._common import json_number, progress_bar
from .layouts import _protocol_spacing, _sample_offsets, exact_fitness_batch, protocol_groups
from .paper_batched import _soft_fitness
from .samples import PROTOCOLS, TEMPERATURES, Protocol, Samples

__all__ = ["PAPER_TABLE1", "Table1", "smooth_model_fitness", "smooth_table1", "table1"]


#: The paper's Table I: mean |differentiable - discrete| fitness, by temperature, for 100, 1000
#: and 10000 points per transect.
PAPER_TABLE1: dict[float, tuple[float, float, float]] = {
    1.0: (0.50798, 0.50795, 0.50408),
    10.0: (0.08480, 0.08369, 0.08367),
    100.0: (0.03090, 0.03001, 0.03167),
    1000.0: (0.00374, 0.00271, 0.00306),
    10000.0: (0.00203, 0.00055, 0.00016),
}


@dataclass(frozen=True)
class Table1:
    """One Table I: mean ``|differentiable - discrete|`` fitness per temperature x column.

    Attributes:
        protocol: the protocol the numbers come from.
        model: ``"paper"`` (Eq. 2-7) or ``"smooth"`` (the closed form, :mod:`boustro.smooth`,
            smoothing ``1 / T``).
        temperatures: the rows.
        points: the columns: points per transect (``None`` for the closed form).
        mean: ``(rows, columns)`` mean absolute error over the samples with a value.
        sem: standard error of that mean (sample std / sqrt(n)).
        max: largest absolute error.
        valid: samples with both fitnesses defined, per cell.
        no_value_discrete: samples whose discrete fitness is undefined (no transect crosses the
            polygon in the window); left out of every cell, never redrawn.
        no_value_model: per cell, samples whose differentiable fitness is not finite.
        n_samples: samples drawn.
    """

    protocol: Protocol
    model: str
    temperatures: tuple[float, ...]
    points: tuple[int | None, ...]
    mean: NDArray[np.float64]
    sem: NDArray[np.float64]
    max: NDArray[np.float64]
    valid: NDArray[np.int64]
    no_value_discrete: int
    no_value_model: NDArray[np.int64]
    n_samples: int

    @classmethod
    def from_json(cls, d: dict[str, Any]) -> Table1:
        """Inverse of :meth:`to_json` (for reports of earlier runs)."""
        st = d["settings"]
        spacing = None if isinstance(st["spacing"], str) else float(st["spacing"])
        protocol = Protocol(
            d["protocol"],
            d["description"],
            clip=st["clip"],
            statistics=st["statistics"],
            spacing=spacing,
            window=st["window"],
            trapezoid=st.get("trapezoid", "library"),
            discrete_clip=st["discrete_clip"],
        )

        def arr(key: str, dtype: Any = np.float64) -> NDArray[Any]:
            return np.array(
                [[np.nan if v is None else v for v in row] for row in d[key]], dtype=dtype
            )

        return cls(
            protocol,
            d["model"],
            tuple(d["temperatures"]),
            tuple(d["points_per_transect"]),
            arr("mean_abs_error"),
            arr("sem"),
            arr("max_abs_error"),
            arr("valid_samples", np.int64),
            int(d["no_value_discrete"]),
            arr("no_value_model", np.int64),
            int(d["n_samples"]),
        )

    def to_json(self) -> dict[str, Any]:
        def cells(a: NDArray[Any]) -> list[list[Any]]:
            return [[json_number(v) for v in row] for row in a.tolist()]

        return {
            "protocol": self.protocol.name,
            "description": self.protocol.description,
            "settings": {
                "clip": self.protocol.clip,
                "discrete_clip": self.protocol.discrete_clip,
                "statistics": self.protocol.statistics,
                "spacing": "uniform(0, 1/3)"
                if self.protocol.spacing is None
                else self.protocol.spacing,
                "window": self.protocol.window,
                "trapezoid": self.protocol.trapezoid,
            },
            "model": self.model,
            "temperatures": list(self.temperatures),
            "points_per_transect": list(self.points),
            "mean_abs_error": cells(self.mean),
            "sem": cells(self.sem),
            "max_abs_error": cells(self.max),
            "valid_samples": cells(self.valid),
            "no_value_discrete": self.no_value_discrete,
            "no_value_model": cells(self.no_value_model),
            "n_samples": self.n_samples,
        }


def _summarise(
    protocol: Protocol,
    model: str,
    temperatures: Sequence[float],
    points: Sequence[int | None],
    exact: NDArray[np.float64],
    soft: dict[tuple[float, int | None], NDArray[np.float64]],
) -> Table1:
    shape = (len(temperatures), len(points))
    mean, sem, mx = np.full(shape, np.nan), np.full(shape, np.nan), np.full(shape, np.nan)
    valid, no_model = np.zeros(shape, dtype=np.int64), np.zeros(shape, dtype=np.int64)
    has_exact = np.isfinite(exact)
    for i, t in enumerate(temperatures):
        for j, pts in enumerate(points):
            f = soft[(t, pts)]
            no_model[i, j] = int(np.sum(~np.isfinite(f)))
            ok = has_exact & np.isfinite(f)
            err = np.abs(f[ok] - exact[ok])
            valid[i, j] = len(err)
            if len(err):
                mean[i, j] = float(err.mean())
                mx[i, j] = float(err.max())
                sem[i, j] = float(err.std(ddof=1) / math.sqrt(len(err))) if len(err) > 1 else 0.0
    return Table1(
        protocol,
        model,
        tuple(float(t) for t in temperatures),
        tuple(points),
        mean,
        sem,
        mx,
        valid,
        int(np.sum(~has_exact)),
        no_model,
        len(exact),
    )


def table1(
    samples: Samples,
    protocols: Sequence[Protocol] = PROTOCOLS,
    temperatures: Sequence[float] = TEMPERATURES,
    *,
    points: Sequence[int] | None = None,
    progress: bool = False,
) -> dict[str, Table1]:
    """Table I of the paper for every protocol, by name.

    The differentiable model is evaluated once per (transect layout, temperature, points) and
    serves every protocol with that layout (each with its own statistics and discrete side).

    Args:
        samples: from :func:`draw_samples`.
        protocols: see :data:`PROTOCOLS`.
        temperatures: rows.
        points: columns for every protocol (default: each protocol's own ``points``).
        progress: a tqdm bar on stderr, in transect points evaluated.

    >>> from boustro.experiments import PROTOCOLS, draw_samples
    >>> tables = table1(draw_samples(2), PROTOCOLS[:1], (1000.0,), points=(100,))
    >>> round(float(tables["paper"].mean[0, 0]), 4), tables["paper"].valid.tolist()
    (0.0038, [[2]])
    """
    cols = {p.name: tuple(points) if points is not None else p.points for p in protocols}
    layouts: dict[tuple[Any, ...], list[Protocol]] = {}
    for p in protocols:
        layouts.setdefault(p.layout, []).append(p)
    exact: dict[tuple[Any, ...], NDArray[np.float64]] = {}
    for p in protocols:
        if p.discrete_layout not in exact:
            exact[p.discrete_layout] = exact_fitness_batch(samples, p)
    groups = {key: protocol_groups(samples, ps[0]) for key, ps in layouts.items()}
    work = {
        key: (
            sum(len(g.position) for g in groups[key]),
            sorted({c for p in ps for c in cols[p.name]}),
        )
        for key, ps in layouts.items()
    }
    total = sum(m * sum(pts) * len(temperatures) for m, pts in work.values())
    soft: dict[str, dict[tuple[float, int | None], NDArray[np.float64]]] = {
        p.name: {} for p in protocols
    }
    with progress_bar(total, "Table I", progress, unit="pt") as bar:
        for key, ps in layouts.items():
            m, pts_list = work[key]
            stats = sorted({p.variant for p in ps})
            for pts in pts_list:
                for t in temperatures:
                    values = {v: np.full(len(samples), np.nan) for v in stats}
                    with torch.no_grad():
                        for g in groups[key]:
                            f = _soft_fitness(g, float(t), int(pts), stats)
                            for v in stats:
                                values[v][g.index] = f[v].numpy()
                    for p in ps:
                        if pts in cols[p.name]:
                            soft[p.name][(float(t), pts)] = values[p.variant]
                    bar.update(m * pts)
    return {
        p.name: _summarise(
            p, "paper", temperatures, cols[p.name], exact[p.discrete_layout], soft[p.name]
        )
        for p in protocols
    }


def smooth_model_fitness(
    samples: Samples, protocol: Protocol, temperature: float
) -> NDArray[np.float64]:
    """Eq. 1 of the closed-form smooth model (:class:`boustro.smooth.SmoothModel`, smoothing
    ``1 / T``) of every sample under ``protocol`` (``"paper"`` window only: the model places
    its own grid), one call per sample.
    """
    if protocol.window != "paper":
        raise InvalidParameterError("the smooth model places the library's grid ('paper' window)")
    model = SmoothModel.from_temperature(float(temperature), clip=protocol.clip)
    spacing = _protocol_spacing(samples, protocol)
    offset = _sample_offsets(samples, spacing)
    out = np.empty(len(samples))
    with torch.no_grad():
        for i, poly in enumerate(samples.polygons):
            tl = model(
                halfplanes(poly),
                torch.tensor(samples.angle[i], dtype=torch.float64),
                torch.tensor(offset[i], dtype=torch.float64),
                float(spacing[i]),
            )
            out[i] = float(smith_fitness(tl.lengths, tl.weights, statistics=protocol.statistics))
    return out


def smooth_table1(
    samples: Samples,
    protocols: Sequence[Protocol],
    temperatures: Sequence[float] = TEMPERATURES,
    *,
    progress: bool = False,
) -> dict[str, Table1]:
    """Table I for the closed-form smooth model (one column), for the protocols it applies
    to: the library's grid (``"paper"`` window) and no trapezoid (``trapezoid="library"``)."""
    usable = [p for p in protocols if p.window == "paper" and p.trapezoid == "library"]
    out: dict[str, Table1] = {}
    with progress_bar(len(usable) * len(temperatures), "Table I, closed form", progress) as bar:
        for p in usable:
            exact = exact_fitness_batch(samples, p)
            soft: dict[tuple[float, int | None], NDArray[np.float64]] = {}
            for t in temperatures:
                soft[(float(t), None)] = smooth_model_fitness(samples, p, t)
                bar.update(1)
            out[p.name] = _summarise(p, "smooth", temperatures, (None,), exact, soft)
    return out
