"""Zip archives as read: a KMZ's KML, a zipped Shapefile's files, with limits (stdlib ``zipfile``).

A zip comes from anywhere, and a small one can expand to gigabytes (a "zip bomb"). A member is
read only if its declared size is at most :data:`MAX_MEMBER_BYTES` and its declared compression
ratio at most :data:`MAX_RATIO`, and it is read in a bounded way (a member whose data expand past
the limit is refused even if its header lies); an archive of more than :data:`MAX_MEMBERS`
members is refused. Every refusal is one :class:`~boustro.errors.PolygonFileError` line naming
the file.
"""

from __future__ import annotations

import io
import posixpath
import zipfile

from ..errors import PolygonFileError

__all__ = [
    "MAX_MEMBERS",
    "MAX_MEMBER_BYTES",
    "MAX_RATIO",
    "kml_from_kmz",
    "open_zip",
    "read_member",
    "shapefile_members",
]

#: The largest member read from a zip, uncompressed (50 MB).
MAX_MEMBER_BYTES = 50 * 1024 * 1024
#: The largest compression ratio accepted for a member of more than 1 MB (a zip bomb's is ~1000).
MAX_RATIO = 200
#: The most members an archive may list.
MAX_MEMBERS = 10_000

_SHAPEFILE_PARTS = (".shp", ".shx", ".dbf", ".prj", ".cpg")


def open_zip(data: bytes, where: str) -> zipfile.ZipFile:
    """The archive in ``data``, or one line saying why it is not a readable zip."""
    try:
        archive = zipfile.ZipFile(io.BytesIO(data))
    except (zipfile.BadZipFile, zipfile.LargeZipFile, OSError, ValueError) as exc:
        raise PolygonFileError(f"{where}: not a readable zip archive: {exc}") from None
    if len(archive.infolist()) > MAX_MEMBERS:
        raise PolygonFileError(
            f"{where}: the zip lists {len(archive.infolist())} members, over {MAX_MEMBERS}"
        )
    return archive


def read_member(archive: zipfile.ZipFile, info: zipfile.ZipInfo, where: str) -> bytes:
    """A member's bytes, within the limits (declared size, ratio, and the bytes really read)."""
    here = f"{where}: {info.filename}"
    if info.file_size > MAX_MEMBER_BYTES:
        raise PolygonFileError(
            f"{here}: {info.file_size} bytes uncompressed, over the limit of {MAX_MEMBER_BYTES}"
        )
    if info.file_size > 1024 * 1024 and info.file_size > MAX_RATIO * max(info.compress_size, 1):
        raise PolygonFileError(
            f"{here}: compressed {info.file_size // max(info.compress_size, 1)} to 1, over "
            f"{MAX_RATIO} to 1: refused as a possible zip bomb"
        )
    try:
        with archive.open(info) as fh:
            data = fh.read(MAX_MEMBER_BYTES + 1)
    except (zipfile.BadZipFile, OSError, ValueError, EOFError, NotImplementedError) as exc:
        raise PolygonFileError(f"{here}: cannot read the zip member: {exc}") from None
    except RuntimeError as exc:  # an encrypted member
        raise PolygonFileError(f"{here}: {exc}") from None
    if len(data) > MAX_MEMBER_BYTES:
        raise PolygonFileError(f"{here}: expands past the limit of {MAX_MEMBER_BYTES} bytes")
    return data


def _files(archive: zipfile.ZipFile) -> list[zipfile.ZipInfo]:
    return [i for i in archive.infolist() if not i.is_dir()]


def kml_from_kmz(data: bytes, where: str) -> str | None:
    """The KML text of a KMZ: its ``doc.kml`` at the top level, else its first ``.kml``
    member; ``None`` when the zip holds no ``.kml``."""
    archive = open_zip(data, where)
    kmls = [i for i in _files(archive) if i.filename.lower().endswith(".kml")]
    if not kmls:
        return None
    doc = next((i for i in kmls if i.filename.lower() == "doc.kml"), kmls[0])
    raw = read_member(archive, doc, where)
    try:
        return raw.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        raise PolygonFileError(f"{where}: {doc.filename}: not UTF-8 text: {exc}") from None


def shapefile_members(data: bytes, where: str) -> dict[str, bytes] | None:
    """The files of the first Shapefile in a zip (``.shp``, ``.shx``, ``.dbf``, ``.prj``,
    ``.cpg``, by extension, read within the limits); ``None`` when it holds no ``.shp``."""
    archive = open_zip(data, where)
    files = _files(archive)
    shp = next((i for i in files if i.filename.lower().endswith(".shp")), None)
    if shp is None:
        return None
    stem = shp.filename[:-4].lower()
    out: dict[str, bytes] = {}
    for info in files:
        base, ext = posixpath.splitext(info.filename)
        if base.lower() == stem and ext.lower() in _SHAPEFILE_PARTS:
            out[ext.lower()] = read_member(archive, info, where)
    return out
