"""Rules that ``boustro plan``, ``boustro batch`` and the page's API share (QA round 19)."""

from __future__ import annotations

import json
import logging

import pytest

import boustro
from boustro.errors import InvalidParameterError
from boustro.io import embedded_field

from .conftest import run_cli


def _closed(ring):
    return ring if ring[0] == ring[-1] else [*ring, ring[0]]


def test_a_turn_time_without_a_speed_is_refused_by_plan_and_batch(capsys, tmp_path):
    """Round 18 refused it in ``plan`` only; ``batch`` ignored it silently."""
    area = tmp_path / "field.geojson"
    area.write_text(
        json.dumps({"type": "Polygon", "coordinates": [_closed(embedded_field().ring.tolist())]})
    )
    for command in (["plan"], ["batch", "--out", tmp_path / "plans.gpkg"]):
        code, _, err = run_cli(capsys, *command, area, "--spacing", "10", "--turn-time", "5")
        assert code == 2 and err.strip() == (
            "boustro: error: --turn-time needs --speed (the duration is path / speed + turns x "
            "turn time)"
        ), command
    assert sorted(p.name for p in tmp_path.iterdir()) == ["field.geojson"]
    with pytest.raises(InvalidParameterError, match="--turn-time needs --speed"):
        boustro.batch(area, tmp_path / "plans.gpkg", spacing=10.0, turn_time=5.0)
    # a speed column gives every field a speed; a turn time of 0 needs none
    boustro.batch(area, tmp_path / "a.gpkg", spacing=10.0, turn_time=0.0, workers=1)


def test_a_far_home_is_called_home(capsys, caplog, tmp_path):
    """Round 18: ``--home`` 165 km away was warned about as "the start"."""
    out = tmp_path / "m.geojson"
    with caplog.at_level(logging.WARNING, logger="boustro"):
        code, _, _ = run_cli(
            capsys, "-q", "plan", "--spacing", "20", "--home", "6,53", "--out", out
        )
    assert code == 0
    assert "home is 1.65e+05 m from the area" in caplog.text and "the start" not in caplog.text
    caplog.clear()
    with caplog.at_level(logging.WARNING, logger="boustro"):
        code, _, _ = run_cli(
            capsys, "-q", "plan", "--spacing", "20", "--start", "6,53", "--out", out
        )
    assert code == 0 and "the start is 1.65e+05 m from the area" in caplog.text
