"""Command line: ``swarm-ik robots | solve | bench …``.

Exit codes: 0 success, 1 target not reached (the best found is still printed), 2 bad input
(one line on stderr, no traceback; with ``--json`` one JSON object ``{"error": …,
"exit_code": 2, …}`` on stdout instead), 3 an unexpected error inside swarm_ik (one line; set
``SWARM_IK_DEBUG=1`` to see the traceback), 130 interrupted (Ctrl-C).

Numbers may be negative in any notation (``--from-q -1e-3 0.5 -2``): the parser does not take
``-1e-3`` for an option.  Usage errors are one line too, naming the sub-command's ``--help``.
"""

from __future__ import annotations

import argparse
import gc
import importlib
import json
import os
import re
import sys
import warnings
from collections.abc import Sequence
from typing import Any, NoReturn

import numpy as np

from swarm_ik import cli_args
from swarm_ik.errors import SwarmIKError

EXIT_NOT_REACHED = 1
EXIT_BAD_INPUT = 2
EXIT_INTERNAL = 3
EXIT_INTERRUPTED = 130

_NEGATIVE_NUMBER = re.compile(
    r"^-(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?$|^-(?:inf|infinity|nan)$", re.IGNORECASE
)
"""What the parser reads as a negative number rather than an option: ``-1``, ``-.5``,
``-1e-3``, ``-2.5E+4``, ``-inf``."""


class UsageError(Exception):
    """A command-line usage error (bad option, missing argument); exit code 2."""


class Parser(argparse.ArgumentParser):
    """``argparse.ArgumentParser`` that takes ``-1e-3`` for a number and reports usage errors
    as :class:`UsageError` (printed as one line by :func:`main`) instead of eight lines of
    usage.  Sub-parsers inherit the class."""

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        self._negative_number_matcher = _NEGATIVE_NUMBER

    def error(self, message: str) -> NoReturn:
        raise UsageError(f"{self.prog}: error: {message} (see `{self.prog} --help`)")


BENCHMARKS = {
    "paper": "swarm_ik.bench.paper",
    "ik": "swarm_ik.bench.ik",
    "throughput": "swarm_ik.bench.throughput",
    "goals": "swarm_ik.bench.goals",
    "many": "swarm_ik.bench.many",
    "collision": "swarm_ik.bench.collision",
}
COMMAND_MODULES = ("swarm_ik.viz_cli", "swarm_ik.batch_cli")
"""Modules adding sub-commands: each has ``add_commands(subparsers) -> {name: handler}``, a
handler taking the parsed ``argparse.Namespace`` and returning the exit code."""
_HANDLERS: dict[str, Any] = {}


def _parse_param(text: str) -> tuple[str, Any]:
    """``name=value`` → (name, value); the value parsed as JSON when possible."""
    if "=" not in text:
        raise argparse.ArgumentTypeError(
            f"solver parameter must look like name=value, got {text!r}"
        )
    key, raw = text.split("=", 1)
    try:
        value = json.loads(raw)
    except json.JSONDecodeError:
        value = raw
    return key.strip(), value


def _build_parser(command: str | None = None) -> argparse.ArgumentParser:
    """The whole parser; given the ``command`` about to run (``argv[0]``), the benchmarks'
    options are added (their modules imported) only if it is ``bench``."""
    from swarm_ik import solvers
    from swarm_ik.api import DEFAULT_SOLVER

    parser = Parser(
        prog="swarm-ik",
        description="Inverse kinematics for URDF robots with swarm optimisers and Pinocchio.",
    )
    sub = parser.add_subparsers(dest="command", required=True)

    sub.add_parser("robots", help="list the robots loadable by name")

    p = sub.add_parser("solve", help="solve one IK target")
    cli_args.add_robot(p, frame=False)
    p.add_argument(
        "--frame",
        action="append",
        default=None,
        help="goal frame; repeat for several (default: the robot's tool frame); --pose and "
        "--from-q are for the first",
    )
    tgt = p.add_mutually_exclusive_group(required=True)
    cli_args.add_pose(tgt)
    tgt.add_argument(
        "--goals",
        default=None,
        metavar="FILE",
        help="JSON list of goal terms (schema in docs/goals.md), e.g. "
        '[{"type": "Position", "frame": "tool0", "point": [0.4, 0, 0.3]}]',
    )
    tgt.add_argument(
        "--from-q",
        nargs="+",
        type=float,
        metavar="Q",
        help="target = FK of these joint values (rad / m), one per joint",
    )
    p.add_argument("--solver", default=DEFAULT_SOLVER, help=f"one of: {', '.join(solvers.names())}")
    p.add_argument("--fitness", default="se3", help="se3, paper-l1, euler-zyz or paper-pso")
    p.add_argument(
        "--position-only",
        action="store_true",
        help="solve for the position of the target only (chains with fewer than six joints)",
    )
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--max-evals", type=int, default=None)
    p.add_argument("--time-limit", type=float, default=None, help="seconds")
    cli_args.add_tolerances(p)
    p.add_argument("--q0", nargs="+", type=float, default=None, help="starting joint values")
    p.add_argument(
        "--scene",
        default=None,
        metavar="FILE",
        help="scene JSON of obstacles: the answer must be collision-free (self and scene)",
    )
    p.add_argument(
        "--no-self-collision",
        action="store_true",
        help="with --scene: check the robot against the scene only",
    )
    p.add_argument(
        "--srdf", default=None, help="SRDF of disabled self-collision pairs (default: found)"
    )
    p.add_argument(
        "--param",
        action="append",
        type=_parse_param,
        default=[],
        metavar="NAME=VALUE",
        help="solver parameter, repeatable (e.g. --param pop_size=50)",
    )
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.add_argument(
        "--show",
        action="store_true",
        help="look at the solution in meshcat (prints the viewer's URL; needs [viz])",
    )
    p.add_argument(
        "--animate",
        action="store_true",
        help="replay the optimiser's best-so-far configuration over its iterations",
    )
    p.add_argument(
        "--html",
        default=None,
        metavar="FILE",
        help="write the scene to a self-contained HTML file (no server needed)",
    )
    p.add_argument(
        "--compare",
        default=None,
        metavar="SOLVER",
        help="also solve with SOLVER (e.g. dls) and draw its answer ghosted",
    )

    b = sub.add_parser(
        "bench",
        help="benchmarks: 'paper' (the papers' tables), 'ik' (TRAC-IK protocol), "
        "'throughput' (batched IK)",
    )
    bsub = b.add_subparsers(dest="bench", required=True)
    for name, module in BENCHMARKS.items():
        bp = bsub.add_parser(name, help=f"benchmark {name}")
        if command not in (None, "bench"):
            continue
        try:
            importlib.import_module(module).add_arguments(bp)
        except ModuleNotFoundError:
            bp.set_defaults(_missing=module)
    for module in COMMAND_MODULES:
        try:
            mod = importlib.import_module(module)
        except ModuleNotFoundError as exc:
            if exc.name != module:
                raise
            continue
        _HANDLERS.update(mod.add_commands(sub))
    return parser


def _cmd_robots() -> int:
    from swarm_ik.robot import BUNDLED, EXAMPLE_ROBOTS

    print("bundled (robots/):")
    for name, (fname, frame) in sorted(BUNDLED.items()):
        print(f"  {name:28s} {fname}  (end effector: {frame})")
    print("example-robot-data:")
    for name, (rel, frames) in sorted(EXAMPLE_ROBOTS.items()):
        shown = frames if isinstance(frames, str) else ", ".join(frames)
        print(f"  {name:28s} {rel}  (goal frames: {shown})")
    return 0


def _cmd_solve(args: argparse.Namespace) -> int:
    import swarm_ik
    from swarm_ik._validate import check_output_path

    if args.html is not None:  # refuse an unwritable page before solving
        check_output_path(args.html, "--html")
    frames = None if not args.frame else (args.frame[0] if len(args.frame) == 1 else args.frame)
    robot = swarm_ik.load_robot(args.robot, ee_frame=frames, srdf=args.srdf, warm_up=False)
    goals = None
    target = None
    if args.goals is not None:
        goals = swarm_ik.goals.load_goals(args.goals)
    elif args.from_q is not None and len(robot.frames) > 1:  # a Pose goal on every frame
        poses = robot.fk_all(robot.check_q(args.from_q, "--from-q"))
        goals = [swarm_ik.goals.Pose(f, t) for f, t in zip(robot.frames, poses, strict=True)]
    elif args.from_q is not None:
        target = robot.fk_pinocchio(robot.check_q(args.from_q, "--from-q"))
    else:
        target = np.asarray(args.pose, dtype=float)
    if args.scene is not None:
        avoid = swarm_ik.goals.AvoidCollisions(
            swarm_ik.Scene.from_json(args.scene), self_collision=not args.no_self_collision
        )
        goals = [*(goals or []), avoid]
    problem = swarm_ik.IKProblem(
        robot, target, goals, args.fitness, w_rot=0.0 if args.position_only else 1.0
    )
    res = swarm_ik.solve(problem, args.solver, **cli_args.solve_kwargs(args), **dict(args.param))
    if args.json:
        d = res.to_dict()
        d.pop("history")
        d.update(
            robot=robot.name,
            joint_names=list(robot.joint_names),
            ee_frame=robot.ee_frame,
            frames=list(robot.frames),
        )
        print(json.dumps(d))
    else:
        status = "reached" if res.success else "NOT reached (best found below)"
        print(
            f"robot {robot.name} ({robot.nq} joints), frame {robot.ee_frame}, solver {res.solver}"
        )
        print(f"target {status}")
        for name, kind, v in zip(robot.joint_names, robot.joint_kinds, res.q, strict=True):
            unit = "m" if kind == "prismatic" else "rad"
            print(f"  {name:24s} {v: .10f} {unit}")
        if len(res.goal_errors) > 1:
            for e in res.goal_errors:
                parts = (
                    [f"{e.position_error:.3e} m"] if e.position_error == e.position_error else []
                )
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
        print(
            f"position error {res.position_error:.3e} m, "
            f"rotation error {res.rotation_error:.3e} rad ({res.reason})"
        )
        print(
            f"evaluations {res.n_evals}, time {res.time_s * 1e3:.2f} ms, "
            f"within limits {res.within_limits}"
        )
    if args.show or args.animate or args.html or args.compare:
        from swarm_ik import viz_cli

        viz_cli.after_solve(args, problem, res)
    return 0 if res.success else 1


def _fail(message: str, code: int, as_json: bool, kind: str) -> int:
    """Report an error as one line on stderr (or one JSON object on stdout); returns ``code``."""
    message = " ".join(str(message).split())
    if as_json:
        print(json.dumps({"error": message, "kind": kind, "exit_code": code}))
    else:
        prefix = "" if message.startswith("swarm-ik") else "swarm-ik: error: "
        print(prefix + message, file=sys.stderr)
    return code


def _dispatch(parser: argparse.ArgumentParser, args: argparse.Namespace) -> int:
    if args.command == "robots":
        return _cmd_robots()
    if args.command == "solve":
        return _cmd_solve(args)
    if args.command == "bench":
        missing = getattr(args, "_missing", None)
        if missing:
            raise UsageError(f"swarm-ik: error: benchmark module {missing} is not available")
        return int(importlib.import_module(BENCHMARKS[args.bench]).run(args))
    extra = _HANDLERS.get(args.command)
    if extra is not None:
        return int(extra(args))
    parser.error(f"unknown command {args.command!r}")


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``swarm-ik`` console script; returns the exit code.

    Never raises (except ``SystemExit`` from ``--help``): bad input gives 2 and one line,
    anything unexpected 3 and one line (``SWARM_IK_DEBUG=1`` re-raises it), Ctrl-C 130.
    """
    script = argv is None  # the console script: this process is ours to tune
    argv = list(sys.argv[1:] if argv is None else argv)
    as_json = "--json" in argv
    if script:
        _own_process()
    try:
        parser = _build_parser(argv[0] if argv else None)
        args = parser.parse_args(argv)
        as_json = bool(getattr(args, "json", False))
        if script and args.command not in SHORT_COMMANDS:
            gc.enable()
            script = False  # a long command: collect, and exit the usual way
        with warnings.catch_warnings():
            warnings.simplefilter("default")
            # Dask's start-up chatter (dashboard port taken, sockets) is not the user's concern
            warnings.filterwarnings("ignore", module=r"distributed(\.|$)")
            warnings.filterwarnings("ignore", category=ResourceWarning)
            return _dispatch(parser, args)
    except UsageError as exc:
        return _fail(str(exc), EXIT_BAD_INPUT, as_json, "UsageError")
    except SwarmIKError as exc:
        return _fail(str(exc), EXIT_BAD_INPUT, as_json, type(exc).__name__)
    except KeyboardInterrupt:
        return _fail("swarm-ik: interrupted", EXIT_INTERRUPTED, as_json, "KeyboardInterrupt")
    except Exception as exc:
        if os.environ.get("SWARM_IK_DEBUG"):
            raise
        what = "out of memory" if isinstance(exc, MemoryError) else f"{type(exc).__name__}: {exc}"
        return _fail(
            f"swarm-ik: internal error ({what}); please report it, with the command line "
            "(set SWARM_IK_DEBUG=1 for the traceback)",
            EXIT_INTERNAL,
            as_json,
            type(exc).__name__,
        )
    finally:
        if script:  # shutdown then skips the ~10^6 objects numba made (~0.25 s): a short
            gc.freeze()  # command only (extensions that report leaks at exit stay quiet)


SHORT_COMMANDS = ("solve", "robots")
"""Commands run with the cyclic garbage collector off: they make few objects after start-up,
and its passes over numba's ~10^6 import-time objects cost ~0.08 s of a ~0.7 s solve."""


def _own_process() -> None:
    """Start-up tuning for the console script only (never for :func:`main` called with
    ``argv``, in someone else's process).

    The collector is off until the command is known (:data:`SHORT_COMMANDS` keep it off), and
    numba's array-maths module is imported with ``scipy.linalg.cython_blas`` hidden: numba
    imports scipy.linalg (≈ 0.13 s) at that point only to learn whether ``np.convolve`` and
    ``np.correlate`` may call BLAS (without it they use numba's own loop).  No swarm_ik kernel
    calls BLAS, and scipy stays importable: only this one import sees it hidden.
    """
    gc.disable()
    blas = "scipy.linalg.cython_blas"
    if "numba.np.arraymath" in sys.modules or "scipy.linalg" in sys.modules:
        return
    sys.modules[blas] = None  # type: ignore[assignment]  # `import` of it now fails at once
    try:
        importlib.import_module("numba.np.arraymath")
    finally:
        if sys.modules.get(blas, 0) is None:
            del sys.modules[blas]


if __name__ == "__main__":
    raise SystemExit(main())
