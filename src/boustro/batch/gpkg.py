"""The batch's GeoPackage, written with :mod:`sqlite3`: three layers committed together.

A batch appends each group of finished fields to the layers ``lanes``, ``paths`` and ``fields``
in ONE SQLite transaction, so the file always holds a set of complete fields: a field's row in
``fields`` is committed with its lanes and path or not at all, and a run killed at any moment
leaves the last committed state (SQLite's journal rolls an unfinished transaction back when
the file is next opened). While it runs the file is in WAL mode, so that readers (GDAL, QGIS, a
resumed run) see the last commit without waiting; :meth:`Store.close` turns it back into one
plain file. The layers are plain GeoPackage 1.3 feature tables (no spatial index), which GDAL
and every GeoPackage reader open. The run's settings are kept in the table ``boustro_batch``
(not a layer), so that a resumed run can refuse other settings.
"""

from __future__ import annotations

import json
import os
import sqlite3
import struct
import tempfile
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

from ..errors import InvalidParameterError

__all__ = ["LAYERS", "Layer", "Store", "gpkg_geometry"]

#: The GeoPackage's application id ("GPKG") and version (1.3.0).
_APPLICATION_ID = 0x47504B47
_USER_VERSION = 10300


@dataclass(frozen=True)
class Layer:
    """A feature table: its name, geometry type and ``(column, SQL type)`` attributes."""

    name: str
    geometry_type: str
    columns: tuple[tuple[str, str], ...]


#: The three layers of a batch's output, in the order they are written.
LAYERS = (
    Layer(
        "lanes",
        "LINESTRING",
        (("field_id", "INTEGER"), ("name", "TEXT"), ("part", "INTEGER"), ("lane", "INTEGER"),
         ("length_m", "REAL"), ("pass", "TEXT")),
    ),
    Layer(
        "paths",
        "LINESTRING",
        (("field_id", "INTEGER"), ("name", "TEXT"), ("part", "INTEGER"), ("length_m", "REAL")),
    ),
    Layer(
        "fields",
        "GEOMETRY",
        (("field_id", "INTEGER"), ("name", "TEXT"), ("status", "TEXT"), ("error", "TEXT"),
         ("parts", "INTEGER"), ("lanes", "INTEGER"), ("segments", "INTEGER"), ("turns", "INTEGER"),
         ("transect_length_m", "REAL"), ("path_length_m", "REAL"), ("duration_s", "REAL"),
         ("covered_share", "REAL"), ("certified", "BOOLEAN"), ("gap", "REAL"),
         ("method", "TEXT"), ("angle_deg", "REAL"), ("bearing_deg", "REAL"),
         ("spacing_m", "REAL"), ("area_m2", "REAL"), ("seconds", "REAL"), ("cpu_seconds", "REAL"),
         ("mission", "TEXT"),
         ("note", "TEXT")),
    ),
)  # fmt: skip

_SRS_TABLE = """CREATE TABLE gpkg_spatial_ref_sys (srs_name TEXT NOT NULL,
 srs_id INTEGER PRIMARY KEY, organization TEXT NOT NULL, organization_coordsys_id INTEGER NOT
 NULL, definition TEXT NOT NULL, description TEXT)"""
_CONTENTS_TABLE = """CREATE TABLE gpkg_contents (table_name TEXT NOT NULL PRIMARY KEY,
 data_type TEXT NOT NULL, identifier TEXT UNIQUE, description TEXT DEFAULT '',
 last_change DATETIME NOT NULL DEFAULT (strftime('%Y-%m-%dT%H:%M:%fZ','now')), min_x DOUBLE,
 min_y DOUBLE, max_x DOUBLE, max_y DOUBLE, srs_id INTEGER,
 CONSTRAINT fk_gc_r_srs_id FOREIGN KEY (srs_id) REFERENCES gpkg_spatial_ref_sys(srs_id))"""
_GEOMETRY_TABLE = """CREATE TABLE gpkg_geometry_columns (table_name TEXT NOT NULL,
 column_name TEXT NOT NULL, geometry_type_name TEXT NOT NULL, srs_id INTEGER NOT NULL,
 z TINYINT NOT NULL, m TINYINT NOT NULL, CONSTRAINT pk_geom_cols PRIMARY KEY (table_name,
 column_name), CONSTRAINT fk_gc_tn FOREIGN KEY (table_name) REFERENCES
 gpkg_contents(table_name), CONSTRAINT fk_gc_srs FOREIGN KEY (srs_id) REFERENCES
 gpkg_spatial_ref_sys (srs_id))"""
#: The ``fields`` layer's description: this, then the run's settings as JSON.
_SETTINGS = "boustro batch settings: "
_UNDEFINED = [
    ("Undefined cartesian SRS", -1, "NONE", -1, "undefined", "undefined cartesian"),
    ("Undefined geographic SRS", 0, "NONE", 0, "undefined", "undefined geographic"),
]


def gpkg_geometry(wkb: bytes | None, bounds: Sequence[float] | None, srs_id: int) -> bytes | None:
    """A GeoPackage geometry blob: the ``GP`` header (version 0, little-endian, the xy
    envelope ``bounds = (minx, miny, maxx, maxy)``, or none and the empty flag) and the WKB."""
    if wkb is None:
        return None
    if bounds is None or any(b != b for b in bounds):  # empty geometry: no envelope
        return b"GP\x00" + bytes([0b10001]) + struct.pack("<i", srs_id) + wkb
    x0, y0, x1, y1 = bounds
    head = b"GP\x00" + bytes([0b00011]) + struct.pack("<i", srs_id)
    return head + struct.pack("<4d", x0, x1, y0, y1) + wkb


def _srs_row(crs: str | None) -> tuple[str, int, str, int, str, str]:
    """The ``gpkg_spatial_ref_sys`` row of ``crs`` (``None``: undefined cartesian)."""
    if crs is None:
        return _UNDEFINED[0]
    import pyproj

    found = pyproj.CRS.from_user_input(crs)
    try:
        wkt = found.to_wkt("WKT1_GDAL")
    except pyproj.exceptions.CRSError:  # pragma: no cover - a CRS WKT1 cannot state
        wkt = found.to_wkt()
    authority = found.to_authority()
    if authority is not None and authority[0] == "EPSG":
        code = int(authority[1])
        return (found.name, code, "EPSG", code, wkt, "")
    return (found.name, 100000, "NONE", 100000, wkt, "")


class Store:
    """The output GeoPackage of a batch, opened for appending (created if missing).

    Args:
        path: the ``.gpkg`` file.
        crs: the CRS of every geometry (the input's), ``None`` for planar coordinates.
        settings: the run's settings, plain JSON; an existing file made with other settings is
            refused (resuming it would mix two plans).
        label: how messages name the output (default ``path``).
    """

    def __init__(
        self, path: str, crs: str | None, settings: dict[str, Any], label: str | None = None
    ) -> None:
        self.path = path
        self.label = label or path
        text = json.dumps(settings, sort_keys=True)
        if not os.path.exists(path) or os.path.getsize(path) == 0:
            self._create_file(crs, text)
        self.db = sqlite3.connect(path, isolation_level=None, timeout=60)
        try:
            self.db.execute("PRAGMA journal_mode=WAL")
            self.srs_id = self._check(text)
        except BaseException:
            self.db.close()
            raise
        self._extents: dict[str, list[float]] = {}

    def _create_file(self, crs: str | None, settings: str) -> None:
        """A new, empty GeoPackage, made beside ``path`` and renamed into place (a reader
        never sees it half-made)."""
        folder = os.path.dirname(os.path.abspath(self.path))
        if not os.path.isdir(folder):
            raise InvalidParameterError(f"--out {self.label}: no such folder {folder}")
        fd, tmp = tempfile.mkstemp(prefix=f".{os.path.basename(self.path)}.", dir=folder)
        os.close(fd)
        try:
            db = sqlite3.connect(tmp, isolation_level=None)
            try:
                db.execute(f"PRAGMA application_id = {_APPLICATION_ID}")
                db.execute(f"PRAGMA user_version = {_USER_VERSION}")
                self._create(db, crs, settings)
            finally:
                db.close()
            umask = os.umask(0)
            os.umask(umask)
            os.chmod(tmp, 0o666 & ~umask)  # as a new file (mkstemp makes it private)
            os.replace(tmp, self.path)
        except BaseException:
            if os.path.exists(tmp):
                os.unlink(tmp)
            raise

    @staticmethod
    def _create(db: sqlite3.Connection, crs: str | None, settings: str) -> None:
        srs = _srs_row(crs)
        db.execute("BEGIN")
        for sql in (_SRS_TABLE, _CONTENTS_TABLE, _GEOMETRY_TABLE):
            db.execute(sql)
        rows = _UNDEFINED + ([srs] if srs[1] not in (-1, 0) else [])
        db.executemany("INSERT INTO gpkg_spatial_ref_sys VALUES (?, ?, ?, ?, ?, ?)", rows)
        for table in LAYERS:
            columns = "".join(f', "{c}" {t}' for c, t in table.columns)
            db.execute(
                f'CREATE TABLE "{table.name}" (fid INTEGER PRIMARY KEY AUTOINCREMENT, '
                f"geom {table.geometry_type}{columns})"
            )
            db.execute(
                "INSERT INTO gpkg_contents (table_name, data_type, identifier, description, "
                "srs_id) VALUES (?, 'features', ?, ?, ?)",
                (
                    table.name,
                    table.name,
                    _SETTINGS + settings if table.name == "fields" else "",
                    srs[1],
                ),
            )
            db.execute(
                "INSERT INTO gpkg_geometry_columns VALUES (?, 'geom', ?, ?, 0, 0)",
                (table.name, table.geometry_type, srs[1]),
            )
        db.execute("CREATE INDEX fields_field_id ON fields (field_id)")
        db.execute("COMMIT")

    def _check(self, settings: str) -> int:
        try:
            described, srs_id = self.db.execute(
                "SELECT description, srs_id FROM gpkg_contents WHERE table_name = 'fields'"
            ).fetchone()
            if not described.startswith(_SETTINGS):
                raise TypeError
            found = described[len(_SETTINGS) :]
        except (sqlite3.Error, TypeError, AttributeError):
            raise InvalidParameterError(
                f"--out {self.label}: exists and is not the output of a boustro batch; give "
                "another file name (or delete it)"
            ) from None
        for table in LAYERS:
            have = {r[1] for r in self.db.execute(f'PRAGMA table_info("{table.name}")')}
            missing = [c for c, _ in table.columns if c not in have]
            if missing:
                raise InvalidParameterError(
                    f"--out {self.label}: was made by another version of boustro (its "
                    f"{table.name} layer has no {', '.join(missing)} column); give another "
                    "file name"
                )
        if found != settings:
            old, new = json.loads(found), json.loads(settings)
            diff = sorted(k for k in set(old) | set(new) if old.get(k) != new.get(k))
            raise InvalidParameterError(
                f"--out {self.label}: was made with other settings ({', '.join(diff)} differ); "
                "resume it with the same command, or give another file name"
            )
        return int(srs_id)

    def done(self) -> set[int]:
        """The field ids already in the ``fields`` layer (planned or reported)."""
        return {r[0] for r in self.db.execute("SELECT field_id FROM fields")}

    def append(self, rows: Mapping[str, Sequence[tuple[Any, ...]]]) -> None:
        """Append ``{layer: [(geometry blob, *attributes)]}`` in one transaction."""
        for name, layer_rows in rows.items():
            for row in layer_rows:
                self._extend(name, row[0])
        db = self.db
        db.execute("BEGIN IMMEDIATE")
        try:
            for table in LAYERS:
                marks = ", ".join("?" * (len(table.columns) + 1))
                names = ", ".join(["geom"] + [f'"{c}"' for c, _ in table.columns])
                db.executemany(
                    f'INSERT INTO "{table.name}" ({names}) VALUES ({marks})',
                    rows.get(table.name, ()),
                )
            db.execute("COMMIT")
        except BaseException:
            db.execute("ROLLBACK")
            raise

    def _extend(self, name: str, blob: bytes | None) -> None:
        if blob is None or blob[3] & 0b1110 != 0b0010:  # no xy envelope
            return
        x0, x1, y0, y1 = struct.unpack_from("<4d", blob, 8)
        box = self._extents.setdefault(name, [x0, y0, x1, y1])
        box[:] = [min(box[0], x0), min(box[1], y0), max(box[2], x1), max(box[3], y1)]

    def close(self) -> None:
        """Record the layers' extents (this run's, joined to those recorded before) and end WAL
        mode: one plain file again."""
        try:
            for name, (x0, y0, x1, y1) in self._extents.items():
                self.db.execute(
                    "UPDATE gpkg_contents SET min_x = min(coalesce(min_x, ?), ?), "
                    "min_y = min(coalesce(min_y, ?), ?), max_x = max(coalesce(max_x, ?), ?), "
                    "max_y = max(coalesce(max_y, ?), ?), "
                    "last_change = strftime('%Y-%m-%dT%H:%M:%fZ','now') WHERE table_name = ?",
                    (x0, x0, y0, y0, x1, x1, y1, y1, name),
                )
            self.db.execute("PRAGMA journal_mode=DELETE")
        finally:
            self.db.close()
