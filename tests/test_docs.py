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


def _slug(heading: str) -> str:
    """GitHub's anchor of a Markdown heading: lower case, punctuation dropped, spaces to hyphens."""
    return re.sub(r"[^\w\- ]", "", heading.strip().lower()).replace(" ", "-")


def _anchors(path: Path) -> set[str]:
    text = re.sub(r"```.*?```", "", path.read_text(), flags=re.S)  # no headings in code blocks
    return {_slug(m) for m in re.findall(r"^#{1,6} +(.+?) *$", text, flags=re.M)}


def test_slug_matches_github():
    slug = _slug("Eq. 1 certified at scale (`eq1_scale.py`)")
    assert slug == "eq-1-certified-at-scale-eq1_scalepy"
    assert _slug("Issue 17's target: a 100-vertex field in under 2 s") == (
        "issue-17s-target-a-100-vertex-field-in-under-2-s"
    )


def test_anchor_links_in_the_docs_resolve():
    """Every `page.md#anchor` (and `#anchor` within a page) link names a heading of that page."""
    bad = []
    for text in TEXTS:
        for target, anchor in re.findall(r"\]\(([^)#:]*)#([^)]+)\)", text.read_text()):
            page = (text.parent / target) if target else text
            if page.suffix == ".md" and anchor not in _anchors(page):
                bad.append(f"{text.name}: {target}#{anchor}")
    assert not bad, f"links to missing headings: {bad}"
