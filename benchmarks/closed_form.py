"""Benchmark: the smooth closed form against the paper's sigmoid integral, fidelity and speed.

Fidelity follows the protocol of the paper's Table I: random convex polygons with 3 to 9 sides
(Valtr's algorithm: uniform random convex polygons), a random angle in [0, 2 pi), a spacing
uniform in (0, 1/3) of the normalised frame (draws below 1e-3 are redrawn, as in the authors'
script) and an offset uniform in [0, spacing). Every model is scored on the SAME samples, and the
error is ``mean |fitness(model) - fitness(exact)|`` (Eq. 1, a = b = 0.5) at:

* the closed form at smoothing ``h = 1/T`` for ``T = 1 .. 10^6``;
* the paper model at ``T = 1 .. 10^4`` and 100, 1000, 10000 points per transect.

Speed: forward + backward of Eq. 1 with respect to (angle, offset), batched over pairs, on the
paper's parallelogram (Figure 1) at its spacing (0.5 units; 18 transects cross it), for the
closed form and for the paper model at 1000 points per transect, each at several batch sizes;
the ratios use each model's fastest batch, against the paper model evaluated at every point and
against its band evaluation (the default, same values to rounding). On the CPU the closed form
runs boustro's compiled kernels (``boustro._compiled``, numba), the path every CPU user gets;
``--tensor`` times the tensor code instead (the path on other devices).

Usage::

    python benchmarks/closed_form.py               # 1000 samples a cell
    python benchmarks/closed_form.py --samples 200
    python benchmarks/closed_form.py --quick       # smoke run, a few seconds
"""

from __future__ import annotations

import argparse
import math
import platform
import time
from datetime import datetime, timezone

import numpy as np
import torch

from boustro import _compiled, smooth
from boustro.fitness import smith_fitness
from boustro.geometry import HalfPlanes, Polygon, halfplanes
from boustro.io import PAPER_PARALLELOGRAM, PAPER_SPACING
from boustro.models import ExactModel, PaperModel, paper_lengths, transect_positions
from boustro.smooth import DEFAULT_SMOOTHING, SmoothModel

#: The paper's Table I (mean |differentiable - discrete| fitness, 1000 samples a cell).
PUBLISHED = {
    1: (0.50798, 0.50795, 0.50408),
    10: (0.08480, 0.08369, 0.08367),
    100: (0.03090, 0.03001, 0.03167),
    1000: (0.00374, 0.00271, 0.00306),
    10000: (0.00203, 0.00055, 0.00016),
}
PAPER_TEMPERATURES = (1.0, 10.0, 100.0, 1000.0, 10000.0)
POINTS = (100, 1000, 10000)
SMOOTH_TEMPERATURES = (1.0, 10.0, 100.0, 1e3, 1e4, 1e5, 1e6)
MIN_SPACING = 1e-3
#: Elements (temperatures x transects x points x edges) per paper-model call.
MAX_ELEMENTS = 20_000_000


# -- random convex polygons (Valtr 1995) ---------------------------------------------------------
def _valtr_components(rng: np.random.Generator, n: int) -> np.ndarray:
    """Random increments that sum to 0: the split of n sorted uniforms into two chains."""
    x = np.sort(rng.random(n))
    lo, hi = x[0], x[-1]
    out = []
    last_a, last_b = lo, lo
    for v in x[1:-1]:
        if rng.random() < 0.5:
            out.append(v - last_a)
            last_a = v
        else:
            out.append(last_b - v)
            last_b = v
    out.append(hi - last_a)
    out.append(last_b - hi)
    return np.asarray(out)


def random_convex_polygon(rng: np.random.Generator, n: int) -> Polygon:
    """A uniformly random convex polygon with ``n`` vertices (Valtr's algorithm)."""
    while True:
        dx = _valtr_components(rng, n)
        dy = _valtr_components(rng, n)
        rng.shuffle(dy)
        vec = np.stack([dx, dy], axis=1)
        vec = vec[np.argsort(np.arctan2(vec[:, 1], vec[:, 0]))]
        pts = np.cumsum(vec, axis=0)
        try:
            poly = Polygon(pts)
        except ValueError:
            continue
        if len(poly) == n and poly.is_convex:
            return poly


def sample_cases(n_samples: int, seed: int) -> list[tuple[Polygon, float, float, float]]:
    """``(normalised polygon, theta, offset, spacing)`` in the Table I protocol."""
    rng = np.random.default_rng(seed)
    cases = []
    while len(cases) < n_samples:
        poly = random_convex_polygon(rng, int(rng.integers(3, 10))).normalised()
        spacing = rng.random() / 3
        if spacing < MIN_SPACING:
            continue
        theta = rng.random() * 2 * math.pi
        offset = rng.random() * spacing
        cases.append((poly, theta, offset, spacing))
    return cases


# -- the paper model, chunked over interleaved sub-grids -------------------------------------------
def paper_chunked(
    hp: HalfPlanes,
    theta: float,
    offset: float,
    spacing: float,
    temperatures: torch.Tensor,
    points: int,
    clip: bool,
) -> tuple[torch.Tensor, torch.Tensor]:
    """Paper-model lengths and weights ``(T, K)`` for several temperatures at once.

    When one call would hold more than ``MAX_ELEMENTS`` elements, the grid of spacing ``s`` is
    split into ``g`` interleaved grids of spacing ``g s`` (offsets ``d + i s``) and the
    candidates of the original grid are gathered back, so the result is the same set of
    transects as one call (the fitness does not depend on their order).
    """
    n_t = len(temperatures)
    th = torch.full((n_t,), theta, dtype=torch.float64)
    off = torch.full((n_t,), offset, dtype=torch.float64)
    half = 0.5 if clip else hp.radius
    full = transect_positions(torch.tensor(offset, dtype=torch.float64), spacing, half)
    n_edges = hp.normals.shape[-2]
    groups = max(1, math.ceil(n_t * len(full) * points * n_edges / MAX_ELEMENTS))
    if groups == 1:
        tl = paper_lengths(
            hp, th, off, spacing, temperature=temperatures, points_per_transect=points, clip=clip
        )
        return tl.lengths, tl.weights
    lengths, weights, count = [], [], 0
    lo, hi = float(full[0]) - spacing / 2, float(full[-1]) + spacing / 2
    for i in range(groups):
        tl = paper_lengths(
            hp,
            th,
            off + i * spacing,
            groups * spacing,
            temperature=temperatures,
            points_per_transect=points,
            clip=clip,
        )
        keep = (tl.positions[0] >= lo) & (tl.positions[0] <= hi)
        lengths.append(tl.lengths[:, keep])
        weights.append(tl.weights[:, keep])
        count += int(keep.sum())
    if count != len(full):
        raise RuntimeError(f"sub-grids gave {count} transects, expected {len(full)}")
    return torch.cat(lengths, dim=-1), torch.cat(weights, dim=-1)


# -- fidelity ------------------------------------------------------------------------------------
def fidelity(
    n_samples: int, seed: int, clip: bool, statistics: str, points: tuple[int, ...]
) -> tuple[dict[float, np.ndarray], dict[tuple[float, int], np.ndarray], dict[str, float]]:
    """Absolute fitness errors per sample: closed form per T, paper model per (T, points)."""
    cases = sample_cases(n_samples, seed)
    smooth_err: dict[float, list[float]] = {t: [] for t in SMOOTH_TEMPERATURES}
    paper_err: dict[tuple[float, int], list[float]] = {
        (t, p): [] for t in PAPER_TEMPERATURES for p in points
    }
    seconds = {"exact": 0.0, "closed form": 0.0, **{f"paper {p}": 0.0 for p in points}}
    temps = torch.tensor(PAPER_TEMPERATURES, dtype=torch.float64)
    exact = ExactModel(clip=clip)
    with torch.no_grad():
        for poly, theta, offset, spacing in cases:
            hp = halfplanes(poly, normalise=False)  # already normalised
            th = torch.tensor(theta, dtype=torch.float64)
            off = torch.tensor(offset, dtype=torch.float64)
            t0 = time.perf_counter()
            tl = exact(hp, th, off, spacing)
            f_exact = float(smith_fitness(tl.lengths, tl.weights))
            seconds["exact"] += time.perf_counter() - t0
            t0 = time.perf_counter()
            for t in SMOOTH_TEMPERATURES:
                tl = SmoothModel.from_temperature(t, clip=clip)(hp, th, off, spacing)
                f = float(smith_fitness(tl.lengths, tl.weights, statistics=statistics))
                smooth_err[t].append(abs(f - f_exact))
            seconds["closed form"] += time.perf_counter() - t0
            for p in points:
                t0 = time.perf_counter()
                lengths, weights = paper_chunked(hp, theta, offset, spacing, temps, p, clip)
                f = smith_fitness(lengths, weights, statistics=statistics)
                for t, value in zip(PAPER_TEMPERATURES, f.tolist(), strict=True):
                    paper_err[(t, p)].append(abs(value - f_exact))
                seconds[f"paper {p}"] += time.perf_counter() - t0
    return (
        {k: np.asarray(v) for k, v in smooth_err.items()},
        {k: np.asarray(v) for k, v in paper_err.items()},
        seconds,
    )


PAPER_BAND = "paper, 1000 points/transect (band evaluation, the default)"
PAPER_FULL = "paper, 1000 points/transect, every point (band=False)"


# -- speed ---------------------------------------------------------------------------------------
def forward_backward(model, hp: HalfPlanes, spacing: float, pairs: int):
    """A closure running one batched forward + backward of Eq. 1 over ``pairs`` pairs."""
    gen = torch.Generator().manual_seed(0)
    theta0 = torch.rand(pairs, generator=gen, dtype=torch.float64) * math.pi
    offset0 = torch.rand(pairs, generator=gen, dtype=torch.float64) * spacing

    def run() -> None:
        theta = theta0.clone().requires_grad_(True)
        offset = offset0.clone().requires_grad_(True)
        tl = model(hp, theta, offset, spacing)
        smith_fitness(tl.lengths, tl.weights).sum().backward()
        if not (torch.isfinite(theta.grad).all() and torch.isfinite(offset.grad).all()):
            raise RuntimeError(f"non-finite gradient from {model}")

    return run


def speed(quick: bool) -> list[tuple[str, int, float]]:
    """Best-of-runs seconds per pair, each model at several batch sizes (a model's cost per pair
    depends on the batch: fixed costs are shared, band gathering pays off on large calls).

    Rounds of short bursts: in each round every setup runs a few times in a row (its steady
    state: caches warm with its own data, not with the previous setup's, which for the paper
    model at every point is gigabytes), and the rounds repeat over all setups, so a machine
    that gets busier or quieter during the benchmark affects them alike.
    """
    poly = Polygon(PAPER_PARALLELOGRAM)
    hp = halfplanes(poly)
    spacing = PAPER_SPACING / poly.diameter
    rounds, burst = (2, 3) if quick else (4, 4)
    closed = f"closed form, h = {DEFAULT_SMOOTHING:g}"
    models = [
        (closed, SmoothModel(), (1, 64, 4096) if quick else (1, 64, 1024, 4096, 16384)),
        (PAPER_BAND, PaperModel(1e4, 1000), (16, 64) if quick else (64, 256, 1024)),
        (PAPER_FULL, PaperModel(1e4, 1000, band=False), (16,) if quick else (16, 64)),
        ("paper, 100 points/transect", PaperModel(1e4, 100), (64,) if quick else (64, 1024)),
    ]
    setups = [(label, model, pairs) for label, model, sizes in models for pairs in sizes]
    runs = [forward_backward(model, hp, spacing, pairs) for _, model, pairs in setups]
    best = [math.inf] * len(runs)
    for _ in range(rounds):
        for i, run in enumerate(runs):
            run()  # warm-up: its own data back in the caches
            for _ in range(burst):
                t0 = time.perf_counter()
                run()
                best[i] = min(best[i], time.perf_counter() - t0)
    return [
        (label, pairs, sec / pairs) for (label, _, pairs), sec in zip(setups, best, strict=True)
    ]


def parallelogram_grid() -> tuple[int, int, int]:
    """Candidates K per pair, and the fewest and most transects crossing, over angles."""
    poly = Polygon(PAPER_PARALLELOGRAM)
    hp = halfplanes(poly)
    spacing = PAPER_SPACING / poly.diameter
    theta = torch.linspace(0, math.pi, 361, dtype=torch.float64)
    offset = torch.rand(361, generator=torch.Generator().manual_seed(1), dtype=torch.float64)
    tl = ExactModel()(hp, theta, offset * spacing, spacing)
    crossing = tl.weights.sum(-1)
    return tl.lengths.shape[-1], int(crossing.min()), int(crossing.max())


# -- report --------------------------------------------------------------------------------------
def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--samples", type=int, default=1000, help="samples a cell (1000)")
    parser.add_argument("--quick", action="store_true", help="30 samples, short timings")
    parser.add_argument("--seed", type=int, default=2024, help="random seed (2024)")
    parser.add_argument(
        "--clip", action="store_true", help="the paper's window |c|, |t| <= 0.5 (all models)"
    )
    parser.add_argument(
        "--statistics",
        choices=("weighted", "paper"),
        default="weighted",
        help="how soft weights enter Eq. 1 (boustro.fitness); the exact reference always "
        "uses 0/1 weights",
    )
    parser.add_argument("--threads", type=int, default=1, help="torch threads (1)")
    parser.add_argument(
        "--tensor",
        action="store_true",
        help="time the tensor code (the path on other devices) instead of the compiled CPU kernels",
    )
    args = parser.parse_args(argv)
    torch.set_num_threads(args.threads)
    smooth.COMPILED = not args.tensor
    path = "tensor code" if args.tensor or _compiled.kernels() is None else "compiled kernels"
    n = 30 if args.quick else args.samples
    points = POINTS

    print(
        f"# boustro closed-form benchmark, {datetime.now(timezone.utc):%Y-%m-%d %H:%M} UTC, "
        f"{platform.processor() or platform.machine()}, torch {torch.__version__}, "
        f"{torch.get_num_threads()} threads, closed form and Eq. 1 by the {path}"
    )
    print(
        f"# fidelity: N = {n} samples a cell (the same samples in every cell), seed {args.seed}, "
        f"clip = {args.clip}, statistics = {args.statistics!r}"
    )
    t0 = time.perf_counter()
    smooth_err, paper_err, seconds = fidelity(n, args.seed, args.clip, args.statistics, points)
    print(
        f"# fidelity took {time.perf_counter() - t0:.1f} s: "
        + ", ".join(f"{k} {v:.1f} s" for k, v in seconds.items())
    )
    print()
    print("mean |fitness(model) - fitness(exact)|")
    head = ["T", "closed form h=1/T"] + [f"paper {p} ppt" for p in points]
    head += [f"published {p}" for p in POINTS]
    print("| " + " | ".join(head) + " |")
    print("|" + "|".join(["---:"] * len(head)) + "|")
    for t in SMOOTH_TEMPERATURES:
        row = [f"{t:g}", f"{smooth_err[t].mean():.2e}"]
        for p in points:
            e = paper_err.get((t, p))
            row.append("" if e is None else f"{e.mean():.2e}")
        pub = PUBLISHED.get(int(t))
        row += [f"{v:.5f}" for v in pub] if pub else ["", "", ""]
        print("| " + " | ".join(row) + " |")
    print()
    print("max |fitness(model) - fitness(exact)| over the samples")
    head = ["T", "closed form h=1/T"] + [f"paper {p} ppt" for p in points]
    print("| " + " | ".join(head) + " |")
    print("|" + "|".join(["---:"] * len(head)) + "|")
    for t in SMOOTH_TEMPERATURES:
        row = [f"{t:g}", f"{smooth_err[t].max():.2e}"]
        for p in points:
            e = paper_err.get((t, p))
            row.append("" if e is None else f"{e.max():.2e}")
        print("| " + " | ".join(row) + " |")
    best_paper = min(PUBLISHED[k][i] for k in PUBLISHED for i in range(3))
    ok = [t for t in SMOOTH_TEMPERATURES if smooth_err[t].mean() < best_paper]
    print()
    print(
        f"closed-form levels with mean error below the paper's best cell ({best_paper}): "
        + (", ".join(f"h = {1 / t:g}" for t in ok) or "none")
    )
    print()

    k_count, fewest, most = parallelogram_grid()
    print(
        "speed: forward + backward of Eq. 1 w.r.t. (angle, offset), batched, on the paper's "
        f"parallelogram at spacing {PAPER_SPACING} (0.0559 normalised: the paper's 18 lines in "
        f"[-0.5, 0.5]); K = {k_count} candidate transects a pair for the paper model, "
        f"{fewest}-{most} crossing; best of rounds of bursts (see speed())"
    )
    rows = speed(args.quick)

    def fastest(label: str) -> float:
        return min(sec for lab, _, sec in rows if lab == label)

    band, full = fastest(PAPER_BAND), fastest(PAPER_FULL)
    print(
        "| model | pairs per batch | us per pair | paper 1000 ppt every point (its best batch) "
        "/ model | paper 1000 ppt band (its best batch) / model |"
    )
    print("|---|---:|---:|---:|---:|")
    for label, pairs, sec in rows:
        print(f"| {label} | {pairs} | {sec * 1e6:.2f} | {full / sec:.0f}x | {band / sec:.0f}x |")
    closed = min(sec for label, _, sec in rows if label.startswith("closed form"))
    print()
    print(
        f"closed form at its best batch: {closed * 1e6:.2f} us per pair, {full / closed:.0f}x "
        f"faster than the paper model at 1000 points evaluated at every point "
        f"({full * 1e6:.0f} us), {band / closed:.1f}x faster than the same model with the band "
        f"evaluation ({band * 1e6:.1f} us); target 100x"
    )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
