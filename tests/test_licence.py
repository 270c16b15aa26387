"""The project's licence, its NOTICE for the shipped third-party data, and the package metadata
that puts both into the wheel (checked on pyproject.toml: building a wheel here is too slow)."""

from __future__ import annotations

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def test_licence_notice_and_metadata_agree():
    licence = (ROOT / "LICENSE").read_text()
    assert licence.startswith("BSD 3-Clause License")
    assert "Copyright (c) 2026, boustro developers" in licence
    notice = (ROOT / "NOTICE").read_text()
    for name in ("fields2cover_test_field.json", "Envelope.xml", "LICENSE-Fields2Cover"):
        assert name in notice
    assert "Wageningen University" in notice and "BSD 3-Clause" in notice
    pyproject = (ROOT / "pyproject.toml").read_text()
    assert re.search(r'^license = "BSD-3-Clause"$', pyproject, flags=re.M)
    files = re.search(r"^license-files = \[(.*)\]$", pyproject, flags=re.M)
    assert files is not None
    named = re.findall(r'"([^"]+)"', files.group(1))
    assert {"LICENSE", "NOTICE"} <= set(named)
    assert all((ROOT / name).is_file() for name in named)
