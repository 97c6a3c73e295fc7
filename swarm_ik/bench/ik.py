"""``swarm-ik bench ik``: the TRAC-IK benchmark protocol, for every solver and TRAC-IK.

Protocol (Beeson & Ames, 2015; SEEDS.md, last section): for each robot, ``N`` joint vectors
are drawn uniformly within the limits (seeded), their forward kinematics are the targets, and
each target is solved from the middle of the joint ranges within a time budget (1, 5 and 20
ms).  Success is judged **by this benchmark, identically for every solver**, with Pinocchio's
own forward kinematics (:func:`swarm_ik.verify`): ``‖Δp‖ ≤ tol`` [m] **and** geodesic rotation
angle ``≤ tol`` [rad] (Euclidean norms, no slack), and the answer within the joint limits.
TRAC-IK checks its own tolerance per twist component in its own frame, so some answers it
reports as solved miss the strict criterion; the CSV keeps what each solver said
(``solver_says``) next to the strict verdict.

Timing (wall clock, per target): ``time_s`` is the solver call given a parsed target —
:func:`swarm_ik.solve` on a built :class:`~swarm_ik.IKProblem` (its independent Pinocchio
verification included) against ``pytracik.ik`` with a quaternion; ``setup_s`` is parsing the
4x4 target (building the ``IKProblem``; TRAC-IK's quaternion); both are in the CSV and the
summary reports the medians with and without setup.

Experiments written under ``--out`` (CSV: one row per run; plots and the Markdown summary are
made from the CSV files):

* ``runs.csv``: every (robot, target, solver, budget) at ``--tol`` plus the high-precision
  runs (``--precise-tol``, 20 ms);
* ``many.csv``: distinct solutions per pose within 50 ms (``solve_many`` against repeated
  restarts of DLS and TRAC-IK);
* ``summary.md``, ``success_vs_budget.png``.

By default everything runs in this process, one solve at a time (a timing benchmark must not
compete with itself for the CPUs).  ``--scheduler local`` (an embedded Dask LocalCluster) or
``--scheduler tcp://host:port`` (an existing Dask scheduler) runs one task per robot and
solver (and per robot for ``many.csv``) on Dask workers through
:func:`swarm_ik.distributed.map_chunks`; the rows are the same (up to timing effects), and the
summary says that its timings were measured on workers sharing the machine.  ``--perf`` always
runs in this process, after the rest.

TRAC-IK is used through the optional ``pytracik`` package (``pip install swarm_ik[tracik]``);
without it the benchmark runs and says so.  Its joint limits are set from the model (its
getter is unreliable).
"""

from __future__ import annotations

import argparse
import contextlib
import csv
import math
import os
import platform
import sys
import time
import xml.etree.ElementTree as ET
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

import swarm_ik
from swarm_ik import distributed
from swarm_ik.errors import InvalidArgumentError
from swarm_ik.pose import matrix_to_quat
from swarm_ik.robot import RobotModel

DEFAULT_ROBOTS = (
    "panda",
    "ur5",
    "ur10",
    "yumi_left",
    "loading_manipulator_long",
    "kinova",
    "xarm7",
)
"""The issue's five robots plus two more from example-robot-data (kinova: continuous joints;
xarm7: a 7-joint arm)."""
CORE_SOLVERS = ("swarm", "dls", "tracik")
"""Solvers run on the full ``N`` targets."""
TRACIK = "tracik"
RUN_FIELDS = (
    "robot",
    "target_id",
    "solver",
    "budget_ms",
    "tol",
    "seed",
    "success",
    "solver_says",
    "position_error",
    "rotation_error",
    "n_evals",
    "time_s",
    "setup_s",
    "solver_time_s",
    "within_limits",
)
PERF_FIELDS = ("robot", "what", "pop", "ours_s", "pinocchio_s", "ratio")
MANY_FIELDS = (
    "robot",
    "pose_id",
    "method",
    "budget_ms",
    "min_distance",
    "n_distinct",
    "time_to_8_s",
    "n_calls",
)


# --------------------------------------------------------------------------- TRAC-IK
def tracik_available() -> bool:
    """Whether the optional ``pytracik`` package imports."""
    try:
        import pytracik  # noqa: F401
    except ImportError:
        return False
    return True


def _urdf_root_link(path: Path) -> str:
    root = ET.parse(path).getroot()
    links = [link.get("name") for link in root.findall("link")]
    children = {j.find("child").get("link") for j in root.findall("joint")}  # type: ignore[union-attr]
    roots = [name for name in links if name not in children]
    return str(roots[0])


@contextlib.contextmanager
def _quiet_c_output() -> Iterator[None]:
    """Silence C-level stdout and stderr (KDL's URDF parser warns about root-link inertias)."""
    fds = []
    for stream in (sys.stdout, sys.stderr):
        try:
            stream.flush()
            fds.append(stream.fileno())
        except (AttributeError, OSError, ValueError):
            continue
    saved = [os.dup(fd) for fd in fds]
    with open(os.devnull, "w") as devnull:
        for fd in fds:
            os.dup2(devnull.fileno(), fd)
        try:
            yield
        finally:
            for fd, keep in zip(fds, saved, strict=True):
                os.dup2(keep, fd)
                os.close(keep)


class TracIK:
    """TRAC-IK (``pytracik``) on the chain of a :class:`RobotModel`.

    Args:
        robot: The robot (its URDF root link → end-effector frame is the chain).
        timeout: TRAC-IK's time budget [s].
        eps: TRAC-IK's tolerance.

    Raises:
        InvalidArgumentError: ``pytracik`` is missing, or its chain does not match the model's.
    """

    def __init__(self, robot: RobotModel, timeout: float, eps: float) -> None:
        try:
            import pytracik
        except ImportError:
            raise InvalidArgumentError(
                "TRAC-IK needs the optional pytracik package: pip install 'swarm_ik[tracik]'"
            ) from None
        self._pt = pytracik
        self.robot = robot
        with _quiet_c_output():
            self._solver = pytracik.TRAC_IK(
                _urdf_root_link(robot.urdf_path),
                robot.ee_frame,
                robot.urdf_path.read_text(),
                float(timeout),
                float(eps),
                pytracik.SolveType.Speed,
            )
        dof = pytracik.get_num_joints(self._solver)
        if dof != robot.nq:
            raise InvalidArgumentError(
                f"TRAC-IK's chain of {robot.name} has {dof} joints, the model {robot.nq}"
            )
        pytracik.set_joint_limits(self._solver, list(robot.lower), list(robot.upper))

    def solve(
        self, target: np.ndarray, quat_xyzw: np.ndarray, seed_q: np.ndarray
    ) -> tuple[np.ndarray | None, float]:
        """``(q or None, seconds)`` of one ``pytracik.ik`` call (timed alone)."""
        p = target[:3, 3]
        qx, qy, qz, qw = (float(v) for v in quat_xyzw)
        t0 = time.perf_counter()
        out = self._pt.ik(self._solver, seed_q, p[0], p[1], p[2], qx, qy, qz, qw)
        dt = time.perf_counter() - t0
        if out[0] < 0:
            return None, dt
        return self.robot.wrap(np.asarray(out[1:], dtype=float)), dt


# --------------------------------------------------------------------------- runs
@dataclass(frozen=True)
class RunRow:
    """One solve of one target: the fields of ``runs.csv`` (errors in m / rad, times in s).

    ``time_s`` is the wall-clock time of the solver call given a parsed target
    (:func:`swarm_ik.solve` on a built :class:`~swarm_ik.IKProblem`, its verification
    included; ``pytracik.ik`` with a quaternion); ``setup_s`` the time to parse the 4x4
    target (building the ``IKProblem``; computing TRAC-IK's quaternion); ``solver_time_s``
    the solver's own run inside ``solve`` (``Result.time_s``; TRAC-IK: ``time_s``).
    """

    robot: str
    target_id: int
    solver: str
    budget_ms: float
    tol: float
    seed: int
    success: bool
    solver_says: bool
    position_error: float
    rotation_error: float
    n_evals: float
    time_s: float
    setup_s: float
    solver_time_s: float
    within_limits: bool

    def as_csv(self) -> dict[str, Any]:
        """The row for :class:`csv.DictWriter`."""
        return {
            "robot": self.robot,
            "target_id": self.target_id,
            "solver": self.solver,
            "budget_ms": f"{self.budget_ms:g}",
            "tol": f"{self.tol:g}",
            "seed": self.seed,
            "success": int(self.success),
            "solver_says": int(self.solver_says),
            "position_error": f"{self.position_error:.3e}",
            "rotation_error": f"{self.rotation_error:.3e}",
            "n_evals": "" if not np.isfinite(self.n_evals) else int(self.n_evals),
            "time_s": f"{self.time_s:.6f}",
            "setup_s": f"{self.setup_s:.6f}",
            "solver_time_s": f"{self.solver_time_s:.6f}",
            "within_limits": int(self.within_limits),
        }


def judge(
    robot: RobotModel, problem: swarm_ik.IKProblem, q: np.ndarray | None, tol: float
) -> tuple[bool, float, float, bool]:
    """The benchmark's own verdict: ``(success, ‖Δp‖ [m], θ [rad], within limits)``."""
    if q is None:
        return False, math.inf, math.inf, False
    dp, dr = swarm_ik.verify(problem, q)
    within = robot.within_limits(q, tol=1e-12)
    return bool(within and dp <= tol and dr <= tol), dp, dr, within


def make_targets(robot: RobotModel, n: int, seed: int) -> np.ndarray:
    """Targets ``(n, 4, 4)``: FK of joint vectors drawn uniformly within the limits."""
    rng = np.random.default_rng(seed)
    return robot.fk(robot.random_q(rng, n))


def run_robot(
    robot: RobotModel,
    targets: np.ndarray,
    solvers: Sequence[str],
    budgets_ms: Sequence[float],
    tol: float,
    seed: int,
    n_full: int,
    n_other: int,
    full_budget_ms: float,
    progress: Callable[[str], None] | None = None,
    label: str | None = None,
) -> list[RunRow]:
    """Solve the targets of one robot with every solver and budget.

    Core solvers (``swarm``, ``dls``, ``tracik``) get ``n_full`` targets at
    ``full_budget_ms`` and ``n_other`` at the other budgets; the paper solvers ``n_other`` at
    every budget.  Targets are interleaved across solvers so that all see the same machine
    load.

    ``label`` names the robot in the rows (default: the URDF's robot name).

    Returns:
        One :class:`RunRow` per solve.
    """
    label = label or robot.name
    mid = robot.mid_q()
    rows: list[RunRow] = []
    trac: dict[float, TracIK] = {}
    if TRACIK in solvers:
        for b in budgets_ms:
            trac[b] = TracIK(robot, b * 1e-3, tol)
    # warm-up: compiled kernels loaded, caches filled (not timed, not recorded)
    warm = swarm_ik.IKProblem(robot, targets[0])
    for name in solvers:
        if name == TRACIK:
            trac[budgets_ms[0]].solve(targets[0], matrix_to_quat(targets[0][:3, :3]), mid)
        else:
            swarm_ik.solve(warm, name, seed=0, q0=mid, time_limit=1e-3)
    for b in budgets_ms:
        for i in range(targets.shape[0]):
            for name in solvers:
                core = name in CORE_SOLVERS
                limit = n_full if (core and b == full_budget_ms) else n_other
                if i >= limit:
                    continue
                rows.append(
                    _one(robot, label, targets[i], i, name, b, tol, seed + i, mid, trac.get(b))
                )
        if progress is not None:
            progress(f"{label}: {b:g} ms at tolerance {tol:g} done")
    return rows


def _one(
    robot: RobotModel,
    label: str,
    target: np.ndarray,
    i: int,
    name: str,
    budget_ms: float,
    tol: float,
    seed: int,
    mid: np.ndarray,
    trac: TracIK | None,
) -> RunRow:
    if name == TRACIK:
        assert trac is not None
        t0 = time.perf_counter()
        quat = matrix_to_quat(target[:3, :3])
        setup = time.perf_counter() - t0
        q, dt = trac.solve(target, quat, mid)
        problem = swarm_ik.IKProblem(robot, target)
        ok, dp, dr, within = judge(robot, problem, q, tol)
        return RunRow(
            label,
            i,
            name,
            budget_ms,
            tol,
            seed,
            ok,
            q is not None,
            dp,
            dr,
            math.nan,
            dt,
            setup,
            dt,
            within,
        )
    t0 = time.perf_counter()
    problem = swarm_ik.IKProblem(robot, target)
    t1 = time.perf_counter()
    res = swarm_ik.solve(
        problem, name, seed=seed, q0=mid, time_limit=budget_ms * 1e-3, tol_pos=tol, tol_rot=tol
    )
    t2 = time.perf_counter()
    ok, dp, dr, within = judge(robot, problem, res.q, tol)
    return RunRow(
        label,
        i,
        name,
        budget_ms,
        tol,
        seed,
        ok,
        res.success,
        dp,
        dr,
        float(res.n_evals),
        t2 - t1,
        t1 - t0,
        res.time_s,
        within,
    )


# --------------------------------------------------------------------------- many solutions
def many_robot(
    robot: RobotModel,
    n_poses: int,
    seed: int,
    budget_ms: float,
    min_distance: float,
    with_tracik: bool,
    label: str | None = None,
) -> list[dict[str, Any]]:
    """Distinct solutions per pose within ``budget_ms``: ``solve_many`` against repeated
    single solves from random seeds (DLS; TRAC-IK when available; each call at most 5 ms),
    distinctness judged identically (wrapped joint distance ≥ ``min_distance``, each solution
    strictly within 1e-5 m / 1e-5 rad and the limits)."""
    from swarm_ik.solvers.hybrid import wrapped_distance

    label = label or robot.name
    rng = np.random.default_rng(seed + 7919)
    targets = make_targets(robot, n_poses, seed + 7919)
    wrap = robot.continuous_mask
    trac = TracIK(robot, 5e-3, 1e-5) if with_tracik else None  # 5 ms per restart call
    rows: list[dict[str, Any]] = []
    budget = budget_ms * 1e-3
    swarm_ik.solve_many(swarm_ik.IKProblem(robot, targets[0]), n=2, seed=0)  # warm-up
    for i, target in enumerate(targets):
        problem = swarm_ik.IKProblem(robot, target)
        sols = swarm_ik.solve_many(
            problem, n=10**6, min_distance=min_distance, seed=seed + i, time_limit=budget
        )
        found = sorted(s.time_s for s in sols)
        rows.append(
            dict(
                robot=label,
                pose_id=i,
                method="swarm_ik.solve_many",
                budget_ms=budget_ms,
                min_distance=min_distance,
                n_distinct=len(sols),
                time_to_8_s=f"{found[7]:.6f}" if len(found) >= 8 else "",
                n_calls=1,
            )
        )

        def dls_call(
            q0: np.ndarray, left: float, p: swarm_ik.IKProblem = problem
        ) -> np.ndarray | None:
            return swarm_ik.solve(
                p,
                "dls",
                q0=q0,
                seed=int(rng.integers(2**31)),
                time_limit=max(min(5e-3, left), 1e-5),
            ).q

        methods: list[tuple[str, Callable[[np.ndarray, float], np.ndarray | None]]] = [
            ("dls restarts", dls_call)
        ]
        if trac is not None:
            quat = matrix_to_quat(target[:3, :3])

            def trac_call(
                q0: np.ndarray,
                left: float,
                t: np.ndarray = target,
                qu: np.ndarray = quat,
                solver: TracIK = trac,
            ) -> np.ndarray | None:
                return solver.solve(t, qu, q0)[0]

            methods.append(("tracik restarts", trac_call))
        for method, call in methods:
            kept: list[np.ndarray] = []
            t_found: list[float] = []
            calls = 0
            t0 = time.perf_counter()
            while time.perf_counter() - t0 < budget:
                q = call(robot.random_q(rng), budget - (time.perf_counter() - t0))
                calls += 1
                ok, _dp, _dr, _w = judge(robot, problem, q, 1e-5)
                if not ok or q is None:
                    continue
                if kept and np.min(wrapped_distance(np.asarray(kept), q, wrap)) < min_distance:
                    continue
                kept.append(q)
                t_found.append(time.perf_counter() - t0)
            rows.append(
                dict(
                    robot=label,
                    pose_id=i,
                    method=method,
                    budget_ms=budget_ms,
                    min_distance=min_distance,
                    n_distinct=len(kept),
                    time_to_8_s=f"{t_found[7]:.6f}" if len(kept) >= 8 else "",
                    n_calls=calls,
                )
            )
    return rows


# --------------------------------------------------------------------------- kernel speed
def _best_time(fn: Callable[[], Any], min_time: float = 0.05, repeats: int = 5) -> float:
    """Best-of-``repeats`` seconds per call of ``fn`` (each repeat loops for ``min_time``)."""
    fn()
    best = math.inf
    for _ in range(repeats):
        k = 0
        t0 = time.perf_counter()
        while True:
            fn()
            k += 1
            dt = time.perf_counter() - t0
            if dt >= min_time:
                break
        best = min(best, dt / k)
    return best


def _pin_fk_loop(model: Any, data: Any, fid: int, q_pin: list[np.ndarray]) -> None:
    import pinocchio as pin

    for qp in q_pin:
        pin.framesForwardKinematics(model, data, qp)
        data.oMf[fid].homogeneous  # noqa: B018 - read the pose


def _pin_jac_loop(model: Any, data: Any, fid: int, q_pin: list[np.ndarray]) -> None:
    import pinocchio as pin

    lwa = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED
    for qp in q_pin:
        pin.computeFrameJacobian(model, data, qp, fid, lwa)
        pin.updateFramePlacement(model, data, fid).homogeneous  # noqa: B018


def _pin_fitness_loop(
    model: Any, data: Any, fid: int, q_pin: list[np.ndarray], target: np.ndarray
) -> None:
    import pinocchio as pin

    from swarm_ik.fitness import se3_fitness

    for qp in q_pin:
        pin.framesForwardKinematics(model, data, qp)
        se3_fitness(data.oMf[fid].homogeneous[None], target)


def perf_rows(
    robot_names: Sequence[str], pops: Sequence[int] = (1, 10, 100, 1000)
) -> list[dict[str, Any]]:
    """Measured seconds per call: the compiled batched kernels against Pinocchio called once
    per individual from Python, for FK, FK + frame Jacobian and the se3 fitness, and one
    iteration of the compiled LM polish against one iteration of the Pinocchio DLS loop.

    Pinocchio's configurations are converted beforehand (not timed).

    Returns:
        Rows ``{robot, what, pop, ours_s, pinocchio_s, ratio}`` (``ratio`` = Pinocchio / ours).
    """
    from functools import partial

    from swarm_ik.solvers.hybrid import Polisher

    rows: list[dict[str, Any]] = []
    for name in robot_names:
        robot = swarm_ik.load_robot(name)
        model, data, fid = robot.model, robot.model.createData(), robot.ee_frame_id
        problem = swarm_ik.IKProblem(robot, robot.fk(robot.mid_q()))
        for pop in pops:
            q = robot.random_q(np.random.default_rng(pop), pop)
            q_pin = [robot.to_pinocchio(qi) for qi in q]
            cases: list[tuple[str, Callable[[], Any], Callable[[], Any]]] = [
                ("FK", partial(robot.fk, q), partial(_pin_fk_loop, model, data, fid, q_pin)),
                (
                    "FK + Jacobian",
                    partial(robot.fk_jacobian, q),
                    partial(_pin_jac_loop, model, data, fid, q_pin),
                ),
                (
                    "se3 fitness",
                    partial(problem.fitness, q),
                    partial(_pin_fitness_loop, model, data, fid, q_pin, problem.target),
                ),
            ]
            for what, ours, ref in cases:
                t_ours, t_ref = _best_time(ours), _best_time(ref)
                rows.append(
                    dict(
                        robot=name,
                        what=what,
                        pop=pop,
                        ours_s=t_ours,
                        pinocchio_s=t_ref,
                        ratio=t_ref / t_ours,
                    )
                )
        rng = np.random.default_rng(1)
        far = swarm_ik.IKProblem(robot, robot.fk(robot.random_q(rng)))
        pol = Polisher.from_problem(far, robot.lower, robot.upper)
        starts = robot.random_q(rng, 200)
        polish = partial(pol.polish, starts, 10**9, False)
        t_lm = _best_time(polish) / polish().used
        unreachable = np.eye(4)
        unreachable[:3, 3] = 100.0
        dls = partial(swarm_ik.solve, swarm_ik.IKProblem(robot, unreachable), "dls", max_evals=200)
        t_dls = _best_time(dls, repeats=3) / 200
        rows.append(
            dict(
                robot=name,
                what="one LM / DLS iteration",
                pop=1,
                ours_s=t_lm,
                pinocchio_s=t_dls,
                ratio=t_dls / t_lm,
            )
        )
    return rows


# --------------------------------------------------------------------------- reporting
def read_csv(path: Path) -> list[dict[str, str]]:
    """Rows of a CSV file as dicts of strings."""
    with open(path, newline="") as fh:
        return list(csv.DictReader(fh))


def summarise(rows: list[dict[str, str]]) -> dict[tuple[str, str, float, float], dict[str, float]]:
    """``(robot, solver, budget_ms, tol) -> {n, success, median, p95, max [ms], evals}``."""
    groups: dict[tuple[str, str, float, float], list[dict[str, str]]] = {}
    for r in rows:
        key = (r["robot"], r["solver"], float(r["budget_ms"]), float(r["tol"]))
        groups.setdefault(key, []).append(r)
    out = {}
    for key, g in groups.items():
        t = np.array([float(r["time_s"]) for r in g]) * 1e3
        ev = [float(r["n_evals"]) for r in g if r["n_evals"] != ""]
        out[key] = {
            "n": float(len(g)),
            "success": 100.0 * np.mean([r["success"] == "1" for r in g]),
            "says": 100.0 * np.mean([r["solver_says"] == "1" for r in g]),
            "median": float(np.median(t)),
            "solver_median": float(np.median([float(r["solver_time_s"]) for r in g])) * 1e3,
            "with_setup_median": float(
                np.median([float(r["time_s"]) + float(r["setup_s"]) for r in g])
            )
            * 1e3,
            "p95": float(np.percentile(t, 95)),
            "max": float(np.max(t)),
            "evals": float(np.mean(ev)) if ev else math.nan,
        }
    return out


def _order(solvers: set[str]) -> list[str]:
    head = [s for s in CORE_SOLVERS if s in solvers]
    return head + sorted(solvers - set(head))


def plot_success(runs_csv: Path, out_png: Path, tol: float) -> Path | None:
    """Success rate against time budget, one panel per robot, from ``runs.csv``.

    Returns the PNG path, or ``None`` when matplotlib is not installed.
    """
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        return None
    stats = summarise(read_csv(runs_csv))
    robots = list(dict.fromkeys(k[0] for k in stats))
    solvers = _order({k[1] for k in stats})
    ncol = min(4, len(robots))
    nrow = math.ceil(len(robots) / ncol)
    fig, axes = plt.subplots(
        nrow, ncol, figsize=(4.0 * ncol, 3.2 * nrow), squeeze=False, sharey=True
    )
    cmap = plt.get_cmap("tab20")
    for ax, robot in zip(axes.flat, robots, strict=False):
        for j, s in enumerate(solvers):
            pts = sorted(
                (k[2], v["success"])
                for k, v in stats.items()
                if k[0] == robot and k[1] == s and k[3] == tol
            )
            if pts:
                x, y = zip(*pts, strict=True)
                core = s in CORE_SOLVERS
                ax.plot(
                    x,
                    y,
                    marker="o" if core else ".",
                    ls="-" if core else "--",
                    lw=2.4 if s == "swarm" else (1.5 if core else 1.0),
                    color=cmap(2 * j % 20 + (j >= 10)),
                    label=s,
                    zorder=3 if core else 2,
                )
        ax.set_xscale("log")
        ax.set_title(robot)
        ax.set_xlabel("time budget [ms]")
        ax.set_ylim(-2, 102)
        ax.grid(alpha=0.3)
    for ax in axes.flat[len(robots) :]:
        ax.axis("off")
    axes[0, 0].set_ylabel(f"success [%] (≤ {tol:g} m and rad)")
    handles, labels = axes[0, 0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="lower center", ncol=min(len(labels), 8), fontsize=8)
    fig.tight_layout(rect=(0, 0.08, 1, 1))
    out_png.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out_png, dpi=110)
    plt.close(fig)
    return out_png


def _fmt(v: float, digits: int = 3) -> str:
    return "–" if not np.isfinite(v) else f"{v:.{digits}g}"


def write_summary(
    out_dir: Path,
    args: argparse.Namespace,
    info: dict[str, str],
    dask_workers: int | None = None,
) -> Path:
    """``summary.md`` from ``runs.csv`` and ``many.csv``: tables and the targets' verdicts.

    ``dask_workers``: the number of Dask workers when the runs were made with ``--scheduler``
    (the summary then says that the timings were measured on workers sharing the machine);
    ``None`` for the default in-process run.
    """
    if dask_workers is None:
        where = (
            "Run in one process, one solve at a time; the solvers take turns target by "
            "target, so all see the same machine load. On a shared machine single long times "
            "(*max*) are preemptions, and TRAC-IK's median (it runs two solver threads) "
            "varies by up to 2x between runs."
        )
    else:
        sched = getattr(args, "scheduler", None)
        sched = sched if isinstance(sched, str) else "<a Dask client>"
        where = (
            f"**Run on Dask** (`--scheduler {sched}`, "
            f"{dask_workers} workers): one task per robot and solver (and per robot for the "
            "many-solutions experiment), several running at the same time. **The timings were "
            "measured on Dask workers that share the machine** (each other's CPUs and memory "
            "bandwidth, and TRAC-IK's two solver threads), so they are slower and noisier than "
            "those of the default sequential run, and a time budget can end a solve that the "
            "sequential run finishes; compare timings only between runs made the same way."
        )
    rows = read_csv(out_dir / "runs.csv")
    stats = summarise(rows)
    tol = float(args.tol)
    lines = [
        "# IK benchmark: TRAC-IK protocol",
        "",
        "Generated by `swarm-ik bench ik` (`swarm_ik/bench/ik.py`); raw data in `runs.csv` and "
        "`many.csv`, plot `success_vs_budget.png`.",
        "",
        "**Protocol.** Per robot, targets = FK of joint vectors drawn uniformly within the "
        f"limits (seed {args.seed}); every solver starts from the middle of the joint ranges "
        "and gets the time budget of the column. **Success is judged by the benchmark, "
        "identically for every solver, with Pinocchio's FK: ‖Δp‖ ≤ "
        f"{tol:g} m and rotation angle ≤ {tol:g} rad (Euclidean norms, no slack) and within "
        "the joint limits.** TRAC-IK checks its own tolerance per twist component, so some of "
        "its reported solutions fail this strict test (its own count is in the column "
        "*says*). **Times** (wall clock, per target): *median/p95/max* = the solver call "
        "given a parsed target: `swarm_ik.solve(problem, …)` on a built `IKProblem` "
        "(its own Pinocchio verification included) against `pytracik.ik(…)` with a "
        "quaternion; *with setup* adds parsing the 4x4 target (building the `IKProblem`; "
        "computing TRAC-IK's quaternion with SciPy); *solver-only* = `Result.time_s`, the "
        "solver's run inside `solve`.",
        "",
        "**Machine.** " + ", ".join(f"{k} {v}" for k, v in info.items()) + ". " + where,
        "",
    ]
    budgets = sorted({k[2] for k in stats if k[3] == tol})
    for b in budgets:
        lines += [
            f"## Budget {b:g} ms (tolerance {tol:g})",
            "",
            "| robot | solver | N | success % | says % | median ms | p95 ms | max ms "
            "| mean evals | median with setup ms | solver-only median ms |",
            "|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|",
        ]
        for robot in dict.fromkeys(k[0] for k in stats):
            for s in _order({k[1] for k in stats if k[0] == robot}):
                v = stats.get((robot, s, b, tol))
                if v is None:
                    continue
                lines.append(
                    f"| {robot} | {s} | {int(v['n'])} | {v['success']:.1f} | {v['says']:.1f} "
                    f"| {v['median']:.3f} | {v['p95']:.3f} | {v['max']:.2f} "
                    f"| {_fmt(v['evals'], 4)} | {v['with_setup_median']:.3f} "
                    f"| {v['solver_median']:.3f} |"
                )
        lines.append("")
    precise = sorted({k[3] for k in stats if k[3] != tol})
    for ptol in precise:
        lines += [
            f"## High precision: tolerance {ptol:g} m / rad",
            "",
            "| robot | solver | budget ms | N | success % | says % | median ms | p95 ms "
            "| max ms | mean evals |",
            "|---|---|---:|---:|---:|---:|---:|---:|---:|---:|",
        ]
        for (robot, s, b, t), v in stats.items():
            if t == ptol:
                lines.append(
                    f"| {robot} | {s} | {b:g} | {int(v['n'])} | {v['success']:.1f} "
                    f"| {v['says']:.1f} | {v['median']:.3f} | {v['p95']:.3f} | {v['max']:.2f} "
                    f"| {_fmt(v['evals'], 4)} |"
                )
        lines.append("")
    many_path = out_dir / "many.csv"
    many = read_csv(many_path) if many_path.exists() else []
    if many:
        lines += [
            "## Many solutions per pose",
            "",
            f"Distinct solutions found within {many[0]['budget_ms']} ms per pose "
            f"(wrapped joint distance ≥ {many[0]['min_distance']}, each strictly within "
            "1e-5 m / 1e-5 rad and the limits): `solve_many` against repeated single "
            "solves from random seeds.",
            "",
            "| robot | method | poses | median distinct | min distinct | poses with ≥ 8 "
            "| median time to 8 ms |",
            "|---|---|---:|---:|---:|---:|---:|",
        ]
        groups: dict[tuple[str, str], list[dict[str, str]]] = {}
        for r in many:
            groups.setdefault((r["robot"], r["method"]), []).append(r)
        for (robot, method), g in groups.items():
            nd = np.array([int(r["n_distinct"]) for r in g])
            t8 = [float(r["time_to_8_s"]) * 1e3 for r in g if r["time_to_8_s"] != ""]
            lines.append(
                f"| {robot} | {method} | {len(g)} | {np.median(nd):g} | {nd.min()} "
                f"| {int(np.sum(nd >= 8))} | {_fmt(float(np.median(t8)) if t8 else math.nan)} |"
            )
        lines.append("")
    perf_path = out_dir / "perf.csv"
    if perf_path.exists():
        lines += [
            "## Compiled kernels against Pinocchio per individual",
            "",
            "Seconds per call for a population of `pop` joint vectors (best of 5); "
            "*ratio* = Pinocchio called once per individual from Python / ours.",
            "",
            "| robot | what | pop | ours µs | Pinocchio loop µs | ratio |",
            "|---|---|---:|---:|---:|---:|",
        ]
        for r in read_csv(perf_path):
            lines.append(
                f"| {r['robot']} | {r['what']} | {r['pop']} "
                f"| {float(r['ours_s']) * 1e6:.2f} | {float(r['pinocchio_s']) * 1e6:.2f} "
                f"| {r['ratio']} |"
            )
        lines.append("")
    lines += ["## Targets of the issue", ""] + _verdicts(stats, many, tol) + [""]
    path = out_dir / "summary.md"
    path.write_text("\n".join(lines))
    return path


def _verdicts(
    stats: dict[tuple[str, str, float, float], dict[str, float]],
    many: list[dict[str, str]],
    tol: float,
) -> list[str]:
    out = []
    robots = list(dict.fromkeys(k[0] for k in stats))
    for robot in robots:
        v = stats.get((robot, "swarm", 5.0, tol))
        if v is not None:
            met = "met" if v["success"] >= 99.9 else "**missed**"
            out.append(
                f"- {robot}: swarm success at 5 ms {v['success']:.2f} % (target ≥ 99.9 %): {met}."
            )
        tr = stats.get((robot, TRACIK, 5.0, tol))
        if v is not None and tr is not None:
            met = "met" if v["median"] <= tr["median"] else "**missed**"
            out.append(
                f"- {robot}: median time at 5 ms swarm {v['median']:.3f} ms vs TRAC-IK "
                f"{tr['median']:.3f} ms (target ≤): {met}."
            )
    for (robot, s, b, t), v in stats.items():
        if s == "swarm" and t != tol and b == 20.0:
            met = "met" if v["success"] >= 99.0 else "**missed**"
            out.append(
                f"- {robot}: swarm at tolerance {t:g} within 20 ms: {v['success']:.2f} % "
                f"(target ≥ 99 %): {met}."
            )
    for r_name in dict.fromkeys(r["robot"] for r in many):
        g = [r for r in many if r["robot"] == r_name and r["method"] == "swarm_ik.solve_many"]
        if g:
            t8 = [float(r["time_to_8_s"]) for r in g if r["time_to_8_s"] != ""]
            frac = len(t8) / len(g)
            text = (
                f"- {r_name}: solve_many found ≥ 8 distinct solutions within "
                f"{g[0]['budget_ms']} ms on {100 * frac:.0f} % of {len(g)} random poses"
            )
            if r_name == "yumi_left":  # the target: a generic YuMi pose
                text += f" (target: a generic YuMi pose): {'met' if frac > 0.5 else '**missed**'}"
            out.append(text + ".")
    return out


# --------------------------------------------------------------------------- CLI
def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Options of ``swarm-ik bench ik``."""
    parser.add_argument(
        "--robots", nargs="+", default=None, help=f"robots (default: {' '.join(DEFAULT_ROBOTS)})"
    )
    parser.add_argument(
        "--n",
        type=int,
        default=1000,
        help="targets per robot for swarm, dls and tracik at --full-budget-ms",
    )
    parser.add_argument(
        "--n-other",
        type=int,
        default=100,
        help="targets per robot for the paper solvers, and for every solver at the other budgets",
    )
    parser.add_argument("--budgets-ms", nargs="+", type=float, default=[1.0, 5.0, 20.0])
    parser.add_argument("--full-budget-ms", type=float, default=5.0)
    parser.add_argument(
        "--solvers",
        nargs="+",
        default=None,
        help="registered solver names and/or 'tracik' (default: all registered "
        "solvers, plus tracik when pytracik is installed)",
    )
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--tol", type=float, default=1e-5, help="success tolerance [m and rad]")
    parser.add_argument(
        "--precise-tol",
        type=float,
        default=1e-10,
        help="tolerance of the high-precision runs (20 ms; 0 to skip)",
    )
    parser.add_argument("--n-precise", type=int, default=1000)
    parser.add_argument(
        "--many-robots",
        nargs="*",
        default=None,
        help="robots of the many-solutions experiment (default: yumi_left, panda, ur5)",
    )
    parser.add_argument("--n-many", type=int, default=30, help="poses per robot for many")
    parser.add_argument("--out", default="docs/results/ik", help="output folder")
    parser.add_argument(
        "--quick", action="store_true", help="a few targets on two robots (for tests)"
    )
    parser.add_argument(
        "--scheduler",
        default="none",
        metavar="none|local|tcp://HOST:PORT",
        help="where the solves run: 'none' (default: this process, one solve at a time, so "
        "that the timings are not disturbed by parallel work; this is a timing benchmark), "
        "'local' (an embedded Dask LocalCluster, one worker process per core) or the address "
        "of an existing Dask scheduler; with Dask, one task per robot and solver, and the "
        "summary says that the timings were measured on workers sharing the machine",
    )
    parser.add_argument(
        "--perf",
        action="store_true",
        help="also time the compiled kernels against Pinocchio per individual (writes perf.csv)",
    )


def _machine_info() -> dict[str, str]:
    import numba
    import pinocchio

    info = {
        "CPU": platform.processor() or platform.machine(),
        "cores": str(os.cpu_count()),
        "Python": platform.python_version(),
        "numpy": np.__version__,
        "numba": numba.__version__,
        "pinocchio": pinocchio.__version__,
    }
    try:
        from importlib.metadata import version

        info["pytracik"] = version("pytracik")
    except Exception:  # noqa: BLE001 - not installed
        info["pytracik"] = "not installed"
    return info


@dataclass(frozen=True)
class Plan:
    """What one invocation runs (sizes already reduced for ``--quick``).

    Attributes:
        robots: Robots of ``runs.csv``.
        solvers: Registered solver names and/or ``"tracik"``.
        budgets_ms: Time budgets [ms], ascending.
        tol: Success tolerance [m and rad].
        precise_tol: Tolerance of the high-precision runs (0: none).
        seed: Seed of the targets.
        n_full: Targets of the core solvers at ``full_budget_ms``.
        n_other: Targets otherwise.
        full_budget_ms: The budget with ``n_full`` targets [ms].
        n_precise: Targets of the high-precision runs.
        many_robots: Robots of the many-solutions experiment.
        n_many: Poses per robot there.
    """

    robots: tuple[str, ...]
    solvers: tuple[str, ...]
    budgets_ms: tuple[float, ...]
    tol: float
    precise_tol: float
    seed: int
    n_full: int
    n_other: int
    full_budget_ms: float
    n_precise: int
    many_robots: tuple[str, ...]
    n_many: int

    @property
    def n_targets(self) -> int:
        """Targets drawn per robot (the high-precision runs use the first ``n_precise``)."""
        return max(self.n_full, self.n_other)


def _runs_of_robot(
    plan: Plan,
    name: str,
    solvers: Sequence[str],
    precise: bool,
    say: Callable[[str], None] | None,
) -> tuple[list[RunRow], str | None]:
    """``runs.csv`` rows of one robot for ``solvers`` (the main budgets, or the high-precision
    runs), and a note when TRAC-IK could not be built for it (then run without it)."""
    robot = swarm_ik.load_robot(name)
    targets = make_targets(robot, plan.n_targets, plan.seed)
    if precise:
        solvers = [s for s in solvers if s in CORE_SOLVERS]
        targets = targets[: plan.n_precise]
        budgets, tol, n_full, n_other, full = [20.0], plan.precise_tol, plan.n_precise, 0, 20.0
    else:
        budgets, tol = list(plan.budgets_ms), plan.tol
        n_full, n_other, full = plan.n_full, plan.n_other, plan.full_budget_ms

    def go(names: Sequence[str]) -> list[RunRow]:
        return run_robot(
            robot, targets, names, budgets, tol, plan.seed, n_full, n_other, full, say, name
        )

    if not solvers:
        return [], None
    try:
        return go(solvers), None
    except InvalidArgumentError as exc:  # e.g. TRAC-IK cannot build this chain
        note = f"{name}: {'precise ' if precise else ''}TRAC-IK skipped ({exc})"
        if say is not None:
            say(note)
        rest = [s for s in solvers if s != TRACIK]
        return (go(rest) if rest else []), note


def _many_of_robot(plan: Plan, name: str) -> list[dict[str, Any]]:
    """``many.csv`` rows of one robot (TRAC-IK restarts left out when it cannot be built)."""
    robot = swarm_ik.load_robot(name)
    try:
        return many_robot(
            robot, plan.n_many, plan.seed, 50.0, 0.1, TRACIK in plan.solvers, label=name
        )
    except InvalidArgumentError:
        return many_robot(robot, plan.n_many, plan.seed, 50.0, 0.1, False, label=name)


def _run_in_process(plan: Plan, out_dir: Path, say: Callable[[str], None]) -> None:
    """The default: everything in this process, one robot after the other, the solvers taking
    turns target by target (all see the same machine load); writes runs.csv and many.csv."""
    with open(out_dir / "runs.csv", "w", newline="") as fh:
        writer = csv.DictWriter(fh, fieldnames=RUN_FIELDS)
        writer.writeheader()
        for name in plan.robots:
            rows, _ = _runs_of_robot(plan, name, plan.solvers, False, say)
            if plan.n_precise:
                rows += _runs_of_robot(plan, name, plan.solvers, True, say)[0]
            writer.writerows(r.as_csv() for r in rows)
            fh.flush()
    with open(out_dir / "many.csv", "w", newline="") as fh:
        writer = csv.DictWriter(fh, fieldnames=MANY_FIELDS)
        writer.writeheader()
        for name in plan.many_robots:
            writer.writerows(_many_of_robot(plan, name))
            say(f"{name}: many-solutions done")


@dataclass(frozen=True)
class Chunk:
    """One Dask task of ``--scheduler``: one robot and solver (``kind`` ``"runs"`` or
    ``"precise"``), or one robot's many-solutions experiment (``kind`` ``"many"``, ``solver``
    empty)."""

    plan: Plan
    kind: str
    robot: str
    solver: str = ""


def run_chunk(chunk: Chunk) -> tuple[list[dict[str, Any]], str | None]:
    """Run one :class:`Chunk` (on a Dask worker): its CSV rows and a note (TRAC-IK skipped)."""
    if chunk.kind == "many":
        return _many_of_robot(chunk.plan, chunk.robot), None
    rows, note = _runs_of_robot(
        chunk.plan, chunk.robot, [chunk.solver], chunk.kind == "precise", None
    )
    return [r.as_csv() for r in rows], note


def dask_chunks(plan: Plan) -> list[Chunk]:
    """The tasks of a Dask run: per robot, one per solver, one per core solver for the
    high-precision runs, and one for the many-solutions experiment."""
    out = [Chunk(plan, "runs", r, s) for r in plan.robots for s in plan.solvers]
    if plan.n_precise:
        out += [
            Chunk(plan, "precise", r, s)
            for r in plan.robots
            for s in plan.solvers
            if s in CORE_SOLVERS
        ]
    return out + [Chunk(plan, "many", r) for r in plan.many_robots]


def _run_on_dask(plan: Plan, out_dir: Path, scheduler: Any, say: Callable[[str], None]) -> int:
    """``--scheduler``: one task per :func:`dask_chunks` entry on the Dask workers; the rows
    are written in the order of the in-process run.  Returns the number of workers."""
    chunks = dask_chunks(plan)
    with distributed.connect(scheduler) as client:
        workers = distributed.n_workers(client)
        name = scheduler if isinstance(scheduler, str) else "a Dask client"
        say(f"{len(chunks)} tasks on {workers} Dask workers ({name})")
        results = distributed.map_chunks(
            run_chunk,
            chunks,
            client=client,
            name="swarm-ik-bench-ik",
            progress=True,
            desc="bench ik",
            unit="task",
        )
    for note in dict.fromkeys(n for _, n in results if n):
        say(note)
    robots = {r: i for i, r in enumerate(plan.robots)}
    solvers = {s: i for i, s in enumerate(plan.solvers)}
    kinds = {"runs": 0, "precise": 1}
    runs = [
        (kinds[c.kind], row)
        for c, (rows, _) in zip(chunks, results, strict=True)
        if c.kind != "many"
        for row in rows
    ]
    runs.sort(
        key=lambda kr: (
            robots[kr[1]["robot"]],
            kr[0],
            float(kr[1]["budget_ms"]),
            int(kr[1]["target_id"]),
            solvers[kr[1]["solver"]],
        )
    )
    with open(out_dir / "runs.csv", "w", newline="") as fh:
        writer = csv.DictWriter(fh, fieldnames=RUN_FIELDS)
        writer.writeheader()
        writer.writerows(row for _, row in runs)
    with open(out_dir / "many.csv", "w", newline="") as fh:
        writer = csv.DictWriter(fh, fieldnames=MANY_FIELDS)
        writer.writeheader()
        for c, (rows, _) in zip(chunks, results, strict=True):
            if c.kind == "many":
                writer.writerows(rows)
    return workers


def run(args: argparse.Namespace) -> int:
    """Run the benchmark with parsed options; returns the exit code (0)."""
    distributed.check_scheduler(getattr(args, "scheduler", None))
    quick = bool(args.quick) or os.environ.get("SWARM_IK_QUICK") == "1"
    robots = list(args.robots or (("panda", "yumi_left") if quick else DEFAULT_ROBOTS))
    n_full, n_other = (min(args.n, 12), min(args.n_other, 3)) if quick else (args.n, args.n_other)
    budgets = [float(b) for b in args.budgets_ms]
    full_budget = float(args.full_budget_ms)
    if full_budget not in budgets:
        budgets.append(full_budget)
    budgets.sort()
    have_tracik = tracik_available()
    if args.solvers:
        solvers = list(args.solvers)
    else:
        solvers = ["swarm", "dls"] + [
            s for s in swarm_ik.solvers.names() if s not in ("swarm", "dls")
        ]
        if have_tracik:
            solvers.append(TRACIK)
    for s in solvers:
        if s != TRACIK:
            swarm_ik.solvers.get(s)  # unknown names refused with the list
    if TRACIK in solvers and not have_tracik:
        print("pytracik is not installed: TRAC-IK skipped (pip install 'swarm_ik[tracik]')")
        solvers.remove(TRACIK)
    out_dir = Path(args.out)
    out_dir.mkdir(parents=True, exist_ok=True)
    t_start = time.perf_counter()

    def say(msg: str) -> None:
        print(f"[{time.perf_counter() - t_start:7.1f} s] {msg}", flush=True)

    n_precise = 0
    if args.precise_tol and args.precise_tol > 0:
        n_precise = min(args.n_precise, 12) if quick else args.n_precise
    many_robots = args.many_robots
    if many_robots is None:
        many_robots = ["yumi_left"] if quick else ["yumi_left", "panda", "ur5"]
    plan = Plan(
        robots=tuple(robots),
        solvers=tuple(solvers),
        budgets_ms=tuple(budgets),
        tol=float(args.tol),
        precise_tol=float(args.precise_tol or 0.0),
        seed=int(args.seed),
        n_full=n_full,
        n_other=n_other,
        full_budget_ms=full_budget,
        n_precise=n_precise,
        many_robots=tuple(many_robots),
        n_many=min(args.n_many, 2) if quick else args.n_many,
    )
    runs_path = out_dir / "runs.csv"
    scheduler = getattr(args, "scheduler", None)
    dask_workers = None
    if distributed.check_scheduler(scheduler) is None:
        _run_in_process(plan, out_dir, say)
    else:
        dask_workers = _run_on_dask(plan, out_dir, scheduler, say)
    if args.perf:
        prows = perf_rows(
            robots[:2] if quick else ["panda", "ur5", "yumi_left", "loading_manipulator_long"],
            (1, 10) if quick else (1, 10, 100, 1000),
        )
        with open(out_dir / "perf.csv", "w", newline="") as fh:
            writer = csv.DictWriter(fh, fieldnames=PERF_FIELDS)
            writer.writeheader()
            writer.writerows(
                {
                    **r,
                    "ours_s": f"{r['ours_s']:.4e}",
                    "pinocchio_s": f"{r['pinocchio_s']:.4e}",
                    "ratio": f"{r['ratio']:.1f}",
                }
                for r in prows
            )
        say("kernel timings done")
    plot_success(runs_path, out_dir / "success_vs_budget.png", args.tol)
    summary = write_summary(out_dir, args, _machine_info(), dask_workers=dask_workers)
    say(f"wrote {runs_path}, {out_dir / 'many.csv'}, {summary}")
    return 0
