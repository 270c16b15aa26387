"""The paper's figures (Figs. 2-5) on its parallelogram: their data and their plots."""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

import numpy as np
import torch
import torch.nn.functional as F
from numpy.typing import NDArray

from ..geometry import Polygon, halfplanes
from ._common import progress_bar
from .layouts import _exact_fitness, _layouts
from .paper_batched import _soft_fitness
from .samples import Statistics, Trapezoid

__all__ = [
    "FIGURES",
    "PARALLELOGRAM",
    "PARALLELOGRAM_SPACING",
    "fig_fitness_vs_angle",
    "fig_indicator",
    "fig_surface_angle_offset",
    "fig_surface_angle_temperature",
    "figure_data",
]


#: The paper's Figure 1 parallelogram and the spacing of the authors' scripts (its own units:
#: 0.0559 of the normalised frame, 18 transects in the window).
PARALLELOGRAM: tuple[tuple[float, float], ...] = ((8, 4), (8, 10), (4, 8), (4, 2))
PARALLELOGRAM_SPACING = 0.5


def _parallelogram() -> tuple[Polygon, float]:
    """The paper's parallelogram in the normalised frame and its spacing there (0.0559)."""
    poly = Polygon(PARALLELOGRAM)
    return poly.normalised(), PARALLELOGRAM_SPACING / poly.diameter


def _parallelogram_fitness(
    angle: NDArray[np.float64],
    phase: NDArray[np.float64],
    temperature: float | None,
    points: int = 1000,
) -> NDArray[np.float64]:
    """Eq. 1 of the paper's model (or the exact one, ``temperature=None``) of the
    parallelogram at each (angle, phase), the authors' script's protocol: transects
    ``arange(-0.5, 0.5, s) + x_offset`` (18 of them), window ``[-0.5, 0.5]``, their weighting."""
    poly, s = _parallelogram()
    n = len(angle)
    spacing = np.full(n, s)
    groups = _layouts(
        [poly] * n,
        np.asarray(angle, dtype=np.float64),
        (phase - 0.5) * s - 0.5,
        spacing,
        np.asarray(phase, dtype=np.float64),
        clip=True,
        window="authors",
    )
    out = np.full(n, np.nan)
    with torch.no_grad():
        for g in groups:
            if temperature is None:
                out[g.index] = _exact_fitness(g, True).numpy()
            else:
                v: tuple[Statistics, Trapezoid] = ("paper", "authors")
                out[g.index] = _soft_fitness(g, temperature, points, [v])[v].numpy()
    return out


def _indicator(
    angle: float, temperature: float, n_points: int
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """Eq. 5 along the parallelogram's 18 transects at ``angle``, x_offset 0: the points'
    ``(x, y)`` in the normalised frame ``(K, n_points)`` each, the values, and the outline."""
    poly, s = _parallelogram()
    hp = halfplanes(poly)
    c = torch.as_tensor(np.arange(-0.5, 0.5, s), dtype=torch.float64)
    t = torch.linspace(-0.5, 0.5, n_points, dtype=torch.float64)
    temp = torch.tensor(float(temperature), dtype=torch.float64)
    u = torch.tensor([math.cos(angle), math.sin(angle)], dtype=torch.float64)
    nrm = torch.tensor([-math.sin(angle), math.cos(angle)], dtype=torch.float64)
    pts = c[:, None, None] * nrm + t[None, :, None] * u  # (K, P, 2)
    v = pts @ hp.normals.T + hp.offsets  # (K, P, E)
    p = torch.exp(F.logsigmoid(temp * v).sum(dim=-1))  # Eq. 4
    p_sigma = torch.sigmoid(temp * (p - 0.5))  # Eq. 5
    outline = np.vstack([poly.vertices, poly.vertices[:1]])
    return pts[..., 0].numpy(), pts[..., 1].numpy(), p_sigma.numpy(), outline


def figure_data(quick: bool = False, *, progress: bool = False) -> dict[str, Any]:
    """Everything the four figures plot (JSON-ready after ``tolist``), on the parallelogram.

    Angles are the library's transect direction in degrees; ``x_offset`` is the authors' offset
    of their transects ``arange(-0.5, 0.5, s) + x_offset``, in the parallelogram's units.
    """
    _, s = _parallelogram()
    scale = Polygon(PARALLELOGRAM).diameter
    n_angle = 36 if quick else 180
    out: dict[str, Any] = {"spacing_normalised": s, "spacing": PARALLELOGRAM_SPACING}
    with progress_bar(4, "figures", progress, unit="fig") as bar:
        fig2 = {}
        for temp in (17.0, 100.0):
            x, y, z, outline = _indicator(math.pi / 2, temp, 100 if quick else 400)
            fig2[temp] = {"x": x, "y": y, "p_sigma": z}
        out["indicator"] = {"angle_deg": 90.0, "outline": outline, "by_temperature": fig2}
        bar.update(1)

        angles = np.arange(4 * n_angle) * (180.0 / (4 * n_angle))
        half = np.full(len(angles), 0.5)
        out["fitness_vs_angle"] = {
            "angle_deg": angles,
            "temperature": 10000.0,
            "points_per_transect": 1000,
            "paper_model": _parallelogram_fitness(np.radians(angles), half, 10000.0),
            "exact": _parallelogram_fitness(np.radians(angles), half, None),
        }
        bar.update(1)

        a = np.arange(n_angle) * (180.0 / n_angle)
        phases = (np.arange(8 if quick else 24) + 0.5) / (8 if quick else 24)
        aa, pp = np.meshgrid(a, phases, indexing="ij")
        f = _parallelogram_fitness(np.radians(aa.ravel()), pp.ravel(), 10000.0)
        out["surface_angle_offset"] = {
            "angle_deg": a,
            "x_offset": (phases - 0.5) * s * scale,
            "temperature": 10000.0,
            "points_per_transect": 1000,
            "fitness": f.reshape(aa.shape),
        }
        bar.update(1)

        temps = np.linspace(1.0, 200.0, 10 if quick else 50)
        rows = [
            _parallelogram_fitness(np.radians(a), np.full(len(a), 0.5), float(t)) for t in temps
        ]
        out["surface_angle_temperature"] = {
            "angle_deg": a,
            "temperature": temps,
            "points_per_transect": 1000,
            "fitness": np.stack(rows),
        }
        bar.update(1)
    return out


_SUBTITLE = "paper's parallelogram, spacing 0.5 (18 transects), window [-0.5, 0.5]"


def fig_indicator(data: dict[str, Any]) -> Any:
    """Fig. 2: Eq. 5's soft indicator along the transects at T = 17 and T = 100."""
    from matplotlib.figure import Figure
    from mpl_toolkits.mplot3d import Axes3D  # noqa: F401  (registers the 3-D projection)

    d = data["indicator"]
    fig = Figure(figsize=(12, 5.2), layout="constrained")
    for k, (temp, v) in enumerate(sorted(d["by_temperature"].items())):
        ax = fig.add_subplot(1, 2, k + 1, projection="3d")
        for x, y, z in zip(v["x"], v["y"], v["p_sigma"], strict=True):
            ax.plot(x, y, z, lw=1.0, color="tab:blue")
        o = d["outline"]
        ax.plot(o[:, 0], o[:, 1], np.zeros(len(o)), color="k", lw=1.2)
        ax.set_xlabel("x (normalised units)")
        ax.set_ylabel("y (normalised units)")
        ax.set_zlabel("soft indicator $P_\\sigma$ (dimensionless)")
        ax.set_zlim(0, 1)
        ax.set_title(f"Temperature = {temp:g}")
    fig.suptitle(
        f"Fig. 2: Eq. 5 along the transects (direction {d['angle_deg']:g}°, x_offset 0); "
        + _SUBTITLE,
        fontsize=10,
    )
    return fig


def fig_fitness_vs_angle(data: dict[str, Any]) -> Any:
    """Fig. 5: fitness against angle at x_offset 0, T = 10000, with the exact fitness."""
    from matplotlib.figure import Figure

    d = data["fitness_vs_angle"]
    fig = Figure(figsize=(8, 4.5), layout="constrained")
    ax = fig.add_subplot()
    ax.plot(
        d["angle_deg"],
        d["paper_model"],
        lw=1.2,
        label=f"paper's model, T = {d['temperature']:g}, {d['points_per_transect']} points",
    )
    ax.plot(d["angle_deg"], d["exact"], lw=1.0, ls="--", color="k", label="exact (discrete)")
    ax.set_xlabel("transect direction θ (degrees)")
    ax.set_ylabel("fitness, Eq. 1 (dimensionless)")
    ax.set_xlim(0, 180)
    ax.legend()
    ax.set_title("Fig. 5: fitness against angle, x_offset 0\n" + _SUBTITLE, fontsize=10)
    return fig


def _surface(
    x: Any, y: Any, z: Any, xlabel: str, ylabel: str, title: str, vmax: float | None = None
) -> Any:
    from matplotlib.figure import Figure

    fig = Figure(figsize=(8, 5), layout="constrained")
    ax = fig.add_subplot()
    mesh = ax.pcolormesh(x, y, z, shading="nearest", cmap="viridis", vmax=vmax)
    extend = "max" if vmax is not None and np.nanmax(z) > vmax else "neither"
    fig.colorbar(mesh, ax=ax, label="fitness, Eq. 1 (dimensionless)", extend=extend)
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    ax.set_title(title, fontsize=10)
    return fig


def fig_surface_angle_offset(data: dict[str, Any]) -> Any:
    """Fig. 3: the fitness surface over angle x offset at T = 10000."""
    d = data["surface_angle_offset"]
    return _surface(
        d["angle_deg"],
        d["x_offset"],
        d["fitness"].T,
        "transect direction θ (degrees)",
        "x_offset (parallelogram units)",
        f"Fig. 3: paper's model over angle x offset, T = {d['temperature']:g}\n" + _SUBTITLE,
    )


def fig_surface_angle_temperature(data: dict[str, Any]) -> Any:
    """Fig. 4: the fitness surface over angle x temperature (T up to 200), x_offset 0."""
    d = data["surface_angle_temperature"]
    # The authors' weighting of the statistics lifts the fitness above 1 at the lowest
    # temperatures (Table I's first row); the colours stop at 1 so the rest stays readable.
    return _surface(
        d["angle_deg"],
        d["temperature"],
        d["fitness"],
        "transect direction θ (degrees)",
        "temperature T (dimensionless)",
        "Fig. 4: paper's model over angle x temperature, x_offset 0 (colours capped at 1)\n"
        + _SUBTITLE,
        vmax=1.0,
    )


#: The figures ``boustro reproduce figures`` writes: file name -> function of :func:`figure_data`.
FIGURES: dict[str, Callable[[dict[str, Any]], Any]] = {
    "fig2_indicator.png": fig_indicator,
    "fig3_surface_angle_offset.png": fig_surface_angle_offset,
    "fig4_surface_angle_temperature.png": fig_surface_angle_temperature,
    "fig5_fitness_vs_angle.png": fig_fitness_vs_angle,
}
