"""Benchmark (issue 2): the paper model, batched, against a per-transect Python loop.

Forward + backward of Eq. 1 through the paper's sigmoid model (T = 1000, 1000 points per
transect) on the paper's parallelogram (spacing 0.0559 of the normalised frame), for N (angle,
offset) pairs in ONE batched call, and the same equations evaluated transect by transect in a
plain Python loop. Both are timed in this run; the ratio is per pair.

    python benchmarks/paper_model_batched.py [--pairs 1000] [--loop-pairs 50] [--repeat 3]

The loop baseline is already vectorised over the points and edges of one transect (4000 elements
per operation), so Python overhead is a small share of its time. The batched model wins by
evaluating only the band of points near the polygon's boundary, where the integrand is not
saturated, and summing the saturated rest in closed form (exact to rounding; see
``boustro.models._SigmoidIntegral``).
"""

from __future__ import annotations

import argparse
import math
import time

import torch
import torch.nn.functional as F

from boustro import PaperModel, Polygon, halfplanes, smith_fitness, transect_positions
from boustro.io import PAPER_PARALLELOGRAM, PAPER_SPACING

T, POINTS = 1000.0, 1000


def loop_fitness(hp, theta, offset, spacing):
    """Eq. 2-7 and Eq. 1 one transect at a time (what a straightforward port would do)."""
    u = torch.stack([torch.cos(theta), torch.sin(theta)])
    n = torch.stack([-torch.sin(theta), torch.cos(theta)])
    t = torch.linspace(-hp.radius, hp.radius, POINTS, dtype=torch.float64)
    lengths, weights = [], []
    for c in transect_positions(offset, spacing, hp.radius):
        points = c * n + t[:, None] * u  # (P, 2)
        v = points @ hp.normals.T + hp.offsets  # (P, E)
        p = torch.exp(F.logsigmoid(T * v).sum(dim=1))
        p_sigma = torch.sigmoid(T * (p - 0.5))
        length = torch.trapezoid(p_sigma, dx=2 * hp.radius / (POINTS - 1))
        lengths.append(length)
        weights.append(2 * torch.sigmoid(T * length) - 1)
    return smith_fitness(torch.stack(lengths), torch.stack(weights))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--pairs", type=int, default=1000, help="pairs in the batched call")
    parser.add_argument("--loop-pairs", type=int, default=50, help="pairs timed in the loop")
    parser.add_argument("--repeat", type=int, default=3, help="best of this many runs")
    parser.add_argument(
        "--threads",
        type=int,
        default=1,
        help="torch threads (default 1: on a shared 2-core machine two threads contend and the "
        "timings swing by 10x)",
    )
    args = parser.parse_args()
    torch.set_num_threads(args.threads)

    poly = Polygon(PAPER_PARALLELOGRAM)
    hp = halfplanes(poly)
    spacing = PAPER_SPACING / poly.diameter
    gen = torch.Generator().manual_seed(0)
    thetas = torch.rand(args.pairs, generator=gen, dtype=torch.float64) * math.pi
    offsets = torch.rand(args.pairs, generator=gen, dtype=torch.float64) * spacing
    model = PaperModel(temperature=T, points_per_transect=POINTS)

    def batched() -> torch.Tensor:
        theta = thetas.clone().requires_grad_(True)
        offset = offsets.clone().requires_grad_(True)
        tl = model(hp, theta, offset, spacing)
        smith_fitness(tl.lengths, tl.weights).sum().backward()
        return theta.grad

    def looped() -> torch.Tensor:
        grads = []
        for i in range(args.loop_pairs):
            theta = thetas[i].clone().requires_grad_(True)
            offset = offsets[i].clone().requires_grad_(True)
            loop_fitness(hp, theta, offset, spacing).backward()
            grads.append(theta.grad)
        return torch.stack(grads)

    # Same equations, same numbers:
    g_batched, g_loop = batched(), looped()
    max_diff = float((g_batched[: args.loop_pairs] - g_loop).abs().max())

    def best(fn) -> float:
        times = []
        for _ in range(args.repeat):
            t0 = time.perf_counter()
            fn()
            times.append(time.perf_counter() - t0)
        return min(times)

    t_batched, t_loop = best(batched), best(looped)
    per_batched = t_batched / args.pairs
    per_loop = t_loop / args.loop_pairs
    print(f"torch {torch.__version__}, threads {torch.get_num_threads()}")
    print(f"parallelogram, spacing {spacing:.4f} (normalised), T={T:g}, {POINTS} points/transect")
    print(f"max |grad batched - grad loop| over {args.loop_pairs} pairs: {max_diff:.2e}")
    print(f"batched: {args.pairs} pairs in {t_batched:.3f} s = {per_batched * 1e3:.3f} ms/pair")
    print(f"loop:    {args.loop_pairs} pairs in {t_loop:.3f} s = {per_loop * 1e3:.3f} ms/pair")
    print(f"speed-up per pair: {per_loop / per_batched:.1f}x (target >= 20x)")


if __name__ == "__main__":
    main()
