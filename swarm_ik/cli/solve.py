"""``swarm-ik solve``: one IK target (a pose, the FK of joint values, or a JSON list of goals)
solved and printed; optionally drawn (``--show``, ``--html``, ``--animate``, ``--compare``).

Exit codes: 0 reached, 1 not reached (the best found is printed), 2 bad input, 3 internal
error, 130 interrupted.
"""

from __future__ import annotations

import argparse
import json
from typing import Any

from swarm_ik import argtypes
from swarm_ik.cli import _viewer
from swarm_ik.cli._args import (
    EXIT_NOT_REACHED,
    EXIT_OK,
    RobotCommand,
    add_collision_options,
    add_pose,
    add_q0,
    add_tolerances,
    check_collision_options,
    check_goals_file,
    load_robot,
    pose_target,
    solve_kwargs,
)
from swarm_ik.errors import InvalidArgumentError

HELP = "solve one IK target (a pose, FK of joint values, or a goals file)"
"""One line for ``swarm-ik --help``."""
DESCRIPTION = (
    "Solve one IK target of a robot and print the joint values; exit 0 when "
    "the target is reached within the tolerances, 1 when not (the best found is printed)."
)
"""The top of ``swarm-ik solve --help``."""


def _parse_param(text: str) -> tuple[str, Any]:
    """``name=value`` → (name, value); the value parsed as JSON when possible."""
    if "=" not in text:
        raise argparse.ArgumentTypeError(
            f"solver parameter must look like name=value, got {text!r}"
        )
    from swarm_ik._validate import json_int  # (numpy: loaded when a parameter is given)

    key, raw = text.split("=", 1)
    try:
        value = json.loads(raw, parse_int=json_int)  # (past int()'s digit cap: a float)
    except (json.JSONDecodeError, RecursionError):
        value = raw
    return key.strip(), value


def _solver_help() -> str:
    """``--solver``'s help with the registry's names, made only when the help is shown (the
    registry loads numba: 0.8 s that every other use of the parser would pay)."""
    from swarm_ik import solvers
    from swarm_ik.api import DEFAULT_SOLVER

    return f"one of: {', '.join(solvers.names())} (default {DEFAULT_SOLVER})"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """The options of ``swarm-ik solve`` after the robot's (see :func:`run`)."""
    tgt = parser.add_mutually_exclusive_group(required=True)
    add_pose(tgt, position_only=True)
    tgt.add_argument(
        "--goals",
        default=None,
        metavar="FILE",
        help="JSON list of goal terms (schema in docs/goals.md), e.g. "
        '[{"type": "Position", "frame": "tool0", "point": [0.4, 0, 0.3]}]; a regular file '
        "of at most 16 MiB",
    )
    tgt.add_argument(
        "--from-q",
        nargs="+",
        type=float,
        metavar="Q",
        help="target = FK of these joint values (rad / m), one per joint",
    )
    solver = parser.add_argument(
        "--solver", default=None, help="a registered solver (the list: swarm-ik solve --help)"
    )
    solver.help_text = _solver_help  # type: ignore[attr-defined]  # (see Formatter)
    parser.add_argument(
        "--fitness",
        default="se3",
        help="se3 (default), paper-l1, euler-zyz or paper-pso",
    )
    parser.add_argument(
        "--position-only",
        action="store_true",
        help="solve for the position of the target only (e.g. chains with fewer than six "
        "joints): --pose X Y Z is enough, and no rotation error is reported (with --from-q "
        "and several --frame: each frame's position; refused with --goals)",
    )
    argtypes.add_seed(parser, "random seed")
    parser.add_argument("--max-evals", type=int, default=None, help="most fitness evaluations")
    parser.add_argument(
        "--time-limit",
        type=float,
        default=None,
        help="most seconds for the solve, its check included (loading the robot and the "
        "scene is not counted; --compare's solve gets a limit of its own)",
    )
    add_tolerances(parser)
    add_q0(parser, "starting joint values (one per joint)")
    add_collision_options(
        parser,
        "obstacles the answer must be clear of (and of itself)",
        "SRDF of disabled self-collision pairs (default: found)",
    )
    parser.add_argument(
        "--param",
        action="append",
        type=_parse_param,
        default=[],
        metavar="NAME=VALUE",
        help="solver parameter, repeatable (e.g. --param pop_size=50)",
    )
    parser.add_argument("--json", action="store_true", help="print one JSON object")
    parser.add_argument(
        "--show",
        action="store_true",
        help="look at the solution in meshcat's live viewer (prints its URL; needs [viz]); "
        "see --show-wait for how long it stays up",
    )
    _viewer.add_show_wait(parser)
    parser.add_argument(
        "--animate",
        action="store_true",
        help="with --show or --html: replay the optimiser's best-so-far configuration over its "
        "iterations",
    )
    parser.add_argument(
        "--html",
        default=None,
        metavar="FILE",
        help="write the scene to a self-contained .html file (no server needed; needs [viz])",
    )
    parser.add_argument(
        "--compare",
        default=None,
        metavar="SOLVER",
        help="with --show or --html: also solve with SOLVER (e.g. dls) and draw its answer ghosted",
    )


FRAME_HELP = (
    "goal frame; repeat for several (default: the robot's tool frame); --pose is for the "
    "first, --from-q poses every frame"
)
"""``--frame``'s help in ``swarm-ik solve``."""

add_parser = RobotCommand("solve", add_arguments, HELP, DESCRIPTION, frame_help=FRAME_HELP)
"""Add ``solve`` to the ``swarm-ik`` sub-parsers."""


def run(args: argparse.Namespace) -> int:
    """``swarm-ik solve``: returns 0 when the target is reached, 1 when not."""
    import numpy as np

    import swarm_ik
    from swarm_ik.api import DEFAULT_SOLVER

    if args.solver is None:  # (the parser leaves the registry unloaded: see _solver_help)
        args.solver = DEFAULT_SOLVER
    if args.compare is not None:  # (refused before the solve it would follow)
        from swarm_ik.solvers import base

        base.get(args.compare)
    check_collision_options(args, srdf_also="--goals")  # (a goals file may avoid collisions)
    if args.show_wait is not None and not args.show:
        raise InvalidArgumentError("--show-wait applies to --show, which was not given")
    drawing = _viewer.wants_drawing(args)
    if drawing:  # refused before solving: meshcat missing, an unwritable page
        _viewer.check_viewer(args, live=bool(args.show))
    if args.goals is not None:
        if args.position_only:
            raise InvalidArgumentError(
                "--position-only applies to --pose and --from-q; a --goals file states each "
                "goal itself (write a Position goal where only the position matters)"
            )
        check_goals_file(args.goals)
    _check_dls_options(args)
    pose = None if args.pose is None else pose_target(args.pose, args.position_only)
    robot = load_robot(args, srdf=args.srdf)  # (every --frame: robot_frames)
    if drawing:
        _viewer.check_meshes(robot, "--html" if args.html else "--show")
    goals = None
    target = None
    if args.goals is not None:
        try:
            goals = swarm_ik.goals.load_goals(args.goals)
        except RecursionError:  # checked before (check_goals_file): a second guard
            raise InvalidArgumentError(f"--goals {args.goals!r}: JSON nested too deep") from None
    elif args.from_q is not None and len(robot.frames) > 1:  # a Pose goal on every frame
        poses = robot.fk_all(robot.target_q(args.from_q, "--from-q"))
        goals = [
            swarm_ik.goals.Position(f, t[:3, 3])
            if args.position_only
            else swarm_ik.goals.Pose(f, t)
            for f, t in zip(robot.frames, poses, strict=True)
        ]
    elif args.from_q is not None:
        target = robot.fk_pinocchio(robot.target_q(args.from_q, "--from-q"))
    else:
        target = np.asarray(pose, dtype=float)
    if args.scene is not None:
        avoid = swarm_ik.goals.AvoidCollisions(
            swarm_ik.Scene.load(args.scene), self_collision=not args.no_self_collision
        )
        goals = [*(goals or []), avoid]
    problem = swarm_ik.IKProblem(
        robot, target, goals, args.fitness, w_rot=0.0 if args.position_only else 1.0
    )
    _check_dls_problem(args, problem)
    _check_closed_form_compare(args, problem)
    res = swarm_ik.solve(problem, args.solver, **solve_kwargs(args), **dict(args.param))
    why = _why_not(problem, res, solve_kwargs(args))
    drawn = args.show or args.animate or args.html or args.compare
    if args.json and drawn and not args.show:  # the page written first: a failed write is
        _viewer.after_solve(args, problem, res)  # then the one JSON object on stdout
        drawn = False
    if args.json:
        _print_json(args, robot, res, why)
    else:
        _print_text(args, robot, res, why)
    if drawn:
        _viewer.after_solve(args, problem, res)
    return EXIT_OK if res.success else EXIT_NOT_REACHED


def _dls_options(args: argparse.Namespace) -> list[str]:
    """The options that name the solver ``dls`` (``--solver dls``, ``--compare dls``)."""
    return [
        option
        for option, name in (("--solver", args.solver), ("--compare", args.compare))
        if name == "dls"
    ]


def _dls_refused(option: str, what: str) -> InvalidArgumentError:
    """The one-line refusal of ``option dls`` for a problem it cannot take (``what``)."""
    from swarm_ik.api import DEFAULT_SOLVER
    from swarm_ik.solvers.dls import TAKES

    instead = (
        f"leave --solver out to use the default solver {DEFAULT_SOLVER}, which takes any goals"
        if option == "--solver"
        else "compare with another solver"
    )
    return InvalidArgumentError(f"{option} dls solves {TAKES}; it cannot take {what}: {instead}")


def _check_dls_options(args: argparse.Namespace) -> None:
    """Refuse ``--solver dls`` (or ``--compare dls``) with options that make a problem it
    cannot solve (:func:`swarm_ik.solvers.dls.support`), before the robot is loaded:
    ``--scene`` (a collision goal), ``--from-q`` with several ``--frame`` (a pose goal on
    each)."""
    for option in _dls_options(args):
        if args.scene is not None:
            raise _dls_refused(option, "--scene (obstacles to avoid: a collision goal)")
        if args.from_q is not None and args.frame and len(args.frame) > 1:
            raise _dls_refused(
                option, f"--from-q with {len(args.frame)} --frame (a pose goal on each frame)"
            )


def _check_dls_problem(args: argparse.Namespace, problem: Any) -> None:
    """Refuse ``--solver dls`` (or ``--compare dls``) for a problem it cannot solve (a
    ``--goals`` file of other goals), before solving."""
    options = _dls_options(args)
    if not options:
        return
    from swarm_ik.solvers.dls import support

    reason = support(problem)
    if reason:
        source = (
            f"--goals {args.goals!r}, which holds" if args.goals is not None else "a problem of"
        )
        raise _dls_refused(options[0], f"{source} {reason}")


def _check_closed_form_compare(args: argparse.Namespace, problem: Any) -> None:
    """Refuse ``--compare`` naming a closed-form solver (``analytic``) for a problem it cannot
    solve, before the solve it would follow (it printed the whole solve, then the refusal:
    two JSON objects with ``--json``).  ``--solver`` itself is refused by ``solve`` before
    any work."""
    if args.compare is None:
        return
    from swarm_ik.solvers import analytic, base

    if base.get(args.compare).closed_form:
        reason = analytic.support(problem)
        if reason:
            raise analytic.AnalyticUnsupportedError(
                f"--compare {args.compare}: no analytic IK for this problem: {reason}"
            )


def _measured(res: Any, field: str) -> bool:
    """Whether some goal of ``res`` has an error of this kind (``position_error`` or
    ``rotation_error``; a Result reports 0.0 where none has: see Result)."""
    return any(getattr(e, field) == getattr(e, field) for e in res.goal_errors)


def _why_not(problem: Any, res: Any, kwargs: dict[str, Any]) -> str | None:
    """What a solve that ended ``unreachable`` or ``conflicting_goals`` found: the goal
    beyond reach (or the goal's own reason, e.g. a centre-of-mass margin deeper than its
    support polygon allows), or the two goals no pose meets together; for a full pose an arm
    of fewer than six joints missed, that it meets few of them; None otherwise."""
    from swarm_ik import api

    tol = (kwargs.get("tol_pos", 1e-5), kwargs.get("tol_rot", 1e-5))
    if res.reason == "unreachable":
        return api.unreachable_goal(problem, *tol)
    if res.reason == "conflicting_goals":
        found = api.conflicting_goals(problem, *tol)
        return None if found is None else f"{found} cannot be met together"
    if not res.success and problem.single_pose and not problem.position_only:
        movable = problem.robot.nq - (6 if problem.robot.floating_base else 0)
        if movable < 6:  # (a pose is six numbers: such an arm meets few of them)
            return (
                f"an arm of {movable} joints meets few full poses (a pose fixes 6 numbers); "
                "--position-only solves the position alone"
            )
    return None


def _print_json(args: argparse.Namespace, robot: Any, res: Any, why: str | None) -> None:
    d = res.to_dict()
    d["why"] = why
    d.pop("history")
    if args.position_only or not _measured(res, "rotation_error"):
        d["rotation_error"] = None  # not measured: no goal asked for a rotation
    if not _measured(res, "position_error"):
        d["position_error"] = None
    d.update(
        robot=robot.name,
        joint_names=list(robot.joint_names),
        ee_frame=robot.ee_frame,
        frames=list(robot.frames),
        # the whole URDF's Pinocchio configuration (free flyer first when floating; locked
        # and off-path joints at their values): checkable with Pinocchio alone
        full_configuration=robot.full_configuration(res.q).tolist(),
    )
    print(json.dumps(d))


def _print_text(args: argparse.Namespace, robot: Any, res: Any, why: str | None) -> None:
    status = "reached" if res.success else "NOT reached (best found below)"
    joints = (
        f"{robot.nq - 6} joints + floating base" if robot.floating_base else f"{robot.nq} joints"
    )
    print(f"robot {robot.name} ({joints}), frame {robot.ee_frame}, solver {res.solver}")
    print(f"target {status}")
    for name, kind, v in zip(robot.joint_names, robot.joint_kinds, res.q, strict=True):
        unit = "m" if kind == "prismatic" else "rad"
        print(f"  {name:24s} {v: .10f} {unit}")
    if len(res.goal_errors) > 1:
        for e in res.goal_errors:
            parts = [f"{e.position_error:.3e} m"] if e.position_error == e.position_error else []
            if e.rotation_error == e.rotation_error:
                parts.append(f"{e.rotation_error:.3e} rad")
            rep = e.details
            if rep is not None and hasattr(rep, "clearance"):
                parts = [f"clearance {rep.clearance:.4f} m"]
                if rep.pairs_in_contact:
                    parts.append(
                        "in contact: " + ", ".join("-".join(p) for p in rep.pairs_in_contact)
                    )
            print(f"  {e.goal}: {', '.join(parts)} ({'met' if e.met else 'NOT met'})")
    if args.position_only:
        rot = "n/a (--position-only)"
    elif not _measured(res, "rotation_error"):
        rot = "n/a (no goal on a rotation)"
    else:
        rot = f"{res.rotation_error:.3e} rad"
    pos = f"{res.position_error:.3e} m" if _measured(res, "position_error") else "n/a"
    print(f"position error {pos}, rotation error {rot} ({res.reason})")
    if why:
        print(f"why: {why}")
    print(
        f"evaluations {res.n_evals}, time {res.time_s * 1e3:.2f} ms, "
        f"within limits {res.within_limits}"
    )
