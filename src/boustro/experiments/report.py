"""``report.md`` of ``boustro reproduce``: the tables, the optimisers, the figures, the notes."""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np

from .optimizers import PAPER_GRID_MINUS_GRADIENT
from .samples import POINTS_PER_TRANSECT
from .table1 import PAPER_TABLE1, Table1

__all__ = ["JSON_KEYS", "PROTOCOL_NOTES", "render_report"]


def _fmt(v: float | None, digits: int = 5) -> str:
    if v is None or not math.isfinite(v):
        return "n/a"
    return f"{v:.{digits}f}"


def _column_label(points: int | None) -> str:
    return "closed form" if points is None else f"{points} PPT"


def _table_markdown(table: Table1, with_paper: bool) -> list[str]:
    head = "| Temperature | " + " | ".join(_column_label(p) for p in table.points) + " |"
    lines = [head, "|---:|" + "---:|" * len(table.points)]
    for i, t in enumerate(table.temperatures):
        cells = []
        for j, p in enumerate(table.points):
            cell = _fmt(float(table.mean[i, j]))
            if with_paper and p in POINTS_PER_TRANSECT and t in PAPER_TABLE1:
                cell += f" ({PAPER_TABLE1[t][POINTS_PER_TRANSECT.index(p)]:.5f})"
            cells.append(cell)
        lines.append(f"| {t:g} | " + " | ".join(cells) + " |")
    return lines


def _counts_line(table: Table1) -> str:
    model = int(table.no_value_model.max()) if table.no_value_model.size else 0
    return (
        f"{table.n_samples} samples; discrete fitness undefined (no transect in the window, "
        f"left out, not redrawn): {table.no_value_discrete}; model fitness not finite: "
        f"{model} (largest over the cells); largest standard error of a cell: "
        f"{_fmt(float(np.nanmax(table.sem)) if np.isfinite(table.sem).any() else None, 6)}."
    )


def _compact_markdown(tables: dict[str, Table1], points: int) -> list[str]:
    """One column (``points``) of every protocol that has it, side by side."""
    names = [n for n, t in tables.items() if points in t.points]
    if not names:
        return []
    lines = [
        "| Temperature | paper, Table I | " + " | ".join(f"`{n}`" for n in names) + " |",
        "|---:|---:|" + "---:|" * len(names),
    ]
    temps = tables[names[0]].temperatures
    for i, t in enumerate(temps):
        paper = PAPER_TABLE1.get(t)
        cells = [
            _fmt(float(tables[n].mean[i, tables[n].points.index(points)]))
            if t in tables[n].temperatures
            else "n/a"
            for n in names
        ]
        ref = f"{paper[POINTS_PER_TRANSECT.index(points)]:.5f}" if paper else "n/a"
        lines.append(f"| {t:g} | {ref} | " + " | ".join(cells) + " |")
    return lines


PROTOCOL_NOTES = """\
- **Samples.** Each sample is a random convex polygon with 3 to 9 vertices (the authors'
  `randint(3, 10)`), a transect angle uniform over the circle, a spacing uniform in (0, 1/3) of
  the normalised frame (diameter 1) and the authors' `x_offset` uniform in [-s/2, s/2]. The
  polygons are drawn as `polygenerator.random_convex_polygon` (0.2.0) draws them, re-implemented
  in `boustro.experiments.polygenerator_convex_polygon`: Valtr's construction like
  `boustro.geometry.random_convex_polygon`, but with the inner coordinates split into two
  chains of exactly half each and the polygon stretched to fill the unit square before the
  rescaling to diameter 1; both change the distribution of shapes. The same samples serve every
  protocol and both models (common random numbers), so differences between protocols come
  from the protocol alone. Sample `i` does not depend on N.
- **Window.** The paper integrates each transect over y in [-0.5, 0.5]. A polygon centred on its
  vertex mean can reach beyond 0.5 (a triangle reaches 0.577), so the window cuts such
  polygons; the discrete fitness is cut the same way, except in `paper-whole-discrete`, which
  scores the discrete side over the whole polygon as a planner would. The transects are the
  authors' script's `np.arange(-0.5, 0.5, s) + x_offset`, a window shifted by the offset; the
  paper's text and boustro's `clip=True` keep the grid lines in [-0.5, 0.5) instead
  (`grid-window`, `boustro-clip`). `project` uses the whole polygon for both sides.
- **Statistics.** The authors' code computes the soft mean as `sum(L) / sum(S)` and the variance
  as `sum((S (L - mean))^2) / sum(S)` (`statistics="paper"`). At T = 1 every transect's weight S
  is about a quarter, the "mean" about 2 and the error about 0.5: that is Table I's first row.
  Weighted statistics (`paper-weighted`, `project`) do not have it.
- **Trapezoid step.** The authors' points are `arange(-0.5, 0.5, 1 / points)` integrated with
  step `1 / points`: a consistent step over the window less its last `1 / points`.
  `trapezoid="authors"` (the `paper` protocol) approximates it with the library's points, which
  span the whole window, and the step `1 / points`: every length `(points - 1) / points` of its
  value, 1% short at 100 points; `paper-step` (the library's step `1 / (points - 1)`, as in
  `boustro-clip` and `project`) is the closer reading of their code. The difference shows only
  in the 100-PPT column at T >= 1000.
- **Spacing.** The paper says the spacings are random; uniform in (0, 1/3) comes from the
  authors' script (a commented-out line), which as released fixes the spacing at 0.5, leaving
  one or two transects in the window (`authors-script`); compare its T = 1 and T = 10 rows with
  the paper's. Spacings near 0 give thousands of transects (the cost of a sample grows as 1/s;
  all are evaluated).
- **Temperature.** The same temperature in Eq. 4/5 and Eq. 7, as in the authors' code.
- **No value.** The authors' script silently redraws a sample whose fitness is NaN (in practice:
  no transect crosses the polygon in the window, so the discrete mean is undefined). Here such
  samples are counted and left out of the means, never redrawn.
- **Arithmetic.** float64. The paper's model is evaluated with the library's arithmetic
  (`boustro.models.paper_lengths`); the batched evaluation agrees with one library call per
  sample to 1e-12 (tested), and points deep inside or outside the polygon (every edge's
  `T * distance` beyond 41) take the limits of Eq. 5, exact to below an ulp.
- **Eq. 2.** As printed, and in the authors' code, Eq. 2's `W = (x1 - x2, y1 - y2)` is the edge
  vector: not a normal (the polygon comes out turned by 90 degrees, which uniform angles do not
  see) and not of unit length. The length is what matters: each edge's sigmoid in Eq. 3 gets the
  temperature `T |edge|`, softer on short edges (a normalised polygon's edges are 0.1 to 1
  long). The `paper` protocol and its one-change variants follow it (`eq2="printed"`);
  `paper-unit-normals` (and boustro's models) use unit normals. With unit normals the rows
  T = 10 to 1000 come out 1.6 to 5 times lower than the paper's; with Eq. 2 as printed they
  are reproduced. (Found by an adversarial review of this reproduction, which re-implemented
  the authors' arithmetic independently.) The figures' angle axis is boustro's: the transect
  direction counter-clockwise from +x, which may be shifted or mirrored against the paper's
  plots.
"""

JSON_KEYS = """\
Every file has `meta`: `command`, `date` (UTC), `n_samples`, `seed`, `quick`, `seconds` (wall
time of the part), `boustro` and `torch` versions, `threads`, `cpus`, `load_start`.

`table1.json`:

- `paper_table1`: the paper's values, `{temperature: [100 PPT, 1000 PPT, 10000 PPT]}`.
- `polygon_redraws`: polygon draws rejected as degenerate and drawn again (expected 0).
- `protocols` (paper's model) and `smooth` (closed-form model), by protocol name, each with
  `description`, `settings` (`clip`, `discrete_clip`, `statistics`, `spacing`, `window`,
  `trapezoid`),
  `model`, `temperatures` (rows), `points_per_transect` (columns; `null` = closed form),
  `mean_abs_error`, `sem` (standard error of the mean), `max_abs_error`, `valid_samples` (rows x
  columns), `no_value_discrete` (samples left out: discrete fitness undefined),
  `no_value_model` (per cell: model fitness not finite), `n_samples`.

`optimizers.json`:

- `n`, `seed`; `paper`: `grid_minus_gradient` (0.13633) and its `n`.
- `methods`, by name (`grid`, `gradient`, `hybrid`, `global`): `available`,
  `unavailable_reason`, `description`, `options`, `fitness` and `seconds` per sample (`null`
  where a run failed), `failures`, `first_error`, `mean_fitness`, `total_seconds`; `gradient`
  also has `final_iterate_fitness` (the exact fitness where the descent ended).
- `comparisons`, by method (`gradient`, `gradient-final`, `hybrid`, `global`) against grid
  search, over the samples where both have an answer: `n`, `mean_grid_minus_other`, `sem`,
  `share_other_higher`, `share_equal` (within 1e-9), `share_grid_higher`; and
  `global_check`: `n`, `largest_excess_over_global` (the most any other optimiser's answer
  exceeds the certified optimum), `beaten_by_more_than_1e-6` (should be 0).

`figures.json`: the data of Figs. 3-5 (`fitness_vs_angle`, `surface_angle_offset`,
`surface_angle_temperature`: `angle_deg`, `x_offset` (parallelogram units), `temperature`,
`fitness`; Fig. 5 has `paper_model` and `exact` instead of `fitness`).
"""


def _meta_line(part: str, meta: dict[str, Any]) -> str:
    n = meta.get("n_samples")
    return (
        f"- {part}: {'' if n is None else f'N = {n}, '}seed {meta.get('seed', 'n/a')}"
        f"{', --quick' if meta.get('quick') else ''}; {meta.get('seconds', float('nan')):.1f} s "
        f"wall time on {meta.get('date', '?')} (boustro {meta.get('boustro')}, torch "
        f"{meta.get('torch')}, {meta.get('threads')} thread(s), {meta.get('cpus')} CPU(s), "
        f"load average {meta.get('load_start', 'n/a')} at the start)."
    )


def _table1_markdown(table1_json: dict[str, Any]) -> list[str]:
    """The Table I section: protocol ``paper``, every protocol, the closed form, the notes."""
    out: list[str] = []
    tables = {k: Table1.from_json(v) for k, v in table1_json.get("protocols", {}).items()}
    smooth = {k: Table1.from_json(v) for k, v in table1_json.get("smooth", {}).items()}
    out += ["## Table I: mean |differentiable - discrete| fitness", ""]
    paper = tables.get("paper")
    if paper is not None:
        out += [
            "Protocol `paper` (the paper's text and, where it is silent, the authors' "
            "code): reproduced (the paper's value).",
            "",
            *_table_markdown(paper, True),
            "",
            _counts_line(paper),
            "",
        ]
    out += [
        "Every protocol at 1000 points per transect (PPT), one choice changed at a time "
        "(definitions below):",
        "",
        *_compact_markdown(tables, 1000),
        "",
    ]
    for name, t in tables.items():
        if name == "paper":
            continue
        out += [
            f"`{name}`: {t.protocol.description}.",
            "",
            *_table_markdown(t, True),
            "",
            _counts_line(t),
            "",
        ]
    if smooth:
        out += [
            "### The closed-form smooth model",
            "",
            "`boustro.smooth.SmoothModel` with smoothing length 1/T (no points per "
            "transect), the same samples and discrete side as each protocol:",
            "",
            "| Temperature | " + " | ".join(f"`{n}`" for n in smooth) + " |",
            "|---:|" + "---:|" * len(smooth),
        ]
        first = next(iter(smooth.values()))
        for i, temp in enumerate(first.temperatures):
            out.append(
                f"| {temp:g} | "
                + " | ".join(_fmt(float(tb.mean[i, 0])) for tb in smooth.values())
                + " |"
            )
        out += ["", _counts_line(first), ""]
    else:
        out += ["The closed-form smooth model (`boustro.smooth`) is not available here.", ""]
    out += ["### Protocol choices that change the numbers", "", PROTOCOL_NOTES]
    return out


def _figures_markdown(figure_files: Sequence[str]) -> list[str]:
    """The figures section."""
    out: list[str] = []
    out += ["## Figures (the paper's parallelogram)", ""]
    captions = {
        "fig2_indicator.png": "Fig. 2: Eq. 5 along the transects, T = 17 and T = 100.",
        "fig3_surface_angle_offset.png": "Fig. 3: fitness over angle x offset, T = 10000.",
        "fig4_surface_angle_temperature.png": "Fig. 4: fitness over angle x temperature.",
        "fig5_fitness_vs_angle.png": "Fig. 5: fitness against angle, T = 10000, with the "
        "exact fitness.",
    }
    for name in figure_files:
        out += [f"![{captions.get(name, name)}]({name})", "", captions.get(name, name), ""]
    out += [
        "Vertices (8,4), (8,10), (4,8), (4,2), spacing 0.5 of its units (0.0559 of the "
        "normalised frame), the authors' 18 transects `arange(-0.5, 0.5, s) + x_offset`, "
        "window [-0.5, 0.5], the authors' statistics, 1000 points per transect. Angles: the "
        "transect direction, degrees counter-clockwise from +x.",
        "",
    ]
    return out


def render_report(
    table1_json: dict[str, Any] | None = None,
    optimizers_json: dict[str, Any] | None = None,
    figures_json: dict[str, Any] | None = None,
    figure_files: Sequence[str] = (),
) -> str:
    """``report.md`` from the JSON files of the parts run (any subset): the reproduced tables
    beside the paper's, the comparison of optimisers, the figures, the protocol notes and the
    keys of the JSON files.

    >>> render_report().splitlines()[0]
    '# Reproducing Manzini & Murphy (ICRA 2024) with boustro'
    """
    out = ["# Reproducing Manzini & Murphy (ICRA 2024) with boustro", ""]
    runs = [
        ("Table I", table1_json),
        ("optimisers", optimizers_json),
        ("figures", figures_json),
    ]
    command = next((j["meta"].get("command") for _, j in runs if j and "meta" in j), None)
    if command:
        out += [f"Command: `{command}`", ""]
    out += [_meta_line(name, j["meta"]) for name, j in runs if j and "meta" in j]
    out.append("")
    if table1_json:
        out += _table1_markdown(table1_json)
    if optimizers_json:
        out += _optimizers_markdown(optimizers_json)
    if figure_files:
        out += _figures_markdown(figure_files)
    out += ["## JSON files", "", JSON_KEYS]
    return "\n".join(out).rstrip() + "\n"


def _optimizers_markdown(res: dict[str, Any]) -> list[str]:
    out = [
        "## Gradient descent vs grid search (Sec. VII)",
        "",
        f"{res['n']} random polygons and spacings (Table I's first {res['n']} samples, seed "
        f"{res['seed']}); every answer scored with the exact fitness (whole polygon, Eq. 1). "
        f"Paper: grid search higher than gradient descent by {PAPER_GRID_MINUS_GRADIENT} on "
        "average over 1000 polygons, gradient descent occasionally higher.",
        "",
        "| method | mean fitness | grid - method (mean ± s.e.) | method higher | equal | "
        "grid higher | failures | time (s) |",
        "|---|---:|---:|---:|---:|---:|---:|---:|",
    ]
    methods, comps = res["methods"], res["comparisons"]
    rows = [("grid", "grid", None)]
    rows += [(m, m, comps.get(m)) for m in ("gradient",)]
    rows += [("gradient (last iterate)", "gradient", comps.get("gradient-final"))]
    rows += [(m, m, comps.get(m)) for m in ("hybrid", "global")]
    for label, key, comp in rows:
        m = methods.get(key)
        if m is None:
            continue
        if not m["available"]:
            out.append(f"| {label} | {m['unavailable_reason']} | | | | | | |")
            continue
        if label.endswith("(last iterate)"):
            vals = [v for v in m.get("final_iterate_fitness", []) if v is not None]
            mean = float(np.mean(vals)) if vals else None
            fails, secs = "", ""
        else:
            mean, fails, secs = m["mean_fitness"], str(m["failures"]), f"{m['total_seconds']:.1f}"
        if comp and comp.get("n"):
            diff = f"{comp['mean_grid_minus_other']:+.5f} ± {comp['sem']:.5f}"
            shares = [
                f"{100 * comp[k]:.1f}%"
                for k in ("share_other_higher", "share_equal", "share_grid_higher")
            ]
        else:
            diff, shares = "", ["", "", ""]
        out.append(
            f"| {label} | {_fmt(mean)} | {diff} | " + " | ".join(shares) + f" | {fails} | {secs} |"
        )
    out.append("")
    check = comps.get("global_check")
    if check:
        out += [
            f"Check against the certified optimum, over {check['n']} samples: largest "
            f"(other optimiser - global) {check['largest_excess_over_global']:+.2e}; samples "
            f"where another optimiser beats it by more than 1e-6: "
            f"{check['beaten_by_more_than_1e-6']}.",
            "",
        ]
    for name, m in methods.items():
        if m["available"]:
            opts = ", ".join(f"{k}={v}" for k, v in m["options"].items()) or "defaults"
            out.append(f"- `{name}`: {m['description']} ({opts}).")
            if m["first_error"]:
                out.append(f"  First failure: {m['first_error']}")
    out.append("")
    return out
