"""``swarm-ik bench throughput``: poses per second of :func:`swarm_ik.solve_batch` against
loops over :func:`swarm_ik.solve` and over TRAC-IK.

Protocol: for each robot, ``N`` joint vectors drawn uniformly within the limits (seeded);
their forward kinematics are the targets (all reachable).  Every method starts from the
middle of the joint ranges and is judged by the same strict test: ``‖Δp‖ ≤ tol`` [m] and
geodesic angle ``≤ tol`` [rad], within the limits (``solve_batch`` checks it with the batched
FK; the loops with Pinocchio's FK through :func:`swarm_ik.verify`).

Methods (one CSV row per robot, method and N):

* ``batch-1proc``: ``solve_batch`` in this process (no Dask), one core;
* ``batch-threads``: ``solve_batch(..., scheduler="threads")``: in this process, a thread per
  core (the kernels release the GIL);
* ``batch-dask``: ``solve_batch`` on ``--scheduler`` (``local``: an embedded LocalCluster
  with one worker process per core; default ``none``: not run).  The cluster is started
  and the workers warmed up (kernels loaded) before timing; its start-up time is reported
  separately (``setup_s``);
* ``loop-solve``: ``[solve(IKProblem(robot, T)) for T in targets]`` with the default solver,
  for ``N ≤ --loop-max``;
* ``loop-tracik``: ``[pytracik.ik(T) for T in targets]`` (TRAC-IK, Speed mode, 5 ms timeout,
  ε = tol) for ``N ≤ --loop-max``, when ``pytracik`` is installed.

With ``--boxes K [K ...]``, for each ``K`` a scene of ``K`` random boxes around the arm
(:func:`box_scene`) and ``N`` targets that are the FK of joint vectors the exact check finds
collision-free (self and scene), then:

* ``boxesK-plain``: ``solve_batch`` without a collision goal on those targets, its answers
  judged afterwards with coal too (success = the pose and no contact; the check not timed);
* ``boxesK-avoid-1proc``: ``solve_batch(..., goals=[AvoidCollisions(scene)])`` in this
  process (the exact check of its answers inside the call, timed);
* ``boxesK-avoid-threads``: the same on a thread per core;
* ``boxesK-avoid-dask``: the same on ``--scheduler`` (when one is given).

Writes under ``--out`` (default ``./bench-throughput``): ``throughput.csv`` (the experiment),
then ``throughput.md`` (from the CSV and ``templates/throughput.md``) and ``throughput.png``
(log-log time vs N), plus ``profile.csv`` (where the time of one batch goes).  Only the public
:func:`swarm_ik.solve_batch` is timed.
"""

from __future__ import annotations

import argparse
import time
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

import swarm_ik
from swarm_ik import argtypes, distributed, solve_batch
from swarm_ik.argtypes import count, positive_number
from swarm_ik.batch import BatchChain, BatchResult, check_targets, pose_errors
from swarm_ik.bench import common, plans
from swarm_ik.robot import RobotModel
from swarm_ik.scene import Box, Scene

DEFAULT_ROBOTS = plans.THROUGHPUT_ROBOTS
DEFAULT_SIZES = plans.THROUGHPUT_SIZES
QUICK_SIZES = plans.THROUGHPUT_QUICK_SIZES
FIELDS = (
    "robot",
    "nq",
    "method",
    "n",
    "workers",
    "time_s",
    "setup_s",
    "poses_per_s",
    "success_rate",
    "n_success",
    "mean_evals",
    "mean_starts",
    "tol",
)
PROFILE_FIELDS = ("robot", "n", "part", "seconds", "share", "note")


HELP = "poses per second of solve_batch against loops over solve and TRAC-IK"
"""One line for ``swarm-ik bench --help``."""


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Options of ``swarm-ik bench throughput``."""
    parser.description = (
        "Poses per second of swarm_ik.solve_batch (one process, and on Dask with --scheduler) "
        "against Python loops over swarm_ik.solve and over TRAC-IK, on FK-sampled targets."
    )
    parser.add_argument(
        "--robots",
        nargs="+",
        default=list(DEFAULT_ROBOTS),
        help=f"robots (default: {' '.join(DEFAULT_ROBOTS)})",
    )
    parser.add_argument(
        "--sizes",
        nargs="+",
        type=count(1),
        default=None,
        help=f"numbers of targets (default {' '.join(map(str, DEFAULT_SIZES))}; "
        f"{' '.join(map(str, QUICK_SIZES))} with --quick)",
    )
    parser.add_argument(
        "--loop-max",
        type=count(0),
        default=1000,
        help="largest N for the loops over solve and TRAC-IK (default 1000)",
    )
    parser.add_argument("--tol", type=positive_number, default=1e-5, help="tolerance [m] and [rad]")
    argtypes.add_seed(parser, "seed of the targets and solves")
    parser.add_argument(
        "--repeat",
        type=count(1),
        default=3,
        help="timed runs of each batch measurement; the fastest is kept (the "
        "results are identical run to run)",
    )
    parser.add_argument(
        "--scheduler",
        default="none",
        metavar="none|local|tcp://HOST:PORT",
        help="where batch-dask runs: 'none' (default: batch-dask not run), 'local' (an "
        "embedded LocalCluster, one worker process per core) or a Dask scheduler address",
    )
    parser.add_argument("--no-tracik", action="store_true", help="skip TRAC-IK")
    parser.add_argument(
        "--boxes",
        nargs="+",
        type=count(1),
        default=[],
        metavar="K",
        help="also time solve_batch with goals=[AvoidCollisions(scene)] on a scene of K random "
        "boxes around the arm, on FK targets of collision-free joint vectors (rows boxesK-*; "
        "default: none)",
    )
    parser.add_argument(
        "--quick",
        action="store_true",
        help="small sizes (a smoke test); never writes into a full run's folder",
    )
    common.add_out(parser, "throughput")


def make_targets(robot: RobotModel, n: int, seed: int) -> np.ndarray:
    """FK of ``n`` joint vectors drawn uniformly within the limits, ``(n, 4, 4)``."""
    return common.fk_targets(robot, n, [seed, n])


def box_scene(robot: RobotModel, k: int, seed: int) -> Scene:
    """``k`` axis-aligned boxes (sides 4–15 cm) around the arm: centres drawn uniformly in the
    upper half-ball of 0.8 × the reach of the first goal frame, at least 25 cm from the base's
    vertical axis (the base and its first links stay free)."""
    rng = np.random.default_rng([int(seed), int(k), 11])
    radius = 0.8 * robot.reach_radius()
    boxes: list[Box] = []
    while len(boxes) < k:
        c = rng.uniform([-radius, -radius, 0.0], [radius, radius, radius])
        if np.linalg.norm(c) > radius or np.linalg.norm(c[:2]) < 0.25:
            continue
        sx, sy, sz = rng.uniform(0.04, 0.15, 3).tolist()
        boxes.append(Box((sx, sy, sz), tuple(c.tolist()), name=f"box{len(boxes)}"))  # type: ignore[arg-type]
    return Scene(boxes)


def collision_free_targets(
    robot: RobotModel, scene: Scene, n: int, seed: int, max_draws: int = 2_000_000
) -> tuple[np.ndarray, np.ndarray]:
    """FK of ``n`` joint vectors drawn uniformly within the limits that coal finds free of
    contact (self and ``scene``): ``(q (n, nq), targets (n, 4, 4))``.

    Raises:
        InvalidArgumentError: fewer than ``n`` found in ``max_draws`` draws.
    """
    rng = np.random.default_rng([int(seed), len(scene), 12])
    return common.collision_free_targets(
        robot, scene, n, rng, batch=1024, max_draws=max_draws, where=robot.name,
        what="joint vectors",
    )  # fmt: skip


def _row(
    robot: RobotModel,
    method: str,
    n: int,
    workers: int,
    time_s: float,
    setup_s: float,
    success: np.ndarray,
    evals: float,
    starts: float,
    tol: float,
) -> dict[str, Any]:
    return {
        "robot": robot.name,
        "nq": robot.nq,
        "method": method,
        "n": n,
        "workers": workers,
        "time_s": f"{time_s:.6f}",
        "setup_s": f"{setup_s:.3f}",
        "poses_per_s": f"{n / time_s:.1f}",
        "success_rate": f"{float(success.mean()):.6f}",
        "n_success": int(success.sum()),
        "mean_evals": "" if not np.isfinite(evals) else f"{evals:.2f}",
        "mean_starts": "" if not np.isfinite(starts) else f"{starts:.3f}",
        "tol": f"{tol:g}",
    }


def loop_solve(
    robot: RobotModel, targets: np.ndarray, tol: float, seed: int
) -> tuple[float, np.ndarray, float]:
    """Time a Python loop over :func:`swarm_ik.solve` (default solver).

    Returns:
        ``(seconds, success (n,), mean evaluations)``.
    """
    ok = np.zeros(len(targets), dtype=bool)
    evals = np.zeros(len(targets))
    swarm_ik.solve(swarm_ik.IKProblem(robot, targets[0]), seed=seed)  # compile outside timing
    t0 = time.perf_counter()
    for i, t in enumerate(targets):
        res = swarm_ik.solve(swarm_ik.IKProblem(robot, t), seed=seed, tol_pos=tol, tol_rot=tol)
        ok[i] = res.success
        evals[i] = res.n_evals
    return time.perf_counter() - t0, ok, float(evals.mean())


def loop_tracik(
    robot: RobotModel, targets: np.ndarray, tol: float
) -> tuple[float, np.ndarray] | None:
    """Time a Python loop over TRAC-IK (Speed, 5 ms timeout, ε = tol) from mid-range, judged
    afterwards with Pinocchio's FK; ``None`` when pytracik is not installed."""
    from swarm_ik.bench import peers

    if not peers.get("tracik-1e-5").available():
        return None
    trac = peers.TracIK(robot, 5e-3, tol)
    seed_q = robot.mid_q()
    answers: list[np.ndarray | None] = []
    t0 = time.perf_counter()
    for t in targets:
        answers.append(trac.solve(t, seed_q, 0).q)
    elapsed = time.perf_counter() - t0
    ok = np.zeros(len(targets), dtype=bool)
    for i, (t, q) in enumerate(zip(targets, answers, strict=True)):
        if q is not None and robot.within_limits(q, tol=1e-12):
            dp, dr = swarm_ik.problem.largest_errors(
                swarm_ik.verify(swarm_ik.IKProblem(robot, t), q)
            )
            ok[i] = dp <= tol and dr <= tol
    return elapsed, ok


def profile_batch(robot: RobotModel, n: int, seed: int, tol: float) -> list[dict[str, Any]]:
    """Where the time of one in-process :func:`swarm_ik.solve_batch` of ``n`` targets goes:
    target validation (:func:`swarm_ik.batch.check_targets`, timed alone), the independent
    check (:func:`swarm_ik.batch.pose_errors`, timed alone), and the rest of the call (the
    compiled kernel), split by the evaluations of targets solved from the first start,
    restarted, and failed."""
    targets = make_targets(robot, n, seed)
    t0 = time.perf_counter()
    res = solve_batch(robot, targets, seed=seed, tol_pos=tol, tol_rot=tol)
    total = time.perf_counter() - t0
    t1 = time.perf_counter()
    poses = check_targets(targets)
    validate = time.perf_counter() - t1
    chain = BatchChain.from_robot(robot).tree
    pose_errors(chain, res.q[:1], poses[:1])  # (loaded first, or compiled for read-only
    # answers: not timed)
    t2 = time.perf_counter()
    pose_errors(chain, res.q, poses)
    check = time.perf_counter() - t2
    kernel = max(total - validate - check, 0.0)
    evals, starts, ok = res.n_evals, res.n_starts, res.success
    per_eval = kernel / max(int(evals.sum()), 1)
    first = ok & (starts == 1)
    restarted = ok & (starts > 1)
    failed = ~ok
    rows = []

    def add(part: str, seconds: float, note: str) -> None:
        rows.append(
            {
                "robot": robot.name,
                "n": n,
                "part": part,
                "seconds": f"{seconds:.5f}",
                "share": f"{seconds / total:.4f}",
                "note": note,
            }
        )

    add("validate targets", validate, "check_targets (timed alone)")
    add(
        "kernel: solved from the first start",
        per_eval * evals[first].sum(),
        f"{first.mean():.1%} of targets, {evals[first].mean():.1f} evaluations each",
    )
    ev_r = float(evals[restarted].mean()) if restarted.any() else 0.0
    st_r = float(starts[restarted].mean()) if restarted.any() else 0.0
    add(
        "kernel: solved after restarts",
        per_eval * evals[restarted].sum(),
        f"{restarted.mean():.1%} of targets, {ev_r:.1f} evaluations and {st_r:.1f} starts each",
    )
    add(
        "kernel: not solved",
        per_eval * evals[failed].sum(),
        f"{failed.mean():.2%} of targets, {evals[failed].mean() if failed.any() else 0:.0f} "
        "evaluations each",
    )
    add("independent check (batched FK)", check, "pose_errors (timed alone)")
    add(
        "total",
        total,
        f"{n / total:.0f} poses/s; {per_eval * 1e6:.2f} µs per LM iteration "
        f"(FK + Jacobian + {robot.nq}x{robot.nq} Cholesky), {evals.mean():.1f} per target",
    )
    return rows


def run_experiment(
    robots: Sequence[str],
    sizes: Sequence[int],
    loop_max: int,
    tol: float,
    seed: int,
    scheduler: Any,
    with_tracik: bool,
    out: Path,
    repeat: int = 3,
    boxes: Sequence[int] = (),
) -> tuple[Path, Path]:
    """Run every method on every robot and size; write ``throughput.csv`` and
    ``profile.csv``; returns their paths.  Batch measurements are repeated ``repeat`` times
    and the fastest kept (the machine may be shared; the answers are identical each time).
    ``boxes``: scene sizes of the collision-free rows (:func:`box_scene`; none by default)."""

    def fastest(on: np.ndarray | None = None, **kwargs: Any) -> Any:
        runs = [
            solve_batch(
                robot,
                targets if on is None else on,
                seed=seed,
                tol_pos=tol,
                tol_rot=tol,
                **kwargs,
            )  # fmt: skip
            for _ in range(max(1, repeat))
        ]
        return min(runs, key=lambda r: r.time_s)

    rows: list[dict[str, Any]] = []

    def record(
        method: str,
        time_s: float,
        success: np.ndarray,
        note: str,
        *,
        n_workers: int = 1,
        setup_s: float = 0.0,
        evals: float = np.nan,
        starts: float = np.nan,
    ) -> None:
        """Add the row of ``method`` on the current robot and size to ``throughput.csv`` and
        print its line (``note`` after the rate)."""
        rows.append(_row(robot, method, n, n_workers, time_s, setup_s, success, evals, starts, tol))
        print(f"  {method:<12s} N={n:>7d} {n / time_s:9.0f} poses/s {note}", flush=True)

    def record_batch(
        method: str, res: BatchResult, note: str, n_workers: int = 1, setup_s: float = 0.0
    ) -> None:
        """:func:`record` of a batch result (its time, success flags, mean evaluations and
        starts)."""
        evals, starts = float(res.n_evals.mean()), float(res.n_starts.mean())
        record(
            method,
            res.time_s,
            res.success,
            note,
            n_workers=n_workers,
            setup_s=setup_s,
            evals=evals,
            starts=starts,
        )

    out.mkdir(parents=True, exist_ok=True)
    prof: list[dict[str, Any]] = []
    loaded = [swarm_ik.load_robot(name) for name in robots]
    for robot in loaded:  # compile / load the kernels once
        solve_batch(robot, make_targets(robot, 10, seed), tol_pos=tol, tol_rot=tol)
    use_dask = distributed.check_scheduler(scheduler) is not None
    cores = distributed.available_cores()
    # (robot, N, boxes) -> the targets, goals and in-process answer, for the Dask rows (the
    # collision-free targets, drawn and checked by coal, not drawn twice)
    kept: dict[tuple[str, int, int], tuple[np.ndarray, Any, np.ndarray]] = {}
    # the rows of this process first, with no Dask cluster alive (its idle processes took
    # 5-8 % of the threads' speed), then the Dask rows
    for robot in loaded:
        print(f"[throughput] {robot.name}", flush=True)
        for n in sizes:
            targets = make_targets(robot, n, seed)
            res = fastest()
            kept[robot.name, n, 0] = (targets, None, res.q)
            record_batch("batch-1proc", res, f"success {res.success_rate:.4f}")
            res_t = fastest(scheduler=distributed.THREADS)
            if not np.array_equal(res_t.q, res.q):  # pragma: no cover - a bug
                raise RuntimeError("threaded and in-process results differ")
            record_batch("batch-threads", res_t, f"({cores} threads)", cores)
            if n <= loop_max:
                t, ok, ev = loop_solve(robot, targets, tol, seed)
                record("loop-solve", t, ok, f"success {ok.mean():.4f}", evals=ev)
                trac = loop_tracik(robot, targets, tol) if with_tracik else None
                if trac is not None:
                    record("loop-tracik", *trac, f"success {trac[1].mean():.4f}")
            for k in boxes:
                scene = box_scene(robot, k, seed)
                _q, free = collision_free_targets(robot, scene, n, seed)
                avoid = [swarm_ik.goals.AvoidCollisions(scene)]
                solve_batch(robot, free[:8], goals=avoid)  # (the sphere model, untimed)
                res = fastest(on=free)
                rc = robot.collision_model()
                ok = res.success & np.array([not rc.collides(q, scene) for q in res.q])
                record_batch(f"boxes{k}-plain", res, f"success {ok.mean():.4f} (coal)")
                rows[-1].update(success_rate=f"{ok.mean():.6f}", n_success=int(ok.sum()))
                res = fastest(on=free, goals=avoid)
                kept[robot.name, n, k] = (free, avoid, res.q)
                record_batch(f"boxes{k}-avoid-1proc", res, f"success {res.success_rate:.4f}")
                res_t = fastest(on=free, goals=avoid, scheduler=distributed.THREADS)
                if not np.array_equal(res_t.q, res.q):  # pragma: no cover - a bug
                    raise RuntimeError("threaded and in-process results differ")
                record_batch(f"boxes{k}-avoid-threads", res_t, f"({cores} threads)", cores)
        prof += profile_batch(robot, min(max(sizes), 10_000), seed, tol)
    if use_dask:
        t_setup = time.perf_counter()
        with distributed.connect(scheduler) as client:
            setup_s = time.perf_counter() - t_setup
            workers = distributed.n_workers(client)
            for robot in loaded:
                print(f"[throughput] {robot.name} on Dask", flush=True)
                solve_batch(  # (the workers warmed up: kernels loaded in every process)
                    robot, make_targets(robot, 64 * workers, seed), scheduler=client, chunk_size=32
                )
                for n in sizes:
                    targets, _, q = kept[robot.name, n, 0]
                    res_d = fastest(scheduler=client)
                    if not np.array_equal(res_d.q, q):  # pragma: no cover - a bug
                        raise RuntimeError("Dask and in-process results differ")
                    record_batch("batch-dask", res_d, f"({workers} workers)", workers, setup_s)
                    for k in boxes:
                        free, avoid, q = kept[robot.name, n, k]
                        solve_batch(robot, free[: 8 * workers], goals=avoid, scheduler=client,
                                    chunk_size=8)  # fmt: skip
                        res_d = fastest(on=free, goals=avoid, scheduler=client)
                        if not np.array_equal(res_d.q, q):  # pragma: no cover - a bug
                            raise RuntimeError("Dask and in-process results differ")
                        record_batch(
                            f"boxes{k}-avoid-dask", res_d, f"({workers} workers)", workers, setup_s
                        )
    names = [r.name for r in loaded]
    rows.sort(key=lambda r: _row_rank(r, names))
    csv_path = common.write_csv(out / "throughput.csv", FIELDS, rows)
    prof_path = common.write_csv(out / "profile.csv", PROFILE_FIELDS, prof)
    return csv_path, prof_path


METHOD_ORDER = (
    "batch-1proc", "batch-threads", "batch-dask", "loop-solve", "loop-tracik", "plain",
    "avoid-1proc", "avoid-threads", "avoid-dask",
)  # fmt: skip
"""The order of a robot's rows of one N in the CSV and the report (``boxesK-`` rows by K, then
by their suffix)."""


def _row_rank(row: dict[str, Any], names: Sequence[str]) -> tuple[int, int, int, int]:
    """Where ``row`` goes: by robot (``names``: in the order run), N, boxes (none first),
    method."""
    method = str(row["method"])
    head, _, rest = method.partition("-")
    boxes = int(head[5:]) if head.startswith("boxes") and head[5:].isdigit() else 0
    name = rest if boxes else method
    rank = METHOD_ORDER.index(name) if name in METHOD_ORDER else len(METHOD_ORDER)
    return names.index(row["robot"]), int(row["n"]), boxes, rank


METHOD_LABELS = {
    "batch-1proc": "solve_batch, 1 process",
    "batch-threads": "solve_batch, a thread per core",
    "batch-dask": "solve_batch on Dask",
    "loop-solve": "loop over solve()",
    "loop-tracik": "loop over TRAC-IK",
}


def method_label(method: str) -> str:
    """Label of a method in the report and the plot (``boxesK-*`` rows included)."""
    if method in METHOD_LABELS:
        return METHOD_LABELS[method]
    head, _, rest = method.partition("-")
    if head.startswith("boxes") and head[5:].isdigit():
        k = head[5:]
        return {
            "plain": f"solve_batch, {k} boxes, no collision goal (judged with coal)",
            "avoid-1proc": f"solve_batch + AvoidCollisions, {k} boxes, 1 process",
            "avoid-threads": f"solve_batch + AvoidCollisions, {k} boxes, a thread per core",
            "avoid-dask": f"solve_batch + AvoidCollisions, {k} boxes, on Dask",
        }.get(rest, method)
    return method


def plot(csv_path: Path, png_path: Path) -> Path:
    """Per robot: log-log time vs N (top) and poses/s vs N (bottom), one line per method, from
    ``throughput.csv``."""
    import matplotlib

    matplotlib.use("Agg", force=False)
    import matplotlib.pyplot as plt

    rows = common.read_csv(csv_path)
    robots = list(dict.fromkeys(r["robot"] for r in rows))
    fig, axs = plt.subplots(
        2, len(robots), figsize=(6.2 * len(robots), 8.4), squeeze=False, constrained_layout=True
    )
    for col, robot in enumerate(robots):
        top, bottom = axs[0][col], axs[1][col]
        mine = [r for r in rows if r["robot"] == robot]
        methods = [*METHOD_LABELS, *dict.fromkeys(r["method"] for r in mine)]
        for method in dict.fromkeys(methods):
            label = method_label(method)
            pts = sorted(
                (int(r["n"]), float(r["time_s"]), r["workers"])
                for r in mine
                if r["method"] == method
            )
            if not pts:
                continue
            n, t, w = zip(*pts, strict=True)
            if method.endswith("dask"):
                label += f" ({w[0]} workers)"
            top.loglog(n, t, "o-", label=label)
            bottom.semilogx(n, np.array(n) / np.array(t), "o-", label=label)
        top.set_title(f"{robot}: FK-sampled targets, tolerance {mine[0]['tol']} m / rad")
        top.set_ylabel("wall-clock time [s]")
        bottom.set_ylabel("throughput [poses/s]")
        bottom.set_ylim(bottom=0)
        for ax in (top, bottom):
            ax.set_xlabel("N (targets)")
            ax.grid(True, which="both", alpha=0.3)
            ax.legend(fontsize=8)
    fig.savefig(png_path, dpi=110)
    plt.close(fig)
    return png_path


def box_ratios(rows: list[dict[str, str]]) -> str:
    """The collision-free rows' poses/s as a ratio of the plain batch's on the same targets
    (a Markdown table, empty without box rows)."""
    rate = {(r["robot"], r["n"], r["method"]): float(r["poses_per_s"]) for r in rows}
    out = []
    for (robot, n, method), plain in rate.items():
        head, _, kind = method.partition("-")
        if not head.startswith("boxes") or kind != "plain" or plain <= 0:
            continue
        cells = [
            f"{rate[(robot, n, f'{head}-{v}')] / plain:.2f}" if (robot, n, f"{head}-{v}") in rate
            else "–"
            for v in ("avoid-1proc", "avoid-threads", "avoid-dask")
        ]  # fmt: skip
        out.append(f"| {robot} | {head[5:]} | {int(n):,} | {' | '.join(cells)} |")
    if not out:
        return ""
    return (
        "\nWith `AvoidCollisions`, poses/s as a ratio of the plain batch's on the same targets:"
        "\n\n| robot | boxes | N | 1 process | a thread per core | on Dask |"
        "\n|---|---:|---:|---:|---:|---:|\n" + "\n".join(out) + "\n"
    )


def report(csv_path: Path, prof_path: Path, md_path: Path, png_name: str, scheduler: str) -> Path:
    """Markdown summary of ``throughput.csv`` and ``profile.csv`` (``templates/throughput.md``)."""
    rows = common.read_csv(csv_path)
    prof = common.read_csv(prof_path)
    table = []
    for r in rows:
        table.append(
            f"| {r['robot']} | {method_label(r['method'])} | {int(r['n']):,} | "
            f"{r['workers']} | {float(r['time_s']):.3f} | {float(r['poses_per_s']):,.0f} | "
            f"{100 * float(r['success_rate']):.2f} % | {r['mean_evals'] or '–'} | "
            f"{r['mean_starts'] or '–'} |"
        )
    setups = sorted({r["setup_s"] for r in rows if r["method"].endswith("dask")})
    profile = [
        f"| {r['robot']} | {int(r['n']):,} | {r['part']} | {float(r['seconds']):.4f} "
        f"| {100 * float(r['share']):.1f} % | {r['note']} |"
        for r in prof
    ]
    info = common.machine_info(("pytracik",))
    md_path.write_text(
        common.render(
            "throughput.md",
            machine=", ".join(f"{k} {v}" for k, v in info.items()),
            scheduler=scheduler,
            png=png_name,
            table="\n".join(table),
            dask_setup=(
                f"Dask start-up (not in the times above): {', '.join(setups)} s.\n"
                if setups
                else ""
            )
            + (
                "\nRows with boxes: a scene of K random boxes around the arm "
                "(`box_scene`), targets the FK of joint vectors free of contact (coal); "
                "`AvoidCollisions` rows judge every answer with coal inside the timed call, "
                "the rows without the goal are judged with coal afterwards (not timed).\n"
                + box_ratios(rows)
                if any(r["method"].startswith("boxes") for r in rows)
                else ""
            ),
            profile="\n".join(profile),
        )
    )
    return md_path


def run(args: argparse.Namespace) -> int:
    """Entry point of ``swarm-ik bench throughput``; returns the exit code."""
    quick = bool(args.quick)
    sizes = args.sizes or (QUICK_SIZES if quick else DEFAULT_SIZES)
    bad = [n for n in sizes if n < 1]
    if bad:
        from swarm_ik.errors import InvalidArgumentError

        raise InvalidArgumentError(f"--sizes must be positive numbers of targets, got {bad}")
    out = common.resolve_out(args.out, "throughput", quick)
    common.check_robots(args.robots)
    distributed.check_scheduler(args.scheduler, threads=False)  # (its threads rows run anyway)
    common.write_run_info(out, "throughput", quick)
    loop_max = min(args.loop_max, 100) if quick else args.loop_max
    csv_path, prof_path = run_experiment(
        args.robots,
        sizes,
        loop_max,
        args.tol,
        args.seed,
        args.scheduler,
        not args.no_tracik,
        out,
        args.repeat,
        args.boxes,
    )
    png = plot(csv_path, out / "throughput.png")
    md = report(csv_path, prof_path, out / "throughput.md", png.name, str(args.scheduler))
    print(f"wrote {csv_path}, {prof_path}, {png}, {md}")
    return 0


main = common.module_main(add_arguments, run, "throughput")


if __name__ == "__main__":
    raise SystemExit(main())
