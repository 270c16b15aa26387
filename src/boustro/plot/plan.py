"""Plot a plan: area, swaths, transects, the path with its direction, start and end, scale bar."""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any, NamedTuple

import numpy as np
from numpy.typing import NDArray

from ..plan import Plan, swath_polygons

if TYPE_CHECKING:
    from ..mission import Mission

__all__ = ["nice_length", "plot_plan"]


def nice_length(span: float) -> float:
    """A round length (1, 2 or 5 times a power of ten) of about a fifth of ``span``."""
    if not span > 0:
        return 1.0
    target = span / 5
    power = 10 ** math.floor(math.log10(target))
    for step in (5, 2, 1):
        if step * power <= target:
            return float(step * power)
    return float(power)  # pragma: no cover


def plot_plan(
    plan: Plan | Mission,
    ax: Any = None,
    *,
    swaths: bool = True,
    title: bool = True,
) -> dict[str, Any]:
    """Draw a plan (or a :class:`~boustro.mission.Mission`) in its metric plan frame.

    The area with its holes (and, for a nearly convex area planned on its hull, the hull
    dashed; for a decomposed plan, the cells dashed and labelled with their angles), the sensor
    footprint of each transect (``swaths``), the transects with an arrow in the direction they
    are driven, the connecting moves, the start and end, and a scale bar. Georeferenced missions
    are drawn in metres from the area's south-west corner with an arrow to true north.

    Args:
        plan: a :class:`~boustro.plan.Plan` or a :class:`~boustro.mission.Mission`.
        ax: matplotlib axes (default: a new figure's).
        swaths: shade the footprints.
        title: set a title with the main statistics.

    Returns:
        the artists by name: ``area``, ``holes``, ``cells``, ``hull``, ``swaths``,
        ``transects``, ``path``, ``arrows``, ``start``, ``end``, ``scalebar``, ``north``.
    """
    import matplotlib.pyplot as plt

    if ax is None:
        _, ax = plt.subplots(figsize=(8, 8))
    scene = _scene(plan, ax)
    artists: dict[str, Any] = {}
    _draw_area(scene, artists)
    _draw_path(scene, artists, swaths=swaths)
    _draw_scale(scene, artists)
    _draw_labels(scene, title=title)
    return artists


class _Scene(NamedTuple):
    """What every drawing step needs: the axes, the plan, and the local frame of the figure."""

    ax: Any
    core: Plan
    mission: Mission | None
    area: NDArray[np.float64]
    holes: list[NDArray[np.float64]]
    origin: NDArray[np.float64]
    georeferenced: bool

    def local(self, points: Any) -> NDArray[np.float64]:
        """Points in the figure's frame (metres from the south-west corner if georeferenced)."""
        return np.asarray(points, dtype=np.float64) - self.origin


def _scene(plan: Plan | Mission, ax: Any) -> _Scene:
    mission = None if isinstance(plan, Plan) else plan
    core: Plan = plan if isinstance(plan, Plan) else plan.plan
    georeferenced = mission is not None and not mission.projection.planar
    if mission is not None:
        area = mission.projection.to_plan(mission.area.ring)
        holes = [mission.projection.to_plan(h) for h in mission.area.holes]
    else:
        area = core.polygon.vertices
        holes = [h.vertices for h in core.region.holes] if core.region is not None else []
    origin = area.min(axis=0) if georeferenced else np.zeros(2)
    return _Scene(ax, core, mission, area, holes, origin, georeferenced)


def _draw_area(sc: _Scene, artists: dict[str, Any]) -> None:
    """The area, its holes, the cells of a decomposed plan, the hull of a nearly convex one."""
    ax, local = sc.ax, sc.local
    artists["area"] = ax.fill(
        *local(sc.area).T, facecolor="#d9ead3", edgecolor="#38761d", lw=1.5, label="area", zorder=1
    )[0]
    artists["holes"] = [
        ax.fill(
            *local(h).T, facecolor="white", edgecolor="#38761d", lw=1.2, hatch="xx", zorder=1.5
        )[0]
        for h in sc.holes
    ]
    if sc.holes:
        artists["holes"][0].set_label("hole")
    artists["cells"] = _draw_cells(sc) if len(sc.core.cells) > 1 else []
    if sc.mission is not None and sc.mission.hull_depth > 0:
        vertices = sc.core.polygon.vertices
        hull = np.concatenate([vertices, vertices[:1]])
        artists["hull"] = ax.plot(
            *local(hull).T, ls="--", lw=0.8, color="#38761d", label="convex hull planned"
        )[0]


def _draw_cells(sc: _Scene) -> list[Any]:
    """The cells dashed, each labelled with its number and angle."""
    ax, local = sc.ax, sc.local
    out = []
    for i, cell in enumerate(sc.core.cells):
        for k, ring in enumerate(
            [cell.region.shell.vertices] + [h.vertices for h in cell.region.holes]
        ):
            closed = local(np.concatenate([ring, ring[:1]]))
            line = ax.plot(*closed.T, ls="--", lw=1.0, color="#b45f06", zorder=2.5)[0]
            if i == 0 and k == 0:
                line.set_label("cells")
            out.append(line)
        label = local(cell.region.shell.vertices).mean(axis=0)
        out.append(
            ax.annotate(
                f"{i + 1}: {math.degrees(cell.angle):.0f}°",
                xy=label,
                ha="center",
                va="center",
                fontsize="small",
                color="#b45f06",
                bbox={"boxstyle": "round", "fc": "white", "ec": "#b45f06", "alpha": 0.8},
                zorder=7,
            )
        )
    return out


def _draw_path(sc: _Scene, artists: dict[str, Any], *, swaths: bool) -> None:
    """The footprints, the path, the transects with their direction, the start and the end."""
    from matplotlib.collections import LineCollection, PolyCollection

    ax, local, core = sc.ax, sc.local, sc.core
    if swaths:
        rects = swath_polygons(core).reshape(-1, 4, 2)
        artists["swaths"] = ax.add_collection(
            PolyCollection(
                list(local(rects)), facecolor="#9fc5e8", edgecolor="none", alpha=0.35, zorder=2
            )
        )
    wp = local(core.waypoints)
    artists["path"] = ax.plot(*wp.T, color="0.35", lw=0.8, label="path", zorder=3)[0]
    tr = local(core.transects)
    palette = {"lane": "#1155cc", "boundary": "#cc4125"}  # passes around holes: violet
    colours = [palette.get(role, "#8e7cc3") for role in core.role()]
    artists["transects"] = ax.add_collection(
        LineCollection(list(tr), colors=colours, linewidths=2.0, label="transects", zorder=4)
    )
    arrows = []
    for seg, role in zip(tr, core.role(), strict=True):
        d = seg[1] - seg[0]
        if np.linalg.norm(d) == 0 or role == "boundary":  # boundary passes: many short edges
            continue
        mid = (seg[0] + seg[1]) / 2
        arrows.append(
            ax.annotate(
                "",
                xy=mid + 0.08 * d,
                xytext=mid - 0.08 * d,
                arrowprops={"arrowstyle": "-|>", "color": "#1155cc", "lw": 1.2},
                zorder=5,
            )
        )
    artists["arrows"] = arrows
    artists["start"] = ax.plot(
        *wp[0], marker="^", ms=11, color="#38761d", mec="k", ls="none", label="start", zorder=6
    )[0]
    artists["end"] = ax.plot(
        *wp[-1], marker="s", ms=9, color="#cc0000", mec="k", ls="none", label="end", zorder=6
    )[0]


def _draw_scale(sc: _Scene, artists: dict[str, Any]) -> None:
    """A scale bar and, for geographic missions, an arrow to true north."""
    from mpl_toolkits.axes_grid1.anchored_artists import AnchoredSizeBar

    ax, mission = sc.ax, sc.mission
    ax.set_aspect("equal")
    ax.autoscale_view()
    pts = np.concatenate([sc.local(sc.area), sc.local(sc.core.waypoints)])
    span = float(np.max(np.ptp(pts, axis=0)))
    length = nice_length(float(np.ptp(pts[:, 0])) or span)
    unit = " m" if (sc.georeferenced or mission is not None) else ""
    bar = AnchoredSizeBar(
        ax.transData,
        length,
        f"{length:g}{unit}",
        "lower left",
        pad=0.6,
        borderpad=0.6,
        sep=4,
        frameon=True,
        size_vertical=span / 300,
    )
    bar.patch.set_alpha(0.8)
    artists["scalebar"] = ax.add_artist(bar)
    artists["north"] = None
    if sc.georeferenced and mission is not None and mission.projection.geographic:
        centre = sc.core.polygon.centre
        lon, lat = mission.projection.to_source(centre)
        north = mission.projection.to_plan(np.array([lon, lat + 1e-4])) - centre
        north /= np.linalg.norm(north)
        base = np.array([pts[:, 0].max(), pts[:, 1].max()]) - 0.08 * span * north
        artists["north"] = ax.annotate(
            "N",
            xy=base + 0.06 * span * north,
            xytext=base - 0.0 * north,
            ha="center",
            va="center",
            arrowprops={"arrowstyle": "-|>", "color": "k", "lw": 1.5},
            zorder=7,
        )


def _draw_labels(sc: _Scene, *, title: bool) -> None:
    """Axis labels, the legend and (``title``) a title with the main statistics."""
    ax, core, mission = sc.ax, sc.core, sc.mission
    if sc.georeferenced:
        ax.set_xlabel("easting from the area's south-west corner (m)")
        ax.set_ylabel("northing from the area's south-west corner (m)")
    else:
        ax.set_xlabel("x")
        ax.set_ylabel("y")
    ax.legend(loc="upper left", fontsize="small", framealpha=0.85)
    if not title:
        return
    s = core.stats
    if mission is not None:
        text = (
            f"{mission.name or 'plan'}: {s.n_transects} transects at {mission.spacing:.3g} m, "
            f"bearing {mission.bearing:.1f}°, path {s.path_length:.0f} m"
        )
        if mission.coverage is not None:
            text += f", {100 * mission.coverage.covered_share:.2f}% covered"
        if len(core.cells) > 1:
            text += f", {len(core.cells)} cells"
    else:
        text = (
            f"{s.n_transects} transects at {core.spacing:.3g}, "
            f"angle {math.degrees(core.angle):.1f}°, path {s.path_length:.3g}"
        )
    ax.set_title(text, fontsize="medium")
