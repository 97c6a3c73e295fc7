"""What several sub-commands of ``swarm-ik`` share: options (one definition each), the checks
of input and output paths made before any work, and the exit codes.

Only the standard library and :mod:`swarm_ik.errors` are imported here at module level, so
that ``import swarm_ik.cli`` stays light (the console script imports it before :func:`main`
can catch a Ctrl-C).
"""

from __future__ import annotations

import argparse
import math
import os
import stat
from collections.abc import Callable
from pathlib import Path
from typing import Any, NamedTuple

from swarm_ik.errors import InvalidArgumentError
from swarm_ik.paths import file_kind

EXIT_OK = 0
EXIT_NOT_REACHED = 1
EXIT_BAD_INPUT = 2
EXIT_INTERNAL = 3
EXIT_OUTPUT_FAILED = 74
EXIT_INTERRUPTED = 130
EXIT_BROKEN_PIPE = 141
"""The reader of the output went away (128 + SIGPIPE, as a shell reports it)."""


class UsageError(Exception):
    """A command-line usage error (bad option, missing argument); exit code 2."""


POSE_HELP = "target position [m] and quaternion qx qy qz qw (x y z w order)"
POSE_HELP_POSITION_ONLY = (
    "target position [m] and quaternion qx qy qz qw (x y z w order); with --position-only "
    "the position X Y Z alone is enough (a quaternion given is ignored)"
)
ROBOT_HELP = (
    "bundled or example-robot-data name (see `swarm-ik robots`), or a .urdf path "
    "(a .xacro must be expanded first)"
)
FRAME_HELP = (
    "goal frame; repeat for several: the model then spans the joints of every one (default: "
    "the robot's tool frame(s))"
)
SCHEDULER_HELP = (
    "where to solve: 'none' (default: this process, no Dask), 'threads' (this process, a "
    "thread per core, no Dask), 'local' (an embedded Dask "
    "LocalCluster, one worker process per core; pip install 'swarm_ik[dask]'), or a Dask "
    "scheduler address tcp://host:port"
)

SCENE_FORMATS = (
    "swarm_ik JSON, cuRobo world YAML (.yml), MoveIt .scene or a URDF of fixed obstacles "
    "(docs/scenes.md)"
)

MAX_GOALS_BYTES = 16 * 2**20
"""Largest ``--goals`` file read [bytes] (16 MiB); larger files are refused unread."""
MAX_JSON_DEPTH = 100
"""Deepest nesting of ``[`` / ``{`` accepted in a ``--goals`` file (a goal list needs 4)."""


# ------------------------------------------------------------------------------ options
class _PoseAction(argparse.Action):
    """``--pose`` taking 7 numbers, or 3 (a position) where ``--position-only`` is offered."""

    whole_metavar = True  # the help shows the metavar as written (swarm_ik.cli.Formatter)

    def __init__(self, *args: Any, three_ok: bool = False, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        self.three_ok = three_ok

    def __call__(
        self,
        parser: argparse.ArgumentParser,
        namespace: argparse.Namespace,
        values: Any,
        option_string: str | None = None,
    ) -> None:
        n = len(values)
        if n != 7 and not (self.three_ok and n == 3):
            valid = "7 arguments (X Y Z QX QY QZ QW)"
            if self.three_ok:
                valid += ", or 3 (X Y Z) with --position-only"
            raise argparse.ArgumentError(self, f"expected {valid}, got {n}")
        setattr(namespace, self.dest, list(values))


def add_pose(group: Any, *, position_only: bool = False) -> None:
    """``--pose X Y Z QX QY QZ QW`` on a parser or a mutually exclusive group; with
    ``position_only`` (the command has ``--position-only``) ``--pose X Y Z`` is taken too
    (:func:`pose_target` then checks that ``--position-only`` is given)."""
    if position_only:
        group.add_argument(
            "--pose",
            nargs="+",
            type=float,
            action=_PoseAction,
            three_ok=True,
            metavar="X Y Z [QX QY QZ QW]",
            help=POSE_HELP_POSITION_ONLY,
        )
        return
    group.add_argument(
        "--pose",
        nargs="+",
        type=float,
        action=_PoseAction,
        metavar="X Y Z QX QY QZ QW",
        help=POSE_HELP,
    )


def pose_target(pose: list[float], position_only: bool) -> list[float]:
    """The 7 numbers of ``--pose``: given as they are, or, for ``--pose X Y Z`` (accepted only
    with ``--position-only``), the position with an identity quaternion that nothing reads.

    Raises:
        UsageError: three numbers without ``--position-only``.
    """
    if len(pose) == 7:
        return list(pose)
    if not position_only:
        raise UsageError(
            "swarm-ik solve: error: argument --pose: expected 7 arguments (X Y Z QX QY QZ QW); "
            "3 (X Y Z) only with --position-only (see `swarm-ik solve --help`)"
        )
    return [*pose, 0.0, 0.0, 0.0, 1.0]


def robot_argument(text: str) -> str:
    """``--robot``'s type: the name or path, unchanged, except that a ``.xacro`` file (a
    macro file, not a URDF) is refused before anything is loaded."""
    name = Path(text).name
    if name.lower().endswith(".xacro"):
        stem = name[: -len(".xacro")]
        urdf = stem if stem.lower().endswith(".urdf") else stem + ".urdf"
        raise argparse.ArgumentTypeError(
            f"{text!r} is a xacro file: xacro files must be expanded first: run "
            f"`xacro {name} > {urdf}` (ROS's xacro package) and pass {urdf}"
        )
    return text


def add_frame(parser: Any, help: str = FRAME_HELP) -> None:
    """``--frame NAME``, repeatable, the one definition of every command that loads a robot
    (``help``: what the command does with the frames): ``args.frame`` is ``None`` or the
    names in the order given (:func:`robot_frames`).  A second ``--frame`` is never dropped:
    the robot is loaded with every frame given."""
    parser.add_argument("--frame", action="append", default=None, metavar="NAME", help=help)


def target_frame_help(what: str) -> str:
    """``--frame``'s help for a command that solves one frame's pose (``what``: its targets,
    waypoints, map): the first frame given is that one; more widen the model, as in
    ``swarm-ik solve``."""
    return (
        f"frame of {what} (default: the robot's tool frame); repeat --frame to load the robot "
        "with several goal frames, as `swarm-ik solve` does: the model then spans the joints "
        f"of every one and {what} are the first's"
    )


def robot_frames(args: argparse.Namespace) -> str | list[str] | None:
    """``load_robot``'s ``ee_frame`` of :func:`add_frame`'s ``--frame``: ``None`` (not given:
    the robot's own frames), the name given once, or the names given (the first is the
    robot's ``ee_frame``)."""
    frames = getattr(args, "frame", None)
    if not frames:
        return None
    return frames[0] if len(frames) == 1 else list(frames)


def add_robot(parser: Any, *, frame_help: str = FRAME_HELP) -> None:
    """``--robot NAME`` (required), ``--frame NAME`` (repeatable, :func:`add_frame`, with
    ``frame_help``), ``--floating-base``, ``--base-box`` and ``--lock JOINT[=VALUE]``
    (:func:`robot_kwargs`)."""
    parser.add_argument("--robot", required=True, type=robot_argument, help=ROBOT_HELP)
    add_frame(parser, frame_help)
    parser.add_argument(
        "--floating-base",
        action="store_true",
        help="give the root link a free flyer (a humanoid, a mobile base): six more joint "
        "values first (base x y z [m], rotation vector rx ry rz [rad])",
    )
    parser.add_argument(
        "--base-box",
        type=float,
        nargs="+",
        default=None,
        metavar="M",
        help="with --floating-base: half-widths [m] of the base's box around the origin, one "
        "number or three (default 2)",
    )
    parser.add_argument(
        "--lock",
        action="append",
        default=[],
        type=lock_argument,
        metavar="JOINT[=VALUE]",
        help="hold a joint at VALUE (rad or m; default its neutral value) even on a goal "
        "path; repeatable",
    )


class RobotCommand(NamedTuple):
    """The ``add_parser(subparsers)`` of a sub-command that works on one robot: called with
    the ``swarm-ik`` sub-parsers, it adds the parser ``name`` (``help``: its line in
    ``swarm-ik --help``; ``description``: the top of ``swarm-ik NAME --help``), with
    :func:`add_robot`'s options first and then the command's own (``add_arguments``).

    Attributes:
        name: The sub-command.
        add_arguments: Adds the command's options (after the robot's) to its parser.
        help: One line for ``swarm-ik --help``.
        description: The paragraph of ``swarm-ik NAME --help``.
        frame_help: The help of ``--frame`` (repeatable in every command: what the command
            does with several frames; see :func:`add_frame`).
    """

    name: str
    add_arguments: Callable[[argparse.ArgumentParser], None]
    help: str
    description: str
    frame_help: str = FRAME_HELP

    def __call__(self, subparsers: Any) -> argparse.ArgumentParser:
        """Add the sub-command to ``subparsers``; returns its parser."""
        parser: argparse.ArgumentParser = subparsers.add_parser(
            self.name, help=self.help, description=self.description
        )
        add_robot(parser, frame_help=self.frame_help)
        self.add_arguments(parser)
        return parser


def lock_argument(text: str) -> tuple[str, float | None]:
    """``--lock``'s type: ``JOINT=VALUE`` or ``JOINT`` → ``(name, value or None)``."""
    name, sep, raw = text.partition("=")
    if not name.strip():
        raise argparse.ArgumentTypeError(f"expected JOINT or JOINT=VALUE, got {text!r}")
    if not sep:
        return name.strip(), None
    try:
        value = float(raw)
    except ValueError:
        value = float("nan")
    if not math.isfinite(value):
        raise argparse.ArgumentTypeError(
            f"expected JOINT=VALUE with a finite number (rad or m), got {text!r}"
        )
    return name.strip(), value


def robot_kwargs(args: argparse.Namespace) -> dict[str, Any]:
    """``load_robot`` keywords of :func:`add_robot`'s options."""
    box = args.base_box
    out: dict[str, Any] = {"floating_base": bool(args.floating_base)}
    if box is not None:
        if not args.floating_base:
            raise InvalidArgumentError("--base-box needs --floating-base")
        if len(box) not in (1, 3):
            raise InvalidArgumentError(f"--base-box takes one number or three, got {len(box)}")
        out["base_box"] = box
    if args.lock:
        names = [name for name, _ in args.lock]
        dup = sorted({n for n in names if names.count(n) > 1})
        if dup:
            raise InvalidArgumentError(f"--lock: joint(s) {dup} given more than once")
        out["locked"] = dict(args.lock)  # (None: the joint's neutral value)
    return out


def load_robot(args: argparse.Namespace, **kwargs: Any) -> Any:
    """``swarm_ik.load_robot(args.robot, **kwargs)`` with :func:`robot_kwargs`'s options and,
    unless ``kwargs`` names it, ``ee_frame`` of every ``--frame`` (:func:`robot_frames`): the
    robot of a command line, a ``--lock`` outside its joint's limits refused in the words of
    the option (:func:`lock_refusal`), not of ``load_robot``'s ``locked=`` keyword.

    Raises:
        SwarmIKError: the loader's error (an :class:`InvalidArgumentError` for ``--lock``).
    """
    import swarm_ik

    model_kwargs = robot_kwargs(args)
    kwargs.setdefault("ee_frame", robot_frames(args))
    try:
        return swarm_ik.load_robot(args.robot, **kwargs, **model_kwargs)
    except InvalidArgumentError as exc:
        if not args.lock or "outside its limits" not in str(exc):  # (another refusal, e.g.
            raise  # a locked mimic follower: the loader's own words)
        line = lock_refusal(args, {**kwargs, **model_kwargs})
        if line is None:
            raise
        raise InvalidArgumentError(line) from None


def lock_refusal(args: argparse.Namespace, load_kwargs: dict[str, Any]) -> str | None:
    """Why a ``--lock`` of ``args`` is refused, as the option was typed with the joint's
    limits (``--lock J=5: 5 is outside its limits [-3.07, -0.07]``, ``--lock J: its neutral
    value 0 is ...; give the value to hold: --lock J=VALUE``); ``None`` when every locked
    value is within its limits (the refusal is of something else).  Called once the load
    refused: the limits are those of the robot loaded without ``locked``."""
    import pinocchio as pin

    import swarm_ik
    from swarm_ik.errors import SwarmIKError

    unlocked = {k: v for k, v in load_kwargs.items() if k != "locked"}
    try:
        full = swarm_ik.load_robot(args.robot, **unlocked).full_model
    except SwarmIKError:
        return None
    for name, value in args.lock:
        if not full.existJointName(name):
            continue
        jm = full.joints[full.getJointId(name)]
        if jm.nq != 1:  # (a continuous joint has no limits)
            continue
        lo, hi = float(full.lowerPositionLimit[jm.idx_q]), float(full.upperPositionLimit[jm.idx_q])
        v = float(pin.neutral(full)[jm.idx_q]) if value is None else float(value)
        if lo - 1e-9 <= v <= hi + 1e-9:
            continue
        limits = f"its limits [{lo:.10g}, {hi:.10g}]"
        if value is None:
            return (
                f"--lock {name}: its neutral value {v:.10g} is outside {limits}; give the value "
                f"to hold: --lock {name}=VALUE"
            )
        return f"--lock {name}={v:.10g}: {v:.10g} is outside {limits}"
    return None


def add_tolerances(parser: Any) -> None:
    """``--tol-pos M`` and ``--tol-rot RAD`` (default 1e-5 each)."""
    parser.add_argument(
        "--tol-pos", type=float, default=1e-5, help="position tolerance [m] (default 1e-5)"
    )
    parser.add_argument(
        "--tol-rot", type=float, default=1e-5, help="rotation tolerance [rad] (default 1e-5)"
    )


def add_lm_options(parser: Any, max_starts: int, starts_help: str) -> None:
    """The options of the compiled Levenberg-Marquardt search (``batch``, ``reach``):
    :func:`add_tolerances`, ``--max-starts N`` and ``--max-iters N``.

    Args:
        parser: The parser to add them to.
        max_starts: Default of ``--max-starts``.
        starts_help: Help of ``--max-starts`` (what one start is for), before its default.
    """
    add_tolerances(parser)
    parser.add_argument(
        "--max-starts",
        type=int,
        default=max_starts,
        help=f"{starts_help} (default {max_starts})",
    )
    parser.add_argument(
        "--max-iters", type=int, default=60, help="most LM iterations per start (default 60)"
    )


def add_scheduler(parser: Any, default: str = "none") -> None:
    """``--scheduler`` (for any command that distributes work with Dask)."""
    parser.add_argument(
        "--scheduler",
        default=default,
        metavar="none|threads|local|tcp://HOST:PORT",
        help=SCHEDULER_HELP,
    )


def add_q0(parser: Any, help: str) -> None:
    """``--q0 Q [Q ...]``: joint values, one per joint (``help`` says what they are for)."""
    parser.add_argument("--q0", nargs="+", type=float, default=None, help=help)


def add_scene(parser: Any, help: str) -> None:
    """``--scene FILE``: obstacles in any format :meth:`swarm_ik.scene.Scene.load` reads,
    named in the help after ``help`` (what the command keeps clear of them)."""
    parser.add_argument(
        "--scene",
        default=None,
        type=input_file,
        metavar="FILE",
        help=f"{help}; formats: {SCENE_FORMATS}",
    )


def add_collision_options(parser: Any, help: str, srdf_help: str) -> None:
    """``--scene FILE`` (:func:`add_scene`, ``help``), ``--no-self-collision`` and ``--srdf
    FILE`` (``srdf_help``): the obstacles and the robot's own pairs a command keeps clear of."""
    add_scene(parser, help)
    parser.add_argument(
        "--no-self-collision",
        action="store_true",
        help="with --scene: check the robot against the scene only",
    )
    parser.add_argument("--srdf", default=None, type=input_file, metavar="FILE", help=srdf_help)


def check_collision_options(args: argparse.Namespace, srdf_also: str | None = None) -> None:
    """Refuse :func:`add_collision_options`'s options where they modify nothing: before any
    work, ``--no-self-collision`` without ``--scene``; ``--srdf`` without ``--scene`` (or
    without the option ``srdf_also`` either, where that one may check collisions too, as
    ``solve --goals`` does); ``--srdf`` with ``--no-self-collision``.

    Raises:
        InvalidArgumentError: one line naming the option.
    """
    srdf_users = [args.scene]
    needs = "--scene"
    if srdf_also is not None:
        srdf_users.append(getattr(args, srdf_also[2:].replace("-", "_")))
        needs = f"--scene or {srdf_also}"
    for given, option, needed, other in (  # an option that modifies one not given
        (args.no_self_collision, "--no-self-collision", args.scene, "--scene"),
        (args.srdf, "--srdf", any(u is not None for u in srdf_users), needs),
    ):
        if given and not needed:
            raise InvalidArgumentError(f"{option} applies to {other}, which was not given")
    if args.srdf and args.no_self_collision:
        raise InvalidArgumentError(
            "--srdf names self-collision pairs, which --no-self-collision does not check"
        )


def non_negative_seconds(text: str) -> float:
    """A number of seconds >= 0 (``inf`` allowed), for ``--show-wait``."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number of seconds, got {text!r}") from None
    if not value >= 0.0:  # also refuses NaN
        raise argparse.ArgumentTypeError(f"must be 0 or more seconds (or inf), got {text!r}")
    return value


def solve_kwargs(args: argparse.Namespace) -> dict[str, Any]:
    """The options of ``swarm-ik solve`` that :func:`swarm_ik.solve` takes (no solver params)."""
    return {
        "seed": args.seed,
        "max_evals": args.max_evals,
        "time_limit": args.time_limit,
        "q0": args.q0,
        "tol_pos": args.tol_pos,
        "tol_rot": args.tol_rot,
    }


# --------------------------------------------------------------------------- input files
def input_file(text: str) -> str:
    """The type of an input-file option read after the robot is loaded (``--scene``,
    ``--srdf``): the path unchanged, refused as soon as it is parsed when it exists but is
    not a regular file (a folder, a FIFO, ``/dev/zero``), with what it is.  A missing path
    is let through: the reader names it as missing.

    Raises:
        argparse.ArgumentTypeError: ``"'PATH' is a folder; give a regular file"`` (exit 2).
    """
    try:
        mode = Path(text).stat().st_mode  # follows links: a link to a FIFO is a FIFO
    except OSError:
        return text
    if not stat.S_ISREG(mode):
        raise argparse.ArgumentTypeError(f"{text!r} is {file_kind(mode)}; give a regular file")
    return text


def check_input_file(path: str | os.PathLike[str], what: str, max_bytes: int | None) -> Path:
    """Refuse an input path that is not a regular file (a folder, a FIFO, ``/dev/zero``),
    or, with ``max_bytes``, a file larger than that, before opening it.

    A path that does not exist is let through: the reader names it as missing.

    Raises:
        InvalidArgumentError: naming the option, the path and the limit.
    """
    p = Path(path)
    try:
        st = p.stat()  # follows links: a link to a FIFO is a FIFO
    except FileNotFoundError:
        return p
    except OSError as exc:
        raise InvalidArgumentError(f"{what} {str(p)!r}: cannot be read ({exc.strerror})") from None
    if not stat.S_ISREG(st.st_mode):
        raise InvalidArgumentError(
            f"{what} {str(p)!r} is {file_kind(st.st_mode)}; give a regular file"
        )
    if max_bytes is not None and st.st_size > max_bytes:
        raise InvalidArgumentError(
            f"{what} {str(p)!r}: {st.st_size} bytes, over the limit of {_size(max_bytes)} "
            "for this file"
        )
    return p


def _size(n: int) -> str:
    return f"{n // 2**20} MiB" if n % 2**20 == 0 else f"{n} bytes"


def json_depth(data: bytes) -> int:
    """How deeply ``[`` and ``{`` nest in JSON text, brackets inside strings not counted,
    found in linear time without parsing (so without recursion).

    A quote ends or starts a string unless an odd number of backslashes precedes it.  For a
    file that is valid JSON up to some point, the count over that part is exactly the depth
    the parser reaches there.

    >>> json_depth(b'[{"a": [1, "]]"], "b": "[{["}]')
    3
    """
    import numpy as np

    arr = np.frombuffer(data, dtype=np.uint8)
    if arr.size == 0:
        return 0
    pos = np.arange(arr.size, dtype=np.int32)  # files are capped far below 2**31
    # length of the run of backslashes just before each byte
    last_other = np.maximum.accumulate(np.where(arr != ord("\\"), pos, -1))
    before = np.empty(arr.size, dtype=np.int32)
    before[0] = 0
    before[1:] = pos[:-1] - last_other[:-1]
    quote = (arr == ord('"')) & (before % 2 == 0)
    del pos, last_other, before  # the file may be 16 MiB: keep the peak low
    outside = ~np.logical_xor.accumulate(quote)  # a bracket is never a quote
    opens = outside & ((arr == ord("[")) | (arr == ord("{")))
    closes = outside & ((arr == ord("]")) | (arr == ord("}")))
    step = opens.astype(np.int32) - closes.astype(np.int32)
    return max(0, int(np.cumsum(step, dtype=np.int32).max()))


def check_goals_file(path: str | os.PathLike[str], what: str = "--goals") -> None:
    """The checks made on ``--goals FILE`` before :func:`swarm_ik.goals.load_goals` reads it:
    a regular file of at most :data:`MAX_GOALS_BYTES`, its JSON nested at most
    :data:`MAX_JSON_DEPTH` deep (a deeper one would exhaust Python's recursion in the
    parser).

    Raises:
        InvalidArgumentError: one line naming the limit.
    """
    p = check_input_file(path, what, MAX_GOALS_BYTES)
    try:
        data = p.read_bytes()
    except OSError:
        return  # missing or unreadable: load_goals says so
    depth = json_depth(data)
    if depth > MAX_JSON_DEPTH:
        raise InvalidArgumentError(
            f"{what} {str(p)!r}: JSON nested {depth} levels deep, over the limit of "
            f"{MAX_JSON_DEPTH} (a goal list needs about 4)"
        )


# -------------------------------------------------------------------------- output paths
def check_output_file(
    path: str | os.PathLike[str],
    what: str,
    suffixes: tuple[str, ...] | None = None,
    inputs: tuple[tuple[str, Any], ...] = (),
) -> Path:
    """Refuse an output file that cannot be written, before any work: what
    :func:`swarm_ik._validate.check_output_path` refuses (a folder, a device, a wrong suffix,
    a missing folder, an existing file that does not open for writing, a folder where no file
    can be created), or one of the command's input files (``inputs``: ``(option, path or
    None)``; ``batch --targets t.csv --out t.csv`` replaced its targets with the answers).

    Returns:
        The path.

    Raises:
        InvalidArgumentError: one line naming the option and why.
    """
    from swarm_ik._validate import check_output_path

    p = check_output_path(path, what, suffixes)
    if p.exists():
        for option, given in inputs:
            if given is not None and Path(given).is_file() and os.path.samefile(p, given):
                raise InvalidArgumentError(
                    f"{what} {str(p)!r} is the file given to {option}: writing the answers "
                    "would replace it; name another file"
                )
    return p


def check_output_folder(path: str | os.PathLike[str], what: str = "--out") -> Path:
    """Refuse an output folder that cannot be written, before any work: a file, or a folder
    (or, when it is to be created, its nearest existing parent) where nothing can be written.

    Raises:
        InvalidArgumentError: one line naming the option and why.
    """
    p = Path(path)
    if p.exists() and not p.is_dir():
        raise InvalidArgumentError(f"{what} {str(p)!r} is a file; give a folder")
    existing = p
    while not existing.exists():
        up = existing.parent
        if up == existing:
            break
        existing = up
    if not existing.is_dir():
        raise InvalidArgumentError(
            f"{what} {str(p)!r}: {str(existing)!r} is a file, so the folder cannot be made"
        )
    from swarm_ik._validate import probe_folder

    reason = probe_folder(existing)
    if reason is not None:
        raise InvalidArgumentError(
            f"{what} {str(p)!r}: cannot write in folder {str(existing)!r} ({reason})"
        )
    return p
