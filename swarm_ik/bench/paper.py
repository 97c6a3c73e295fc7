"""``swarm-ik bench paper``: the source papers' tables, rerun, beside the published numbers.

Experiments (ids for ``--experiments``):

``000-table2``
    [HLFOA], Table 2: YuMi left arm, the given pose, (a) **as printed** (rounded, not exactly
    orthonormal: every solver stops at its rounding floor, computed and reported) and (b) **at
    full precision**, the FK of the joint vector that best reproduces it.  FOA and HLFOA
    with the paper's population 100 and 1000 iterations, GWO, MGWO, PSO (same population and
    iterations), DLS and the default ``swarm`` solver (same evaluation
    budget, ``m·t_max + m``) for context; fitness ``paper-l1``; 10 runs.
``000-table4``
    [HLFOA], Table 4: 10 arbitrary reachable poses (FK of joint vectors drawn uniformly
    within the limits, seed :data:`POSE_SEED`), the same solvers and statistics, pooled.
``003-table3``
    [MGWO], Table 3: F1–F4, 30 wolves, 200 iterations, 50 runs, GWO against MGWO.
``003-table4``
    [MGWO], Table 4: the loading manipulator, target FK(x*), 30 wolves, 200 iterations,
    50 runs, fitness ``euler-zyz``; on ``loading_manipulator_long`` (reachable) and on
    ``loading_manipulator`` (the stated limits: unreachable, reported with the best error and
    ``success = false``).  GWO, MGWO, DLS and ``swarm`` on the same budget for context
    (VAGWO, not implemented here, is listed with its published numbers).
``budget``
    Every registered search solver against Pinocchio DLS on equal evaluation budgets, fitness
    ``se3``, stopping at the tolerance (‖Δp‖ ≤ 1e-5 m and θ ≤ 1e-5 rad, judged with Pinocchio's FK).

Every run is one row of ``<experiment>.csv`` under ``--out`` (schema:
:mod:`swarm_ik.bench.common`); ``report.md`` (its prose from ``templates/paper.md``) and the
PNG plots are made from those files.
Interrupt it at any time (Ctrl-C) and run the same command again: finished runs are kept.
By default the runs go over a local process pool (``--jobs``); ``--scheduler local`` runs them
on an embedded Dask LocalCluster and ``--scheduler tcp://host:port`` on an existing Dask
scheduler's workers (through :func:`swarm_ik.distributed.map_chunks`, a batch of runs at a
time, each batch's rows written as it comes back, so resuming works the same way).
``--quick`` runs a reduced version of everything (fewer runs, fewer iterations, fewer poses);
its report says so.
"""

from __future__ import annotations

import argparse
import inspect
import json
import math
import platform
import re
import sys
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from swarm_ik.argtypes import count
from swarm_ik.bench import common, published, runner, solve_runs
from swarm_ik.bench.common import Stats
from swarm_ik.bench.plans import (
    FULL,
    IK_FLOOR,
    PAPER000_SOLVERS,
    PAPER003_SOLVERS,
    POSE_SEED,
    Q_EXACT,
    QUICK,
    TOL,
    Config,
    RunSpec,
    available,
    budget_solvers,
    printed_floor,
    specs_000_table2,
    specs_000_table4,
    specs_003_table3,
    specs_003_table4,
    specs_budget,
)
from swarm_ik.bench.report import (
    Comparison,
    Headline,
    fmt,
    per_target_means,
    render_block,
    render_budget,
    render_comparison,
    render_headline,
)
from swarm_ik.errors import InvalidArgumentError, unknown
from swarm_ik.solvers import mgwo
from swarm_ik.testfunctions import FUNCTIONS


# --------------------------------------------------------------------------- experiments
@dataclass(frozen=True)
class Experiment:
    """One experiment: how to generate its runs, its report section and its plots.

    Attributes:
        id: Identifier (``--experiments``, CSV file name).
        title: Heading in the report.
        specs: ``Config -> runs``.
        section: ``(Config, rows, Headline, out folder) -> Markdown``.
        plots: ``(Config, rows, histories, out folder) -> written PNG paths``.
    """

    id: str
    title: str
    specs: Callable[[Config], list[RunSpec]]
    section: Callable[[Config, list[dict[str, Any]], Headline, Path], str]
    plots: Callable[[Config, list[dict[str, Any]], dict[str, Any], Path], list[Path]]


def _by(**want: Any) -> Callable[[Mapping[str, Any]], bool]:
    return lambda r: all(r[k] == v for k, v in want.items())


def _img(out: Path, name: str, alt: str) -> str:
    return f"![{alt}]({name})\n" if (out / name).exists() else ""


def _join(parts: Sequence[str]) -> str:
    return "\n\n".join(p.strip("\n") for p in parts if p.strip()) + "\n"


def _quick_why(cfg: Config) -> str | None:
    if cfg.iterations_000 >= FULL.iterations_000:
        return None
    return (
        f"quick run: {cfg.iterations_000} iterations instead of the paper's {FULL.iterations_000}"
    )


def _g(v: float) -> str:
    """A number for the prose: ``%g`` without the exponent's leading zero (``1e-5``)."""
    return re.sub(r"e([+-])0(\d)", r"e\1\2", f"{v:g}")


def _text(block: str, *, inline: bool = False, **values: Any) -> str:
    """A block of ``templates/paper.md`` (:func:`swarm_ik.bench.report.render_block`)."""
    return render_block("paper.md", block, inline=inline, **values)


def _published_mean(table: published.PublishedTable, solver: str, stat: str = "mean") -> str:
    row = table.row_for(solver)
    return fmt(row.stats.get(stat) if row is not None else None)


def _printed_row(table: published.PublishedTable, algorithm: str) -> published.PublishedRow:
    """The row of ``table`` named ``algorithm`` as the paper prints it."""
    return next(r for r in table.rows if r.algorithm == algorithm)


def _closing(solvers: Sequence[str], out: Path, exp_id: str, value: str = "fitness") -> list[str]:
    """The end of an experiment's section: solvers not registered, then its two plots."""
    label = exp_id.replace("-table", " Table ")
    return [
        *_missing_note(solvers),
        _img(out, f"convergence_{exp_id}.png", f"convergence, {label}"),
        _img(out, f"box_{exp_id}.png", f"final {value}, {label}"),
    ]


def _missing_note(solvers: Sequence[str]) -> list[str]:
    _, missing = available(solvers)
    if not missing:
        return []
    return [f"Not registered, so not run: {', '.join(f'`{m}`' for m in missing)}."]


def _setup_000(cfg: Config) -> str:
    return _text(
        "setup-000",
        pop=cfg.pop_000,
        iterations=cfg.iterations_000,
        paper_pop=FULL.pop_000,
        paper_iterations=FULL.iterations_000,
        budget=f"{cfg.pop_000 * (cfg.iterations_000 + 1):,}",
        tol=_g(TOL),
    )


AT_FLOOR_FACTOR = 2.0
"""A row of the printed pose counts as *at the rounding floor* when its mean fitness is at most
this many times the floor (the floor itself is found numerically, and runs that converged end
a few per cent above it)."""


def printed_pose_reason(st: Stats, floor: float) -> str | None:
    """Why a row on [HLFOA]'s printed (rounded) pose is *worse* than the paper, when the
    rounding explains it.

    The rounding floor bounds every run from below, so it explains a row only when the row
    itself is at the floor: its **mean** (the statistic the verdict is on) at most
    :data:`AT_FLOOR_FACTOR` × ``floor``.  A row far above the floor (runs that did not
    converge, e.g. in a ``--quick`` run) gets ``None``: the caller's default reason (the quick
    run's fewer iterations) or "cause not identified".

    Args:
        st: The row's statistics (our runs on the printed pose).
        floor: The rounding floor used in the report (the lowest fitness attainable).

    Returns:
        The rounding reason, or ``None``.
    """
    if st.mean <= AT_FLOOR_FACTOR * floor:
        return _text("why-printed", inline=True, floor=f"{floor:.3g}")
    return None


def _section_000_table2(cfg: Config, rows: list[dict[str, Any]], hl: Headline, out: Path) -> str:
    floor, q_floor = printed_floor()
    ours_best = min((r["fitness"] for r in rows if r["target_id"] == "printed"), default=math.inf)
    floor_used = min(floor, ours_best)

    def why_printed(solver: str, st: Stats) -> str | None:
        return printed_pose_reason(st, floor_used)

    sol = PAPER000_SOLVERS
    t = published.P000_TABLE2
    singular = np.linalg.svd(published.P000_TARGET_MM[:3, :3], compute_uv=False)
    parts = [
        _setup_000(cfg),
        "",
        render_comparison(
            Comparison(
                "(a) the pose as printed",
                _by(target_id="printed"),
                sol,
                t,
                floor=IK_FLOOR,
                why_worse=why_printed,
                why_default=_quick_why(cfg),
                attainable=floor_used,
                case="printed pose",
                notes=(
                    _text(
                        "note-printed",
                        singular_values=", ".join(f"{v:.7f}" for v in singular),
                        floor=f"{floor:.3g}",
                        q_floor=np.round(np.rad2deg(q_floor), 2).tolist(),
                        ours_best=fmt(ours_best),
                        paper_hlfoa=_published_mean(t, "hlfoa"),
                        tol=_g(TOL),
                    ),
                ),
            ),
            rows,
            hl,
            "000-table2",
        ),
        render_comparison(
            Comparison(
                "(b) full precision: target = FK(q*)",
                _by(target_id="exact"),
                sol,
                t,
                floor=IK_FLOOR,
                why_default=_quick_why(cfg),
                case="FK(q*)",
                notes=(
                    _text(
                        "note-exact",
                        q_exact=np.round(np.rad2deg(Q_EXACT), 4).tolist(),
                        paper_hlfoa=_published_mean(t, "hlfoa"),
                    ),
                    _text("note-foa", paper_foa_best=_published_mean(t, "foa", "best")),
                ),
            ),
            rows,
            hl,
            "000-table2",
        ),
        *_closing(sol, out, "000-table2"),
    ]
    return _join(parts)


Panel = tuple[str, Callable[[Mapping[str, Any]], bool], float]


def _plot_pair(
    exp_id: str,
    out: Path,
    rows: list[dict[str, Any]],
    hist: dict[str, Any],
    panels: Sequence[Panel],
    solvers: Sequence[str],
    title: str,
    *,
    refs: Sequence[tuple[float, str] | None] | None = None,
    value: str = "fitness",
) -> list[Path]:
    """An experiment's two plots: convergence (``convergence_<id>.png``) and the final values
    (``box_<id>.png``) of the registered ``solvers``, per panel."""
    from swarm_ik.bench import plots

    sol, _ = available(solvers)
    written = (
        plots.convergence(
            out / f"convergence_{exp_id}.png",
            rows,
            hist,
            panels,
            sol,
            title=title,
            ylabel=f"best {value}",
            refs=refs,
        ),
        plots.boxes(
            out / f"box_{exp_id}.png", rows, panels, sol, title=title, ylabel=f"final {value}"
        ),
    )
    return [p for p in written if p]


def _plots_000_table2(
    cfg: Config, rows: list[dict[str, Any]], hist: dict[str, Any], out: Path
) -> list[Path]:
    panels: list[Panel] = [
        ("(a) printed pose", _by(target_id="printed"), 0.0),
        ("(b) full precision, FK(q*)", _by(target_id="exact"), 0.0),
    ]
    printed = [r["fitness"] for r in rows if r["target_id"] == "printed"]
    floor = min(printed_floor()[0], min(printed, default=math.inf))
    title = "[HLFOA] Table 2 — YuMi left arm, fitness paper-l1"
    refs = [(floor, f"rounding floor {floor:.3g}"), None]
    return _plot_pair("000-table2", out, rows, hist, panels, PAPER000_SOLVERS, title, refs=refs)


def _section_000_table4(cfg: Config, rows: list[dict[str, Any]], hl: Headline, out: Path) -> str:
    sol = PAPER000_SOLVERS
    parts = [
        _setup_000(cfg)
        + "\n"
        + _text("poses-000", poses=cfg.poses_000, pose_seed=POSE_SEED, runs=cfg.runs_000_t4),
        "",
        render_comparison(
            Comparison(
                f"{cfg.poses_000} arbitrary reachable poses (pooled)",
                lambda r: True,
                sol,
                published.P000_TABLE4,
                floor=IK_FLOOR,
                why_default=_quick_why(cfg),
                case="arbitrary poses",
            ),
            rows,
            hl,
            "000-table4",
        ),
        "Mean fitness per pose:",
        "",
        per_target_means(rows, available(sol)[0]),
        *_closing(sol, out, "000-table4"),
    ]
    return _join(parts)


def _plots_000_table4(
    cfg: Config, rows: list[dict[str, Any]], hist: dict[str, Any], out: Path
) -> list[Path]:
    panels: list[Panel] = [(f"{cfg.poses_000} arbitrary poses, all runs", lambda r: True, 0.0)]
    title = "[HLFOA] Table 4 — YuMi left arm, arbitrary reachable poses"
    return _plot_pair("000-table4", out, rows, hist, panels, PAPER000_SOLVERS, title)


def _f_min(key: str) -> float:
    return published.HARTMANN3_MIN if key == "F4" else float(FUNCTIONS[key].f_min)


def _setup_003(block: str, cfg: Config, **values: Any) -> str:
    """``block`` filled with the [MGWO] set-up of this run (``pop``, ``iterations``, ``runs``)
    and of the paper (``paper_pop``, …), then ``values``."""
    keys = ("pop", "iterations", "runs")
    ours = {k: getattr(cfg, f"{k}_003") for k in keys}
    paper = {f"paper_{k}": getattr(FULL, f"{k}_003") for k in keys}
    return _text(block, **ours, **paper, mgwo_settings=_mgwo_settings(), **values)


def _mgwo_settings() -> str:
    """MGWO's defaults that [MGWO] does not give (the sub-packs, γ, ω, c1, c2), as
    ``swarm_ik.solvers.mgwo.run`` has them."""
    params = inspect.signature(mgwo.run).parameters
    names = {"subpops": "m", "gamma": "γ", "omega": "ω", "c1": "c1", "c2": "c2"}
    return ", ".join(f"{sym} = {params[k].default:g}" for k, sym in names.items())


def _gain_note(rows: list[dict[str, Any]]) -> str:
    """[MGWO] Table 4's MGWO-over-GWO gain on the reachable robot beside ours (mean fitness
    ratios), empty when a solver has no run."""
    mine = {
        s: [r["fitness"] for r in rows if r["robot"] == "loading_manipulator_long"
            and r["solver"] == s]
        for s in ("gwo", "mgwo")
    }  # fmt: skip
    if not mine["gwo"] or not mine["mgwo"]:
        return ""
    t = published.P003_TABLE4
    p_gwo, p_mgwo = (_printed_row(t, a).stats["mean"] for a in ("GWO", "MGWO"))
    o_gwo, o_mgwo = (float(np.mean(mine[s])) for s in ("gwo", "mgwo"))
    paper_gain, our_gain = p_gwo / p_mgwo, o_gwo / max(o_mgwo, 1e-300)
    ratio = our_gain / paper_gain
    word = (
        "the gain is of the paper's size" if 0.5 <= ratio <= 2.0
        else f"the gain is {'smaller' if ratio < 1 else 'larger'} than the paper's"
        + (" (MGWO is no better than GWO here)" if our_gain <= 1.0 else "")
    )  # fmt: skip
    return _text(
        "note-003-table4-gain", paper_gain=f"{paper_gain:.3g}", paper_gwo=fmt(p_gwo, 5),
        paper_mgwo=fmt(p_mgwo, 5), our_gain=f"{our_gain:.3g}", our_gwo=f"{o_gwo:.3g}",
        our_mgwo=f"{o_mgwo:.3g}", gain_word=word,
    )  # fmt: skip


def _f4_worst_note() -> str:
    """The note under F4: [MGWO] prints 0 as F4's worst value, which its means rule out."""
    t = published.P003_TABLE3["F4"]
    runs = FULL.runs_003
    means = {r.algorithm: r.stats["mean"] for r in t.rows}
    return _text(
        "note-f4-worst",
        worst=fmt(published.F4_WORST_AS_PRINTED),
        runs=runs,
        bound=f"{(runs - 1) / runs * published.HARTMANN3_MIN:.4f}",
        means=", ".join(f"{a} {m:g}" for a, m in means.items()),
    )


def _section_003_table3(cfg: Config, rows: list[dict[str, Any]], hl: Headline, out: Path) -> str:
    def why_mgwo(solver: str, st: Stats) -> str | None:
        if solver != "mgwo":
            return None
        return _text("why-mgwo", inline=True, pop=cfg.pop_003, mgwo_settings=_mgwo_settings())

    parts = [
        _setup_003(
            "setup-003-table3",
            cfg,
            hartmann_min=published.HARTMANN3_MIN,
            f4_resolution=_g(published.P003_TABLE3["F4"].resolution),
        ),
        "",
    ]
    for key, table in published.P003_TABLE3.items():
        parts.append(
            render_comparison(
                Comparison(
                    f"{key}: {table.caption}",
                    _by(robot=key),
                    ("gwo", "mgwo"),
                    table,
                    stats=("mean", "best", "worst", "var", "median"),  # the paper's order
                    f_min=_f_min(key),
                    floor=table.resolution,
                    digits=6 if key == "F4" else 3,
                    ik=False,
                    case=key,
                    why_worse=why_mgwo if key != "F4" else None,
                    notes=(_f4_worst_note(),) if key == "F4" else (),
                ),
                rows,
                hl,
                "003-table3",
            )
        )
    parts += [
        *_closing(("gwo", "mgwo"), out, "003-table3", value="values"),
    ]
    return _join(parts)


def _plots_003_table3(
    cfg: Config, rows: list[dict[str, Any]], hist: dict[str, Any], out: Path
) -> list[Path]:
    panels: list[Panel] = [
        (f"{k}: {t.caption}", _by(robot=k), _f_min(k)) for k, t in published.P003_TABLE3.items()
    ]
    title = "[MGWO] Table 3 — benchmark functions"
    return _plot_pair("003-table3", out, rows, hist, panels, ("gwo", "mgwo"), title, value="value")


def _stated_limits() -> dict[str, str]:
    """θ3's upper limit [deg] and d4..d6's [m] of the stated loading manipulator, and θ3 of
    x* [deg] (the paper's target violates the first two)."""
    upper = common.cached_robot("loading_manipulator").upper
    return {
        "theta3_max": f"{np.rad2deg(upper[2]):.2f}",
        "d_max": _g(upper[3]),
        "theta3_star": _g(np.rad2deg(published.P003_X_STAR[2])),
    }


def _section_003_table4(cfg: Config, rows: list[dict[str, Any]], hl: Headline, out: Path) -> str:
    limits = _stated_limits()
    stated = [r for r in rows if r["robot"] == "loading_manipulator"]
    best = min(stated, key=lambda r: r["fitness"], default=None)

    def why_unreachable(solver: str, st: Stats) -> str | None:
        if best is None:
            return None
        return _text(
            "why-unreachable",
            inline=True,
            fitness=f"{best['fitness']:.3g}",
            position_error=f"{best['position_error']:.3g}",
            theta3_max=limits["theta3_max"],
            d_max=limits["d_max"],
        )

    sol = PAPER003_SOLVERS
    budget = cfg.pop_003 * cfg.iterations_003
    t = published.P003_TABLE4
    stats = ("mean", "best", "worst", "var")
    parts = [
        _setup_003("setup-003-table4", cfg, budget=f"{budget:,}", **limits),
        "",
        render_comparison(
            Comparison(
                "`loading_manipulator_long` (d4..d6 ∈ [0, 1.5] m, the stroke D of the parameter "
                "table): reachable",
                _by(robot="loading_manipulator_long"),
                sol,
                t,
                stats=stats,
                floor=IK_FLOOR,
                case="long stroke (reachable)",
                notes=(
                    _text(
                        "note-003-table4-printed",
                        repeated=", ".join(published.P003_TABLE4_REPEATED_VAR),
                        vagwo_best=fmt(_printed_row(t, "VAGWO").stats["best"], 5),
                        mgwo_var=fmt(_printed_row(t, "MGWO").stats["var"], 5),
                    ),
                )
                + ((gain,) if (gain := _gain_note(rows)) else ()),
            ),
            rows,
            hl,
            "003-table4",
        ),
        render_comparison(
            Comparison(
                "`loading_manipulator` (stated limits, d4..d6 ∈ [0, 0.5] m): unreachable",
                _by(robot="loading_manipulator"),
                sol,
                t,
                stats=stats,
                floor=IK_FLOOR,
                why_worse=why_unreachable,
                case="stated limits (unreachable)",
                attainable=None if best is None else float(best["fitness"]),
                notes=(_text("note-unreachable"),),
            ),
            rows,
            hl,
            "003-table4",
        ),
        *_closing(sol, out, "003-table4"),
    ]
    return _join(parts)


def _plots_003_table4(
    cfg: Config, rows: list[dict[str, Any]], hist: dict[str, Any], out: Path
) -> list[Path]:
    panels: list[Panel] = [
        ("loading_manipulator_long (reachable)", _by(robot="loading_manipulator_long"), 0.0),
        ("loading_manipulator, stated limits (unreachable)", _by(robot="loading_manipulator"), 0.0),
    ]
    title = "[MGWO] Table 4 — loading manipulator, target FK(x*), fitness euler-zyz"
    return _plot_pair("003-table4", out, rows, hist, panels, PAPER003_SOLVERS, title)


def _section_budget(cfg: Config, rows: list[dict[str, Any]], hl: Headline, out: Path) -> str:
    sol = budget_solvers()
    parts = [
        _text(
            "setup-budget",
            budgets=", ".join(f"{b:,}" for b in cfg.budgets),
            tol=_g(TOL),
            poses=cfg.budget_poses,
            runs=cfg.budget_seeds,
        ),
        "",
    ]
    for robot in ("yumi_left", "loading_manipulator_long"):
        parts.append(
            render_budget(f"`{robot}`", [r for r in rows if r["robot"] == robot], sol, cfg.budgets)
        )
    parts.append(_img(out, "budget_success.png", "success rate against budget"))
    return _join(parts)


def _plots_budget(
    cfg: Config, rows: list[dict[str, Any]], hist: dict[str, Any], out: Path
) -> list[Path]:
    from swarm_ik.bench import plots

    p = plots.budget_success(
        out / "budget_success.png",
        rows,
        ["yumi_left", "loading_manipulator_long"],
        budget_solvers(),
        title=f"Success rate (‖Δp‖ ≤ {_g(TOL)} m, θ ≤ {_g(TOL)} rad) on equal evaluation budgets",
    )
    return [p] if p else []


EXPERIMENTS: dict[str, Experiment] = {
    e.id: e
    for e in (
        Experiment(
            "000-table2",
            "[HLFOA], Table 2 — YuMi left arm, the given pose",
            specs_000_table2,
            _section_000_table2,
            _plots_000_table2,
        ),
        Experiment(
            "000-table4",
            "[HLFOA], Table 4 — YuMi left arm, arbitrary reachable poses",
            specs_000_table4,
            _section_000_table4,
            _plots_000_table4,
        ),
        Experiment(
            "003-table3",
            "[MGWO], Table 3 — benchmark functions F1–F4",
            specs_003_table3,
            _section_003_table3,
            _plots_003_table3,
        ),
        Experiment(
            "003-table4",
            "[MGWO], Table 4 — loading manipulator, target FK(x*)",
            specs_003_table4,
            _section_003_table4,
            _plots_003_table4,
        ),
        Experiment(
            "budget",
            "Every solver against DLS on equal evaluation budgets",
            specs_budget,
            _section_budget,
            _plots_budget,
        ),
    )
}
"""The experiments, by id, in report order."""


# --------------------------------------------------------------------------- report
def plan_rows(exp: Experiment, cfg: Config, out: Path) -> list[dict[str, Any]]:
    """The CSV rows of ``exp`` that belong to configuration ``cfg`` (others ignored)."""
    keys = {s.key for s in exp.specs(cfg)}
    return [
        r
        for r in runner.read_rows(runner.csv_path(out, exp.id), solve_runs.SCHEMA)
        if r["key"] in keys
    ]


def _meta_path(out: Path) -> Path:
    return out / "meta.json"


def load_meta(out: Path) -> dict[str, Any]:
    """The bookkeeping of previous invocations (``meta.json``), or an empty record."""
    p = _meta_path(out)
    if p.exists():
        try:
            data = json.loads(p.read_text())
            if isinstance(data, dict):
                return data
        except json.JSONDecodeError:
            pass
    return {}


def environment() -> dict[str, Any]:
    """Machine and versions, for the report."""
    import numpy
    import pinocchio

    import swarm_ik

    return {
        "python": platform.python_version(),
        "platform": platform.platform(),
        "processor": platform.processor() or platform.machine(),
        "cpus": common.cpu_count(),
        "numpy": numpy.__version__,
        "pinocchio": pinocchio.__version__,
        "swarm_ik": swarm_ik.__version__,
    }


def build_report(cfg: Config, out: Path, experiments: Sequence[str] | None = None) -> str:
    """The Markdown report of the rows under ``out`` for configuration ``cfg``."""
    meta = load_meta(out)
    hl = Headline()
    body = []
    for exp in EXPERIMENTS.values():
        if experiments is not None and exp.id not in experiments:
            continue
        rows = plan_rows(exp, cfg, out)
        n_plan = len(exp.specs(cfg))
        info = meta.get("experiments", {}).get(exp.id, {})
        cpu = sum(float(r["time_s"]) for r in rows)
        status = (
            f"{len(rows)} of {n_plan} runs recorded" if len(rows) < n_plan else f"{n_plan} runs"
        )
        timing = f"sum of run times {cpu:.0f} s"
        if "wall_s" in info:
            where = info.get("where", f"--jobs {info.get('jobs', '?')}")
            new = info.get("new_runs")
            which = ", ".join(f"`{s}`" for s in info.get("new_solvers", []))
            timing += (
                f", wall-clock {info['wall_s']:.0f} s with {where} in the last invocation that "
                "ran it"
                + (
                    f" ({new} new runs" + (f" of {which}" if which else "") + ")"
                    if new is not None and new < n_plan
                    else ""
                )
            )
        if not rows:
            body.append(
                f"## {exp.title}\n\n_`{exp.id}`: not run yet ({n_plan} runs planned; "
                f"`--experiments {exp.id}`)._\n"
            )
            continue
        body.append(
            f"## {exp.title}\n\n_`{exp.id}`: {status}; {timing}._\n\n"
            + exp.section(cfg, rows, hl, out)
        )
    env = meta.get("environment") or environment()
    quick = cfg.name == "quick"
    last = ""
    if "last_wall_s" in meta:
        where = meta.get("last_where", f"--jobs {meta.get('last_jobs', '?')}")
        last = (
            f" Last invocation that ran experiments: {meta['last_wall_s']:.0f} s wall-clock "
            f"with {where}."
        )
    return (
        _text(
            "report",
            quick_title=" (QUICK run)" if quick else "",
            command="swarm-ik bench paper" + (" --quick" if quick else ""),
            quick_note=_text("quick") + "\n" if quick else "",
            tol=_g(TOL),
            factor=_g(common.VERDICT_FACTOR),
            ik_floor=_g(IK_FLOOR),
            environment=", ".join(f"{k} {v}" for k, v in env.items()),
            last_invocation=last,
            headline=render_headline(hl),
            sections="\n".join(body),
        )
        + "\n"
    )


def make_plots(cfg: Config, out: Path, experiments: Sequence[str] | None = None) -> list[Path]:
    """Write every experiment's plots from the files under ``out``."""
    written: list[Path] = []
    for exp in EXPERIMENTS.values():
        if experiments is not None and exp.id not in experiments:
            continue
        rows = plan_rows(exp, cfg, out)
        if not rows:
            continue
        hist = runner.read_histories(runner.history_path(out, exp.id))
        written += exp.plots(cfg, rows, hist, out)
    return written


# --------------------------------------------------------------------------- CLI
HELP = "the source papers' tables rerun, beside the published numbers"
"""One line for ``swarm-ik bench --help``."""


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Options of ``swarm-ik bench paper``."""
    parser.description = __doc__.split("\n\n")[0] if __doc__ else None
    parser.add_argument(
        "--quick",
        action="store_true",
        help="reduced version of everything (fewer runs, iterations and poses; about a "
        "minute on one core); default folder ./bench-paper-quick; never writes into a folder "
        "holding a full run",
    )
    parser.add_argument(
        "--jobs",
        type=count(1),
        default=common.cpu_count(),
        help="worker processes (default: the CPUs available)",
    )
    parser.add_argument(
        "--scheduler",
        default="none",
        metavar="none|local|tcp://HOST:PORT",
        help="where the runs execute: 'none' (default: no Dask, the local process pool of "
        "--jobs, as without this option), 'local' (an embedded Dask LocalCluster, one worker "
        "process per core; --jobs is then ignored) or the address of an existing Dask "
        "scheduler (its workers need swarm_ik installed). The default is 'none' "
        "because on one machine a LocalCluster is no faster than the pool; "
        "the results are the same either way (only time_s differs)",
    )
    common.add_out(parser, "paper", type=Path)
    subset = "subset to run: " + ", ".join(EXPERIMENTS)
    parser.add_argument("--experiments", nargs="+", metavar="ID", help=subset)
    runs = "override the number of runs per case and solver everywhere"
    parser.add_argument("--runs", type=count(1), help=runs)
    parser.add_argument("--no-plots", action="store_true", help="skip the PNG plots")
    parser.add_argument("--no-progress", action="store_true", help="no progress bar")
    parser.add_argument(
        "--report-only",
        action="store_true",
        help="only rebuild report.md and the plots from the CSV files",
    )


def config_from_args(args: argparse.Namespace) -> tuple[Config, Path, list[str]]:
    """Configuration, output folder and experiment ids from parsed options.

    Raises:
        UnknownNameError: an experiment id is not known (the valid ones listed).
        InvalidArgumentError: ``--runs`` or ``--jobs`` below 1, or an invalid ``--scheduler``
            (the valid forms listed).
    """
    from swarm_ik import distributed

    distributed.check_scheduler(getattr(args, "scheduler", None), threads=False)
    cfg = QUICK if args.quick else FULL
    if args.runs is not None:
        cfg = cfg.with_runs(args.runs)
    if args.jobs < 1:
        raise InvalidArgumentError(f"--jobs must be >= 1, got {args.jobs}")
    ids = list(args.experiments) if args.experiments else list(EXPERIMENTS)
    for i in ids:
        if i not in EXPERIMENTS:
            raise unknown("experiment", i, EXPERIMENTS)
    out = common.resolve_out(args.out, "paper", bool(args.quick))
    return cfg, out, ids


def _where(jobs: int, scheduler: Any, client: Any) -> str:
    """Where the runs executed, for ``meta.json`` and the report."""
    if client is None:
        return f"--jobs {jobs}"
    from swarm_ik import distributed

    name = scheduler if isinstance(scheduler, str) else "(a Dask client)"
    return f"--scheduler {name} ({distributed.n_workers(client)} Dask workers)"


def run(args: argparse.Namespace) -> int:
    """Run the selected experiments (resuming), then write the report and plots.

    Returns:
        0 when done, 130 when interrupted (finished runs are saved; rerun to resume).
    """
    cfg, out, ids = config_from_args(args)
    if args.report_only:
        common.require_results(
            out, [runner.csv_path(out, i) for i in ids], "paper", bool(args.quick)
        )
    common.write_run_info(out, "paper", cfg.name == "quick")
    meta = load_meta(out)
    meta["config"] = cfg.name
    meta["environment"] = environment()
    meta.setdefault("experiments", {})
    t_all = time.perf_counter()
    interrupted = False
    if not args.report_only:
        from swarm_ik import distributed

        scheduler = getattr(args, "scheduler", None)
        with distributed.connect(scheduler) as client:
            where = _where(args.jobs, scheduler, client)
            for i in ids:
                exp = EXPERIMENTS[i]
                specs = exp.specs(cfg)
                todo, _ = runner.pending(specs, out, solve_runs.SCHEMA)
                summary = runner.execute(
                    specs,
                    out,
                    solve_runs.run_one,
                    solve_runs.SCHEMA,
                    jobs=args.jobs,
                    client=client,
                    initializer=solve_runs.warm_up
                    if any(s.fitness_name != "function" for s in todo)
                    else None,
                    progress=False if args.no_progress else None,
                    desc=exp.id,
                )
                print(
                    f"{exp.id}: {summary.new} new, {summary.skipped} already done, "
                    f"of {summary.total} runs ({summary.wall_s:.1f} s)",
                    file=sys.stderr,
                )
                if summary.new:
                    meta["experiments"][exp.id] = {
                        "wall_s": summary.wall_s,
                        "jobs": args.jobs,
                        "where": where,
                        "new_runs": summary.new,
                        "new_solvers": sorted({s.solver for s in todo}),
                        "runs": summary.total,
                        "complete": summary.new + summary.skipped == summary.total,
                    }
                if summary.interrupted:
                    interrupted = True
                    break
        meta["last_wall_s"] = time.perf_counter() - t_all
        meta["last_jobs"] = args.jobs
        meta["last_where"] = where
        _meta_path(out).write_text(json.dumps(meta, indent=2) + "\n")
    written: list[Path] = []
    if not args.no_plots and not interrupted:
        from swarm_ik.bench.plots import PlotExtraMissingError

        try:
            written = make_plots(cfg, out)
        except PlotExtraMissingError as exc:
            print(f"swarm-ik: {exc}", file=sys.stderr)
    if interrupted:  # (no report: the run that resumes writes it; Ctrl-C ends at once)
        print(
            "interrupted: finished runs are saved; run the same command again to resume "
            "(it writes the report)",
            file=sys.stderr,
        )
        return 130
    report = out / "report.md"
    report.write_text(build_report(cfg, out))
    print(
        f"report: {report}" + (f"; plots: {len(written)} PNG in {out}" if written else ""),
        file=sys.stderr,
    )
    return 0


main = common.module_main(add_arguments, run, "paper")


if __name__ == "__main__":
    raise SystemExit(main())
