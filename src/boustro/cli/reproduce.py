"""``boustro reproduce``: the paper's experiments in one command.

Table I (Sec. V), gradient descent vs grid search (Sec. VII) and the figures (Figs. 2-5), written
into ``--out`` as ``report.md``, ``table1.json``, ``optimizers.json``, ``figures.json`` and PNG
files, each atomically. The computations live in :mod:`boustro.experiments`.
"""

from __future__ import annotations

import argparse
import datetime as _dt
import io
import json
import logging
import os
import shlex
import sys
import time
from typing import Any

import numpy as np

from .._files import atomic_write
from .._torch import torch
from .._version import __version__
from ._common import nonnegative_int, positive_int

log = logging.getLogger(__name__)

PARTS = ("table1", "optimizers", "figures")

#: Samples of each part by default, and with ``--quick`` (a smoke test, under a minute).
DEFAULT_SAMPLES = 1000
QUICK_SAMPLES = {"table1": 20, "optimizers": 5}

DETAILS = """\
parts:
  table1      Table I (Sec. V): mean |differentiable - discrete| fitness over N random samples
              for temperature 1..10000 x 100, 1000, 10000 points per transect, under the paper's
              protocol and variants that change one choice each, beside the paper's values;
              the same for the closed-form smooth model
  optimizers  Sec. VII: grid search (200 samples) vs gradient descent (momentum 0.8) on N random
              polygons, and boustro's hybrid and global optimisers
  figures     Figs. 2-5 on the paper's parallelogram
  all         all three (default)

output (in --out, default reproduce-out/):
  report.md, table1.json, optimizers.json, figures.json, fig2_indicator.png,
  fig3_surface_angle_offset.png, fig4_surface_angle_temperature.png, fig5_fitness_vs_angle.png.
  report.md covers every part whose JSON is in --out, so parts can be run one at a time.

The full run (N = 1000, all parts) took 6.6 minutes on a shared 2-core CPU; --quick takes seconds.
"""


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "reproduce",
        help="reproduce the paper: Table I, gradient descent vs grid search, the figures",
        description="Reproduce the experiments of Manzini & Murphy (ICRA 2024), 'Differentiable "
        "Boustrophedon Paths That Enable Optimization Via Gradient Descent', and write a report.",
        epilog=DETAILS,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    p.add_argument(
        "part",
        nargs="?",
        choices=(*PARTS, "all"),
        default="all",
        help="what to reproduce (default: all)",
    )
    p.add_argument(
        "--samples",
        type=positive_int,
        default=None,
        help=f"random samples of Table I and of the optimiser comparison (default "
        f"{DEFAULT_SAMPLES}, the paper's; with --quick {QUICK_SAMPLES['table1']} and "
        f"{QUICK_SAMPLES['optimizers']})",
    )
    p.add_argument("--seed", type=nonnegative_int, default=0, help="random seed, >= 0 (default 0)")
    p.add_argument("--out", default="reproduce-out", help="output folder (default reproduce-out)")
    p.add_argument(
        "--quick",
        action="store_true",
        help="a smoke test: few samples and coarse figures, under a minute",
    )
    p.add_argument(
        "--threads",
        type=positive_int,
        default=1,
        help="torch CPU threads (default 1: the work is many small tensor operations, and on a "
        "shared machine one thread is often faster than two)",
    )
    p.set_defaults(func=run)


def _jsonable(obj: Any) -> Any:
    if isinstance(obj, dict):
        return {str(k): _jsonable(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [_jsonable(v) for v in obj]
    if isinstance(obj, np.ndarray):
        return _jsonable(obj.tolist())
    if isinstance(obj, (np.floating, float)):
        v = float(obj)
        return v if np.isfinite(v) else None
    if isinstance(obj, np.integer):
        return int(obj)
    return obj


def _write_json(path: str, obj: Any) -> None:
    atomic_write(path, json.dumps(_jsonable(obj), indent=1, allow_nan=False) + "\n")


def _read_json(path: str, part: str) -> dict[str, Any] | None:
    """The results of ``part`` stored in ``path`` by an earlier run, or None (with a warning when
    the file exists but is not such a result: another program's file, an older format)."""
    if not os.path.exists(path):
        return None
    from .. import experiments as ex  # torch: imported by `boustro reproduce` only

    try:
        with open(path, encoding="utf-8") as fh:
            data = json.load(fh)
        if not isinstance(data, dict) or not isinstance(data.get("meta"), dict):
            raise ValueError("no 'meta' object")
        table1, optimizers, figures = (data if p == part else None for p in PARTS)
        ex.render_report(table1, optimizers, figures)  # the report can be built from it
    except (OSError, ValueError, KeyError, TypeError, AttributeError, IndexError) as exc:
        log.warning("ignoring %s: not a result of 'boustro reproduce %s' (%s)", path, part, exc)
        return None
    return data


def _meta(args: argparse.Namespace, n: int | None, seconds: float, load: str) -> dict[str, Any]:
    return {
        "command": _command(args),
        "date": _dt.datetime.now(_dt.timezone.utc).strftime("%Y-%m-%d %H:%M UTC"),
        "n_samples": n,
        "seed": args.seed,
        "quick": args.quick,
        "seconds": round(seconds, 2),
        "boustro": __version__,
        "torch": torch.__version__,
        "threads": torch.get_num_threads(),
        "cpus": os.cpu_count(),
        "load_start": load,
    }


def _command(args: argparse.Namespace) -> str:
    words = ["boustro", "reproduce", args.part, "--seed", str(args.seed), "--out", args.out]
    if args.samples is not None:
        words += ["--samples", str(args.samples)]
    if args.quick:
        words.append("--quick")
    if args.threads != 1:
        words += ["--threads", str(args.threads)]
    return shlex.join(words)


def _load() -> str:
    try:
        return " ".join(f"{v:.2f}" for v in os.getloadavg())
    except OSError:
        return "n/a"


def _show_progress(args: argparse.Namespace) -> bool:
    """Progress bars on stderr when it is a terminal and ``-q`` was not given, as the other
    commands show theirs (a log file or a pipe gets no bar frames)."""
    return not getattr(args, "quiet", False) and sys.stderr.isatty()


def run(args: argparse.Namespace) -> int:
    from .. import experiments as ex  # torch: imported by `boustro reproduce` only

    parts = PARTS if args.part == "all" else (args.part,)
    progress = _show_progress(args)
    os.makedirs(args.out, exist_ok=True)
    previous_threads = torch.get_num_threads()
    torch.set_num_threads(args.threads)
    status = 0
    try:
        for part in parts:
            t0, load = time.perf_counter(), _load()
            if part == "table1":
                n = args.samples or (QUICK_SAMPLES["table1"] if args.quick else DEFAULT_SAMPLES)
                samples = ex.draw_samples(n, args.seed)
                tables = ex.table1(samples, progress=progress)
                smooth = ex.smooth_table1(samples, list(ex.PROTOCOLS), progress=progress)
                result = {
                    "paper_table1": {f"{t:g}": list(v) for t, v in ex.PAPER_TABLE1.items()},
                    "protocols": {k: v.to_json() for k, v in tables.items()},
                    "smooth": {k: v.to_json() for k, v in smooth.items()},
                    "polygon_redraws": samples.redrawn,
                }
                result = {"meta": _meta(args, n, time.perf_counter() - t0, load), **result}
                _write_json(os.path.join(args.out, "table1.json"), result)
            elif part == "optimizers":
                n = args.samples or (QUICK_SAMPLES["optimizers"] if args.quick else DEFAULT_SAMPLES)
                result = ex.compare_optimizers(ex.draw_samples(n, args.seed), progress=progress)
                result = {"meta": _meta(args, n, time.perf_counter() - t0, load), **result}
                _write_json(os.path.join(args.out, "optimizers.json"), result)
            else:
                try:
                    import matplotlib  # noqa: F401
                except ImportError:
                    print(
                        "boustro: error: the figures need matplotlib: pip install 'boustro[plot]'",
                        file=sys.stderr,
                    )
                    status = 2
                    continue
                data = ex.figure_data(args.quick, progress=progress)
                for name, draw in ex.FIGURES.items():
                    buf = io.BytesIO()
                    draw(data).savefig(buf, format="png", dpi=120)
                    atomic_write(os.path.join(args.out, name), buf.getvalue())
                keep = ("fitness_vs_angle", "surface_angle_offset", "surface_angle_temperature")
                result = {
                    "meta": _meta(args, None, time.perf_counter() - t0, load),
                    **{k: data[k] for k in keep},
                }
                _write_json(os.path.join(args.out, "figures.json"), result)
            log.info("%s: %.1f s", part, time.perf_counter() - t0)
        present = [f for f in ex.FIGURES if os.path.exists(os.path.join(args.out, f))]
        table1, optimizers, figures = (
            _read_json(os.path.join(args.out, f"{part}.json"), part) for part in PARTS
        )
        report = ex.render_report(table1, optimizers, figures, present)
        atomic_write(os.path.join(args.out, "report.md"), report)
    finally:
        torch.set_num_threads(previous_threads)
    print(os.path.join(args.out, "report.md"))
    return status
