"""``swarm-ik bench ik``: a fair peer table for single IK calls.

Protocol: per robot, ``N`` joint vectors drawn uniformly within the limits (seeded); their
FK are the targets (all reachable).  Each target is one task of :mod:`swarm_ik.bench.runner`:
**every peer solves it in turn, in a seeded random order** (drawn uniformly among the orders
in which ``swarm`` and ``ik-solver``, the same search, do not run one right after the other:
with those two and one other peer, that peer runs between them every time; with more, each of
the two runs first more often than another peer, in a third of the targets against a sixth
with four peers), from the middle of the joint ranges, within the time budget where the peer
has one.  Every process runs one thread per numeric library
(:func:`swarm_ik.bench.common.single_thread`; TRAC-IK's Speed mode still runs its two solver
threads, that is how it works).

Each answer is checked by the benchmark, identically for every peer, with Pinocchio's FK
(:func:`swarm_ik.verify`): **strict** success = ‖Δp‖ ≤ tol [m] and geodesic angle ≤ tol
[rad] (Euclidean norms) and within the joint limits; **lenient** the same at
``--lenient-tol``.  The peer's own success flag is kept beside it (``claimed``).  Times per
call: ``call_s`` is the user-facing call from the 4x4 target to the answer; ``own_s`` the
solver's own part (see :mod:`swarm_ik.bench.peers`).

Writes under ``--out``: ``peers.csv`` (one row per target and peer, appended as tasks
finish; rerun to resume), ``summary.md`` (from the CSV and ``templates/ik.md``) and
``run.json``.
"""

from __future__ import annotations

import argparse
import dataclasses
import functools
import json
import math
import sys
import time
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from swarm_ik import argtypes
from swarm_ik.argtypes import count, positive_number
from swarm_ik.bench import common, peers, plans, runner
from swarm_ik.bench.plans import IKPlan, IKTask
from swarm_ik.errors import InvalidArgumentError

FIELDS = (
    "key",
    "experiment",
    "robot",
    "target_id",
    "budget_ms",
    "solver",
    "order",
    "seed",
    "claimed",
    "strict",
    "lenient",
    "within_limits",
    "position_error",
    "rotation_error",
    "call_s",
    "own_s",
    "iterations",
    "note",
)
"""Columns of ``peers.csv``."""

SCHEMA = runner.Schema(
    FIELDS,
    ints=frozenset({"target_id", "order", "seed"}),
    floats=frozenset(
        {"budget_ms", "position_error", "rotation_error", "call_s", "own_s", "iterations"}
    ),
    bools=frozenset({"claimed", "strict", "lenient", "within_limits"}),
)
"""Typed schema of ``peers.csv``.  A row with a ``note`` is a peer that could not be built for
that robot (no answer; left out of the statistics and listed in the summary)."""

COMMAND = "ik"


# --------------------------------------------------------------------------- worker
TARGET_BLOCK = 1024
"""Targets drawn at once per robot and seed (target ``i`` is row ``i`` of a draw of
``TARGET_BLOCK · (i // TARGET_BLOCK + 1)``: the first rows of a draw do not depend on its
size).  A draw per task (``i + 1`` targets, a cache miss each time) ran hundreds of forward
kinematics between two timed calls and slowed the next call of a peer by up to 20 µs (its
caches evicted), ours more than the C++ peers."""


@functools.lru_cache(maxsize=8)
def _targets(robot_name: str, n: int, seed: int) -> np.ndarray:
    return common.fk_targets(common.cached_robot(robot_name), n, seed)


def _target(robot_name: str, i: int, seed: int) -> np.ndarray:
    """Target ``i`` of a robot and seed (see :data:`TARGET_BLOCK`)."""
    return _targets(robot_name, TARGET_BLOCK * (i // TARGET_BLOCK + 1), seed)[i]


@functools.lru_cache(maxsize=64)
def _peer(name: str, robot_name: str, budget_ms: float, tol: float) -> tuple[Any, str]:
    """``(adapter, "")`` built and warmed up (one untimed call), or ``(None, why not)``."""
    robot = common.cached_robot(robot_name)
    try:
        p = peers.make(name, robot, budget_ms * 1e-3, tol)
    except InvalidArgumentError as exc:
        return None, str(exc)
    warm = np.asarray(robot.fk(robot.random_q(np.random.default_rng(12345))), dtype=float)
    p.solve(warm, robot.mid_q(), 0)  # kernels compiled / loaded, caches filled: not timed
    return p, ""


def check(robot: Any, target: np.ndarray, q: np.ndarray | None) -> tuple[float, float, bool]:
    """The benchmark's own check of an answer with Pinocchio: ``(‖Δp‖ [m], angle [rad],
    within limits)``; ``(inf, inf, False)`` without an answer.

    Pinocchio's FK of the frame (:meth:`RobotModel.fk_pinocchio`) and the angle of
    ``R*ᵀR`` (:func:`swarm_ik.kernels.lie.relative_angles`: NumPy and libm, the bits of the
    judge's own), not ``swarm_ik.verify`` nor a compiled call: the check runs between peers'
    calls, and going through our route warmed our next call (35 % off its median after a
    cold peer, review 117; rtb's 4 %)."""
    from swarm_ik.kernels.lie import relative_angles

    if q is None or not np.all(np.isfinite(q)):
        return math.inf, math.inf, False
    pose = robot.fk_pinocchio(q)
    dp = float(np.linalg.norm(pose[:3, 3] - target[:3, 3]))
    angle = float(relative_angles(target[:3, :3], pose[:3, :3]))
    return dp, angle, robot.within_limits(q, tol=1e-12)


def run_task(task: IKTask) -> runner.Outcome:
    """Solve one target with every peer of the task, in the task's order; one row each."""
    robot = common.cached_robot(task.robot)
    target = _target(task.robot, task.target_id, task.seed)
    q0 = robot.mid_q()
    rows: list[dict[str, Any]] = []
    answers = []  # (checked after every peer of the task has run: see check)
    for k, name in enumerate(task.order()):
        base = {
            "key": f"{task.key}|{name}",
            "experiment": task.experiment,
            "robot": task.robot,
            "target_id": task.target_id,
            "budget_ms": task.budget_ms,
            "solver": name,
            "order": k,
            "seed": task.seed,
        }
        peer, why = _peer(name, task.robot, task.budget_ms, task.tol)
        if peer is None:
            nan = math.nan
            rows.append(
                {
                    **base,
                    **dict.fromkeys(("claimed", "strict", "lenient", "within_limits"), False),
                    **dict.fromkeys(
                        ("position_error", "rotation_error", "call_s", "own_s", "iterations"),
                        nan,
                    ),
                    "note": why,
                }
            )
            continue
        answers.append((base, peer.solve(target, q0, task.seed + task.target_id)))
    for base, ans in answers:
        dp, dr, within = check(robot, target, ans.q)
        rows.append(
            {
                **base,
                "claimed": ans.claimed,
                "strict": bool(within and dp <= task.tol and dr <= task.tol),
                "lenient": bool(within and dp <= task.lenient_tol and dr <= task.lenient_tol),
                "within_limits": within,
                "position_error": dp,
                "rotation_error": dr,
                "call_s": ans.call_s,
                "own_s": ans.own_s,
                "iterations": ans.iterations,
                "note": "",
            }
        )
    rows.sort(key=lambda r: int(r["order"]))  # (the order the peers ran in)
    return runner.Outcome(rows, task_key=task.key)


def init_worker() -> None:
    """Worker-process set-up: one thread per numeric library."""
    common.single_thread()


# --------------------------------------------------------------------------- statistics
def summarise(rows: Sequence[dict[str, Any]]) -> list[dict[str, Any]]:
    """One record per (robot, budget, solver), in first-seen robot/budget order and plan peer
    order, plus a pooled record per (budget, solver) with ``robot = "all"``."""
    groups: dict[tuple[str, float, str], list[dict[str, Any]]] = {}
    for r in rows:
        if r["note"]:
            continue
        groups.setdefault((r["robot"], r["budget_ms"], r["solver"]), []).append(r)
        groups.setdefault(("all", r["budget_ms"], r["solver"]), []).append(r)
    rank: dict[str, int] = {}
    for r in rows:
        rank.setdefault(r["solver"], len(rank))
    out = []
    for (robot, budget, solver), g in sorted(
        groups.items(), key=lambda kv: (kv[0][0] == "all", kv[0][1], rank[kv[0][2]])
    ):
        call = common.timing(r["call_s"] for r in g)
        own = common.timing(r["own_s"] for r in g)
        out.append(
            {
                "robot": robot,
                "budget_ms": budget,
                "solver": solver,
                "n": len(g),
                "strict": 100.0 * float(np.mean([r["strict"] for r in g])),
                "lenient": 100.0 * float(np.mean([r["lenient"] for r in g])),
                "claimed": 100.0 * float(np.mean([r["claimed"] for r in g])),
                "disagree": 100.0 * float(np.mean([r["claimed"] != r["strict"] for r in g])),
                "call": call,
                "own": own,
            }
        )
    return out


def _ms(v: float) -> str:
    return "–" if not np.isfinite(v) else f"{1e3 * v:.3f}"


def _table(stats: Sequence[dict[str, Any]], robot: str, budget: float) -> str:
    head = (
        "| solver | N | strict % | lenient % | claims % | flag ≠ check % | call median ms "
        "| call p95 | call p99 | call max | own median ms | own p99 |\n"
        "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n"
    )
    lines = []
    for s in stats:
        if s["robot"] != robot or s["budget_ms"] != budget:
            continue
        c, o = s["call"], s["own"]
        lines.append(
            f"| {s['solver']} | {s['n']} | {s['strict']:.1f} | {s['lenient']:.1f} "
            f"| {s['claimed']:.1f} | {s['disagree']:.1f} | {_ms(c.median)} | {_ms(c.p95)} "
            f"| {_ms(c.p99)} | {_ms(c.max)} | {_ms(o.median)} | {_ms(o.p99)} |"
        )
    return head + "\n".join(lines) + "\n"


def write_summary(out: Path, plan: IKPlan, quick: bool, wall_s: float | None) -> Path:
    """``summary.md`` from ``peers.csv`` and the template ``templates/ik.md``."""
    order = {p: i for i, p in enumerate(plan.peers)}
    # (the plan's own tasks only: rows of another --n, --seed, --tol, budget or peer set in
    # the same folder were pooled under this plan's header)
    planned = {task.key for task in plans.ik_tasks(plan)}
    rows = sorted(
        (
            r
            for r in runner.read_rows(runner.csv_path(out, "peers"), SCHEMA)
            if r["key"].rsplit("|", 1)[0] in planned and r["solver"] in order
        ),
        key=lambda r: order[r["solver"]],
    )
    stats = summarise(rows)
    sections = []
    for b in plan.budgets_ms:
        for robot in (*plan.robots, *(("all",) if len(plan.robots) > 1 else ())):
            if any(s["robot"] == robot and s["budget_ms"] == b for s in stats):
                title = "all robots pooled" if robot == "all" else f"`{robot}`"
                sections.append(f"### {title}, budget {b:g} ms\n\n" + _table(stats, robot, b))
    notes = sorted({(r["robot"], r["solver"], r["note"]) for r in rows if r["note"]})
    skipped = "\n".join(f"- `{s}` on `{r}`: {n}" for r, s, n in notes) or "- none"
    described = "\n".join(f"- `{n}`: {peers.PEERS[n].what}" for n in plan.peers if n in peers.PEERS)
    # (a run records its machine before its report: none recorded is an older run's, whose
    # host is not this one's)
    info = recorded_machine(out) or {"host": "not recorded by the run"}
    command = (
        f"swarm-ik bench ik --robots {' '.join(plan.robots)} --peers {' '.join(plan.peers)} "
        f"--n {plan.n} --budgets-ms {' '.join(f'{b:g}' for b in plan.budgets_ms)} "
        f"--seed {plan.seed} --tol {plan.tol:g} --lenient-tol {plan.lenient_tol:g}"
        + (" --quick" if quick else "")
    )
    text = common.render(
        "ik.md",
        command=command,
        quick_note="**Quick run** (a smoke test, few targets): do not quote these numbers.\n"
        if quick
        else "",
        robots=", ".join(f"`{r}`" for r in plan.robots),
        n=plan.n,
        seed=plan.seed,
        budgets=", ".join(f"{b:g}" for b in plan.budgets_ms),
        tol=f"{plan.tol:g}",
        lenient_tol=f"{plan.lenient_tol:g}",
        peers=described,
        skipped=skipped,
        tables="\n".join(sections) if sections else "_no rows yet_\n",
        machine=", ".join(f"{k} {v}" for k, v in info.items()),
        wall=""
        if wall_s is None
        else f" This invocation took {wall_s:.{0 if wall_s >= 10 else 1}f} s of wall-clock time.",
        n_rows=len(rows),
    )
    path = out / "summary.md"
    path.write_text(text)
    return path


# --------------------------------------------------------------------------- CLI
HELP = (
    "fair peer table for single IK calls (ours, TRAC-IK, rtb, pink, ikpy), checked with Pinocchio"
)
"""One line for ``swarm-ik bench --help``."""


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Options of ``swarm-ik bench ik``."""
    parser.description = (
        "Fair peer table for single IK calls: every peer (ours, TRAC-IK, roboticstoolbox, "
        "pink, ikpy) solves the same FK-sampled targets, interleaved per target in a seeded "
        "random order, one thread each; success is checked with Pinocchio (strict and "
        "lenient), the peer's own flag kept beside it; user-facing and solver-own call times."
    )
    parser.add_argument(
        "--robots",
        nargs="+",
        default=None,
        help=f"robots (default: {' '.join(plans.IK_ROBOTS)}; with --quick "
        f"{' '.join(plans.IK_QUICK_ROBOTS)})",
    )
    parser.add_argument(
        "--peers",
        "--solvers",
        dest="peers",
        nargs="+",
        default=None,
        metavar="PEER",
        help=f"peer adapters (default: those installed among {', '.join(plans.IK_PEERS)}; "
        "optional ones need pip install 'swarm_ik[bench]')",
    )
    parser.add_argument(
        "--n",
        type=count(1),
        default=None,
        help=f"targets per robot (default 1000; with --quick {plans.IK_QUICK_N})",
    )
    budgets = " ".join(f"{b:g}" for b in IKPlan.budgets_ms)  # IKPlan's default
    parser.add_argument(
        "--budgets-ms",
        nargs="+",
        type=positive_number,
        default=list(IKPlan.budgets_ms),
        metavar="MS",
        help=f"time budgets per call [ms] (default {budgets}); peers without a time limit "
        "(rtb, ikpy) run to their own iteration limits, and their times show it",
    )
    argtypes.add_seed(parser, "seed of targets and run order")
    parser.add_argument(
        "--tol",
        type=positive_number,
        default=1e-5,
        help="strict tolerance [m and rad] (default 1e-5)",
    )
    parser.add_argument(
        "--lenient-tol",
        type=positive_number,
        default=2e-5,
        help="lenient tolerance [m and rad] (default 2e-5)",
    )
    parser.add_argument(
        "--jobs",
        type=count(1),
        default=1,
        help="worker processes (default 1: one call at a time, as a timing benchmark should; "
        "more only to check that it works)",
    )
    parser.add_argument(
        "--scheduler",
        default="none",
        metavar="none|local|tcp://HOST:PORT",
        help="'none' (default: this process or --jobs processes), 'local' (a Dask "
        "LocalCluster) or a Dask scheduler address; timings on shared workers are noisier",
    )
    common.add_out(parser, COMMAND)
    parser.add_argument(
        "--quick",
        action="store_true",
        help="a smoke test: few targets on two robots; never writes into a full run's folder",
    )
    parser.add_argument(
        "--report-only", action="store_true", help="only rebuild summary.md from peers.csv"
    )
    parser.add_argument(
        "--no-progress", action="store_true", help="no progress bar (shown only on a terminal)"
    )


PACKAGES = ("pytracik", "roboticstoolbox-python", "pin-pink", "ikpy", "threadpoolctl")
"""The peers' distributions whose versions a report names."""


def recorded_machine(out: Path) -> dict[str, str] | None:
    """The machine a run recorded in ``out``'s :data:`~swarm_ik.bench.common.RUN_INFO` (where
    its rows were measured: ``--report-only`` on another host names the run's), or None."""
    try:
        rec = json.loads((Path(out) / common.RUN_INFO).read_text()).get("machine")
    except (OSError, ValueError, AttributeError):
        return None
    ok = isinstance(rec, dict) and all(isinstance(v, str) for v in rec.values())
    return rec if ok else None


def recorded_plan(out: Path) -> IKPlan | None:
    """The plan a run recorded in ``out``'s :data:`~swarm_ik.bench.common.RUN_INFO` (what
    ``--report-only`` reports, whatever its own arguments), or None where it recorded none."""
    try:
        rec = json.loads((Path(out) / common.RUN_INFO).read_text()).get("plan")
        if not isinstance(rec, dict):
            return None
        return IKPlan(
            robots=tuple(rec["robots"]), peers=tuple(rec["peers"]),
            budgets_ms=tuple(float(b) for b in rec["budgets_ms"]), n=int(rec["n"]),
            seed=int(rec["seed"]), tol=float(rec["tol"]), lenient_tol=float(rec["lenient_tol"]),
        )  # fmt: skip
    except (OSError, ValueError, KeyError, TypeError, InvalidArgumentError):
        return None


def plan_from_args(args: argparse.Namespace) -> tuple[IKPlan, bool]:
    """The plan of an invocation and whether it is ``--quick``.

    Raises:
        InvalidArgumentError: unknown peer or robot, or invalid sizes.
    """
    quick = bool(args.quick)
    robots = tuple(args.robots or (plans.IK_QUICK_ROBOTS if quick else plans.IK_ROBOTS))
    n = args.n if args.n is not None else (plans.IK_QUICK_N if quick else 1000)
    if args.peers:
        names = tuple(args.peers)
        for p in names:
            peers.get(p)  # unknown names refused with the list
    else:
        names = tuple(p for p in plans.IK_PEERS if peers.get(p).available())
    import swarm_ik

    known = swarm_ik.robot_names()
    flat = {r for v in known.values() for r in v}
    for r in robots:
        if r not in flat and not r.endswith(".urdf"):
            raise InvalidArgumentError(f"unknown robot {r!r}; valid: {', '.join(sorted(flat))}")
    plan = IKPlan(
        robots=robots,
        peers=names,
        budgets_ms=tuple(float(b) for b in args.budgets_ms),
        n=int(n),
        seed=int(args.seed),
        tol=float(args.tol),
        lenient_tol=float(args.lenient_tol),
    )
    return plan, quick


def run(args: argparse.Namespace) -> int:
    """Run ``bench ik`` with parsed options; returns the exit code (0; 130 when interrupted)."""
    from swarm_ik import distributed

    distributed.check_scheduler(getattr(args, "scheduler", None), threads=False)
    if args.jobs < 1:
        raise InvalidArgumentError(f"--jobs must be >= 1, got {args.jobs}")
    plan, quick = plan_from_args(args)
    out = common.resolve_out(args.out, COMMAND, quick)
    if args.report_only:
        common.require_results(out, [runner.csv_path(out, "peers")], COMMAND, quick)
        recorded = recorded_plan(out)  # (the header names the run, not this invocation)
        if recorded is None:
            print(
                f"{out}: the run recorded no plan; the report's header names this invocation's",
                file=sys.stderr,
            )
        plan = recorded or plan
    else:  # (a .urdf path is only checked by loading it)
        common.check_robots([r for r in plan.robots if r.endswith(".urdf")])
        absent = [p for p in plan.peers if not peers.get(p).available()]
        if absent:  # (named by the caller: refused, not recorded as done without answers, a
            # row that a later run with the package installed never replaced)
            raise InvalidArgumentError(
                f"peer(s) {', '.join(absent)} cannot run here (their packages do not import): "
                f"{peers.EXTRA_HINT}, or leave them out of --peers"
            )
        common.write_run_info(
            out,
            COMMAND,
            quick,
            plan=dataclasses.asdict(plan),
            machine=common.machine_info(PACKAGES),
        )
    common.single_thread()
    missing = [p for p in plans.IK_PEERS if not peers.get(p).available()]
    if missing and not args.peers:
        print(
            f"not available here, skipped: {', '.join(missing)} ({peers.EXTRA_HINT})",
            file=sys.stderr,
        )
    wall = None
    interrupted = False
    if not args.report_only:
        t0 = time.perf_counter()
        with distributed.connect(getattr(args, "scheduler", None)) as client:
            summary = runner.execute(
                plans.ik_tasks(plan),
                out,
                run_task,
                SCHEMA,
                jobs=args.jobs,
                client=client,
                initializer=init_worker,
                multi_row=True,
                progress=False if args.no_progress else None,
                desc="bench ik",
            )
        wall = time.perf_counter() - t0
        interrupted = summary.interrupted
        print(
            f"bench ik: {summary.new} new, {summary.skipped} already done, of {summary.total} "
            f"targets ({wall:.1f} s)",
            file=sys.stderr,
        )
    if interrupted:  # (as bench paper: no report of a part; the run that resumes writes it)
        print(
            "interrupted: finished targets are saved; run the same command again to resume "
            "(it writes the report)",
            file=sys.stderr,
        )
        return 130
    path = write_summary(out, plan, quick, wall)
    written = [path] if args.report_only else [runner.csv_path(out, "peers"), path]
    print(f"wrote {', '.join(map(str, written))}", file=sys.stderr)
    return 0


main = common.module_main(add_arguments, run, "ik")


if __name__ == "__main__":
    raise SystemExit(main())
