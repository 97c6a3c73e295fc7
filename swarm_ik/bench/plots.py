"""Plots of the paper benchmark, made from the CSV and history files only.

matplotlib is an optional extra (``pip install swarm_ik[plot]``); it is imported when a plot
is made, never when this module is imported.  Figures are built with
``matplotlib.figure.Figure`` (no pyplot, no global state) and written as PNG.

* :func:`convergence`: mean best fitness against evaluations, log scale, one line per solver,
  the inter-quartile band shaded (runs resampled onto a common evaluation grid).
* :func:`boxes`: box plots of the final fitness per solver.
* :func:`budget_success`: success rate against the evaluation budget per solver.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from swarm_ik.errors import SwarmIKError

Row = Mapping[str, Any]
CLIP = 1e-17
"""Values at or below this (exact zeros included) are drawn at this level on log axes."""


class PlotExtraMissingError(SwarmIKError, ImportError):
    """matplotlib is not installed."""


def _figure(
    n: int, ncols: int = 2, size: tuple[float, float] = (6.0, 4.2)
) -> tuple[Any, list[Any]]:
    try:
        from matplotlib.figure import Figure
    except ImportError:  # pragma: no cover - depends on the environment
        raise PlotExtraMissingError(
            "plots need matplotlib: pip install 'swarm_ik[plot]' (or pass --no-plots)"
        ) from None
    ncols = max(1, min(ncols, n))
    nrows = (n + ncols - 1) // ncols
    fig = Figure(figsize=(size[0] * ncols, size[1] * nrows), layout="constrained")
    axes = [fig.add_subplot(nrows, ncols, i + 1) for i in range(n)]
    return fig, axes


def _save(fig: Any, path: Path, title: str, note: str = "") -> Path:
    """Write ``fig`` as a PNG to ``path`` (its folder made) and return ``path``; with a
    ``title``, the figure is titled with it (``note`` on a second line when given)."""
    if title:
        fig.suptitle(f"{title}\n{note}" if note else title, fontsize=10)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)
    return path


EXTRA_COLORS = ("#000000", "#b8860b", "#008080", "#000080", "#800000")
"""Colours after matplotlib's ten ``tab10`` ones."""


def _colors(solvers: Sequence[str]) -> dict[str, Any]:
    """A colour per solver, the same in every figure (by the solver's place in the registry)."""
    from matplotlib import colormaps

    palette = [colormaps["tab10"](i) for i in range(10)] + list(EXTRA_COLORS)
    try:
        from swarm_ik.solvers import names

        universe = names()
    except ImportError:  # pragma: no cover
        universe = []
    order = list(universe) + [s for s in solvers if s not in universe]
    return {s: palette[order.index(s) % len(palette)] for s in solvers}


def run_curve(history: Mapping[str, Any]) -> tuple[np.ndarray, np.ndarray]:
    """Evaluations and best fitness at the stored points of a compact history.

    The ``i``-th iteration is placed at ``(i + 1)·n_evals / n_iter`` evaluations.
    """
    it = np.asarray(history["it"], dtype=float)
    f = np.array([np.nan if v is None else v for v in history["f"]], dtype=float)
    n_iter = max(int(history["n_iter"]), 1)
    return (it + 1.0) * float(history["n_evals"]) / n_iter, f


def resample(curves: Sequence[tuple[np.ndarray, np.ndarray]], grid: np.ndarray) -> np.ndarray:
    """Step-resample run curves onto ``grid``: the value of the last point at or before each
    grid point (NaN before a run's first point and after its end is held constant).

    Returns:
        Array ``(runs, len(grid))``.
    """
    out = np.full((len(curves), grid.shape[0]), np.nan)
    for k, (x, f) in enumerate(curves):
        if x.size == 0:
            continue
        idx = np.searchsorted(x, grid, side="right") - 1
        ok = idx >= 0
        out[k, ok] = f[idx[ok]]
    return out


def convergence(
    path: Path,
    rows: Sequence[Row],
    histories: Mapping[str, Mapping[str, Any]],
    panels: Sequence[tuple[str, Callable[[Row], bool], float]],
    solvers: Sequence[str],
    *,
    title: str = "",
    ylabel: str = "best fitness",
    refs: Sequence[tuple[float, str] | None] | None = None,
) -> Path | None:
    """Convergence curves, one panel per case.

    Args:
        path: PNG to write.
        rows: Run rows (CSV).
        histories: Compact histories by run key.
        panels: ``(panel title, row predicate, f_min)``; the curve is ``f − f_min``.
        solvers: Solvers in legend order.
        title: Figure title.
        ylabel: Y axis label.
        refs: Per panel, an optional ``(value, label)`` drawn as a dashed horizontal line
            (e.g. a rounding floor).

    Returns:
        ``path``, or ``None`` when no run had a history.  The mean and quartiles are drawn
        only where every run has started (no mean over a changing set of runs).
    """
    fig, axes = _figure(len(panels))
    colors = _colors(solvers)
    drawn = False
    refs = list(refs) if refs is not None else [None] * len(panels)
    for ax, (ptitle, select, f_min), ref in zip(axes, panels, refs, strict=True):
        chosen = [r for r in rows if select(r) and r["key"] in histories]
        for solver in solvers:
            runs = [r for r in chosen if r["solver"] == solver]
            if not runs:
                continue
            curves = [run_curve(histories[r["key"]]) for r in runs]
            top = max(float(c[0][-1]) for c in curves if c[0].size)
            grid = np.linspace(top / 200.0, top, 200)
            vals = np.maximum(resample(curves, grid) - f_min, CLIP)  # NaN stays NaN
            mean = np.mean(vals, axis=0)  # NaN where some run has not started yet
            q25, q75 = np.percentile(vals, [25, 75], axis=0)
            c = colors[solver]
            ax.plot(grid, mean, color=c, lw=1.6, label=f"{solver} ({len(runs)} runs)")
            ax.fill_between(grid, q25, q75, color=c, alpha=0.18, lw=0)
            drawn = True
        if ref is not None:
            ax.axhline(max(ref[0] - f_min, CLIP), color="0.3", ls="--", lw=1.0, label=ref[1])
        ax.set_yscale("log")
        ax.set_title(ptitle, fontsize=10)
        ax.set_xlabel("evaluations (iteration × population for the swarm solvers)")
        ax.set_ylabel(ylabel if not f_min else f"{ylabel} − f_min")
        ax.grid(True, which="major", alpha=0.3)
        ax.legend(fontsize=7, loc="upper right")
    if not drawn:
        return None
    note = (
        f"mean over runs (line), inter-quartile range (band); values ≤ {CLIP:g} drawn at {CLIP:g}"
    )
    return _save(fig, path, title, note)


def boxes(
    path: Path,
    rows: Sequence[Row],
    panels: Sequence[tuple[str, Callable[[Row], bool], float]],
    solvers: Sequence[str],
    *,
    title: str = "",
    ylabel: str = "final fitness",
) -> Path | None:
    """Box plots of the final fitness (``f − f_min``, log scale), one panel per case."""
    fig, axes = _figure(len(panels))
    colors = _colors(solvers)
    drawn = False
    for ax, (ptitle, select, f_min) in zip(axes, panels, strict=True):
        data, labels, cols = [], [], []
        for solver in solvers:
            vals = [
                float(r["fitness"]) - f_min for r in rows if select(r) and r["solver"] == solver
            ]
            if vals:
                data.append(np.maximum(vals, CLIP))
                labels.append(solver)
                cols.append(colors[solver])
        if not data:
            continue
        bp = ax.boxplot(data, patch_artist=True, widths=0.6)
        for patch, c in zip(bp["boxes"], cols, strict=True):
            patch.set_facecolor(c)
            patch.set_alpha(0.5)
        ax.set_xticks(range(1, len(labels) + 1), labels, rotation=30, ha="right", fontsize=8)
        ax.set_yscale("log")
        ax.set_title(ptitle, fontsize=10)
        ax.set_ylabel(ylabel if not f_min else f"{ylabel} − f_min")
        ax.grid(True, axis="y", alpha=0.3)
        drawn = True
    if not drawn:
        return None
    return _save(fig, path, title, f"values ≤ {CLIP:g} drawn at {CLIP:g}")


def budget_success(
    path: Path,
    rows: Sequence[Row],
    robots: Sequence[str],
    solvers: Sequence[str],
    *,
    title: str = "",
) -> Path | None:
    """Success rate per solver at each evaluation budget: grouped horizontal bars, one panel
    per robot."""
    budgets = sorted({int(r["max_evals"]) for r in rows if r["max_evals"] is not None})
    if not budgets:
        return None
    fig, axes = _figure(len(robots), size=(6.0, 0.45 * len(solvers) + 1.6))
    from matplotlib import colormaps  # available: _figure checked matplotlib

    shades = colormaps["viridis"](np.linspace(0.15, 0.85, len(budgets)))
    height = 0.8 / len(budgets)
    for ax, robot in zip(axes, robots, strict=True):
        y = np.arange(len(solvers))
        for k, b in enumerate(budgets):
            rate = []
            for solver in solvers:
                runs = [
                    r
                    for r in rows
                    if r["robot"] == robot and r["solver"] == solver and r["max_evals"] == b
                ]
                rate.append(100.0 * np.mean([r["success"] for r in runs]) if runs else np.nan)
            pos = y - 0.4 + (k + 0.5) * height
            ax.barh(pos, rate, height=height, color=shades[k], label=f"{b:,} evaluations")
            for yy, v in zip(pos, rate, strict=True):
                if np.isfinite(v):
                    ax.text(min(v, 100.0) + 1.0, yy, f"{v:.0f}", va="center", fontsize=6)
        ax.set_yticks(y, solvers, fontsize=8)
        ax.invert_yaxis()
        ax.set_xlim(0, 112)
        ax.set_title(robot, fontsize=10)
        ax.set_xlabel("success rate [%]")
        ax.grid(True, axis="x", alpha=0.3)
        ax.legend(fontsize=7, loc="lower right")
    return _save(fig, path, title)
