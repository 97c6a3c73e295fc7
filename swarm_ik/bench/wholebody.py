"""``swarm-ik bench wholebody``: Talos standing, both hands to poses, the centre of mass over
the feet — swarm_ik beside placo and pink on the same targets, judged the same way.

Targets (:func:`swarm_ik.bench.wholebody_peers.talos_wholebody_targets`): the torso and arm
joints drawn uniformly within their limits, the legs in the half-sitting posture with both
soles flat on the ground, kept when the centre of mass lies over the support polygon (so a
balanced answer exists).  Each problem: both soles at their poses (6-D), both hands at their
poses (6-D), the centre of mass inside the polygon, the joints within their limits and the
torso at its drawn values (locked).  Every solver starts from the half-sitting posture.

Solvers, interleaved chunk by chunk on the same targets, in an order drawn anew for each
chunk (seeded by ``--seed``), so that no solver always runs after the same one:

* ``swarm_ik``: :func:`swarm_ik.solve` of ``Pose`` goals on the soles and hands and a
  ``CenterOfMass(support=polygon)`` goal, a floating base (``load_robot(...,
  floating_base=True)``), the torso held by bounds ``lower = upper`` = its drawn values (the
  same problem as ``locked=``, whose reduced model would be rebuilt for every target);
  ``--time-limit-ms`` per call (the whole call: the problem built, solved, checked).
* ``swarm_ik-tolerance``: the same with the hand goals given per-axis tolerances
  (``Pose(..., tolerance=TOL)``, :data:`HAND_TOLERANCE`): how much faster a tolerance goal
  converges than the exact one (judged by swarm_ik's own Pinocchio check, inside the bounds).
* ``placo`` (in its own environment: :func:`~swarm_ik.bench.wholebody_peers.run_placo`) and
  ``pink`` (:func:`~swarm_ik.bench.wholebody_peers.run_pink`), each iterated to convergence
  under the same time limit.

Every answer is judged by :func:`~swarm_ik.bench.wholebody_peers.judge_wholebody` (Pinocchio
alone on the whole URDF: soles and hands to 1e-5 m / 1e-5 rad, centre of mass inside the
polygon, limits, torso values) and by the solver's own claim; both are reported.  Writes
``wholebody.csv`` (one row per target and solver), ``summary.md`` and ``times.png`` under
``--out``.
"""

from __future__ import annotations

import argparse
import math
import os
import platform
import time
from pathlib import Path
from typing import Any

import numpy as np

from swarm_ik import argtypes
from swarm_ik.argtypes import count, positive_number
from swarm_ik.bench import common
from swarm_ik.bench import wholebody_peers as wp
from swarm_ik.errors import InvalidArgumentError, SwarmIKError

COMMAND = "wholebody"
SOLVERS = ("swarm_ik", "swarm_ik-tolerance", "placo", "pink")
"""Every solver the benchmark can run (``--solvers``)."""
HAND_TOLERANCE = (0.005, 0.005, 0.005, 0.05, 0.05, 0.05)
"""Per-axis bounds of the hand goals of ``swarm_ik-tolerance``: ±5 mm and ±0.05 rad about
each axis of the target frame."""
GOAL_TOL = 1e-5
"""Success tolerance of every goal [m, rad]."""
FIELDS = (
    "solver", "target", "success", "claimed", "time_ms", "iterations", "sole_pos",
    "hand_pos", "hand_rot", "com_margin", "error",
)  # fmt: skip


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """The options of ``swarm-ik bench wholebody``."""
    parser.add_argument("--n", type=count(1), default=500, help="number of targets (default 500)")
    argtypes.add_seed(parser, "seed of the targets", default=1)
    parser.add_argument(
        "--time-limit-ms",
        type=positive_number,
        default=100.0,
        help="limit of one call [ms] (default 100)",
    )
    parser.add_argument(
        "--chunk", type=count(1), default=50, help="targets per interleaved chunk (default 50)"
    )
    parser.add_argument(
        "--solvers",
        default=",".join(SOLVERS),
        help=f"comma-separated, of: {', '.join(SOLVERS)} (default all)",
    )
    parser.add_argument(
        "--quick", action="store_true", help="20 targets, a smoke run (not for the docs)"
    )
    parser.add_argument("--no-plots", action="store_true", help="skip times.png")
    common.add_out(parser, COMMAND)


# --------------------------------------------------------------------------- swarm_ik
class Ours:
    """swarm_ik on the whole-body targets (one robot, loaded once)."""

    def __init__(self, targets: wp.WholebodyTargets) -> None:
        import swarm_ik

        frames = list(wp.SOLE_FRAMES + wp.HAND_FRAMES)
        self.robot = swarm_ik.load_robot(
            targets.model_path, frames, floating_base=True, base_box=(1.0, 1.0, 2.0)
        )
        if self.robot.full_model.nq != targets.q0.shape[1]:
            raise InvalidArgumentError("the robot's model does not match the targets")
        self.torso = [self.robot.joint_names.index(j) for j in wp.LOCKED_JOINTS]
        self.targets = targets

    def problem(self, k: int, tolerance: Any = None) -> Any:
        """The IK problem of target ``k`` (hand goals with ``tolerance`` when given)."""
        import swarm_ik
        from swarm_ik import goals

        t = self.targets
        lo, hi = self.robot.lower.copy(), self.robot.upper.copy()
        lo[self.torso] = hi[self.torso] = t.locked[k]
        hands = {"tolerance": tolerance} if tolerance is not None else {}
        terms = [
            goals.Pose(wp.SOLE_FRAMES[0], t.left_sole[k]),
            goals.Pose(wp.SOLE_FRAMES[1], t.right_sole[k]),
            goals.Pose(wp.HAND_FRAMES[0], t.left_hand[k], **hands),
            goals.Pose(wp.HAND_FRAMES[1], t.right_hand[k], **hands),
            goals.CenterOfMass(support=t.polygon[k]),
        ]
        return swarm_ik.IKProblem(self.robot, goals=terms, lower=lo, upper=hi)

    def solve(self, index: np.ndarray, time_limit: float, tolerance: Any = None) -> wp.PeerAnswers:
        """Solve the targets ``index``: one :func:`swarm_ik.solve` each, timed whole."""
        import swarm_ik

        n = len(index)
        q = np.full((n, self.robot.full_model.nq), np.nan)
        secs = np.zeros(n)
        solve_s = np.zeros(n)
        claimed = np.zeros(n, dtype=bool)
        evals = np.zeros(n, dtype=np.int64)
        for i, k in enumerate(index):
            t0 = time.perf_counter()
            problem = self.problem(int(k), tolerance)
            q0 = self.robot.from_full_configuration(self.targets.q0[k])
            t1 = time.perf_counter()
            res = swarm_ik.solve(problem, seed=int(k), time_limit=time_limit, q0=q0)
            secs[i] = time.perf_counter() - t0
            solve_s[i] = time.perf_counter() - t1
            q[i] = self.robot.full_configuration(res.q)
            claimed[i] = res.success
            evals[i] = res.n_evals
        name = "swarm_ik" if tolerance is None else "swarm_ik-tolerance"
        return wp.PeerAnswers(
            name, q, secs, solve_s, claimed, evals, ("",) * n,
            {"swarm_ik": common.package_version("swarm_ik")},
        )  # fmt: skip


# --------------------------------------------------------------------------- report
def _rows(name: str, index: np.ndarray, ans: wp.PeerAnswers, judged: Any) -> list[dict[str, Any]]:
    def num(v: float, digits: int = 3) -> str:
        return "" if not math.isfinite(float(v)) else f"{float(v):.{digits}e}"

    return [
        {
            "solver": name,
            "target": int(k),
            "success": int(judged.success[i]),
            "claimed": int(ans.converged[i]),
            "time_ms": f"{1e3 * float(ans.time_s[i]):.4f}",
            "iterations": int(ans.iterations[i]),
            "sole_pos": num(np.max(judged.sole_pos[i])),
            "hand_pos": num(np.max(judged.hand_pos[i])),
            "hand_rot": num(np.max(judged.hand_rot[i])),
            "com_margin": num(judged.com_margin[i]),
            "error": ans.errors[i][:200].replace("\n", " "),
        }
        for i, k in enumerate(index)
    ]


def _stats(rows: list[dict[str, Any]], solver: str) -> dict[str, float] | None:
    mine = [r for r in rows if r["solver"] == solver]
    if not mine:
        return None
    t = np.array([float(r["time_ms"]) for r in mine])
    ok = np.array([int(r["success"]) for r in mine], dtype=bool)
    claim = np.array([int(r["claimed"]) for r in mine], dtype=bool)
    return {
        "n": float(len(mine)),
        "success": 100.0 * float(ok.mean()),
        "claimed": 100.0 * float(claim.mean()),
        "false": float(np.sum(claim & ~ok)),
        "median": float(np.median(t)),
        "p95": float(np.percentile(t, 95)),
        "iters": float(np.median([int(r["iterations"]) for r in mine])),
    }


def summarize(rows: list[dict[str, Any]], args: argparse.Namespace, info: dict[str, Any]) -> str:
    """The Markdown report of a run."""
    lines = [
        "# Whole body: Talos standing, hands to poses, centre of mass over the feet",
        "",
        f"`swarm-ik bench wholebody --n {info['n']} --seed {args.seed} --time-limit-ms "
        f"{args.time_limit_ms:g}` — {info['n']} targets, judged with Pinocchio alone (soles "
        f"and hands to {GOAL_TOL:g} m / {GOAL_TOL:g} rad, centre of mass inside the support "
        "polygon, joint limits, torso at its locked values); every solver starts from the "
        "half-sitting posture; solvers interleaved in chunks of "
        f"{info['chunk']} targets, in an order drawn anew for each chunk. Time: the whole call "
        "per target.",
        "",
        "| solver | success (judged) | claimed | claimed but failed | median [ms] | "
        "p95 [ms] | median iterations |",
        "|---|---:|---:|---:|---:|---:|---:|",
    ]
    for s in info["solvers"]:
        st = _stats(rows, s)
        if st is None:
            continue
        judged = "n/a" if s == "swarm_ik-tolerance" else f"{st['success']:.1f} %"
        lines.append(
            f"| {s} | {judged} | {st['claimed']:.1f} % | "
            f"{'—' if s == 'swarm_ik-tolerance' else int(st['false'])} | {st['median']:.2f} | "
            f"{st['p95']:.2f} | {st['iters']:.0f} |"
        )
    exact, tol = _stats(rows, "swarm_ik"), _stats(rows, "swarm_ik-tolerance")
    if exact and tol:
        lines += [
            "",
            f"**Tolerance goals.** With the hand goals bounded (`Pose(..., tolerance="
            f"{HAND_TOLERANCE})`: ±5 mm, ±0.05 rad about each target axis) swarm_ik meets "
            f"{tol['claimed']:.1f} % (its own Pinocchio check of the bounds) with a median "
            f"of {tol['median']:.2f} ms against {exact['median']:.2f} ms for the exact hands: "
            f"a ratio of **{tol['median'] / exact['median']:.2f}** (median iterations "
            f"{tol['iters']:.0f} against {exact['iters']:.0f}). The judged column is n/a: "
            "the exact judge does not apply to bounded goals.",
        ]
    for s, why in info["skipped"].items():
        lines += ["", f"**{s} not run:** {why}"]
    lines += [
        "",
        "Versions: " + "; ".join(f"{k}: {v}" for k, v in info["versions"].items()) + ".",
        f"Machine: {info['machine']}; load average at the start {info['load']}.",
        "",
        "Per-target rows: [wholebody.csv](wholebody.csv)"
        + ("." if getattr(args, "no_plots", False) else "; times: [times.png](times.png)."),
        "",
    ]
    return "\n".join(lines)


def plot_times(path: Path, rows: list[dict[str, Any]], solvers: list[str]) -> Path | None:
    """Cumulative share of targets solved (judged; the tolerance variant: claimed) against
    the time per call."""
    from swarm_ik.bench.plots import _figure, _save

    fig, axes = _figure(1, size=(6.4, 4.2))
    ax = axes[0]
    for s in solvers:
        mine = [r for r in rows if r["solver"] == s]
        if not mine:
            continue
        key = "claimed" if s == "swarm_ik-tolerance" else "success"
        t = np.sort([float(r["time_ms"]) for r in mine if int(r[key])])
        if t.size == 0:
            continue
        share = 100.0 * np.arange(1, t.size + 1) / len(mine)
        ax.step(t, share, where="post", label=s)
    ax.set_xscale("log")
    ax.set_xlabel("time per call [ms]")
    ax.set_ylabel("targets solved [%]")
    ax.set_ylim(0, 101)
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8, loc="lower right")
    return _save(fig, path, "Talos whole body: targets solved within a time")


def run(args: argparse.Namespace) -> int:
    """Run the benchmark; write ``wholebody.csv``, ``summary.md`` and ``times.png``."""
    n = 20 if args.quick else common.positive_int(args.n, "--n")
    limit_ms = float(args.time_limit_ms)
    if not (math.isfinite(limit_ms) and limit_ms > 0):
        raise InvalidArgumentError(f"--time-limit-ms must be positive, got {args.time_limit_ms}")
    chunk = common.positive_int(args.chunk, "--chunk")
    solvers = [s.strip() for s in str(args.solvers).split(",") if s.strip()]
    bad = [s for s in solvers if s not in SOLVERS]
    if bad or not solvers:
        raise InvalidArgumentError(f"--solvers: unknown {bad}; valid: {', '.join(SOLVERS)}")
    out = common.resolve_out(args.out, COMMAND, args.quick)
    common.single_thread()
    load = f"{os.getloadavg()[0]:.2f}" if hasattr(os, "getloadavg") else "?"
    targets = wp.talos_wholebody_targets(n, int(args.seed))
    limit = limit_ms / 1e3
    ours = Ours(targets)
    skipped: dict[str, str] = {}
    env = None
    if "placo" in solvers:
        try:
            env = wp.placo_env()
        except SwarmIKError as exc:
            skipped["placo"] = str(exc)
    ours.solve(np.arange(min(3, n)), limit)  # compiled kernels loaded before any clock
    rows: list[dict[str, Any]] = []
    versions: dict[str, str] = {}
    order_rng = np.random.default_rng([int(args.seed), 1])  # (not the targets' stream)
    for start in range(0, n, chunk):
        index = np.arange(start, min(n, start + chunk))
        sub = targets.subset(index)
        for k in order_rng.permutation(len(solvers)):
            s = solvers[int(k)]
            if s in skipped:
                continue
            try:
                if s == "swarm_ik":
                    ans = ours.solve(index, limit)
                elif s == "swarm_ik-tolerance":
                    ans = ours.solve(index, limit, HAND_TOLERANCE)
                elif s == "placo":
                    ans = wp.run_placo(sub, env=env, time_limit=limit)
                else:
                    ans = wp.run_pink(sub, time_limit=limit)
            except (SwarmIKError, ImportError) as exc:
                skipped[s] = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
                continue
            versions[s] = ", ".join(f"{k} {v}" for k, v in sorted(ans.versions.items()))
            judged = wp.judge_wholebody(targets.model_path, ans.q, sub, tol=GOAL_TOL)
            rows += _rows(s, index, ans, judged)
    common.write_csv(out / "wholebody.csv", FIELDS, rows)
    info = {
        "n": n, "chunk": chunk, "solvers": solvers, "skipped": skipped, "versions": versions,
        "load": load, "machine": f"{platform.processor() or platform.machine()}, "
        f"{common.cpu_count()} CPUs",
    }  # fmt: skip
    (out / "summary.md").write_text(summarize(rows, args, info))
    if not args.no_plots:
        plot_times(out / "times.png", rows, solvers)
    common.write_run_info(out, COMMAND, args.quick, n=n, seed=int(args.seed))
    print((out / "summary.md").read_text())
    return 0


main = common.module_main(add_arguments, run, COMMAND, __doc__.splitlines()[0] if __doc__ else None)

if __name__ == "__main__":
    raise SystemExit(main())
