"""``boustro._torch``: torch imported on first use, and the chord kernel on numpy arrays.

The import rules themselves (which modules may import torch, which commands run without it)
are checked by ``tests/test_architecture.py``; here: what the stand-in promises.
"""

from __future__ import annotations

import math
import subprocess
import sys

import numpy as np
import pytest
import torch

from boustro._torch import autograd_function, namespace, once_differentiable, set_threads, threads
from boustro.geometry import halfplanes, random_convex_polygon
from boustro.models import exact_chords


def _fresh(code: str) -> str:
    run = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    return run.stdout.strip()


@pytest.mark.parametrize("seed", range(6))
def test_the_chord_kernel_on_numpy_arrays_is_the_kernel_on_tensors(seed):
    rng = np.random.default_rng(seed)
    poly = random_convex_polygon(rng, int(rng.integers(3, 9)))
    spacing = float(rng.uniform(0.03, 0.3))
    for angle in (0.0, math.pi / 2, float(rng.uniform(0, math.pi))):
        offset = float(rng.uniform(-1, 1))
        arrays = exact_chords(halfplanes(poly, tensors=False), angle, offset, spacing)
        tensors = exact_chords(halfplanes(poly), angle, offset, spacing)
        assert all(isinstance(a, np.ndarray) for a in arrays)
        for a, t in zip(arrays, tensors, strict=True):
            shown = t.numpy() > 0 if t is tensors.lengths else slice(None)
            np.testing.assert_allclose(a[shown], t.numpy()[shown], rtol=1e-13, atol=1e-15)
        assert (arrays.lengths > 0).sum() == (tensors.lengths > 0).sum() > 0


def test_namespace():
    assert namespace(np.zeros(2)) is np
    assert namespace(torch.zeros(2)).zeros is torch.zeros


def test_an_autograd_function_defined_lazily_differentiates():
    @autograd_function
    class Cube:
        @staticmethod
        def forward(ctx, x):
            ctx.save_for_backward(x)
            return x**3

        @staticmethod
        def backward(ctx, grad):
            (x,) = ctx.saved_tensors
            return 3 * x**2 * grad

    x = torch.tensor([0.5, -2.0], dtype=torch.float64, requires_grad=True)
    assert torch.autograd.gradcheck(Cube.apply, (x,))


def test_threads_wait_for_torch_and_are_restored():
    out = _fresh(
        "import sys\n"
        "from boustro._torch import threads, torch\n"
        "with threads(1):\n"
        "    before = 'torch' in sys.modules\n"
        "    inside = torch.get_num_threads()\n"
        "print(before, inside)\n"
    )
    before, inside = out.split()
    assert (before, inside) == ("False", "1")
    default = _fresh("import torch; print(torch.get_num_threads())")
    restored = _fresh(
        "from boustro._torch import threads, torch\n"
        "with threads(1):\n"
        "    torch.zeros(1)\n"
        "print(torch.get_num_threads())\n"
    )
    assert restored == default
    assert (
        _fresh(
            "from boustro._torch import set_threads, torch\n"
            "set_threads(1)\n"
            "print(torch.get_num_threads())\n"
        )
        == "1"
    )


def test_threads_and_set_threads_with_torch_imported():
    before = torch.get_num_threads()
    with threads(before + 1):
        assert torch.get_num_threads() == before + 1
    assert torch.get_num_threads() == before
    try:
        set_threads(before + 2)
        assert torch.get_num_threads() == before + 2
    finally:
        torch.set_num_threads(before)


def test_threads_nested_and_after_set_threads_before_torch():
    """An inner block (or one after :func:`set_threads`) keeps the outer wish for torch."""
    out = _fresh(
        "from boustro._torch import set_threads, threads, torch\n"
        "with threads(3):\n"
        "    with threads(1):\n"
        "        pass\n"
        "    inside = torch.get_num_threads()\n"
        "print(inside)\n"
    )
    assert out == "3"
    out = _fresh(
        "from boustro._torch import set_threads, threads, torch\n"
        "set_threads(3)\n"
        "with threads(1):\n"
        "    pass\n"
        "print(torch.get_num_threads())\n"
    )
    assert out == "3"


def test_once_differentiable_is_applied_in_the_call():
    @autograd_function
    class Square:
        @staticmethod
        def forward(ctx, x):
            ctx.save_for_backward(x)
            return x**2

        @staticmethod
        @once_differentiable
        def backward(ctx, grad):
            (x,) = ctx.saved_tensors
            return 2 * x * grad

    x = torch.tensor([0.5, -2.0], dtype=torch.float64, requires_grad=True)
    (g,) = torch.autograd.grad(Square.apply(x).sum(), x, create_graph=True)
    assert torch.equal(g, 2 * x.detach())
    assert not g.requires_grad  # once_differentiable: the backward pass is not differentiated


def test_a_function_naming_the_stand_in_pickles_before_torch_is_imported():
    code = (
        "import sys, cloudpickle\n"
        "from boustro._torch import torch\n"
        "f = lambda n: float(torch.ones(n, dtype=torch.float64).sum())\n"
        "data = cloudpickle.dumps(f)\n"
        "print('torch' in sys.modules, cloudpickle.loads(data)(3))\n"
    )
    assert _fresh(code) == "False 3.0"
