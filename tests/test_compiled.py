"""The compiled CPU kernels (boustro._compiled) against the tensor code they replace on the CPU.

Every test in test_smooth.py also runs on the compiled path (its ``kernel_path`` fixture); here
the two paths are compared directly on the same inputs, values and gradients, and the switches
that choose between them are checked.
"""

from __future__ import annotations

import math
import subprocess
import sys

import pytest
import torch

import boustro._compiled as compiled
import boustro.smooth as smooth_module
from boustro.fitness import smith_fitness
from boustro.geometry import HalfPlanes, Polygon, halfplanes
from boustro.smooth import smooth_lengths

from .test_smooth import batch

F64 = torch.float64


@pytest.fixture(autouse=True)
def _every_call_compiled(monkeypatch):
    """The kernels for every call size here (by default small calls keep the tensor code)."""
    monkeypatch.setattr(smooth_module, "COMPILED_MIN", 0)


def _both(monkeypatch, run):
    """``run()`` on the compiled path and on the tensor path."""
    results = []
    for flag in (True, False):
        monkeypatch.setattr(smooth_module, "COMPILED", flag)
        results.append(run())
    return results


def test_numba_kernels_are_available():
    # numba is a dependency: on the CPU the compiled path is the one users get
    assert compiled.kernels() is not None
    assert smooth_module._compiled_kernels(torch.zeros(1, dtype=F64), 1) is not None
    assert smooth_module._compiled_kernels(torch.zeros(1, dtype=torch.float32), 1) is not None


def test_other_devices_dtypes_and_small_calls_take_the_tensor_path(monkeypatch):
    assert smooth_module._compiled_kernels(torch.zeros(1, dtype=F64, device="meta"), 1) is None
    assert smooth_module._compiled_kernels(torch.zeros(1, dtype=torch.float16), 1) is None
    monkeypatch.setattr(smooth_module, "COMPILED_MIN", 1000)
    x = torch.zeros(1, dtype=F64)
    assert smooth_module._compiled_kernels(x, 999) is None
    assert smooth_module._compiled_kernels(x, 1000) is not None


def test_small_calls_do_not_import_numba():
    """``boustro plan``'s calls are small: the process never imports numba (0.5 s or more)."""
    code = (
        "import sys, torch;"
        "from boustro.smooth import smooth_lengths;"
        "from boustro.fitness import smith_fitness;"
        "from boustro.geometry import Polygon, halfplanes;"
        "hp = halfplanes(Polygon([(0, 0), (1, 0), (0, 1)]));"
        "th = torch.rand(100, dtype=torch.float64, requires_grad=True);"
        "tl = smooth_lengths(hp, th, 0.0, 0.1);"
        "smith_fitness(tl.lengths, tl.weights).sum().backward();"
        "assert 'numba' not in sys.modules, 'numba imported'"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert out.returncode == 0, out.stderr


@pytest.mark.grad
@pytest.mark.parametrize("clip", [False, True])
@pytest.mark.parametrize("h", [3e-2, 1e-3, 1e-4])
@pytest.mark.parametrize("seed", [21, 22])
def test_compiled_equals_tensor_code(monkeypatch, clip, h, seed):
    """Padded batches of 3-9-gons, per-pair smoothing: lengths, weights, Eq. 1 and its
    gradients with respect to angle, offset and smoothing agree to rounding."""
    hp, theta, offset, s = batch(seed, polygons=10, pairs=3, spacing=0.05)
    smoothing = h * (0.5 + torch.rand(theta.shape, generator=torch.Generator().manual_seed(seed)))

    def run():
        th, off = theta.clone().requires_grad_(True), offset.clone().requires_grad_(True)
        hh = smoothing.to(F64).clone().requires_grad_(True)
        tl = smooth_lengths(hp, th, off, s, smoothing=hh, clip=clip)
        f = smith_fitness(tl.lengths, tl.weights)
        value = f.sum() + tl.lengths.sum() + 0.3 * tl.weights.sum()
        return (tl.lengths, tl.weights, tl.positions, f, *torch.autograd.grad(value, (th, off, hh)))

    fast, reference = _both(monkeypatch, run)
    names = ("lengths", "weights", "positions", "fitness", "d/dangle", "d/doffset", "d/dh")
    for name, x, y in zip(names, fast, reference, strict=True):
        scale = max(float(y.detach().abs().max()), 1.0)
        torch.testing.assert_close(x, y, atol=1e-10 * scale, rtol=1e-10, msg=name)


@pytest.mark.grad
def test_compiled_equals_tensor_code_in_float32(monkeypatch):
    hp64, theta, offset, s = batch(23, polygons=6, pairs=2, spacing=0.05)
    hp = HalfPlanes(hp64.normals.float(), hp64.offsets.float(), hp64.radius)

    def run():
        th = theta.float().requires_grad_(True)
        off = offset.float().requires_grad_(True)
        tl = smooth_lengths(hp, th, off, s, smoothing=1e-2)
        f = smith_fitness(tl.lengths, tl.weights)
        return (tl.lengths, tl.weights, f, *torch.autograd.grad(f.sum(), (th, off)))

    fast, reference = _both(monkeypatch, run)
    for x, y in zip(fast, reference, strict=True):
        assert x.dtype == torch.float32
        torch.testing.assert_close(x, y, atol=2e-4, rtol=2e-4)


def test_large_batch_hits_both_paths_of_the_kernel(monkeypatch):
    """A batch where most transects take the hard path and some the soft one (competing
    bounds near vertices, chords near empty): the compiled kernels' two paths, against the
    tensor code's sparse path."""
    hp = halfplanes(Polygon([(0, 0), (4, 0), (5, 2), (1, 3)]))
    gen = torch.Generator().manual_seed(3)
    theta = torch.rand(3000, generator=gen, dtype=F64) * 2 * math.pi
    offset = torch.rand(3000, generator=gen, dtype=F64) * 0.05

    def run():
        th, off = theta.clone().requires_grad_(True), offset.clone().requires_grad_(True)
        tl = smooth_lengths(hp, th, off, 0.05, smoothing=1e-4)
        f = smith_fitness(tl.lengths, tl.weights)
        soft = ((tl.weights > 0) & (tl.weights < 1)).sum()
        return (tl.lengths, tl.weights, f, *torch.autograd.grad(f.sum(), (th, off))), soft

    (fast, soft), (reference, _) = _both(monkeypatch, run)
    assert soft > 100  # the soft path was taken, and the hard one (3000 x K transects)
    for x, y in zip(fast, reference, strict=True):
        torch.testing.assert_close(x, y, atol=1e-10, rtol=1e-10)


def test_halfplanes_that_need_gradients_take_the_tensor_path():
    hp = halfplanes(Polygon([(0, 0), (1, 0), (1, 1), (0, 1)]))
    normals = hp.normals.clone().requires_grad_(True)
    offsets = hp.offsets.clone().requires_grad_(True)
    tl = smooth_lengths(HalfPlanes(normals, offsets, hp.radius), 0.3, 0.01, 0.1, smoothing=1e-3)
    smith_fitness(tl.lengths, tl.weights).backward()
    assert normals.grad is not None and torch.isfinite(normals.grad).all()
    assert offsets.grad is not None and float(offsets.grad.abs().sum()) > 0


# -- Eq. 1 ---------------------------------------------------------------------------------------
def _fitness_cases():
    gen = torch.Generator().manual_seed(5)
    lengths = torch.rand(4, 6, 9, generator=gen, dtype=F64)
    weights = torch.rand(4, 6, 9, generator=gen, dtype=F64)
    weights[0, 0] = 0.0  # nothing counts: f = b
    lengths[0, 1] = 0.25  # equal lengths: std 0
    weights[0, 1] = 1.0
    weights[0, 2] = (weights[0, 2] > 0.5).to(F64)  # 0/1 weights
    return lengths, weights


@pytest.mark.grad
@pytest.mark.parametrize(("a", "b"), [(0.5, 0.5), (0.2, 1.3), (1.0, 0.0)])
def test_compiled_fitness_equals_the_formula(monkeypatch, a, b):
    lengths, weights = _fitness_cases()

    def run():
        L, w = lengths.clone().requires_grad_(True), weights.clone().requires_grad_(True)
        f = smith_fitness(L, w, a=a, b=b)
        return (f, *torch.autograd.grad((f * torch.linspace(-1, 2, 6, dtype=F64)).sum(), (L, w)))

    fast, reference = _both(monkeypatch, run)
    for name, x, y in zip(("fitness", "d/dlengths", "d/dweights"), fast, reference, strict=True):
        torch.testing.assert_close(x, y, atol=1e-12, rtol=1e-12, msg=name)
    assert float(fast[0][0, 0].detach()) == b


@pytest.mark.grad
def test_compiled_fitness_gradcheck_and_layouts():
    lengths, weights = _fitness_cases()
    # away from the degenerate rows of batch 0 (no weight, zero variance): kinks there
    L = lengths[1:3, :3].clone().requires_grad_(True)
    w = weights[1:3, :3].clone().requires_grad_(True)
    assert torch.autograd.gradcheck(lambda x, y: smith_fitness(x, y, a=0.3, b=0.7), (L, w))
    # a transposed (non-contiguous) input gives the same values and gradient as a contiguous one
    t = lengths[1].T.contiguous().T.requires_grad_(True)
    c = lengths[1].clone().requires_grad_(True)
    assert not t.is_contiguous()
    f_t, f_c = smith_fitness(t, weights[1]), smith_fitness(c, weights[1])
    assert f_t.grad_fn is not None and "Compiled" in type(f_t.grad_fn).__name__
    torch.testing.assert_close(f_t, f_c)
    (g_t,), (g_c,) = torch.autograd.grad(f_t.sum(), t), torch.autograd.grad(f_c.sum(), c)
    torch.testing.assert_close(g_t, g_c)


def test_a_forward_pass_of_eq1_alone_keeps_the_tensor_code():
    lengths, weights = _fitness_cases()
    assert smith_fitness(lengths, weights).grad_fn is None
    with torch.no_grad():
        f = smith_fitness(lengths.clone().requires_grad_(True), weights)
    torch.testing.assert_close(f, smith_fitness(lengths, weights))


def test_environment_switch_turns_the_kernels_off():
    code = (
        "import torch, boustro._compiled as c, boustro.smooth as s;"
        "assert c.kernels() is None;"
        "assert s._compiled_kernels(torch.zeros(1, dtype=torch.float64), 1 << 20) is None;"
        "from boustro.geometry import Polygon, halfplanes;"
        "tl = s.smooth_lengths(halfplanes(Polygon([(0,0),(1,0),(0,1)])), 0.2, 0.0, 0.1);"
        "print(float(tl.lengths.sum()))"
    )
    env = {"BOUSTRO_COMPILED": "0", "PATH": "", "PYTHONPATH": ":".join(sys.path)}
    out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True)
    assert out.returncode == 0, out.stderr
    assert float(out.stdout) > 0


# -- found by review: each was a disagreement between the paths ---------------------------------
@pytest.mark.grad
@pytest.mark.parametrize("k", [500, 10_000])
def test_equal_lengths_have_zero_std_and_its_gradient(monkeypatch, k):
    """Thousands of equal lengths: a plain sum puts the mean ulps off and the variance above
    eps^2; the refined mean makes it exactly 0, and dF/dL = a w / W on both paths."""
    lengths = torch.full((8, k), 0.9567033908212682, dtype=F64)
    weights = torch.ones(8, k, dtype=F64)

    def run():
        L = lengths.clone().requires_grad_(True)
        f = smith_fitness(L, weights, a=0.5, b=0.5)
        return f, torch.autograd.grad(f.sum(), L)[0]

    for f, g in _both(monkeypatch, run):
        torch.testing.assert_close(f, torch.full((8,), 0.5 * 0.9567033908212682 + 0.5, dtype=F64))
        torch.testing.assert_close(g, torch.full((8, k), 0.5 / k, dtype=F64), atol=0, rtol=1e-12)


def test_nan_angle_or_offset_gives_nan_on_both_paths(monkeypatch):
    hp = halfplanes(Polygon([(0, 0), (3, 0), (1, 2)]))
    for theta, offset in (([math.nan, 0.3], [0.01, 0.01]), ([0.3, 0.3], [math.nan, 0.01])):

        def run(theta=theta, offset=offset):
            th = torch.tensor(theta, dtype=F64, requires_grad=True)
            off = torch.tensor(offset, dtype=F64, requires_grad=True)
            tl = smooth_lengths(hp, th, off, 0.05, smoothing=1e-3)
            f = smith_fitness(tl.lengths, tl.weights)
            return (tl.lengths, tl.weights, f, *torch.autograd.grad(f.sum(), (th, off)))

        for results in _both(monkeypatch, run):
            for x in results:
                assert torch.isnan(x[0]).all() and torch.isfinite(x[1]).all()


def test_inplace_change_before_backward_is_an_error():
    base = halfplanes(Polygon([(0, 0), (3, 0), (1, 2)]))
    hp = HalfPlanes(base.normals.clone(), base.offsets.clone(), base.radius)
    th = torch.tensor([0.3, 1.2], dtype=F64, requires_grad=True)
    tl = smooth_lengths(hp, th, 0.01, 0.05, smoothing=1e-2)
    hp.offsets.mul_(1.5)  # the caller reuses the buffer before the backward pass
    with pytest.raises(RuntimeError, match="inplace"):
        (tl.lengths.sum() + tl.weights.sum()).backward()


@pytest.mark.grad
def test_create_graph_differentiates_like_the_tensor_code(monkeypatch):
    hp = halfplanes([Polygon([(0, 0), (3, 0), (1, 2)]), Polygon([(0, 0), (1, 0), (1, 1), (0, 1)])])

    def run():
        th = torch.tensor([0.3, 1.0], dtype=F64, requires_grad=True)
        h = torch.tensor([1e-2, 2e-2], dtype=F64, requires_grad=True)
        tl = smooth_lengths(hp, th, 0.01, 0.05, smoothing=h)
        f = smith_fitness(tl.lengths, tl.weights).sum() + tl.lengths.sum()
        g_th, g_h = torch.autograd.grad(f, (th, h), create_graph=True)
        return (g_th, g_h, *torch.autograd.grad((g_th.sum() + g_h.sum()), (th, h)))

    fast, reference = _both(monkeypatch, run)
    for x, y in zip(fast, reference, strict=True):
        torch.testing.assert_close(x, y, atol=1e-10, rtol=1e-10, equal_nan=True)


def test_a_tensor_weight_that_needs_its_gradient_gets_it():
    lengths, weights = _fitness_cases()
    a = torch.tensor(0.3, dtype=F64, requires_grad=True)
    f = smith_fitness(lengths.requires_grad_(True), weights, a=a, b=0.7)
    (g,) = torch.autograd.grad(f.sum(), a)
    assert float(g) > 0


def test_inference_mode_and_gradients_with_respect_to_the_lengths(monkeypatch):
    """The compiled call under inference_mode; Eq. 1 differentiated w.r.t. the lengths and
    weights themselves (not only the angle) gives the tensor code's gradient."""
    hp, theta, offset, s = batch(32, polygons=4, pairs=3, spacing=0.05)
    with torch.inference_mode():
        tl = smooth_lengths(hp, theta, offset, s, smoothing=1e-3)
        assert torch.isfinite(tl.lengths).all()

    def run():
        th = theta.clone().requires_grad_(True)
        tl = smooth_lengths(hp, th, offset, s, smoothing=1e-3)
        f = smith_fitness(tl.lengths, tl.weights)
        return torch.autograd.grad(f.sum(), (tl.lengths, tl.weights, th))

    for x, y in zip(*_both(monkeypatch, run), strict=True):
        torch.testing.assert_close(x, y, atol=1e-10, rtol=1e-10)
