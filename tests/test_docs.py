"""The product points only inside itself, and describes its layers in one place."""

from __future__ import annotations

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
TEXTS = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]
SOURCES = sorted((ROOT / "src" / "boustro").rglob("*.py"))


def test_no_reference_outside_the_repository():
    pattern = re.compile(r"DESIGN\.md|STYLE\.md|ARCHITECTURE-REVIEW|\.\./shared|shared/data")
    bad = [str(p.relative_to(ROOT)) for p in [*TEXTS, *SOURCES] if pattern.search(p.read_text())]
    assert not bad, f"references to files outside the repository in {bad}"


def test_layers_are_described_only_in_the_architecture_page():
    """Module docstrings name no layer numbers (the order lives in docs/architecture.md)."""
    pattern = re.compile(r"\blayer [0-9]\b|\(layer\b", re.I)
    bad = [str(p.relative_to(ROOT)) for p in SOURCES if pattern.search(p.read_text())]
    assert not bad, f"layer descriptions outside docs/architecture.md: {bad}"


def test_relative_links_in_the_docs_resolve():
    for text in TEXTS:
        for target in re.findall(r"\]\(([^)#:]+)(?:#[^)]*)?\)", text.read_text()):
            assert (text.parent / target).exists(), f"{text.name}: broken link {target}"
