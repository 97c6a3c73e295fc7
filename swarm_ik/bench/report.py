"""Markdown report of the paper benchmark: our statistics beside the published ones.

Reads rows (from the CSV files, see :mod:`swarm_ik.bench.common`) and renders

* :class:`Comparison` tables: per solver, our best / mean / worst / … next to the paper's
  value of the same statistic (adjacent columns), the success rate, and a one-line verdict
  (:func:`swarm_ik.bench.common.judge`, applied to the **mean**, the statistic every published
  row has);
* budget tables (every solver against DLS on equal evaluation budgets);
* a headline table collecting every verdict;
* the prose around them, from the blocks of a template (:func:`render_block`).

Nothing here runs an experiment.
"""

from __future__ import annotations

import math
import re
import string
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from swarm_ik.bench.common import (
    TEMPLATES,
    Stats,
    Verdict,
    group_rows,
    judge,
    success_rate,
    summarize,
)
from swarm_ik.bench.published import PublishedTable
from swarm_ik.errors import InvalidArgumentError

Row = Mapping[str, Any]

_BLOCK = re.compile(r"^<!-- block ([\w-]+) -->\n", re.MULTILINE)


def template_blocks(template: str) -> dict[str, str]:
    """The blocks of a template file of :data:`swarm_ik.bench.common.TEMPLATES`: each
    starts at a line ``<!-- block NAME -->`` and runs to the next (text before the first
    block is a comment for the reader)."""
    parts = _BLOCK.split((TEMPLATES / template).read_text())
    return {parts[i]: parts[i + 1].rstrip("\n") for i in range(1, len(parts) - 1, 2)}


def render_block(template: str, block: str, *, inline: bool = False, **values: Any) -> str:
    """One block of ``template`` (:func:`template_blocks`) with its ``$name`` placeholders
    filled (``string.Template``; every placeholder must be given).

    Args:
        template: File name under :data:`swarm_ik.bench.common.TEMPLATES`.
        block: Block name.
        inline: Join the block's lines into one (for a table cell or a reason).
        **values: Placeholder values (``str()`` of each).

    Raises:
        InvalidArgumentError: no such block, or a placeholder has no value.
    """
    blocks = template_blocks(template)
    if block not in blocks:
        raise InvalidArgumentError(
            f"template {template} has no block {block!r}; its blocks: {', '.join(blocks)}"
        )
    try:
        text = string.Template(blocks[block]).substitute({k: str(v) for k, v in values.items()})
    except KeyError as exc:
        raise InvalidArgumentError(
            f"template {template}, block {block}: no value for {exc}"
        ) from None
    return " ".join(text.split()) if inline else text


def fmt(v: float | None, digits: int = 3) -> str:
    """A number for a table: ``digits`` significant digits, ``—`` for missing/NaN."""
    if v is None or (isinstance(v, float) and math.isnan(v)):
        return "—"
    if v == 0:
        return "0"
    return f"{v:.{digits}g}"


@dataclass(frozen=True)
class Comparison:
    """One table of the report: runs of some solvers on one case, against a published table.

    Attributes:
        title: Heading of the table.
        select: Predicate choosing the rows (runs) of this table.
        solvers: Solvers in display order (those without rows are skipped).
        published: The published table (``None``: ours only).
        stats: Statistics shown, each ours beside the paper's.
        f_min: Known minimum of the fitness (0 for IK).
        floor: Level below which values are not distinguished (see
            :func:`swarm_ik.bench.common.judge`).
        digits: Significant digits in the table.
        why_worse: ``(solver, our stats) -> reason or None``, shown when the verdict is
            *worse*.
        why_default: Reason shown when ``why_worse`` gives none (e.g. "quick run").
        attainable: Lowest fitness attainable (or found) for this target when it is above 0
            (a rounding floor, an unreachable pose).  A published mean below it cannot be
            reproduced: the verdict is *worse*, with the reason, whatever the ratio.
        ik: Whether the runs are IK runs (adds success and error columns).
        notes: Paragraphs printed under the table.
        case: Short label of the case for the headline table.
    """

    title: str
    select: Callable[[Row], bool]
    solvers: Sequence[str]
    published: PublishedTable | None
    stats: Sequence[str] = ("best", "mean", "worst", "std")
    f_min: float = 0.0
    floor: float = 0.0
    digits: int = 3
    why_worse: Callable[[str, Stats], str | None] | None = None
    why_default: str | None = None
    attainable: float | None = None
    ik: bool = True
    notes: Sequence[str] = ()
    case: str = ""


@dataclass
class Headline:
    """Collects the verdict rows for the headline table."""

    rows: list[tuple[str, str, str, str, str, str]] = field(default_factory=list)


def _verdict(comp: Comparison, solver: str, st: Stats) -> Verdict | None:
    if comp.published is None:
        return None
    prow = comp.published.row_for(solver)
    if prow is None or "mean" not in prow.stats:
        return None
    why = comp.why_worse(solver, st) if comp.why_worse is not None else None
    why = why or comp.why_default
    pub = prow.stats["mean"]
    v = judge(st.mean, pub, f_min=comp.f_min, floor=comp.floor, why_worse=why)
    if comp.attainable is not None and pub < comp.attainable and v.label != "worse":
        reason = why or (
            f"the paper's value lies below the lowest fitness attainable here "
            f"({comp.attainable:.3g})"
        )
        return Verdict("worse", v.ratio, f"worse (ratio {v.ratio:.2g}, but): {reason}", reason)
    return v


def short_verdict(v: Verdict) -> str:
    """The verdict label with the first clause of its reason (for the headline)."""
    if not v.reason:
        return v.text if v.label == "same order" else v.label
    reason = v.reason
    for cut in (";", " ("):
        reason = reason.split(cut)[0]
    return f"{v.label}: {reason}"


def render_comparison(
    comp: Comparison, rows: Iterable[Row], headline: Headline | None = None, experiment: str = ""
) -> str:
    """Markdown of one comparison table (with its notes)."""
    chosen = [r for r in rows if comp.select(r)]
    by_solver = group_rows(chosen, "solver")
    pub = comp.published
    head = ["algorithm", "runs"]
    for s in comp.stats:
        head += [f"{s} (ours)", f"{s} (paper)"]
    if comp.ik:
        head += ["success", "median ‖Δp‖ [m]"]
    head += ["verdict (on the mean)"]
    lines = [
        f"#### {comp.title}",
        "",
        "| " + " | ".join(head) + " |",
        "|" + "|".join("---" for _ in head) + "|",
    ]
    shown: set[str] = set()
    for solver in comp.solvers:
        runs = by_solver.get((solver,))
        if not runs:
            continue
        shown.add(solver)
        st = summarize(float(r["fitness"]) for r in runs)
        prow = pub.row_for(solver) if pub is not None else None
        name = f"{prow.algorithm} (`{solver}`)" if prow else f"`{solver}` (context)"
        cells = [name, str(st.n)]
        for s in comp.stats:
            cells.append(fmt(st.get(s), comp.digits))
            cells.append(fmt(prow.stats.get(s), comp.digits) if prow and s in prow.stats else "—")
        if comp.ik:
            cells.append(f"{100 * success_rate(r['success'] for r in runs):.0f} %")
            cells.append(fmt(float(np.median([float(r["position_error"]) for r in runs]))))
        v = _verdict(comp, solver, st)
        cells.append(v.text if v else "— (no published number)")
        lines.append("| " + " | ".join(cells) + " |")
        if v and headline is not None and prow is not None:
            headline.rows.append(
                (
                    experiment,
                    comp.case or comp.title,
                    prow.algorithm,
                    fmt(prow.stats["mean"], comp.digits),
                    fmt(st.mean, comp.digits),
                    short_verdict(v),
                )
            )
    if pub is not None:
        for prow in pub.rows:
            if prow.solver in shown:
                continue
            why = (
                "published only (not implemented here)"
                if prow.solver is None
                else f"published only (solver `{prow.solver}` not registered)"
            )
            cells = [prow.algorithm, "—"]
            for s in comp.stats:
                cells += ["—", fmt(prow.stats.get(s), comp.digits) if s in prow.stats else "—"]
            if comp.ik:
                cells += ["—", "—"]
            cells.append(why)
            lines.append("| " + " | ".join(cells) + " |")
    if not shown:
        lines.append("")
        lines.append("_No runs recorded yet for this table._")
    for note in comp.notes:
        lines += ["", note]
    return "\n".join(lines) + "\n"


def render_budget(
    title: str, rows: Iterable[Row], solvers: Sequence[str], budgets: Sequence[int]
) -> str:
    """Markdown of the equal-budget table: one block of rows per budget.

    Columns: success rate, median evaluations of the successful runs, median time, median
    position and rotation errors (all runs).
    """
    rows = list(rows)
    by = group_rows(rows, "max_evals", "solver")
    head = [
        "budget",
        "solver",
        "runs",
        "success",
        "median evals (successes)",
        "median time [ms]",
        "median ‖Δp‖ [m]",
        "median θ [rad]",
    ]
    lines = [
        f"#### {title}",
        "",
        "| " + " | ".join(head) + " |",
        "|" + "|".join("---" for _ in head) + "|",
    ]
    for b in budgets:
        for solver in solvers:
            runs = by.get((b, solver))
            if not runs:
                continue
            ok = [r for r in runs if r["success"]]
            evals = fmt(float(np.median([r["n_evals"] for r in ok]))) if ok else "—"
            lines.append(
                "| "
                + " | ".join(
                    [
                        f"{b:,}",
                        f"`{solver}`",
                        str(len(runs)),
                        f"{100 * success_rate(r['success'] for r in runs):.0f} %",
                        evals,
                        fmt(1e3 * float(np.median([r["time_s"] for r in runs]))),
                        fmt(float(np.median([r["position_error"] for r in runs]))),
                        fmt(float(np.median([r["rotation_error"] for r in runs]))),
                    ]
                )
                + " |"
            )
    return "\n".join(lines) + "\n"


def render_headline(headline: Headline) -> str:
    """Markdown of the headline table (every row with a published mean and its verdict)."""
    head = ["experiment", "case", "algorithm", "mean (paper)", "mean (ours)", "verdict"]
    lines = ["| " + " | ".join(head) + " |", "|" + "|".join("---" for _ in head) + "|"]
    for r in headline.rows:
        lines.append("| " + " | ".join(r) + " |")
    return "\n".join(lines) + "\n"


def per_target_means(rows: Iterable[Row], solvers: Sequence[str], digits: int = 3) -> str:
    """Markdown table of the mean fitness per target (rows) and solver (columns)."""
    rows = list(rows)
    by = group_rows(rows, "target_id", "solver")
    targets = list(dict.fromkeys(r["target_id"] for r in rows))
    cols = [s for s in solvers if any((t, s) in by for t in targets)]
    lines = [
        "| target | " + " | ".join(f"`{s}`" for s in cols) + " |",
        "|---|" + "|".join("---" for _ in cols) + "|",
    ]
    for t in targets:
        cells = [
            fmt(float(np.mean([r["fitness"] for r in by[(t, s)]])), digits) if (t, s) in by else "—"
            for s in cols
        ]
        lines.append(f"| {t} | " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"
