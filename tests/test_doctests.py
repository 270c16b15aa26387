"""The ``>>>`` examples in boustro's docstrings run, and the public entry points have one."""

from __future__ import annotations

import doctest
import importlib
import pkgutil

import pytest

import boustro

_NAMES = sorted(
    m.name
    for m in pkgutil.walk_packages(boustro.__path__, "boustro.")
    if not m.name.endswith("__main__")
)


def _unique_modules():
    seen, out = set(), []
    for name in ["boustro", *_NAMES]:
        module = importlib.import_module(name)  # an alias shim yields its target: run it once
        if id(module) not in seen:
            seen.add(id(module))
            out.append(module.__name__)
    return out


MODULES = _unique_modules()

# Entry points a newcomer meets first (the README's API tour): each shows a runnable example.
ENTRY_POINTS = [
    "boustro.geometry.Polygon",
    "boustro.geometry.halfplanes",
    "boustro.models.exact_chords",
    "boustro.models.ExactModel",
    "boustro.models.PaperModel",
    "boustro.models.SmoothModel",
    "boustro.objectives.smith_fitness",
    "boustro.objectives.FewestTransects",
    "boustro.objectives.objective_sense",
    "boustro.scoring.score",
    "boustro.optimize.optimize",
    "boustro.optimize.grid_search",
    "boustro.optimize.hybrid",
    "boustro.optimize.exact.global_optimum",
    "boustro.plan.build_plan",
    "boustro.plan.coverage",
    "boustro.plan.plan_region",
    "boustro.learned.learned",
    "boustro.sensors.Camera",
]


def _run(module_name: str) -> doctest.TestResults:
    module = importlib.import_module(module_name)
    finder = doctest.DocTestFinder(exclude_empty=True)
    runner = doctest.DocTestRunner(optionflags=doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE)
    for test in finder.find(module, module.__name__):
        runner.run(test)
    return runner.summarize(verbose=False)


@pytest.mark.parametrize("module_name", MODULES)
def test_docstring_examples_run(module_name):
    results = _run(module_name)
    assert results.failed == 0, f"{results.failed} of {results.attempted} examples failed"


@pytest.mark.parametrize("dotted", ENTRY_POINTS)
def test_entry_point_has_an_example(dotted):
    module_name, _, attr = dotted.rpartition(".")
    obj = getattr(importlib.import_module(module_name), attr)
    examples = doctest.DocTestParser().get_examples(obj.__doc__ or "")
    assert examples, f"{dotted} has no >>> example in its docstring"
