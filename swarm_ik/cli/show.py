"""``swarm-ik show``: a robot configuration, or several solutions of a target, in meshcat
(live, or exported to a self-contained HTML page); see :mod:`swarm_ik.cli._viewer` for how
long the live viewer stays up."""

from __future__ import annotations

import argparse
import sys
import warnings
from typing import Any

from swarm_ik import argtypes
from swarm_ik.cli import _viewer
from swarm_ik.cli._args import EXIT_NOT_REACHED, EXIT_OK, RobotCommand, add_pose, load_robot

HELP = (
    "look at a robot configuration, or at several solutions of a target, in meshcat "
    "(live, or exported to a self-contained HTML file)"
)
"""One line for ``swarm-ik --help``."""
DESCRIPTION = (
    "Draw a robot at given joint values (--q, repeatable) and/or a target pose "
    "(--pose or --from-q); with a target and no --q, solve it first "
    "(--solutions N distinct solutions).  Without --html the live viewer opens (its URL "
    "is printed); needs [viz]."
)
"""The top of ``swarm-ik show --help``."""


MAX_SHOWN = 64
"""Most solutions ``swarm-ik show --solutions`` finds and draws (one robot each, side by side):
``--solutions 1000000`` searched without end, and no page shows a million robots."""


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """The options of ``swarm-ik show`` after the robot's (see :func:`run`)."""
    parser.add_argument(
        "--q",
        nargs="+",
        type=float,
        action="append",
        default=None,
        metavar="Q",
        help="joint values (rad / m, one per joint); repeat --q for several",
    )
    tgt = parser.add_mutually_exclusive_group()
    add_pose(tgt)
    tgt.add_argument(
        "--from-q", nargs="+", type=float, metavar="Q", help="target = FK of these joint values"
    )
    parser.add_argument(
        "--solutions",
        type=int,
        default=None,
        metavar="N",
        help="with a target and no --q: how many distinct solutions to find and show (default 1, "
        f"at most {MAX_SHOWN})",
    )
    parser.add_argument(
        "--min-distance",
        type=float,
        default=None,
        help="with a target and no --q: smallest joint-space distance between two shown "
        "solutions (rad / m, default 0.5)",
    )
    parser.add_argument(
        "--solver",
        default=None,
        help="solver for the target (default: swarm_ik.solve_many; with a name, that solver "
        "from successive seeds)",
    )
    argtypes.add_seed(parser, "random seed")
    parser.add_argument(
        "--layout",
        default="side",
        choices=["side", "steps"],
        help="several configurations: side by side (default), or one robot stepping through them",
    )
    parser.add_argument(
        "--html", default=None, metavar="FILE", help="write a self-contained HTML page"
    )
    parser.add_argument(
        "--show", action="store_true", help="also keep the live viewer open when --html is given"
    )
    _viewer.add_show_wait(parser)
    parser.add_argument("--open", action="store_true", help="open the live viewer in a web browser")


FRAME_HELP = (
    "goal frame; repeat for several: the model then spans the joints of every one (--q gives "
    "them all); --pose is the first's target, --from-q poses every frame, as in `swarm-ik "
    "solve` (default: the robot's tool frame(s))"
)
"""``--frame``'s help in ``swarm-ik show``."""

add_parser = RobotCommand("show", add_arguments, HELP, DESCRIPTION, frame_help=FRAME_HELP)
"""Add ``show`` to the ``swarm-ik`` sub-parsers."""


def run(args: argparse.Namespace) -> int:
    """``swarm-ik show``: returns 0, or 1 when a target was given and not reached."""
    import numpy as np

    import swarm_ik
    from swarm_ik import viz
    from swarm_ik._validate import degrees_hint
    from swarm_ik.errors import InvalidArgumentError

    live = bool(args.show or not args.html)
    for option, given in (("--show-wait", args.show_wait is not None), ("--open", args.open)):
        if given and not live:
            raise InvalidArgumentError(f"{option} applies to the live viewer: add --show")
    if args.q:  # (given q's are drawn as they are: nothing is solved)
        for option, value in (
            ("--solutions", args.solutions),
            ("--min-distance", args.min_distance),
            ("--solver", args.solver),
        ):
            if value is not None:
                raise InvalidArgumentError(f"{option} applies to a target solved, not to --q")
    if args.solutions is not None and not 1 <= args.solutions <= MAX_SHOWN:
        raise InvalidArgumentError(
            f"--solutions must be a count from 1 to {MAX_SHOWN} (swarm_ik.cli.show.MAX_SHOWN), "
            f"got {args.solutions}"
        )
    _viewer.check_viewer(args, live=live)
    robot = load_robot(args)  # (every --frame: robot_frames)
    _viewer.check_meshes(robot, "show")
    target = None
    goals = None  # (several frames and --from-q: a pose goal on each, as `swarm-ik solve`)
    if args.from_q is not None and len(robot.frames) > 1:
        poses = robot.fk_all(robot.target_q(args.from_q, "--from-q"))
        goals = [swarm_ik.goals.Pose(f, t) for f, t in zip(robot.frames, poses, strict=True)]
    elif args.from_q is not None:
        target = robot.fk(robot.target_q(args.from_q, "--from-q"))
    elif args.pose is not None:
        target = np.asarray(args.pose, dtype=float)
    if args.q:
        qs = [robot.check_q(q, "--q") for q in args.q]
        for k, q in enumerate(qs):  # (drawn as given, as `solve --q0` would clip it: said)
            outside = np.flatnonzero((q < robot.lower) | (q > robot.upper))
            if outside.size:
                names = [robot.joint_names[i] for i in outside.tolist()]
                hint = degrees_hint(q[outside])  # (review 136)
                print(
                    f"swarm-ik: note: --q #{k + 1} lies outside the joint limits at {names}"
                    f"{hint}; drawn as given",
                    file=sys.stderr,
                )
        if target is None and goals is None:
            lines = [f"{robot.name}: " + ", ".join(f"{v:.3f}" for v in q) for q in qs]
            scene = (
                viz.show_pose(robot, qs[0], lines=lines)
                if len(qs) == 1
                else viz.show_configurations(robot, qs, lines=lines, layout=args.layout)
            )
            _viewer.present(scene, args, live=live)
            return EXIT_OK
        problem = swarm_ik.IKProblem(robot, target, goals)
        results = [_as_result(problem, q) for q in qs]
    else:
        if target is None and goals is None:
            raise InvalidArgumentError("show needs --q, or a target (--pose or --from-q)")
        problem = swarm_ik.IKProblem(robot, target, goals)
        results = viz.several_solutions(
            problem,
            1 if args.solutions is None else args.solutions,
            solver=args.solver,
            min_distance=0.5 if args.min_distance is None else args.min_distance,
            seed=args.seed,
        )
        asked = 1 if args.solutions is None else args.solutions
        if len(results) < asked and results[0].success:
            why = (
                f"--solver {args.solver} solved from successive seeds reaches the solutions its "
                "starts lead to; without --solver, swarm_ik.solve_many looks for every branch"
                if args.solver is not None
                else "the target has no more distinct ones, or the search's budget ended"
            )
            warnings.warn(
                f"found {len(results)} of the {asked} solutions asked for (at least "
                f"{0.5 if args.min_distance is None else args.min_distance:g} apart): {why}",
                stacklevel=1,
            )
    for k, r in enumerate(results):
        print(
            f"#{k + 1} " + _viewer.result_line(r) + "\n   q = " + " ".join(f"{v:.6f}" for v in r.q)
        )
    if len(results) == 1:
        scene = viz.show_result(problem, results[0])
    else:
        scene = viz.show_solutions(problem, results, layout=args.layout)
    _viewer.present(scene, args, live=live)
    return EXIT_OK if all(r.success for r in results) else EXIT_NOT_REACHED


def _as_result(problem: Any, q: Any) -> Any:
    """A :class:`~swarm_ik.result.Result` describing a given configuration (no solve)."""
    import numpy as np

    from swarm_ik.problem import largest_errors
    from swarm_ik.result import Result

    q = np.asarray(q, dtype=float)
    dp, dr = largest_errors(problem.verify(q))
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
