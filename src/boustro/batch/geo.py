"""The geo-stack entry: a shapely or GeoJSON geometry in, geometries with
``__geo_interface__`` out (``boustro.plan_area``).

``boustro.plan`` is the planning subpackage (:mod:`boustro.plan`: lanes, coverage, cells), so
the entry is ``boustro.plan_area``. It takes a shapely Polygon or MultiPolygon, any object with
``__geo_interface__`` or a GeoJSON mapping, plans each polygon with
:func:`boustro.mission.plan_area` (the one implementation; a MultiPolygon's parts are planned
one by one) and returns a :class:`GeoPlan`, whose ``lanes``, ``path`` and ``area`` are shapely
geometries and which is itself a GeoJSON FeatureCollection through ``__geo_interface__``
(``geopandas.GeoDataFrame.from_features(plan)``). Coordinates are the input's; a geometry
object carries no CRS, so it is planar unless ``crs`` says otherwise (``crs="EPSG:4326"`` for
longitude/latitude). shapely is imported on use.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

from ..io.read_objects import areas_from_object
from ..io.repair import check_area, repair_area
from ..mission import Mission
from ..mission import plan_area as _plan_one

__all__ = ["GeoPlan", "plan_area"]


@dataclass(frozen=True)
class GeoPlan:
    """The plans of a geometry's polygons, as shapely geometries and GeoJSON.

    Attributes:
        missions: one :class:`~boustro.mission.Mission` per polygon, in order.
    """

    missions: tuple[Mission, ...]

    @property
    def mission(self) -> Mission:
        """The first polygon's mission (the only one for a Polygon)."""
        return self.missions[0]

    @property
    def crs(self) -> str | None:
        """The CRS of the coordinates (the input's: ``"EPSG:n"``, another name, or ``None`` for
        planar), for ``geopandas.GeoDataFrame.from_features(plan, crs=plan.crs)``: GeoJSON,
        and so ``__geo_interface__``, carries none."""
        return self.missions[0].area.crs

    @property
    def lanes(self) -> Any:
        """Every lane (transect) as a shapely MultiLineString, in driving order."""
        import shapely

        return shapely.MultiLineString([t for m in self.missions for t in m.transects])

    @property
    def path(self) -> Any:
        """The path through the waypoints: a LineString, a MultiLineString for several parts."""
        import shapely

        lines = [shapely.LineString(m.waypoints) for m in self.missions]
        return lines[0] if len(lines) == 1 else shapely.MultiLineString(lines)

    @property
    def area(self) -> Any:
        """The area planned, as a shapely Polygon (MultiPolygon for several parts)."""
        import shapely

        polys = [shapely.Polygon(m.area.ring, list(m.area.holes)) for m in self.missions]
        return polys[0] if len(polys) == 1 else shapely.MultiPolygon(polys)

    def summary(self) -> list[dict[str, Any]]:
        """Each mission's :meth:`~boustro.mission.Mission.summary`."""
        return [m.summary() for m in self.missions]

    @property
    def __geo_interface__(self) -> dict[str, Any]:
        """A GeoJSON FeatureCollection: each transect (``kind: "lane"``, ``part``, ``lane``,
        ``pass``: ``"lane"``, or ``"hole"``, ``"boundary"``, ``"headland"`` for an edge of a
        pass, as in the GeoJSON export) and each part's path (``kind: "path"``, ``part`` and
        the part's summary)."""
        features = []
        for part, m in enumerate(self.missions, start=1):
            for k, (t, role) in enumerate(zip(m.transects, m.plan.role(), strict=True), start=1):
                props = {"kind": "lane", "part": part, "lane": k, "pass": role}
                features.append(_feature("LineString", t.tolist(), props))
            props = {"kind": "path", "part": part, **_flat(m.summary())}
            features.append(_feature("LineString", m.waypoints.tolist(), props))
        return {"type": "FeatureCollection", "features": features}


def _feature(kind: str, coords: Any, props: dict[str, Any]) -> dict[str, Any]:
    return {"type": "Feature", "geometry": {"type": kind, "coordinates": coords},
            "properties": props}  # fmt: skip


def _flat(summary: dict[str, Any]) -> dict[str, Any]:
    """The summary's scalar entries (GeoDataFrame columns take no lists)."""
    return {k: v for k, v in summary.items() if not isinstance(v, (list, dict))}


def plan_area(
    geometry: Any,
    spacing: float | Any,
    *,
    crs: Any = None,
    repair: bool = False,
    **options: Any,
) -> GeoPlan:
    """Plan a shapely Polygon/MultiPolygon, a ``__geo_interface__`` object or a GeoJSON mapping.

    Args:
        geometry: the area; a MultiPolygon's (or collection's) polygons are planned one by one.
        spacing: metres on the ground (planar units for planar input), or a sensor.
        crs: the CRS of the coordinates (default planar; a mapping's ``crs`` member is used):
            a name, an EPSG integer or a ``pyproj.CRS`` (``gdf.crs``).
        repair: make an invalid polygon valid first (``boustro plan --repair``); else an invalid
            one is refused with GEOS's reason.
        options: the other arguments of :func:`boustro.mission.plan_area`.

    Example:
        >>> import shapely
        >>> plan = plan_area(shapely.box(0, 0, 100, 60), 10.0)
        >>> plan.lanes.geom_type, len(plan.lanes.geoms), plan.path.geom_type
        ('MultiLineString', 8, 'LineString')
    """
    return GeoPlan(tuple(_plan_each(areas_from_object(geometry, crs), spacing, repair, options)))


def _plan_each(areas: Sequence[Any], spacing: Any, repair: bool, options: dict[str, Any]):
    for area in areas:
        if repair:
            area = repair_area(area)[0]
        else:
            check_area(area)
        yield _plan_one(area, spacing, **options)
