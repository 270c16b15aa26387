"""``boustro train``: train the learned planner through the differentiable fitness."""

from __future__ import annotations

import argparse
import math
from pathlib import Path
from typing import Any

from .. import learned  # its network and training import torch when first used (PEP 562)
from ..errors import InvalidParameterError
from ..learned import PlannerConfig, TrainConfig
from ._common import (
    check_plot_target,
    nonnegative_int,
    positive_float,
    positive_int,
    print_json,
    print_table,
)

DETAILS = """\
what it does:
  trains a small network that maps a convex polygon (its edges, in the normalised frame) and a
  spacing to K candidate layouts (angle, offset), WITHOUT labels: the loss is minus the fitness
  (Eq. 1) of its own candidates through the smooth closed-form model, on random convex polygons
  (3-9 vertices) with spacings uniform in (0.01, 1/3) of the diameter. The smoothing is annealed
  from a large to a small fraction of the spacing. Every epoch the exact fitness of the best
  candidate is measured on held-out polygons (another seed).

output:
  OUT (state_dict, loaded with torch.load(weights_only=True)) and OUT with suffix .json
  (hyperparameters, training settings, final validation fitness). Use the result with
  boustro.learned.learned(..., planner=OUT) or optimize(..., method="learned", planner=OUT).
  The defaults reproduce the weights shipped in boustro/data/learned_planner.pt.
"""


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "train",
        help="train the learned planner (a small network) through the differentiable fitness",
        description="Train the learned planner without labels by maximising the differentiable "
        "fitness of its predictions on random convex polygons; write the weights and a "
        "training-curve plot.",
        epilog=DETAILS,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    d = TrainConfig()
    n = PlannerConfig()
    p.add_argument("--epochs", type=positive_int, default=d.epochs, help=f"({d.epochs})")
    p.add_argument(
        "--steps-per-epoch", type=positive_int, default=d.steps_per_epoch,
        help=f"batches per epoch ({d.steps_per_epoch})",
    )  # fmt: skip
    p.add_argument(
        "--batch-size", type=positive_int, default=d.batch_size,
        help=f"polygons per batch ({d.batch_size})",
    )  # fmt: skip
    p.add_argument(
        "--pool", type=positive_int, default=d.pool,
        help=f"random training polygons, generated once ({d.pool})",
    )  # fmt: skip
    p.add_argument(
        "--validation", type=positive_int, default=d.validation,
        help=f"held-out polygons ({d.validation})",
    )  # fmt: skip
    p.add_argument("--lr", type=positive_float, default=d.lr, help=f"learning rate ({d.lr:g})")
    p.add_argument("--seed", type=nonnegative_int, default=d.seed, help=f"random seed ({d.seed})")
    p.add_argument(
        "--hypotheses", type=positive_int, default=n.hypotheses,
        help=f"candidate layouts per polygon ({n.hypotheses})",
    )  # fmt: skip
    p.add_argument("--hidden", type=positive_int, default=n.hidden, help=f"width ({n.hidden})")
    p.add_argument(
        "--threads", type=positive_int, default=d.threads,
        help=f"torch CPU threads ({d.threads}; the shipped weights were trained on 1)",
    )  # fmt: skip
    p.add_argument(
        "--out", type=Path, default=Path("learned_planner.pt"),
        help="weights file to write, plus its .json (default: ./learned_planner.pt)",
    )  # fmt: skip
    p.add_argument(
        "--plot", type=Path, default=None,
        help="write the training curve to this image (needs matplotlib)",
    )  # fmt: skip
    p.add_argument("--json", action="store_true", help="print the summary as JSON")
    p.set_defaults(func=run)


def plot_training(history: dict[str, list[float]], path: Path | None = None, *, ax: Any = None):
    """Plot the training curve: the batches' smooth winner-takes-all fitness (per step, and its
    running mean) and the held-out exact fitness of the best candidate (per epoch); saved to
    ``path`` when given. Returns the figure."""
    import matplotlib

    if ax is None and path is not None:
        matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import numpy as np

    if ax is None:
        fig, ax = plt.subplots(figsize=(7, 4))
    else:
        fig = ax.figure
    if history.get("train_fitness"):
        loss = np.asarray(history["train_fitness"])
        label = "training batch: smooth fitness of the winning candidates"
    else:
        loss = -np.asarray(history["loss"])
        label = "training: minus the loss"
    steps = np.arange(1, len(loss) + 1)
    ax.plot(steps, loss, color="0.8", lw=0.6, label=label)
    window = max(1, len(loss) // 50)
    if len(loss) >= window:
        run = np.convolve(loss, np.ones(window) / window, mode="valid")
        ax.plot(steps[window - 1 :], run, color="C0", lw=1.5, label=f"running mean ({window})")
    val = history.get("val_fitness", [])
    if val:
        per_epoch = len(loss) // len(val)
        x = np.concatenate([[0], per_epoch * np.arange(1, len(val) + 1)])
        y = np.concatenate([history.get("initial_val_fitness", [np.nan]), val])
        ax.plot(x, y, "o-", color="C1", ms=3, label="held-out: exact fitness, best candidate")
    ax.set_xlabel("step")
    ax.set_ylabel("fitness (Eq. 1)")
    ax.set_title("learned planner: training through the differentiable fitness")
    ax.grid(alpha=0.3)
    ax.legend(loc="lower right", fontsize=8)
    if path is not None:
        fig.tight_layout()
        fig.savefig(path, dpi=120)
    return fig


def _check_outputs(args: argparse.Namespace) -> None:
    """Fail before training if the results cannot be written."""
    learned.check_weights_path(args.out)
    if args.out.is_dir():
        raise InvalidParameterError(f"--out {args.out}: is a folder; give a file name")
    if args.plot is not None:
        check_plot_target(args.plot)


def run(args: argparse.Namespace) -> int:
    _check_outputs(args)
    config = TrainConfig(
        epochs=args.epochs,
        steps_per_epoch=args.steps_per_epoch,
        batch_size=args.batch_size,
        pool=args.pool,
        validation=args.validation,
        lr=args.lr,
        seed=args.seed,
        threads=args.threads,
    )
    planner = PlannerConfig(hidden=args.hidden, hypotheses=args.hypotheses)
    result = learned.train_planner(config, planner_config=planner, progress=not args.quiet)
    final = result.history["val_fitness"][-1]
    if not math.isfinite(final):
        raise InvalidParameterError(
            f"training diverged (held-out fitness {final}); nothing written: try a smaller --lr "
            f"than {args.lr:g}"
        )
    weights, meta = learned.save_planner(result.planner, args.out, metadata=result.metadata())
    if args.plot is not None:
        plot_training(result.history, args.plot)
    h = result.history
    summary = {
        "weights": str(weights),
        "config": str(meta),
        "plot": None if args.plot is None else str(args.plot),
        "seconds": round(result.seconds, 1),
        "steps": len(h["loss"]),
        "initial_val_fitness": h["initial_val_fitness"][0],
        "val_fitness": h["val_fitness"][-1],
    }
    if args.json:
        print_json(summary)
    else:
        print_table([(k, "" if v is None else str(v)) for k, v in summary.items()])
    return 0
