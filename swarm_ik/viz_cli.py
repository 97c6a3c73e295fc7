"""Command line of the viewer: ``swarm-ik show …`` and the ``--show/--animate/--html/--compare``
options of ``swarm-ik solve``.

``--show`` (and ``show`` without ``--html``) starts meshcat's local server, prints its URL and
keeps it up until Enter (on a terminal) or Ctrl-C; ``SWARM_IK_NO_WAIT=1`` returns at once (for
scripts and tests).  ``--html FILE`` writes one self-contained page that any browser opens
without a server.  ``solve --animate`` or ``--compare`` without ``--html`` or ``--show`` draws
nothing: it says so on stderr and returns (it never starts a viewer that blocks).
"""

from __future__ import annotations

import argparse
import os
import signal
import sys
import time
from typing import Any

import numpy as np

from swarm_ik import cli_args

NO_WAIT_ENV = "SWARM_IK_NO_WAIT"
"""Environment variable: when set (to anything but ``0`` or empty), the live viewer is not
kept open (the command returns right after printing the URL)."""


def add_commands(subparsers: Any) -> dict[str, Any]:
    """Add ``show`` to the ``swarm-ik`` sub-parsers; returns its handler."""
    p = subparsers.add_parser(
        "show",
        help="look at a robot configuration, or at several solutions of a target, in meshcat "
        "(live, or exported to a self-contained HTML file)",
        description="Draw a robot at given joint values (--q, repeatable) and/or a target pose "
        "(--pose or --from-q); with a target and no --q, solve it first "
        "(--solutions N distinct solutions).",
    )
    cli_args.add_robot(p)
    p.add_argument(
        "--q",
        nargs="+",
        type=float,
        action="append",
        default=None,
        metavar="Q",
        help="joint values (rad / m, one per joint); repeat --q for several",
    )
    tgt = p.add_mutually_exclusive_group()
    cli_args.add_pose(tgt)
    tgt.add_argument(
        "--from-q", nargs="+", type=float, metavar="Q", help="target = FK of these joint values"
    )
    p.add_argument(
        "--solutions",
        type=int,
        default=1,
        metavar="N",
        help="with a target and no --q: how many distinct solutions to find and show",
    )
    p.add_argument(
        "--min-distance",
        type=float,
        default=0.5,
        help="smallest joint-space distance between two shown solutions (rad / m)",
    )
    p.add_argument(
        "--solver",
        default=None,
        help="solver for the target (default: swarm_ik.solve_many / the default solver)",
    )
    p.add_argument("--seed", type=int, default=0)
    p.add_argument(
        "--layout",
        default="side",
        choices=["side", "steps"],
        help="several configurations: side by side, or one robot stepping through them",
    )
    p.add_argument("--html", default=None, metavar="FILE", help="write a self-contained HTML page")
    p.add_argument(
        "--show", action="store_true", help="also keep the live viewer open when --html is given"
    )
    p.add_argument("--open", action="store_true", help="open the live viewer in a web browser")
    return {"show": run_show}


# ------------------------------------------------------------------------------ helpers
def _say(args: argparse.Namespace, text: str) -> None:
    """Print a viewer message: on stdout, or stderr when stdout carries JSON."""
    print(text, file=sys.stderr if getattr(args, "json", False) else sys.stdout, flush=True)


def _wait(args: argparse.Namespace) -> None:
    """Keep the process (and so meshcat's server) alive until the user is done."""
    if os.environ.get(NO_WAIT_ENV, "") not in ("", "0"):
        return

    def stop(signum: int, frame: Any) -> None:
        raise KeyboardInterrupt

    try:  # a SIGTERM ends the wait like Ctrl-C, so that meshcat's server is stopped too
        signal.signal(signal.SIGTERM, stop)
    except ValueError:  # not the main thread
        pass
    try:
        if sys.stdin is not None and sys.stdin.isatty():
            input("press Enter to close the viewer ")
        else:
            _say(args, "the viewer stays up until Ctrl-C")
            while True:
                time.sleep(3600)
    except (KeyboardInterrupt, EOFError):
        pass


def present(scene: Any, args: argparse.Namespace, *, live: bool) -> None:
    """Write ``--html`` if asked; print the live URL and wait when ``live``; then close."""
    try:
        html = getattr(args, "html", None)
        if html:
            path = scene.save_html(html)
            size = path.stat().st_size / 1e6
            _say(
                args, f"wrote {path} ({size:.1f} MB): a self-contained page, open it in any browser"
            )
        if live:
            _say(args, f"meshcat viewer: {scene.url}")
            if getattr(args, "open", False):
                import webbrowser

                webbrowser.open(scene.url, new=2)
            _wait(args)
    finally:
        scene.close()


def _result_line(res: Any) -> str:
    status = "reached" if res.success else "NOT reached"
    return (
        f"{res.solver}: {status}, position error {res.position_error:.3e} m, rotation error "
        f"{res.rotation_error:.3e} rad, {res.n_evals} evaluations, "
        f"{res.time_s * 1e3:.2f} ms"
    )


# ------------------------------------------------------------------------- solve hook
def after_solve(args: argparse.Namespace, problem: Any, result: Any) -> None:
    """Called by ``swarm-ik solve`` when one of ``--show/--animate/--html/--compare`` is given.

    ``--animate`` solves again with the same options and seed, recording the best-so-far
    configuration of every iteration (:func:`swarm_ik.viz.solve_traced`); ``--compare SOLVER``
    solves the target with SOLVER too and draws its answer ghosted.  Without ``--html`` or
    ``--show`` there is nowhere to draw: a note on stderr, and nothing else is done.
    """
    if not (args.html or args.show):
        print(
            "swarm-ik: note: --animate/--compare draw a scene; add --html FILE to write it or "
            "--show to open the live viewer (nothing drawn)",
            file=sys.stderr,
        )
        return
    from swarm_ik import viz

    viz.require_meshcat()
    if args.html:
        viz.check_output_path(args.html, "--html", (".html", ".htm"))
    kwargs = cli_args.solve_kwargs(args)
    trace = None
    if args.animate:
        traced, trace = viz.solve_traced(problem, args.solver, **kwargs, **dict(args.param))
        if not np.allclose(traced.q, result.q):  # e.g. a time limit cut the runs differently
            _say(
                args,
                "note: the recorded run ended elsewhere than the one printed; showing "
                "the recorded one",
            )
            result = traced
        _say(
            args,
            f"animation: best-so-far configuration over {len(trace.fitness)} iterations "
            f"({trace.improvements} improvements)",
        )
    compare = None
    if args.compare:
        import swarm_ik

        compare = swarm_ik.solve(problem, args.compare, **kwargs)
        _say(args, "compare " + _result_line(compare))
    scene = viz.show_result(problem, result, trace=trace, compare=compare)
    col = getattr(problem, "collision_goal", None)
    if col is not None:  # the obstacles, and what is in contact in red
        report = next((e.details for e in result.goal_errors if e.goal == "AvoidCollisions"), None)
        named = set() if report is None else {n for p in report.pairs_in_contact for n in p}
        viz.add_obstacles(scene, col.scene, [n for n in col.scene.names if n in named])
        if named - set(col.scene.names):
            viz.add_contact_bodies(scene, problem.robot, result.q, sorted(named))
    present(scene, args, live=bool(args.show))


# ------------------------------------------------------------------------- show command
def run_show(args: argparse.Namespace) -> int:
    """``swarm-ik show``: returns 0, or 1 when a target was given and not reached."""
    import swarm_ik
    from swarm_ik import viz
    from swarm_ik.errors import InvalidArgumentError

    viz.require_meshcat()
    if args.html:
        viz.check_output_path(args.html, "--html", (".html", ".htm"))
    robot = swarm_ik.load_robot(args.robot, ee_frame=args.frame)
    target = None
    if args.from_q is not None:
        target = robot.fk(robot.check_q(args.from_q, "--from-q"))
    elif args.pose is not None:
        target = np.asarray(args.pose, dtype=float)
    live = bool(args.show or not args.html)
    if args.q:
        qs = [robot.check_q(q, "--q") for q in args.q]
        if target is None:
            lines = [f"{robot.name}: " + ", ".join(f"{v:.3f}" for v in q) for q in qs]
            scene = (
                viz.show_pose(robot, qs[0], lines=lines)
                if len(qs) == 1
                else viz.show_configurations(robot, qs, lines=lines, layout=args.layout)
            )
            present(scene, args, live=live)
            return 0
        problem = swarm_ik.IKProblem(robot, target)
        results = [_as_result(problem, q) for q in qs]
    else:
        if target is None:
            raise InvalidArgumentError("show needs --q, or a target (--pose or --from-q)")
        problem = swarm_ik.IKProblem(robot, target)
        results = viz.several_solutions(
            problem,
            args.solutions,
            solver=args.solver,
            min_distance=args.min_distance,
            seed=args.seed,
        )
    for k, r in enumerate(results):
        print(f"#{k + 1} " + _result_line(r) + "\n   q = " + " ".join(f"{v:.6f}" for v in r.q))
    if len(results) == 1:
        scene = viz.show_result(problem, results[0])
    else:
        scene = viz.show_solutions(problem, results, layout=args.layout)
    present(scene, args, live=live)
    return 0 if all(r.success for r in results) else 1


def _as_result(problem: Any, q: Any) -> Any:
    """A :class:`~swarm_ik.result.Result` describing a given configuration (no solve)."""
    from swarm_ik.api import verify
    from swarm_ik.result import Result

    q = np.asarray(q, dtype=float)
    dp, dr = verify(problem, q)
    within = problem.robot.within_limits(q)
    return Result(
        q=q,
        fitness=float(problem.fitness(q[None])[0]),
        position_error=dp,
        rotation_error=dr,
        n_evals=0,
        time_s=0.0,
        success=bool(within and dp <= 1e-5 and dr <= 1e-5),
        within_limits=within,
        history=np.empty(0),
        solver="given q",
        seed=None,
    )
