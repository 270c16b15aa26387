"""Fuzz test of every area reader: mutated files through ``read_area``/``read_areas`` and
``boustro plan FILE --out``.

Valid files of each text format (GeoJSON, a JSON vertex list, KML, GML, WKT; the QGC ``.plan``
reader does not exist yet) are mutated with a seeded generator: truncated at a random byte,
random bytes flipped, numbers replaced by ``1e308``, ``NaN``, ``Infinity``, deep nesting
(10000 levels), wrong nesting, an empty file, a BOM, a very long line. Every case must end with
exit status 0 and a valid plan, or 2 with exactly one line on stderr starting
``boustro: error:`` and no output file; the readers raise nothing but :class:`BoustroError`.
Each case runs under a 30 s alarm. ``FUZZ_CASES`` cases per format in the default run (seeded,
deterministic), ten times as many with ``-m slow``.
"""

from __future__ import annotations

import json
import random
import re
import signal
from contextlib import contextmanager

import pytest

from boustro.errors import BoustroError
from boustro.io import read_area, read_areas

from .conftest import run_cli

RING = [(5.0, 52.0), (5.002, 52.0), (5.0025, 52.0015), (5.0005, 52.0018)]
_CLOSED = [*RING, RING[0]]
_POS = " ".join(f"{x} {y}" for x, y in _CLOSED)
_KML_COORDS = " ".join(f"{x},{y}" for x, y in _CLOSED)

VALID = {
    ".geojson": json.dumps(
        {
            "type": "FeatureCollection",
            "features": [
                {
                    "type": "Feature",
                    "properties": {"name": "f"},
                    "geometry": {"type": "Polygon", "coordinates": [_CLOSED]},
                }
            ],
        }
    ),
    ".json": json.dumps(RING),
    ".kml": (
        '<?xml version="1.0" encoding="UTF-8"?><kml xmlns="http://www.opengis.net/kml/2.2">'
        "<Placemark><name>f</name><Polygon><outerBoundaryIs><LinearRing><coordinates>"
        f"{_KML_COORDS}</coordinates></LinearRing></outerBoundaryIs></Polygon></Placemark></kml>"
    ),
    ".gml": (
        '<gml:Polygon xmlns:gml="http://www.opengis.net/gml/3.2" srsName="EPSG:4326">'
        "<gml:exterior><gml:LinearRing><gml:posList>"
        + " ".join(f"{y} {x}" for x, y in _CLOSED)
        + "</gml:posList></gml:LinearRing></gml:exterior></gml:Polygon>"
    ),
    ".wkt": "POLYGON ((" + ", ".join(f"{x} {y}" for x, y in _CLOSED) + "))",
}

FUZZ_CASES = 40
_NUMBER = re.compile(rb"-?\d+\.?\d*(?:[eE][-+]?\d+)?")


def _mutate(data: bytes, rng: random.Random) -> bytes:
    """One seeded mutation of ``data``."""
    kind = rng.randrange(10)
    if kind == 0:  # truncated
        return data[: rng.randrange(len(data))]
    if kind == 1:  # random bytes flipped
        out = bytearray(data)
        for _ in range(rng.randint(1, 4)):
            out[rng.randrange(len(out))] = rng.randrange(256)
        return bytes(out)
    if kind in (2, 3):  # a number replaced by a huge or non-finite one
        spans = [m.span() for m in _NUMBER.finditer(data)]
        if not spans:
            return data + b"1e308"
        a, b = rng.choice(spans)
        new = rng.choice([b"1e308", b"-1e308", b"NaN", b"Infinity", b"-Infinity", b"nan", b"1e999"])
        return data[:a] + new + data[b:]
    if kind == 4:  # deep nesting
        depth = 10_000
        return rng.choice([b"[" * depth + b"]" * depth, b"[" * depth, b"<a>" * depth])
    if kind == 5:  # wrong nesting: brackets or tags moved
        out = data
        for _ in range(rng.randint(1, 3)):
            at = rng.randrange(len(out) + 1)
            out = out[:at] + rng.choice([b"[", b"]", b"{", b"}", b"(", b")", b"<", b">"]) + out[at:]
        return out
    if kind == 6:  # empty or blank
        return rng.choice([b"", b" ", b"\n", b"\xef\xbb\xbf"])
    if kind == 7:  # a byte-order mark, or two
        return rng.choice([b"\xef\xbb\xbf", b"\xef\xbb\xbf\xef\xbb\xbf", b"\xff\xfe"]) + data
    if kind == 8:  # a very long line
        at = rng.randrange(len(data) + 1)
        return data[:at] + rng.choice([b" ", b"0", b"1,", b"a"]) * 200_000 + data[at:]
    # a slice duplicated or removed
    a, b = sorted(rng.randrange(len(data) + 1) for _ in range(2))
    return data[:a] + data[a:b] * rng.randint(0, 3) + data[b:]


@contextmanager
def _deadline(seconds: int):
    def expired(signum, frame):
        raise TimeoutError(f"case took over {seconds} s")

    old = signal.signal(signal.SIGALRM, expired)
    signal.alarm(seconds)
    try:
        yield
    finally:
        signal.alarm(0)
        signal.signal(signal.SIGALRM, old)


def _check_case(tmp_path, capsys, ext: str, data: bytes, label: str) -> None:
    path = tmp_path / f"area{ext}"
    path.write_bytes(data)
    out = tmp_path / "out.geojson"
    out.unlink(missing_ok=True)
    with _deadline(30):
        for reader in (read_area, read_areas):
            try:
                reader(path)
            except BoustroError as exc:
                assert "\n" not in str(exc), label
        code, _, err = run_cli(capsys, "plan", path, "--spacing", "20", "--out", out)
    if code == 0:
        doc = json.loads(out.read_text())
        assert doc["type"] == "FeatureCollection", label
    else:
        assert code == 2, label
        lines = err.splitlines()
        assert len(lines) == 1 and lines[0].startswith("boustro: error:"), (label, err[:500])
        assert not out.exists(), label


def _cases(count: int, seed: int):
    rng = random.Random(seed)
    for ext, text in VALID.items():
        data = text.encode()
        for i in range(count):
            yield ext, _mutate(data, rng), f"{ext} case {i} (seed {seed})"


def test_valid_files_plan(tmp_path, capsys):
    for ext, text in VALID.items():
        path = tmp_path / f"area{ext}"
        path.write_text(text)
        assert len(read_area(path).ring) == 4, ext
        code, _, err = run_cli(
            capsys, "plan", path, "--spacing", "20", "--out", tmp_path / "o.geojson"
        )
        assert code == 0, (ext, err)


def test_fuzz_readers(tmp_path, capsys):
    for ext, data, label in _cases(FUZZ_CASES, seed=20):
        _check_case(tmp_path, capsys, ext, data, label)


@pytest.mark.slow
def test_fuzz_readers_slow(tmp_path, capsys):
    for ext, data, label in _cases(10 * FUZZ_CASES, seed=21):
        _check_case(tmp_path, capsys, ext, data, label)


@pytest.mark.parametrize("ext", [".json", ".geojson"])
def test_deeply_nested_json_is_one_error(tmp_path, capsys, ext):
    # Found by the fuzz test: json.loads raised RecursionError (a traceback, exit 1).
    path = tmp_path / f"deep{ext}"
    path.write_text("[" * 10_000)
    for reader in (read_area, read_areas):
        with pytest.raises(BoustroError, match="nested too deeply"):
            reader(path)
    code, _, err = run_cli(capsys, "plan", path, "--spacing", "20", "--out", tmp_path / "o.json")
    assert code == 2 and err.splitlines() == [
        f"boustro: error: {path}: JSON nested too deeply to read"
    ]
    assert not (tmp_path / "o.json").exists()
