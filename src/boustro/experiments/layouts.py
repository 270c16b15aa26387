"""The transects of every Table I sample under a protocol, grouped, and their exact fitness."""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import torch
from numpy.typing import NDArray

from ..geometry import HalfPlanes, Polygon, halfplanes
from ..models import PAPER_WINDOW, line_chords
from ..models.base import _components
from ..objectives.smith import smith_fitness
from .samples import Eq2, Protocol, Samples, Window

__all__ = ["exact_fitness_batch", "protocol_groups"]


@dataclass
class _Group:
    """Samples with the same edge count, their transects flattened (no padding)."""

    index: NDArray[np.int64]  # (B,) positions of the samples in the experiment
    across: torch.Tensor  # (B, E) n_j . n(theta): edge j holds iff across c + along t + b >= 0
    along: torch.Tensor  # (B, E) n_j . u(theta)
    b: torch.Tensor  # (B, E)
    half: torch.Tensor  # (B,) half-width of the integration window in t
    radius: torch.Tensor  # (B,) largest vertex distance from the origin
    sample: torch.Tensor  # (M,) long: the sample (row in the group) of each transect
    slot: torch.Tensor  # (M,) long: the transect's column in the (B, K) result
    position: torch.Tensor  # (M,) transect positions c
    width: int  # K: columns of the (B, K) result


def _positions(
    clip: bool, window: Window, half: float, offset: float, spacing: float, phase: float
) -> NDArray[np.float64]:
    """The positions of the transects that exist, as :func:`boustro.models.transect_positions`
    computes them (same arithmetic), masked to the window with ``clip``; or the authors'."""
    if window == "authors":
        return np.arange(-0.5, 0.5, spacing) + (phase - 0.5) * spacing
    m = math.ceil(half / spacing) + 1
    k = torch.arange(2 * m, dtype=torch.float64) - m
    c = torch.remainder(torch.tensor(offset, dtype=torch.float64), spacing) + k * spacing
    if clip:
        c = c[(c >= -PAPER_WINDOW) & (c < PAPER_WINDOW)]
    return c.numpy()


def _layouts(
    polygons: Sequence[Polygon],
    angle: NDArray[np.float64],
    offset: NDArray[np.float64],
    spacing: NDArray[np.float64],
    phase: NDArray[np.float64],
    *,
    clip: bool,
    window: Window = "paper",
    eq2: Eq2 = "unit",
    max_width: int = 1 << 18,
) -> list[_Group]:
    """Group the samples by edge count (and bounded size) and flatten their transects.

    ``offset`` is the library's offset (ignored with the authors' window, which uses
    ``phase``). Half-planes come from :func:`boustro.geometry.halfplanes`, exactly as the
    library's models get them for one polygon.
    """
    n = len(polygons)
    edges = np.array([len(p) for p in polygons])
    radius = np.array(
        [float(np.max(np.linalg.norm(p.normalised().vertices, axis=1))) for p in polygons]
    )
    half = np.full(n, PAPER_WINDOW) if clip else radius
    pos = [_positions(clip, window, half[i], offset[i], spacing[i], phase[i]) for i in range(n)]
    counts = np.array([len(c) for c in pos])
    groups: list[_Group] = []
    for e in np.unique(edges):
        members = np.flatnonzero(edges == e)
        members = members[np.argsort(counts[members], kind="stable")]
        start = 0
        while start < len(members):
            stop = start + 1
            while stop < len(members) and (stop + 1 - start) * counts[members[stop]] <= max_width:
                stop += 1
            groups.append(
                _group(
                    [polygons[i] for i in members[start:stop]],
                    members[start:stop],
                    angle,
                    half,
                    radius,
                    pos,
                    counts,
                    eq2,
                )
            )
            start = stop
    return groups


def _group(
    polys: list[Polygon],
    index: NDArray[np.int64],
    angle: NDArray[np.float64],
    half: NDArray[np.float64],
    radius: NDArray[np.float64],
    pos: list[NDArray[np.float64]],
    counts: NDArray[np.int64],
    eq2: Eq2 = "unit",
) -> _Group:
    hp = halfplanes(polys)
    if eq2 == "printed":  # Eq. 2's W = (x1 - x2, y1 - y2): unit normals times |edge|
        scale = torch.ones(hp.offsets.shape, dtype=torch.float64)  # padding stays as it is
        for row, poly in enumerate(polys):
            v = poly.normalised().vertices
            scale[row, : len(v)] = torch.as_tensor(
                np.linalg.norm(np.roll(v, -1, axis=0) - v, axis=1)
            )
        hp = HalfPlanes(hp.normals * scale[..., None], hp.offsets * scale, hp.radius)
    theta = torch.as_tensor(angle[index], dtype=torch.float64)
    across, along, b = _components(torch.cos(theta), torch.sin(theta), hp.normals, hp.offsets)
    k = counts[index]
    sample = torch.as_tensor(np.repeat(np.arange(len(index)), k), dtype=torch.long)
    slot = torch.as_tensor(np.concatenate([np.arange(c) for c in k]), dtype=torch.long)
    position = torch.as_tensor(np.concatenate([pos[i] for i in index]), dtype=torch.float64)
    return _Group(
        index=index,
        across=across,
        along=along,
        b=b,
        half=torch.as_tensor(half[index], dtype=torch.float64),
        radius=torch.as_tensor(radius[index], dtype=torch.float64),
        sample=sample,
        slot=slot,
        position=position,
        width=int(max(1, k.max(initial=1))),
    )


def _scatter(g: _Group, values: torch.Tensor) -> torch.Tensor:
    """Per-transect values ``(M,)`` into the ``(B, K)`` layout, zeros elsewhere."""
    out = torch.zeros(len(g.index), g.width, dtype=values.dtype)
    out[g.sample, g.slot] = values
    return out


# -- the discrete (exact) fitness ------------------------------------------------------------


def _exact_lengths(g: _Group, clip: bool) -> torch.Tensor:
    """Exact chord lengths ``(M,)``: the library's kernel (:func:`boustro.models.exact_chords`)
    at each transect's own position."""
    at = g.sample
    chords = line_chords(g.across[at], g.along[at], g.b[at], g.position[:, None], clip=clip)
    return chords.lengths[:, 0]


def _exact_fitness(g: _Group, clip: bool) -> torch.Tensor:
    """Discrete Eq. 1 per sample ``(B,)`` (``ExactModel`` weights); NaN where none crosses."""
    lengths = _scatter(g, _exact_lengths(g, clip))
    tiny = (1e-12 * g.radius.clamp(min=1e-300))[:, None]
    weights = (lengths > tiny).to(lengths.dtype)
    f = smith_fitness(lengths, weights)
    return torch.where(weights.sum(dim=-1) > 0, f, torch.nan)


def _sample_offsets(samples: Samples, spacing: NDArray[np.float64]) -> NDArray[np.float64]:
    """The library's offset of the authors' grid ``-0.5 + x_offset + k s``."""
    return (samples.phase - 0.5) * spacing - 0.5


def _protocol_spacing(samples: Samples, protocol: Protocol) -> NDArray[np.float64]:
    if protocol.spacing is None:
        return samples.spacing
    return np.full(len(samples), float(protocol.spacing))


def protocol_groups(samples: Samples, protocol: Protocol) -> list[_Group]:
    """The samples' transects under ``protocol`` (see :class:`Protocol`), grouped."""
    spacing = _protocol_spacing(samples, protocol)
    return _layouts(
        samples.polygons,
        samples.angle,
        _sample_offsets(samples, spacing),
        spacing,
        samples.phase,
        clip=protocol.clip,
        window=protocol.window,
        eq2=protocol.eq2,
    )


def exact_fitness_batch(samples: Samples, protocol: Protocol) -> NDArray[np.float64]:
    """The discrete fitness of every sample under ``protocol`` (its ``discrete_clip``); NaN
    where no transect crosses the polygon.

    >>> from boustro.experiments import PROTOCOLS, draw_samples
    >>> exact_fitness_batch(draw_samples(2), PROTOCOLS[0]).round(4).tolist()
    [0.6893, 0.6979]
    """
    out = np.full(len(samples), np.nan)
    clip = bool(protocol.discrete_clip)
    if clip != protocol.clip:  # the whole polygon: the library's grid at the same offset
        protocol = Protocol(
            "discrete", "", clip=False, statistics="weighted", spacing=protocol.spacing
        )
    with torch.no_grad():
        for g in protocol_groups(samples, protocol):
            out[g.index] = _exact_fitness(g, clip).numpy()
    return out
