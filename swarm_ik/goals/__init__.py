"""Goals: what an IK problem asks of the robot, each a residual with its Jacobian.

A goal is a small frozen object: a frame (for frame goals), its data (a pose, a point, an
axis…), a ``weight`` and whether it is ``primary``.  Primary goals must be met to tolerance
(success = every primary goal within tolerance and the joints within limits); secondary goals
(the default for :class:`Posture`, :class:`CenterJoints` and :class:`MinimalDisplacement`) are
optimised lexicographically *after* the primary ones, in the null space of the primary
Jacobian (:func:`swarm_ik.kernels.lm.secondary_descent`), so a secondary goal never costs
primary accuracy.

Each goal type is one file of this package (the protocol: :mod:`swarm_ik.goals.base`); a goal
of your own is a subclass of :class:`Goal` with ``residual(state)`` and ``jacobian(state)``
(see ``docs/goals.md``).

>>> import numpy as np, swarm_ik
>>> from swarm_ik import goals
>>> robot = swarm_ik.load_robot("panda")
>>> down = goals.Axis("panda_hand_tcp", axis=[0, 0, 1], direction=[0, 0, -1])
>>> at = goals.Position("panda_hand_tcp", [0.5, 0, 0.3])
>>> problem = swarm_ik.IKProblem(robot, goals=[at, down])
>>> swarm_ik.solve(problem).success
True
"""

from __future__ import annotations

import functools
import json
import os
import reprlib
from collections.abc import Mapping, Sequence
from dataclasses import MISSING, Field, fields
from pathlib import Path
from typing import Any, TypeVar

import numpy as np

from swarm_ik._validate import json_int
from swarm_ik.errors import InvalidArgumentError, InvalidTargetError, unknown
from swarm_ik.goals.avoid_collisions import AvoidCollisions
from swarm_ik.goals.axis import Axis
from swarm_ik.goals.base import Encoded, Goal, Pin, State, kernel_slot, kernels
from swarm_ik.goals.center_joints import CenterJoints
from swarm_ik.goals.center_of_mass import CenterOfMass
from swarm_ik.goals.joint import JointGoal
from swarm_ik.goals.joint_value import JointValue
from swarm_ik.goals.look_at import LookAt
from swarm_ik.goals.minimal_displacement import MinimalDisplacement
from swarm_ik.goals.orientation import Orientation
from swarm_ik.goals.pose import Pose
from swarm_ik.goals.position import Position
from swarm_ik.goals.posture import Posture

GOALS: dict[str, type[Goal]] = {}
"""Goal types by name (the ``type`` field of the JSON schema)."""

G = TypeVar("G", bound=type[Goal])


def register_goal(cls: G) -> G:
    """Make a goal type known by its class name (JSON, CLI); usable as a class decorator.

    Raises:
        InvalidArgumentError: not a Goal subclass, or a goal type of that name is already
            registered.
    """
    if not (isinstance(cls, type) and issubclass(cls, Goal)):
        raise InvalidArgumentError(f"register_goal takes a Goal subclass, got {cls!r}")
    name = cls.__name__
    if name in GOALS and GOALS[name] is not cls:
        raise InvalidArgumentError(f"goal type {name!r} is already registered")
    GOALS[name] = cls
    return cls


for _cls in (Pose, Position, Orientation, Axis, LookAt, Posture, CenterJoints,
             MinimalDisplacement, JointValue, AvoidCollisions, CenterOfMass):  # fmt: skip
    register_goal(_cls)

MAX_GOALS_FILE = 16 * 2**20
"""Largest goals file read [bytes] (16 MiB)."""


def _init_fields(cls: type[Goal]) -> list[Field[Any]]:
    """The goal type's constructor fields in the order of its signature (keyword-only last)."""
    init = [f for f in fields(cls) if f.init]
    return sorted(init, key=lambda f: bool(f.kw_only))


def _json_scene(value: Any, base_dir: str | os.PathLike[str] | None) -> Any:
    """The ``scene`` of an ``AvoidCollisions`` goal's JSON form: a scene file's path (relative
    to ``base_dir``, the goals file's folder, when given; ``~`` expanded) or null; a JSON
    object or list (an inline scene) is refused in the schema's terms.  Anything else (a
    :class:`~swarm_ik.scene.Scene`, a list of shapes, given from Python) is passed on."""
    inline = isinstance(value, Mapping) or (
        isinstance(value, (list, tuple)) and any(isinstance(v, Mapping) for v in value)
    )
    if inline or isinstance(value, (bool, int, float)):
        got = "an object" if isinstance(value, Mapping) else (
            "a list" if inline else reprlib.repr(value)
        )  # fmt: skip
        raise InvalidArgumentError(
            'goal AvoidCollisions: "scene" must be a scene file\'s path (a string: .json, '
            ".yml/.yaml, .scene or .urdf; docs/scenes.md) or null (self-collision only), got "
            f'{got}: write the obstacles to a scene file (e.g. {{"obstacles": [...]}} as a '
            ".json file) and give its path"
        )
    if isinstance(value, str) and value and base_dir is not None:
        try:
            path = Path(value).expanduser()
        except RuntimeError:  # ("~nobody/…": the scene's reader says so)
            return value
        if not path.is_absolute():
            return str(Path(base_dir) / path)
    return value


def goal_from_dict(
    data: Mapping[str, Any], *, base_dir: str | os.PathLike[str] | None = None
) -> Goal:
    """One goal from its JSON form ``{"type": "Pose", "frame": ..., ...}``.

    Args:
        data: The goal's JSON object.
        base_dir: Folder against which a relative ``scene`` path of an ``AvoidCollisions``
            goal is read (:func:`load_goals` gives the goals file's folder; default: the
            working directory).

    Raises:
        UnknownNameError: unknown ``type`` (the goal types listed).
        InvalidArgumentError: missing or unknown fields (the valid ones listed), bad values
            (an ``AvoidCollisions`` ``scene`` given inline as a JSON object or list: it is a
            scene file's path or null).
    """
    if not isinstance(data, Mapping):
        raise InvalidArgumentError(
            f"a goal must be a JSON object with a 'type', got {reprlib.repr(data)}"
        )
    kind = data.get("type")
    if not isinstance(kind, str) or kind not in GOALS:
        raise unknown("goal type", kind if isinstance(kind, str) else reprlib.repr(kind), GOALS)
    cls = GOALS[kind]
    valid = [f.name for f in _init_fields(cls)]
    given = {k: v for k, v in data.items() if k != "type"}
    bad = sorted(str(k) for k in set(given) - set(valid))
    if bad:
        raise InvalidArgumentError(
            f"goal {kind}: unknown field(s) {bad}; valid fields: {', '.join(valid)}"
        )
    required = [
        f.name for f in _init_fields(cls) if f.default is MISSING and f.default_factory is MISSING
    ]
    missing = [name for name in required if name not in given]
    if missing:
        raise InvalidArgumentError(f"goal {kind}: missing field(s) {missing}")
    for name in ("frame", "joint"):
        if name in given and not isinstance(given[name], str):
            raise InvalidArgumentError(
                f"goal {kind}: {name} must be a name (a string), got {reprlib.repr(given[name])}"
            )
    if "target" in given and isinstance(given["target"], Mapping):
        t = given["target"]
        extra = sorted(set(t) - {"position", "quaternion"})
        if extra or "position" not in t or "quaternion" not in t:
            raise InvalidTargetError(
                f"goal {kind}: target must be a 4x4 matrix, 7 numbers (x y z qx qy qz qw) or "
                '{"position": [x, y, z], "quaternion": [qx, qy, qz, qw]}'
            )
        given["target"] = (t["position"], t["quaternion"])
    if cls is AvoidCollisions and "scene" in given:
        given["scene"] = _json_scene(given["scene"], base_dir)
    try:
        return cls(**given)
    except TypeError as exc:
        raise InvalidArgumentError(f"goal {kind}: {exc}") from None


def goal_to_dict(goal: Goal) -> dict[str, Any]:
    """JSON form of a goal (inverse of :func:`goal_from_dict`)."""
    out: dict[str, Any] = {"type": type(goal).__name__}
    for f in _init_fields(type(goal)):
        v = getattr(goal, f.name)
        out[f.name] = v.tolist() if isinstance(v, np.ndarray) else v
    return out


def _no_repeats(where: Path, pairs: list[tuple[str, Any]]) -> dict[str, Any]:
    """A JSON object of a goals file, a key given twice in it refused (json would keep the
    last value silently)."""
    out: dict[str, Any] = {}
    for key, value in pairs:
        if key in out:
            raise InvalidArgumentError(
                f"{where}: key {key!r} given twice in one JSON object (each key once)"
            )
        out[key] = value
    return out


def load_goals(source: str | os.PathLike[str] | Sequence[Mapping[str, Any]]) -> list[Goal]:
    """Goals from a JSON file (a list of goal objects, or ``{"goals": [...]}``) or from the
    already-parsed list.

    The ``scene`` of an ``AvoidCollisions`` goal is a scene file's path or null; read from a
    file, a relative path is taken from the goals file's folder (as a scene file's relative
    mesh paths are from its own), from a parsed list from the working directory.

    Raises:
        InvalidArgumentError: not a regular file, larger than :data:`MAX_GOALS_FILE`,
            unreadable, nested too deeply, a key given twice in one object, not a list of goal
            objects, bad goals.
    """
    if isinstance(source, (str, os.PathLike)):
        p = Path(source)
        if not p.exists():
            raise InvalidArgumentError(f"goals file not found: {str(p)!r}")
        if not p.is_file():
            raise InvalidArgumentError(f"{p}: not a regular file (a goals file is JSON on disk)")
        if p.stat().st_size > MAX_GOALS_FILE:
            raise InvalidArgumentError(
                f"{p}: larger than the {MAX_GOALS_FILE // 2**20} MiB limit of a goals file"
            )
        try:
            data = json.loads(
                p.read_text(encoding="utf-8-sig"),  # (a byte-order mark dropped)
                object_pairs_hook=functools.partial(_no_repeats, p),
                parse_int=json_int,  # (an integer past Python's digit cap: a float)
            )
        except RecursionError:
            raise InvalidArgumentError(f"{p}: JSON nested too deeply") from None
        except (OSError, UnicodeDecodeError, json.JSONDecodeError) as exc:
            raise InvalidArgumentError(f"{p}: not a readable JSON goals file ({exc})") from None
        base_dir: Path | None = p.resolve().parent
    else:
        data = source
        base_dir = None
    if isinstance(data, Mapping) and "goals" in data:
        data = data["goals"]
    if not isinstance(data, Sequence) or isinstance(data, (str, bytes)) or not data:
        raise InvalidArgumentError("goals must be a non-empty JSON list of goal objects")
    return [goal_from_dict(d, base_dir=base_dir) for d in data]


__all__ = [
    "GOALS",
    "AvoidCollisions",
    "Axis",
    "CenterJoints",
    "CenterOfMass",
    "Encoded",
    "Goal",
    "JointGoal",
    "JointValue",
    "LookAt",
    "MinimalDisplacement",
    "Orientation",
    "Pin",
    "Pose",
    "Position",
    "Posture",
    "State",
    "goal_from_dict",
    "goal_to_dict",
    "kernel_slot",
    "kernels",
    "load_goals",
    "register_goal",
]
