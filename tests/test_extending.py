"""The worked examples of ``docs/architecture.md``: a new objective, optimiser and format, each
ONE new file in its package plus its test, run exactly as printed.

Each example's source file is written into a temporary folder added to its package's path and
found by the package's registry discovery (what happens to a new file in the source tree); its
test file then runs, and everything is unregistered afterwards.
"""

from __future__ import annotations

import importlib
import inspect
import re
import sys
from pathlib import Path

import pytest

DOC = Path(__file__).resolve().parents[1] / "docs" / "architecture.md"

# Which registry discovers the files of which package.
REGISTRIES = {
    "boustro.objectives": ("boustro.objectives", "OBJECTIVES"),
    "boustro.optimize": ("boustro.optimize", "METHODS"),
    "boustro.io.formats": ("boustro.io.formats", "FORMATS"),
}


def _examples() -> dict[str, list[tuple[str, str]]]:
    """``{example: [(path, code), ...]}`` from the page's ``<!-- example:NAME -->`` sections."""
    text = DOC.read_text(encoding="utf-8")
    out = {}
    for part in text.split("<!-- example:")[1:]:
        name, _, body = part.partition(" -->")
        body = body.split("<!-- example:")[0]
        blocks = re.findall(r"```python\n(# file: (\S+)\n.*?)```", body, flags=re.S)
        out[name.strip()] = [(path, code) for code, path in blocks]
    return out


EXAMPLES = _examples()


def test_the_page_has_the_three_examples():
    assert sorted(EXAMPLES) == ["format", "method", "objective"]
    for name, files in EXAMPLES.items():
        kinds = [path.split("/")[0] for path, _ in files]
        assert kinds == ["src", "tests"], f"example {name}: one source file, then its test"


@pytest.mark.parametrize("name", sorted(EXAMPLES))
def test_worked_example(name, tmp_path, capsys, monkeypatch):
    (src_path, src), (_, test_code) = EXAMPLES[name]
    package = ".".join(Path(src_path).with_suffix("").parts[1:-1])  # src/boustro/x/y.py
    module = f"{package}.{Path(src_path).stem}"
    reg_module, reg_name = REGISTRIES[package]
    registry = getattr(importlib.import_module(reg_module), reg_name)
    pkg = importlib.import_module(package)
    folder = tmp_path / "new_files"
    folder.mkdir()
    (folder / Path(src_path).name).write_text(src, encoding="utf-8")
    before = dict(registry)
    monkeypatch.setattr(pkg, "__path__", [*pkg.__path__, str(folder)])
    try:
        assert module in registry.discover()  # found like a new file of the package
        added = set(registry) - set(before)
        assert added, f"{src_path} registered nothing"
        namespace: dict = {"__name__": f"example_{name}"}
        exec(compile(test_code, f"docs/architecture.md ({name} test)", "exec"), namespace)
        tests = [f for key, f in namespace.items() if key.startswith("test_") and callable(f)]
        assert tests
        fixtures = {"capsys": capsys, "tmp_path": tmp_path, "monkeypatch": monkeypatch}
        for test in tests:
            test(**{p: fixtures[p] for p in inspect.signature(test).parameters})
    finally:
        for key in set(registry) - set(before):
            registry.pop(key)
        sys.modules.pop(module, None)
