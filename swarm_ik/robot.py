"""RobotModel: a URDF loaded into Pinocchio and reduced to the serial chain root → end effector.

>>> import swarm_ik
>>> robot = swarm_ik.load_robot("yumi_left")
>>> robot.nq, robot.ee_frame
(7, 'yumi_tool')
"""

from __future__ import annotations

import math
import os
import reprlib
import threading
import warnings
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, NamedTuple

import numpy as np
import pinocchio as pin
from numpy.typing import NDArray

from swarm_ik import urdf
from swarm_ik._types import FloatArray
from swarm_ik._validate import (
    DEGREES_HINT,
    count,
    degrees_hint,
    floats_or,
    keywords_checked,
    user_stacklevel,
)
from swarm_ik.errors import (
    InvalidArgumentError,
    RobotFileNotFoundError,
    RobotModelError,
    RobotModelWarning,
    unknown,
)
from swarm_ik.kernels import lie
from swarm_ik.kernels.fk import BALL, CONTINUOUS, KIND_NAMES, PRISMATIC, REVOLUTE, TreeArrays
from swarm_ik.paths import (  # (the robot tables live there: no kernels to list them)
    BUNDLED,
    EXAMPLE_ROBOTS,
    bundled_robot_dir,
    example_robot_data_dir,
    example_robot_files,
)
from swarm_ik.pose import FLOAT64, unit


def _joint_kind_axis(jmodel: Any) -> tuple[int, FloatArray]:
    """Kind code and unit axis (in the joint frame) of a one-DoF Pinocchio joint."""
    short = jmodel.shortname()
    if jmodel.nv != 1:
        raise RobotModelError(f"joint type {short} ({jmodel.nv} DoF) is not supported on the chain")
    jdata = jmodel.createData()
    if jmodel.nq == 2:  # revolute unbounded: (cos, sin)
        kind = CONTINUOUS
        jmodel.calc(jdata, np.array([1.0, 0.0]))
    else:
        jmodel.calc(jdata, np.zeros(1))
        kind = -1
    s = np.asarray(jdata.S).reshape(6)
    lin, ang = s[:3], s[3:]
    if kind == -1:
        if np.linalg.norm(ang) > 0.5:
            kind = REVOLUTE
        elif np.linalg.norm(lin) > 0.5:
            kind = PRISMATIC
        else:
            raise RobotModelError(f"cannot read the axis of joint type {short}")
    axis = ang if kind in (REVOLUTE, CONTINUOUS) else lin
    return kind, axis / np.linalg.norm(axis)


def _entries(model: Any, joint: str) -> set[int]:
    """The configuration entries of ``joint`` in ``model``."""
    jm = model.joints[model.getJointId(joint)]
    return set(range(jm.idx_q, jm.idx_q + jm.nq))


class _Reduction(NamedTuple):
    reduced: Any
    locked: list[int]
    q_ref: FloatArray
    frame_ids: list[int]
    names: list[str]
    kinds: list[int]
    tree: TreeArrays
    lower: FloatArray
    upper: FloatArray
    followers: dict[str, tuple[str, float, float]]


FREE_FLYER_ENTRIES = ("root_joint.x", "root_joint.y", "root_joint.z",
                      "root_joint.rx", "root_joint.ry", "root_joint.rz")  # fmt: skip
"""Names of the joint-vector entries of a floating base (Pinocchio's ``root_joint``): the
base position [m] in the world, then its orientation as a rotation vector [rad]
(``R = exp([r]×)``, no gimbal lock)."""


MAX_SOLVED_DOF = 150
"""Most degrees of freedom of the reduced model (a humanoid has about 40): Pinocchio's
``Data`` allocates second-order tensors of ``nv³`` numbers (216 MB each at 150 joints)."""


DEFAULT_BASE_BOX = 2.0
"""Half-width [m] of a floating base's box when ``base_box`` is not given: a standing
humanoid's pelvis, a base driving a few metres."""


def _base_box(value: Any, floating_base: bool) -> FloatArray:
    """Half-widths [m] of a floating base's box around the origin: one positive number or
    three (None: :data:`DEFAULT_BASE_BOX`); refused without a floating base, which it would
    not bound."""
    if value is None:
        value = DEFAULT_BASE_BOX
    elif not floating_base:
        raise InvalidArgumentError(
            f"base_box bounds a floating base: give floating_base=True with it (got "
            f"base_box={reprlib.repr(value)} and no floating base)"
        )
    try:
        box = np.broadcast_to(np.asarray(value, dtype=float), (3,)).copy()
    except (TypeError, ValueError):
        raise InvalidArgumentError(
            f"base_box must be a positive number or 3 of them [m], got {value!r}"
        ) from None
    if isinstance(value, (bool, str)) or not np.all(np.isfinite(box) & (box > 0.0)):
        raise InvalidArgumentError(
            f"base_box must be a positive number or 3 of them [m], got {value!r}"
        )
    return box


def _tree_joint(jid: int, shift: int) -> int:
    """The kernels' tree index of Pinocchio joint ``jid`` (``-1``: the world), with ``shift``
    tree joints before Pinocchio's joint 1 (3 for a free flyer's x, y, z, whose rotation is
    then tree joint 3)."""
    return -1 if jid == 0 else jid - 1 + shift


def _locked_values(
    p: Path,
    full: Any,
    locked: Any,
    mimic: dict[str, tuple[str, float, float]],
    renamed: Mapping[str, str] | None = None,
) -> dict[int, float]:
    """The joints to hold (``{joint id: value}``) from ``locked``: a dict name -> value (rad
    or m) or a list of names (held at their neutral value).  A locked mimic driver holds its
    followers too.  A joint renamed because a link has the same name (``renamed``: URDF name
    -> model name, :attr:`swarm_ik.urdf.UrdfInfo.renamed`) is found under either name.

    Raises:
        UnknownNameError: a name is not a one-DoF joint of the URDF (the joints listed).
        InvalidArgumentError: a value is not a finite number within the joint's limits.
    """
    if locked is None:
        return {}
    if isinstance(locked, str):
        locked = [locked]
    if isinstance(locked, (bytes, bytearray)):  # (iterated, its bytes read as joint ids)
        raise InvalidArgumentError(
            f"locked must be a dict joint -> value or a list of joint names (text), got "
            f"{reprlib.repr(locked)}"
        )
    if isinstance(locked, dict):
        items = list(locked.items())
    else:
        try:
            items = [(name, None) for name in locked]
        except TypeError:
            raise InvalidArgumentError(
                f"locked must be a dict joint -> value or a list of joint names, got {locked!r}"
            ) from None
    names = [full.names[j] for j in range(1, full.njoints) if full.joints[j].nv == 1]

    def outside(jid: int, v: float) -> str | None:
        """The limits ``[lo, hi]`` of joint ``jid`` as text when ``v`` lies outside them
        (a continuous joint has none)."""
        jm = full.joints[jid]
        if jm.nq != 1:
            return None
        lo, hi = float(full.lowerPositionLimit[jm.idx_q]), float(full.upperPositionLimit[jm.idx_q])
        return None if lo - 1e-9 <= v <= hi + 1e-9 else f"[{lo:g}, {hi:g}]"

    out: dict[int, float] = {}
    given_as: dict[str, str] = {}
    for given, value in items:
        name = (renamed or {}).get(given, given) if isinstance(given, str) else given
        if not isinstance(name, str) or name not in names:
            if isinstance(name, str) and full.existJointName(name):  # (review 133: a hint of
                # another joint misled) a joint of more than one degree of freedom
                jm = full.joints[full.getJointId(name)]
                base = " (the floating base: bound it with base_box=)" if jm.nv == 6 else ""
                raise InvalidArgumentError(
                    f"locked joint {name!r} moves in {jm.nv} degrees of freedom{base}; only "
                    "joints of one degree of freedom can be locked"
                )
            raise unknown("joint", given, names)
        if given_as.setdefault(name, given) != given:
            raise InvalidArgumentError(
                f"locked joint {name!r} is given twice, as {given_as[name]!r} and {given!r} "
                "(its URDF name and the name it was renamed to): give it once"
            )
        if name in mimic:
            driver, a, b = mimic[name]
            raise InvalidArgumentError(
                f"locked joint {name!r} mimics {driver!r} ({name} = {a:g}·{driver} + {b:g}): "
                f"lock its driver {driver!r} instead (its followers follow it)"
            )
        jid = int(full.getJointId(name))
        jm = full.joints[jid]
        if value is None:
            v = 0.0 if jm.nq == 2 else float(pin.neutral(full)[jm.idx_q])
            what = f"its neutral value {v:g}"
        else:
            try:
                v = float(value)
            except (TypeError, ValueError):
                v = float("nan")
            if isinstance(value, (bool, str)) or not math.isfinite(v):
                raise InvalidArgumentError(
                    f"locked joint {name!r}: the value must be a finite number, got {value!r}"
                )
            what = f"{v:g}"
        lim = outside(jid, v)
        if lim is not None:
            hint = f"; give the value to hold: locked={{{name!r}: v}}" if value is None else ""
            if value is not None:
                hint = degrees_hint(v)
            raise InvalidArgumentError(
                f"locked joint {name!r}: {what} is outside its limits {lim}" + hint
            )
        out[jid] = v
    for follower, (driver, a, b) in mimic.items():
        d = int(full.getJointId(driver))
        if d in out and full.existJointName(follower):
            fid = int(full.getJointId(follower))
            out[fid] = v = a * out[d] + b
            lim = outside(fid, v)
            if lim is not None:
                raise InvalidArgumentError(
                    f"locked joint {driver!r} at {out[d]:g} holds its mimic follower "
                    f"{follower!r} at {v:g} ({follower} = {a:g}·{driver} + {b:g}), outside "
                    f"its limits {lim}"
                )
    return out


def _reduce(
    p: Path,
    full: Any,
    frames: list[str],
    mimic: dict[str, tuple[str, float, float]],
    held: dict[int, float] | None = None,
    base_box: FloatArray | None = None,
    floating_base: bool = False,
) -> _Reduction:
    """Reduce ``full`` to the union of the root → frame paths of ``frames`` (a chain or a
    tree) and read the kinematic arrays off it.

    A mimic follower is kept and driven by its driver wherever that driver is solved: on a
    path (its driver must be on a path too: a follower on a path whose driver is on none is
    refused), and off the paths (a counterweight turning with a solved joint: the follower
    and the links it carries then move with the driver, in :attr:`RobotModel.model`, the
    collision bodies and the centre of mass); its range narrows the driver's.  A follower
    whose driver is off the paths is locked at ``multiplier·driver + offset`` of the driver's
    locked value, and one whose driver is held follows the held value.  The joints of
    ``held`` (id -> value) are locked at their values even on a path; every other joint off
    the paths at its neutral value.  A free-flyer root joint (``full`` built with one)
    becomes four tree joints: three prismatic ones along the world axes, bounded by
    ``± base_box`` [m], and a ``BALL`` (its rotation vector bounded by ``±π``).

    Raises:
        RobotModelError: no movable joint on a path, every one locked, too many degrees of
            freedom; a kept mimic follower whose driver is missing, is itself a mimic joint
            or is not solved; a kept follower or its driver continuous; a follower's range
            that no value of its driver's range meets; an unsupported joint type; a reduction
            Pinocchio refuses.
    """
    held = held or {}
    keep: set[int] = set()
    where = f"chain to {frames[0]!r}" if len(frames) == 1 else f"paths to {frames}"
    fids = [_frame_id(full, f) for f in frames]
    for f, fid in zip(frames, fids, strict=False):
        parent = full.frames[fid].parentJoint
        path_ids = [int(j) for j in full.supports[parent] if j != 0]
        if not path_ids:
            hint = (  # (one frame: the robot may be a free flyer; among others: a frame fixed
                # to the root, which no joint moves and no goal on it could change)
                "a free-flying robot? load it with floating_base=True, --floating-base on "
                "the command line"
                if len(frames) == 1
                else "no joint moves it: leave it out of the goal frames, or load a free-flying "
                "robot with floating_base=True"
            )
            raise RobotModelError(
                f"{p}: no movable joint between the root and frame {f!r} ({hint})"
            )
        keep.update(path_ids)
    keep -= set(held)
    jid = {full.names[j]: j for j in range(1, full.njoints)}
    grown = True
    while grown:  # off the paths, driven by a solved joint (to a fixed point: a follower of
        # a follower is met whatever the file's order, and refused below)
        grown = False
        for follower, (driver, _, _) in mimic.items():
            fj = jid.get(follower)
            if fj is not None and fj not in keep and fj not in held and jid.get(driver) in keep:
                keep.add(fj)
                grown = True
    for j in sorted(keep):
        name = full.names[j]
        if name in mimic:
            driver = mimic[name][0]
            if driver not in jid:
                raise RobotModelError(
                    f"{p}: joint {name!r} mimics joint {driver!r}, which is not in the model"
                )
            if driver == name:
                raise RobotModelError(f"{p}: joint {name!r} mimics itself")
            if driver in mimic:
                raise RobotModelError(
                    f"{p}: joint {name!r} mimics {driver!r}, itself a mimic joint (chains of "
                    "mimic joints are not supported)"
                )
            if jid[driver] not in keep:
                raise RobotModelError(
                    f"{p}: joint {name!r} on the {where} mimics joint {driver!r}, which is not "
                    f"on the {where}; a mimic joint is supported where its driver is solved too"
                )
    if not keep:
        raise RobotModelError(f"{p}: every joint on the {where} is locked: nothing to solve")
    nv = sum(int(full.joints[j].nv) for j in keep)
    if nv > MAX_SOLVED_DOF:
        raise RobotModelError(
            f"{p}: {nv} degrees of freedom on the {where}; at most {MAX_SOLVED_DOF} are solved "
            "(swarm_ik.robot.MAX_SOLVED_DOF: Pinocchio's Data holds tensors of nv³ numbers, "
            "1.7 GB at 300); lock joints (locked=) or choose fewer goal frames"
        )
    locked = [j for j in range(1, full.njoints) if j not in keep]
    q_ref = pin.neutral(full)
    for j in locked:  # off the paths: the neutral value, the nearest within the limits
        jm = full.joints[j]
        if jm.nq == 1 and j not in held:
            lo, hi = full.lowerPositionLimit[jm.idx_q], full.upperPositionLimit[jm.idx_q]
            if lo <= hi:
                q_ref[jm.idx_q] = min(max(q_ref[jm.idx_q], lo), hi)
    for follower, (driver, a, b) in mimic.items():  # an off-path follower follows its driver
        if follower in jid and driver in jid and jid[follower] in locked:
            jf, jd = full.joints[jid[follower]], full.joints[jid[driver]]
            if jid[follower] not in held:  # (a continuous joint, nq = 2, as (cos, sin))
                i, k = jd.idx_q, jf.idx_q
                x = math.atan2(q_ref[i + 1], q_ref[i]) if jd.nq == 2 else q_ref[i]
                v = a * x + b
                if jf.nq == 2:
                    q_ref[k : k + 2] = (math.cos(v), math.sin(v))
                else:
                    q_ref[k] = v
    for j, v in held.items():
        jm = full.joints[j]
        if jm.nq == 2:
            q_ref[jm.idx_q : jm.idx_q + 2] = (math.cos(v), math.sin(v))
        else:
            q_ref[jm.idx_q] = v
    try:
        reduced = pin.buildReducedModel(full, locked, q_ref) if locked else full.copy()
    except Exception as exc:
        raise RobotModelError(f"{p}: could not reduce the model ({exc})") from None
    names: list[str] = []
    kinds: list[int] = []
    axes, rot_p, pos_p, parent = [], [], [], []
    lower: list[float] = []
    upper: list[float] = []
    joint_kind: dict[str, int] = {}
    joint_range: dict[str, tuple[float, float]] = {}
    floating = (  # (a URDF's own floating joint stays refused below, as any 6-DoF joint)
        floating_base
        and reduced.njoints > 1
        and reduced.joints[1].shortname() == "JointModelFreeFlyer"
    )
    shift = 3 if floating else 0  # tree joints before the one of Pinocchio's joint 1
    for j in range(1, reduced.njoints):
        jm = reduced.joints[j]
        jname = reduced.names[j]
        if floating and j == 1:  # x, y, z along the world axes, then the rotation
            placement = reduced.jointPlacements[1]
            box = np.asarray(DEFAULT_BASE_BOX if base_box is None else base_box, dtype=float)
            box = np.broadcast_to(box, (3,))
            for k in range(4):
                kinds.append(PRISMATIC if k < 3 else BALL)
                axes.append(np.eye(3)[k] if k < 3 else np.array([0.0, 0.0, 1.0]))
                rot_p.append(np.array(placement.rotation) if k == 0 else np.eye(3))
                pos_p.append(np.array(placement.translation) if k == 0 else np.zeros(3))
                parent.append(k - 1)
            for k, entry in enumerate(FREE_FLYER_ENTRIES):
                names.append(entry)
                lower.append(-box[k] if k < 3 else -np.pi)
                upper.append(box[k] if k < 3 else np.pi)
            continue
        try:
            kind, axis = _joint_kind_axis(jm)
        except RobotModelError as exc:
            hint = ""  # (review 136: a URDF's own floating joint, with no way out named)
            if jm.nv == 6:
                hint = (
                    "; a floating base is swarm_ik's own: remove the URDF's floating joint and "
                    "load with floating_base=True (--floating-base)"
                )
            raise RobotModelError(
                f"{p}: joint {jname!r} on the {where}: {exc}; supported: revolute, "
                f"continuous, prismatic (and fixed){hint}"
            ) from None
        kinds.append(kind)
        axes.append(axis)
        placement = reduced.jointPlacements[j]
        rot_p.append(np.array(placement.rotation))
        pos_p.append(np.array(placement.translation))
        parent.append(_tree_joint(int(reduced.parents[j]), shift))
        if kind == CONTINUOUS:
            lo, hi = -np.pi, np.pi
        else:
            lo = float(reduced.lowerPositionLimit[jm.idx_q])
            hi = float(reduced.upperPositionLimit[jm.idx_q])
        if not (np.isfinite(lo) and np.isfinite(hi)) or lo > hi:
            raise RobotModelError(f"{p}: joint {jname!r} has invalid limits [{lo}, {hi}]")
        joint_kind[jname] = kind
        joint_range[jname] = (lo, hi)
    # joint vector: one entry per non-follower joint, in the reduced model's order
    q_of: dict[str, int] = {}
    for j in range(2 if floating else 1, reduced.njoints):
        jname = reduced.names[j]
        if jname not in mimic:
            q_of[jname] = len(names)
            names.append(jname)
            lower.append(joint_range[jname][0])
            upper.append(joint_range[jname][1])
    q_index: list[int] = [0, 1, 2, 3] if floating else []
    mult: list[float] = [1.0] * len(q_index)
    offs: list[float] = [0.0] * len(q_index)
    followers: dict[str, tuple[str, float, float]] = {}
    for j in range(2 if floating else 1, reduced.njoints):
        jname = reduced.names[j]
        if jname in mimic:
            driver, a, b = mimic[jname]
            if joint_kind[jname] == CONTINUOUS or joint_kind[driver] == CONTINUOUS:
                raise RobotModelError(
                    f"{p}: mimic joint {jname!r} or its driver {driver!r} is continuous; "
                    "supported: revolute and prismatic mimic joints"
                )
            d = q_of[driver]
            flo, fhi = joint_range[jname]
            lo_d, hi_d = sorted(((flo - b) / a, (fhi - b) / a))
            lower[d] = max(lower[d], lo_d)
            upper[d] = min(upper[d], hi_d) + 0.0  # (+0.0: a follower's 0 · -1 gave -0.0, and
            # numpy's uniform refuses a range of [0, -0.0])
            if lower[d] > upper[d]:
                raise RobotModelError(
                    f"{p}: mimic joint {jname!r} cannot stay within its limits for any value "
                    f"of its driver {driver!r} within the driver's limits"
                )
            q_index.append(d)
            mult.append(a)
            offs.append(b)
            followers[jname] = (driver, a, b)
        else:
            q_index.append(q_of[jname])
            mult.append(1.0)
            offs.append(0.0)
    rfids = [_frame_id(reduced, f) for f in frames]
    f_joint = [_tree_joint(int(reduced.frames[i].parentJoint), shift) for i in rfids]
    f_rot = [np.array(reduced.frames[i].placement.rotation) for i in rfids]
    f_pos = [np.array(reduced.frames[i].placement.translation) for i in rfids]
    tree = TreeArrays.canonical(
        kind=np.array(kinds, dtype=np.int64),
        parent=np.array(parent, dtype=np.int64),
        q_index=np.array(q_index, dtype=np.int64),
        multiplier=np.array(mult, dtype=float),
        offset=np.array(offs, dtype=float),
        axes=np.asarray(axes, dtype=float).reshape(-1, 3),
        rot_p=np.asarray(rot_p, dtype=float).reshape(-1, 3, 3),
        pos_p=np.asarray(pos_p, dtype=float).reshape(-1, 3),
        frame_joint=np.array(f_joint, dtype=np.int64),
        frame_rot=np.asarray(f_rot, dtype=float).reshape(-1, 3, 3),
        frame_pos=np.asarray(f_pos, dtype=float).reshape(-1, 3),
        nq=len(names),
    )
    return _Reduction(
        reduced,
        locked,
        np.asarray(q_ref, dtype=float),
        rfids,
        names,
        [
            BALL
            if n in FREE_FLYER_ENTRIES[3:]
            else PRISMATIC
            if n in FREE_FLYER_ENTRIES
            else kinds[reduced.getJointId(n) - 1 + shift]
            for n in names
        ],  # fmt: skip
        tree,
        np.array(lower),
        np.array(upper),
        followers,
    )


def _converted(
    plan: tuple[tuple[int, float, float, int, bool], ...], nq_pin: int, qv: list[float]
) -> list[float]:
    """Pinocchio's configuration (``nq_pin`` values) of the joint values ``qv`` by
    :meth:`RobotModel._to_pinocchio_plan`: mimic followers read their drivers, continuous
    joints become (cos, sin).  Scalar maths: a few joints, in every solve's check."""
    out = [0.0] * nq_pin
    for qi, mult, offset, at, continuous in plan:
        if qi < 0:  # a free flyer: position, then the quaternion (x, y, z, w) of exp([r]x)
            out[0:3] = qv[0:3]
            rx, ry, rz = qv[3], qv[4], qv[5]
            half = 0.5 * math.sqrt(rx * rx + ry * ry + rz * rz)
            k = 0.5 - half * half / 12.0 if half < 1e-4 else math.sin(half) / (2.0 * half)
            out[3:7] = [k * rx, k * ry, k * rz, math.cos(half)]
            continue
        v = mult * qv[qi] + offset
        if continuous:
            out[at] = math.cos(v)
            out[at + 1] = math.sin(v)
        else:
            out[at] = v
    return out


def _unit(v: FloatArray, what: str) -> FloatArray:
    """``v`` normalised (:func:`swarm_ik.pose.unit`).

    Raises:
        InvalidArgumentError: the norm is below 1e-9 (``what`` names the entries).
    """
    u = unit(v)
    if u is None:
        raise InvalidArgumentError(f"{what} has zero norm: {v.tolist()}")
    return u


def _real_values(q: Any) -> FloatArray:
    """``q`` as an array of real numbers (its shape checked by the caller), or
    :class:`InvalidArgumentError` naming what it holds (text, complex values, None)."""
    if isinstance(q, np.ndarray) and q.dtype.kind in "fiu":
        return q
    return floats_or(q, lambda: f"q must be real joint values, got {reprlib.repr(q)}")


@dataclass(frozen=True, eq=False)
class RobotModel:
    """A URDF reduced to the joints between the root and its goal frames, with limits, joint
    kinds and batched kinematics of every goal frame.

    Build it with :func:`load_robot` or :meth:`from_urdf`.  With one goal frame the model is
    the serial chain root → frame; with several it is the union of the root → frame paths (a
    tree: Baxter's two arms, a humanoid's hands), every other joint locked.  With a floating
    base the root is a free flyer whose six entries come first in ``q``
    (:data:`FREE_FLYER_ENTRIES`: position, then rotation vector).

    Attributes:
        name: Robot name (from the URDF).
        urdf_path: The URDF file.
        ee_frame: The first goal frame (the end effector of single-frame problems).
        frames: Every goal frame, in the order given, shape ``(nf,)``.
        model: Pinocchio model of the solved joints and the mimic followers they drive (other
            joints locked).
        full_model: Pinocchio model of the whole URDF.
        locked_joints: Names of the URDF joints locked.
        q_locked: Full-model configuration used for the locked joints.
        joint_names: Names of the solved joints, shape ``(nq,)``.
        joint_kinds: ``"revolute"``, ``"prismatic"``, ``"continuous"`` per entry of ``q``
            (``"ball"``: the three rotation-vector entries of a floating base).
        lower: Lower limits (rad or m), shape ``(nq,)``; ``-π`` for continuous joints.
        upper: Upper limits (rad or m), shape ``(nq,)``; ``+π`` for continuous joints.
            These arrays, like :attr:`tree`'s, are read once into what the robot's solves
            keep (bounds, reach, tables): narrow a solve's range with an
            :class:`~swarm_ik.IKProblem`'s ``lower``/``upper``, not by writing into them (answers
            after such an edit differ from those of a robot loaded with it).
        tree: The arrays behind the batched FK and Jacobian of every goal frame.
        frame_ids: Ids of the goal frames in ``model``, shape ``(nf,)``.
        mimic: Mimic joints of ``model`` driven by a solved joint (on a goal path or off
            the paths: a counterweight turning with a solved joint moves with it): follower
            name -> ``(driver, multiplier, offset)``; the follower's value is
            ``multiplier·q + offset``.
        ee_frame_reason: Why ``ee_frame`` was chosen ("given", "the robot's usual tool
            frame", or the rule used for a file).
        srdf: SRDF of the self-collision pairs to disable (``None``: found next to the URDF,
            as example-robot-data ships them; ``False``: none, pairs chosen by sampling).
        floating_base: Whether the root is a free flyer (``full_model`` is then built with
            ``pinocchio.JointModelFreeFlyer()``).
        held: Joints locked by request, name -> value (rad or m).
    """

    name: str
    urdf_path: Path
    ee_frame: str
    model: Any
    full_model: Any
    locked_joints: tuple[str, ...]
    q_locked: FloatArray
    joint_names: tuple[str, ...]
    joint_kinds: tuple[str, ...]
    lower: FloatArray
    upper: FloatArray
    tree: TreeArrays
    frames: tuple[str, ...] = ()
    frame_ids: tuple[int, ...] = ()
    mimic: dict[str, tuple[str, float, float]] = field(default_factory=dict)
    ee_frame_reason: str = "given"
    srdf: Any = None
    floating_base: bool = False
    held: dict[str, float] = field(default_factory=dict)
    _local: threading.local = field(default_factory=threading.local, repr=False)
    _cache: dict[Any, Any] = field(default_factory=dict, repr=False)

    # --------------------------------------------------------------- building
    @classmethod
    def from_urdf(
        cls,
        path: str | os.PathLike[str],
        ee_frame: str | Sequence[str] | None = None,
        *,
        frame_reason: str = "given",
        floating_base: bool = False,
        locked: Mapping[str, float] | Sequence[str] | None = None,
        base_box: Any = None,
    ) -> RobotModel:
        """Load a URDF and reduce it to the joints between the root and the goal frame(s).

        Args:
            path: URDF file.
            ee_frame: Goal frame (a link or fixed-joint name) or a list of them.  Default:
                the last link attached to the deepest joint of the model.
            frame_reason: How ``ee_frame`` was chosen (stored as ``ee_frame_reason``).
            floating_base, locked, base_box: See :func:`load_robot`.

        Raises:
            RobotFileNotFoundError: the file does not exist.
            RobotModelError: not a regular file, not a URDF, loops, bad limits, no movable
                joint on a path.
            UnknownNameError: a frame is not a frame of the model (the valid ones listed).
        """
        p = Path(path)
        if not p.is_file():
            if p.exists():  # (a folder, a device, a pipe: reading it would fail or hang)
                raise RobotModelError(f"URDF path {str(p)!r} is not a regular file")
            hint = ""
            if p.stem in BUNDLED or p.stem in EXAMPLE_ROBOTS:  # ("panda.urdf" for "panda")
                hint = f"; {p.stem!r} is a robot loadable by name (--robot {p.stem})"
            raise RobotFileNotFoundError(f"URDF file not found: {str(p)!r}{hint}")
        if not isinstance(floating_base, (bool, np.bool_)):
            raise InvalidArgumentError(
                f"floating_base must be true or false, got {floating_base!r}"
            )
        box = _base_box(base_box, bool(floating_base))
        # decoded, checked, joints renamed, stderr captured
        full, info = urdf.load_urdf(p, floating_base=bool(floating_base))
        body_frames = [f.name for f in full.frames if f.type == pin.FrameType.BODY]
        all_frames = [f.name for f in full.frames if f.name != "universe"]
        if ee_frame is None:
            ee_frame, frame_reason = urdf.default_ee_frame(full, info)
            urdf.log.info("%s: %s", p, frame_reason)
        if not isinstance(ee_frame, (str, list, tuple)):
            raise InvalidArgumentError(
                f"ee_frame must be a frame name or a list of them, got {ee_frame!r:.80}"
            )
        frames = [ee_frame] if isinstance(ee_frame, str) else list(ee_frame)
        if not frames:
            raise InvalidArgumentError("ee_frame: give a frame name or a non-empty list of them")
        for f in frames:
            if not isinstance(f, str):
                raise InvalidArgumentError(f"frame names must be strings, got {f!r}")
            if f not in all_frames:
                raise unknown("frame", f, body_frames)
        dup = sorted({f for f in frames if frames.count(f) > 1})
        if dup:
            raise InvalidArgumentError(f"frame(s) {dup} given more than once")
        mimic = {k: (m.driver, m.multiplier, m.offset) for k, m in info.mimic.items()}
        held = _locked_values(p, full, locked, mimic, info.renamed)
        red = _reduce(p, full, frames, mimic, held, box, bool(floating_base))
        return cls(
            name=full.name or p.stem,
            urdf_path=p.resolve(),
            ee_frame=frames[0],
            model=red.reduced,
            full_model=full,
            locked_joints=tuple(full.names[j] for j in red.locked),
            q_locked=red.q_ref,
            joint_names=tuple(red.names),
            joint_kinds=tuple(KIND_NAMES[k] for k in red.kinds),
            lower=red.lower,
            upper=red.upper,
            tree=red.tree,
            frames=tuple(frames),
            frame_ids=tuple(red.frame_ids),
            mimic=red.followers,
            ee_frame_reason=frame_reason,
            floating_base=bool(floating_base),
            held={full.names[j]: v for j, v in held.items()},
        )

    # ------------------------------------------------------------- properties
    @property
    def nq(self) -> int:
        """Number of solved joints (one value per joint; mimic followers excluded)."""
        return self.tree.nq

    @property
    def _shift(self) -> int:
        """Tree joints before the one of Pinocchio's joint 1: a free flyer's x, y, z (3), else
        0 (the kernels' index of Pinocchio joint ``j >= 1`` is ``j - 1 + _shift``)."""
        return 3 if self.floating_base else 0

    @property
    def continuous_mask(self) -> NDArray[np.bool_]:
        """True for continuous joints, shape ``(nq,)``."""
        return np.array([k == "continuous" for k in self.joint_kinds], dtype=bool)

    @property
    def prismatic_mask(self) -> NDArray[np.bool_]:
        """True for prismatic joints, shape ``(nq,)``."""
        return np.array([k == "prismatic" for k in self.joint_kinds], dtype=bool)

    @property
    def ee_frame_id(self) -> int:
        """Id of :attr:`ee_frame` in :attr:`model`."""
        return self.frame_ids[0]

    def frame_index(self, frame: str | None) -> int:
        """Index of goal frame ``frame`` in :attr:`frames` (``None``: the first).

        Raises:
            UnknownNameError: not a goal frame of this robot (the goal frames listed).
        """
        if frame is None:
            return 0
        try:
            return self.frames.index(frame)
        except ValueError:
            raise unknown("goal frame", frame, self.frames) from None

    def canonical_frames(
        self, joint_ids: Any, rots: Any, poss: Any
    ) -> tuple[NDArray[np.int64], FloatArray, FloatArray]:
        """Frames given in the joint frames of :attr:`model` as the kernels' tree frames.

        Args:
            joint_ids: Joint of :attr:`model` each frame is attached to (0: the world), ``(k,)``.
            rots: Frame rotations in those joint frames, ``(k, 3, 3)``.
            poss: Frame translations [m], ``(k, 3)``.

        Returns:
            ``(frame_joint (k,), frame_rot (k, 3, 3), frame_pos (k, 3))`` for
            :meth:`swarm_ik.kernels.fk.TreeArrays.with_frames` (joint index ``id − 1``, plus
            three after a free flyer; the placement turned into the canonical joint frame
            whose axis is z).
        """
        from swarm_ik.kernels.fk import rotation_z_to

        ids = np.asarray(joint_ids, dtype=np.int64).reshape(-1)
        out_r = np.empty((ids.size, 3, 3))
        out_p = np.empty((ids.size, 3))
        shift = self._shift
        bases = self._cache.get("bases")
        if bases is None:  # each joint's rotation taking z onto its axis, made once
            bases = np.repeat(np.eye(3)[None], self.model.njoints, axis=0)
            for jid in range(1 + (shift > 0), self.model.njoints):  # (world, free flyer: I)
                bases[jid] = rotation_z_to(_joint_kind_axis(self.model.joints[jid])[1])
            self._cache["bases"] = bases
        for k, j in enumerate(ids):
            b = bases[int(j)]
            out_r[k] = b.T @ np.asarray(rots[k], dtype=float)
            out_p[k] = b.T @ np.asarray(poss[k], dtype=float)
        tree_ids = np.array([_tree_joint(int(j), shift) for j in ids], dtype=np.int64)
        return tree_ids, out_r, out_p

    def mass_frames(self) -> tuple[NDArray[np.int64], FloatArray, FloatArray, FloatArray]:
        """The bodies of :attr:`model` with mass, as frames at their centres of mass:
        ``(joint ids (nb,), rotations (nb, 3, 3), centres in the joint frames (nb, 3) [m],
        mass fractions m_b / M (nb,))``, from the URDF's inertials.  Locked and off-path links
        are merged into the body of the joint that carries them (Pinocchio's reduced model),
        and the links a held joint next to the world carries (merged into the world's body)
        are one fixed point at joint 0 (:meth:`held_world_mass`), so ``Σ μ_b p_b`` is the
        whole URDF's centre of mass as ``pinocchio.centerOfMass`` gives it: of the links
        that joints of the URDF move (on a fixed base the links fixed to the world are left
        out, as Pinocchio does; a floating base carries every link).

        Raises:
            RobotModelError: the URDF gives no link masses.
        """
        cached = self._cache.get("mass_frames")
        if cached is None:
            model = self.model
            ids = [j for j in range(1, model.njoints) if model.inertias[j].mass > 0.0]
            mass = [float(model.inertias[j].mass) for j in ids]
            lever = [np.asarray(model.inertias[j].lever, dtype=float) for j in ids]
            m_w, c_w = self.held_world_mass()
            if m_w > 0.0:
                ids, mass, lever = [0, *ids], [m_w, *mass], [c_w, *lever]
            if not ids:
                raise RobotModelError(f"{self.urdf_path}: the URDF gives no link masses")
            m = np.array(mass)
            rots = np.repeat(np.eye(3)[None], len(ids), axis=0)
            cached = (np.array(ids, dtype=np.int64), rots, np.array(lever).reshape(-1, 3),
                      m / m.sum())  # fmt: skip
            self._cache["mass_frames"] = cached
        return cached  # type: ignore[no-any-return]

    def held_world_mass(self) -> tuple[float, FloatArray]:
        """The mass [kg] and world centre [m] of the links that joints of the URDF move but
        that this model holds fixed to the world (a locked joint next to the root, on a fixed
        base, or an off-path one: Pinocchio's reduced model merges them into its world body,
        which ``pinocchio.centerOfMass`` leaves out), ``(0, zeros)`` when none."""
        cached = self._cache.get("held_world_mass")
        if cached is None:
            red, full = self.model.inertias[0], self.full_model.inertias[0]
            m_w = float(red.mass) - float(full.mass)
            moment = float(red.mass) * np.asarray(red.lever, dtype=float) - float(
                full.mass
            ) * np.asarray(full.lever, dtype=float)
            total = sum(float(i.mass) for i in self.full_model.inertias)
            if m_w <= 1e-12 * max(total, 1e-300):  # (nothing merged but rounding)
                cached = (0.0, np.zeros(3))
            else:
                cached = (m_w, moment / m_w)
            self._cache["held_world_mass"] = cached
        return cached  # type: ignore[no-any-return]

    def collision_model(self) -> Any:
        """The robot's collision geometry and self-collision pairs
        (:class:`swarm_ik.collision.RobotCollision`; built once, with :attr:`srdf`)."""
        rc = self._cache.get("collision")
        if rc is None:
            from swarm_ik.collision import RobotCollision

            rc = self._cache["collision"] = RobotCollision.from_robot(self, srdf=self.srdf)
        return rc

    def reach_radius(self, frame: str | None = None, *, base: bool = True) -> float:
        """An upper bound [m] on the distance from the world origin that ``frame`` can reach:
        the sum of the joint offsets along its path, the prismatic strokes and the frame
        offset; ``base=False`` leaves out a floating base's box (the reach from the base: a
        length scale of the robot itself).  Computed once per frame (the model's arrays,
        as its other cached values, are not changed after loading)."""
        f = self.frame_index(frame)
        known = self._cache.setdefault("reach_radius", {})
        got = known.get((f, base))
        if got is None:
            got = known[(f, base)] = self._reach_radius(f, base)
        return float(got)

    def _reach_radius(self, f: int, base: bool) -> float:
        """:meth:`reach_radius` of goal frame index ``f``, computed."""
        t = self.tree
        total = float(np.linalg.norm(t.frame_pos[f]))
        j = int(t.frame_joint[f])
        stop = 3 if (self.floating_base and not base) else -1  # (tree joints 0-3: the base)
        while j > stop:
            total += float(np.linalg.norm(t.pos_p[j]))
            if t.kind[j] == PRISMATIC:
                qi = int(t.q_index[j])
                m = abs(float(t.multiplier[j]))
                total += m * max(abs(self.lower[qi]), abs(self.upper[qi])) + abs(t.offset[j])
            j = int(t.parent[j])
        return total

    # ------------------------------------------------------------- kinematics
    def fk(self, q: FloatArray, frame: str | None = None) -> FloatArray:
        """Pose(s) [m] of one goal frame (default the first):
        ``(nq,) -> (4, 4)`` (Pinocchio's FK, :meth:`fk_pinocchio`: nothing to compile for
        one pose) or ``(pop, nq) -> (pop, 4, 4)`` (the compiled batch FK)."""
        f = self.frame_index(frame)
        arr = _real_values(q)
        if arr.shape == (self.nq,):
            # (a Data of its own: the State a Python goal reads stays valid if it calls fk)
            return self._frame_pose(arr, self.frame_ids[f], self._data("fk_data"))
        out = self.tree.fk(arr)
        return out[..., f, :, :]

    def fk_all(self, q: FloatArray) -> FloatArray:
        """Poses of every goal frame: ``(nq,) -> (nf, 4, 4)``, ``(pop, nq) -> (pop, nf, 4, 4)``."""
        return self.tree.fk(_real_values(q))

    def fk_jacobian(self, q: FloatArray, frame: str | None = None) -> tuple[FloatArray, FloatArray]:
        """Pose(s) and LOCAL_WORLD_ALIGNED frame Jacobian(s) ``(…, 6, nq)``, rows ``[v; ω]``,
        of one goal frame (default the first)."""
        f = self.frame_index(frame)
        t, j = self.tree.fk_jacobian(_real_values(q))
        return t[..., f, :, :], j[..., f, :, :]

    def _pinocchio_q_is_q(self) -> bool:
        """Whether Pinocchio's configuration of :attr:`model` is ``q`` itself (no continuous
        joint in (cos, sin), no mimic follower; decided once)."""
        same = self._cache.get("q_is_pinocchio_q")
        if same is None:
            same = self._cache["q_is_pinocchio_q"] = (
                self.model.nq == self.nq and not self.mimic and not self.floating_base
            )
        return bool(same)

    def to_pinocchio(self, q: FloatArray, copy: bool = True) -> FloatArray:
        """Pinocchio configuration of :attr:`model` for ``q`` (continuous → cos, sin; mimic
        followers set from their drivers); ``copy=False``: ``q`` itself where the two vectors
        are the same (for a caller that only reads it, such as Pinocchio's FK)."""
        try:
            q = np.asarray(q, dtype=float).reshape(self.nq)
        except (TypeError, ValueError):
            q = self.check_q(q)  # (refused there, the problem named)
        if self._pinocchio_q_is_q():
            return q.copy() if copy else q
        return np.array(_converted(self._to_pinocchio_plan(), self.model.nq, q.tolist()))

    def _to_pinocchio_plan(self) -> tuple[tuple[int, float, float, int, bool], ...]:
        """Per Pinocchio joint: (driver's index in ``q``, multiplier, offset, index in
        Pinocchio's configuration, continuous), made once."""
        plan = self._cache.get("to_pinocchio")
        if plan is None:
            t, shift, model = self.tree, self._shift, self.model
            head = ((-1, 1.0, 0.0, 0, False),) if shift else ()  # the free flyer
            plan = self._cache["to_pinocchio"] = head + tuple(
                (int(t.q_index[j - 1 + shift]), float(t.multiplier[j - 1 + shift]),
                 float(t.offset[j - 1 + shift]), int(model.joints[j].idx_q),
                 model.joints[j].nq == 2)
                for j in range(2 if shift else 1, model.njoints)
            )  # fmt: skip
        return plan  # type: ignore[no-any-return]

    def from_pinocchio(self, q_pin: FloatArray) -> FloatArray:
        """Inverse of :meth:`to_pinocchio`: one value per solved joint."""
        q_pin = np.asarray(q_pin, dtype=float)
        out = np.empty(self.nq)
        shift = self._shift
        if shift:
            out[0:3] = q_pin[0:3]
            out[3:6] = lie.log3(pin.Quaternion(np.asarray(q_pin[3:7])).toRotationMatrix())
        for j in range(2 if shift else 1, self.model.njoints):
            if self.model.names[j] in self.mimic:
                continue
            jm = self.model.joints[j]
            qi = int(self.tree.q_index[j - 1 + shift])
            if jm.nq == 2:
                out[qi] = np.arctan2(q_pin[jm.idx_q + 1], q_pin[jm.idx_q])
            else:
                out[qi] = q_pin[jm.idx_q]
        return out

    def __getstate__(self) -> dict[str, Any]:
        state = dict(self.__dict__)
        state.pop("_local", None)  # per-thread Pinocchio Data: rebuilt on demand
        # (caches are rebuilt on demand, but the record of the warnings already given travels:
        # a Dask worker said the always-in-contact warning again)
        state["_cache"] = {k: v for k, v in self._cache.items() if k in _CACHE_KEPT_IN_PICKLES}
        return state

    def __setstate__(self, state: dict[str, Any]) -> None:
        self.__dict__.update(state)
        object.__setattr__(self, "_local", threading.local())

    def _data(self, slot: str = "data") -> Any:
        """Pinocchio ``Data`` of :attr:`model`, one per thread and ``slot`` (reused between
        calls)."""
        data = getattr(self._local, slot, None)
        if data is None:
            data = self.model.createData()
            setattr(self._local, slot, data)
        return data

    def _frame_pose(self, q: FloatArray, fid: int, data: Any) -> FloatArray:
        """Pose ``(4, 4)`` of Pinocchio frame ``fid`` at ``q`` by Pinocchio's FK on ``data``."""
        pin.forwardKinematics(self.model, data, self.to_pinocchio(q, copy=False))
        # (eigenpy returns the 4x4 as a new array of its own: no copy needed)
        return pin.updateFramePlacement(self.model, data, fid).homogeneous  # type: ignore[no-any-return]

    def fk_pinocchio(self, q: FloatArray, frame: str | None = None) -> FloatArray:
        """Reference FK of one goal frame through ``pinocchio.forwardKinematics`` +
        ``updateFramePlacement``; used to verify results.

        Args:
            q: Joint values, shape ``(nq,)``.
            frame: Goal frame (default the first).

        Returns:
            Pose, shape ``(4, 4)``.
        """
        return self._frame_pose(q, self.frame_ids[self.frame_index(frame)], self._data())

    def fk_pinocchio_bound(self, configuration: bool = False) -> Callable[[FloatArray], FloatArray]:
        """:meth:`fk_pinocchio` of the first goal frame as a function of ``q`` with its
        lookups made once (the check of :class:`swarm_ik.IKSolver`'s answers; 7 µs instead of
        12 with cold caches).  Where Pinocchio's configuration is not ``q`` itself
        (continuous joints in (cos, sin), mimic followers), the conversion's plan is bound
        too (:meth:`to_pinocchio`'s scalar loop, without its checks and lookups), unless
        ``configuration``: then the function takes Pinocchio's configuration
        (:meth:`to_pinocchio` of ``q``, ``(model.nq,)``) itself."""
        forward, place = pin.forwardKinematics, pin.updateFramePlacement
        model, fid, data_of, local = self.model, self.frame_ids[0], self._data, self._local
        if configuration or self._pinocchio_q_is_q():

            def pose(q: FloatArray) -> FloatArray:
                try:
                    data = local.data  # (one per thread; made by _data on a thread's first call)
                except AttributeError:
                    data = data_of()
                forward(model, data, q)
                return place(model, data, fid).homogeneous  # type: ignore[no-any-return]

            return pose
        plan, nq_pin, array = self._to_pinocchio_plan(), model.nq, np.array

        def pose_converted(q: FloatArray) -> FloatArray:
            try:
                data = local.data
            except AttributeError:
                data = data_of()
            forward(model, data, array(_converted(plan, nq_pin, q.tolist())))
            return place(model, data, fid).homogeneous  # type: ignore[no-any-return]

        return pose_converted

    def fk_pinocchio_many(self, qs: FloatArray, frame: str | None = None) -> FloatArray:
        """Reference poses of one goal frame (default the first) for each row of ``qs``
        ``(k, nq)``, as :meth:`fk_pinocchio` computes them: shape ``(k, 4, 4)``."""
        return np.array([self.fk_pinocchio(q, frame) for q in qs]).reshape(len(qs), 4, 4)

    def fk_pinocchio_all(self, q: FloatArray) -> FloatArray:
        """Reference poses of every goal frame with Pinocchio, shape ``(nf, 4, 4)``."""
        data = self._data()
        pin.forwardKinematics(self.model, data, self.to_pinocchio(q))
        return np.array(
            [pin.updateFramePlacement(self.model, data, fid).homogeneous for fid in self.frame_ids]
        ).reshape(len(self.frame_ids), 4, 4)

    def jacobian_pinocchio(self, q: FloatArray, frame: str | None = None) -> FloatArray:
        """Reference LOCAL_WORLD_ALIGNED frame Jacobian ``(6, nq)`` from Pinocchio (mimic
        columns summed into their drivers' columns)."""
        fid = self.frame_ids[self.frame_index(frame)]
        data = self._data()
        pin.computeJointJacobians(self.model, data, self.to_pinocchio(q))
        pin.updateFramePlacements(self.model, data)
        jac = pin.getFrameJacobian(self.model, data, fid, pin.ReferenceFrame.LOCAL_WORLD_ALIGNED)
        return self.velocity_to_q(np.array(jac).reshape(6, self.model.nv), q)

    def velocity_to_q(self, jac: FloatArray, q: FloatArray | None = None) -> FloatArray:
        """A Jacobian ``(m, model.nv)`` over Pinocchio's velocity as one over ``q``
        ``(m, nq)``: a mimic follower's column summed into its driver's (times its
        multiplier); a free flyer's local velocity ``(v, ω)`` as the derivative over its
        world position ``p`` (``v = Rᵀ ṗ``) and rotation vector ``r`` (``ω = Jr(r) ṙ``), which
        needs ``q``."""
        jac = np.asarray(jac, dtype=float)
        if self.model.nv == self.nq and not self.mimic and not self.floating_base:
            return jac
        out = np.zeros((jac.shape[0], self.nq))
        shift = self._shift
        if shift:
            if q is None:
                raise InvalidArgumentError("velocity_to_q needs q for a floating base")
            r = np.asarray(q, dtype=float)[3:6]
            out[:, 0:3] = jac[:, 0:3] @ lie.exp3(r).T
            out[:, 3:6] = jac[:, 3:6] @ lie.jr(r)
        for j in range(2 if shift else 1, self.model.njoints):
            iv = self.model.joints[j].idx_v
            t = j - 1 + shift
            out[:, self.tree.q_index[t]] += self.tree.multiplier[t] * jac[:, iv]
        return out

    def full_configuration(self, q: Any) -> FloatArray:
        """Configuration of :attr:`full_model` (the whole URDF, with its free flyer
        ``[x y z qx qy qz qw, joints…]`` when floating) for the solved joints at ``q``, the
        locked and off-path joints at their held values: anyone can check an answer with
        Pinocchio alone.

        Every mimic follower reads ``multiplier·driver + offset`` of its driver's value: a
        solved driver's value in ``q`` (followers on a goal path and off the paths alike,
        :attr:`mimic`), a locked driver's held value otherwise.

        Args:
            q: Joint vector (rad / m), shape ``(nq,)``.

        Returns:
            Pinocchio configuration of the full model, shape ``(full_model.nq,)``.
        """
        q_red = self.to_pinocchio(self.check_q(q))
        out = np.array(self.q_locked, dtype=float, copy=True)
        full = self.full_model
        for j in range(1, self.model.njoints):
            jr = self.model.joints[j]
            jf = full.joints[full.getJointId(self.model.names[j])]
            out[jf.idx_q : jf.idx_q + jf.nq] = q_red[jr.idx_q : jr.idx_q + jr.nq]
        return out

    def from_full_configuration(self, q_full: Any) -> FloatArray:
        """The joint vector of a configuration of :attr:`full_model`: the inverse of
        :meth:`full_configuration` on the solved joints (the other joints' values are checked
        to be finite, not read).

        A floating base's quaternion is normalised first (any norm of at least 1e-9), as
        :func:`swarm_ik.pose.quat_to_matrix` does for targets (Pinocchio itself would read a
        non-unit quaternion as a scaled, non-rigid rotation); a continuous joint's
        ``(cos θ, sin θ)`` pair gives its angle ``atan2(sin θ, cos θ)``, whatever its norm.

        Args:
            q_full: Pinocchio configuration of the whole URDF, shape ``(full_model.nq,)``
                (rad / m; a floating base's ``[x y z qx qy qz qw]`` first, in metres and a
                quaternion ``(x, y, z, w)``; a continuous joint as ``(cos θ, sin θ)``).

        Returns:
            Joint vector (rad / m), shape ``(nq,)``; a floating base's rotation as a rotation
            vector [rad] of norm at most π.

        Raises:
            InvalidArgumentError: ``q_full`` is not real numbers (text, ragged nesting,
                complex values), not of shape ``(full_model.nq,)``, holds a NaN or infinite
                value, or a solved joint's quaternion or ``(cos, sin)`` pair has a norm below
                1e-9 (no rotation to read).
        """
        full = self.full_model
        n_full = int(full.nq)
        what = "q_full (a configuration of full_model)"
        arr = floats_or(
            q_full, lambda: f"{what} must be {n_full} numbers, got {reprlib.repr(q_full)}"
        )
        if arr.shape != (n_full,):
            hint = (
                f" (that is the length of a joint vector q: full_configuration(q) gives the "
                f"{n_full} values)"
                if arr.shape == (self.nq,)
                else ""
            )
            raise InvalidArgumentError(
                f"{what} must hold {n_full} values (full_model.nq); got shape {arr.shape}{hint}"
            )
        if not np.isfinite(arr).all():
            raise InvalidArgumentError(f"{what} contains NaN or infinite values: {arr.tolist()}")
        q_red = np.empty(self.model.nq)
        solved = np.zeros(n_full, dtype=bool)
        for j in range(1, self.model.njoints):
            jr = self.model.joints[j]
            jf = full.joints[full.getJointId(self.model.names[j])]
            at, name = jf.idx_q, self.model.names[j]
            solved[at : at + jf.nq] = True
            seg = arr[at : at + jf.nq]
            if jr.nq == 7:  # the free flyer: [x y z qx qy qz qw], the quaternion normalised
                where = f"the quaternion of {name} (entries {at + 3} to {at + 6})"
                seg = np.concatenate((seg[:3], _unit(seg[3:], f"{what}: {where}")))
            elif jr.nq == 2:  # a continuous joint: (cos, sin), read by atan2
                _unit(seg, f"{what}: the (cos, sin) pair of {name} (entries {at}, {at + 1})")
            q_red[jr.idx_q : jr.idx_q + jr.nq] = seg
        q = self.from_pinocchio(q_red)
        # the held joints (locked, off the goal paths, mimic followers) are not read: say so
        # where q_full holds other values for them (the way back would silently change them)
        held = self.full_configuration(q)
        moved = np.flatnonzero(~solved & (np.abs(arr - held) > 1e-9))
        if moved.size:
            names = [n for n in full.names[1:] if _entries(full, n) & set(moved.tolist())]
            warnings.warn(
                f"q_full holds other values than this model holds for {len(names)} joint(s) "
                f"it does not solve ({', '.join(names[:3])}{', …' if len(names) > 3 else ''}):"
                " they are not read (load_robot's locked= sets a held value)",
                RobotModelWarning,
                stacklevel=user_stacklevel(),
            )
        return q

    # ----------------------------------------------------------------- limits
    def within_limits(self, q: FloatArray, tol: float = 1e-9) -> bool:
        """Whether ``q`` (shape ``(nq,)``, or ``(..., nq)``: every row) lies within the limits
        (± ``tol``; NaN: outside)."""
        q = floats_or(q, lambda: f"q must be {self.nq} numbers, got {reprlib.repr(q)}")
        if q.ndim == 0 or q.shape[-1] != self.nq:
            raise InvalidArgumentError(f"q must end in {self.nq} values, got shape {q.shape}")
        return bool(np.all(q >= self.lower - tol) and np.all(q <= self.upper + tol))

    def wrap(self, q: FloatArray) -> FloatArray:
        """Continuous joints wrapped into ``[-π, π)``; other values unchanged (same shape:
        ``(..., nq)``)."""
        q = floats_or(q, lambda: f"q must be numbers, got {reprlib.repr(q)}")
        if q.ndim == 0 or q.shape[-1] != self.nq:
            raise InvalidArgumentError(f"q must end in {self.nq} values, got shape {q.shape}")
        m = self.wrapped_mask()
        if m is not None:
            q[..., m] = (q[..., m] + np.pi) % (2 * np.pi) - np.pi
        return q

    def wrapped_mask(self) -> NDArray[np.bool_] | None:
        """:attr:`continuous_mask`, or None when the robot has no continuous joint (nothing
        for :meth:`wrap` to do); made once."""
        if "wrapped" not in self._cache:
            m = self.continuous_mask
            self._cache["wrapped"] = m if m.any() else None
        return self._cache["wrapped"]  # type: ignore[no-any-return]

    def random_q(self, rng: np.random.Generator, n: int | None = None) -> FloatArray:
        """Joint vector(s) drawn uniformly within the limits: ``(nq,)`` or ``(n, nq)``; a
        floating base's orientation uniform over the rotations (a uniform unit quaternion,
        as a rotation vector of norm ≤ π)."""
        if not isinstance(rng, (np.random.Generator, np.random.RandomState)):
            raise InvalidArgumentError(
                f"rng must be a numpy.random.Generator (np.random.default_rng(seed)), got "
                f"{reprlib.repr(rng)}"
            )
        if n is not None:
            n = count(n, "n (or None)", 0)
        size = self.nq if n is None else (n, self.nq)
        out = rng.uniform(self.lower, self.upper, size=size)
        if self.floating_base:
            quat = rng.standard_normal(size=(1 if n is None else n, 4))
            quat /= np.linalg.norm(quat, axis=1, keepdims=True)
            quat[quat[:, 3] < 0] *= -1.0  # w >= 0: angle <= π
            vec = np.linalg.norm(quat[:, :3], axis=1)
            angle = 2.0 * np.arctan2(vec, quat[:, 3])
            scale = np.where(vec > 1e-12, angle / np.where(vec > 1e-12, vec, 1.0), 2.0)
            rot = quat[:, :3] * scale[:, None]
            out[..., 3:6] = rot[0] if n is None else rot
        return out

    def mid_q(self) -> FloatArray:
        """The middle of the joint ranges, shape ``(nq,)`` (TRAC-IK's benchmark seed; a
        floating base at the centre of its box, not turned)."""
        return 0.5 * (self.lower + self.upper)

    def is_q(self, q: Any) -> bool:
        """Whether ``q`` is already a finite float64 vector ``(nq,)`` (nothing to convert)."""
        return (
            type(q) is np.ndarray
            and q.dtype is FLOAT64
            and q.shape == (self.nq,)
            and math.isfinite(sum(q.tolist()))  # (a sum that overflows: the full check decides)
        )

    def target_q(self, q: Any, what: str = "q") -> FloatArray:
        """A joint vector whose forward kinematics makes a target (:meth:`check_q`), with a
        warning when it lies outside the joint limits: its pose may still be reachable, but
        values beyond the limits are often degrees given where radians are due."""
        q = self.check_q(q, what)
        beyond = (q < self.lower - 1e-9) | (q > self.upper + 1e-9)
        outside = np.flatnonzero(beyond & ~self.continuous_mask)  # (any angle: continuous)
        if outside.size:
            names = [self.joint_names[i] for i in outside]
            warnings.warn(
                f"{what} lies outside the joint limits at {names} ({DEGREES_HINT}); the "
                "target is its forward kinematics all the same",
                stacklevel=user_stacklevel(),
            )
        return q

    def check_q(self, q: Any, what: str = "q") -> FloatArray:
        """Validate a joint vector: shape ``(nq,)`` and finite; returns it as floats (a
        copy)."""
        if self.is_q(q):
            return q.copy()  # type: ignore[no-any-return]
        arr = floats_or(
            q, lambda: f"{what} must be {self.nq} numbers (one per joint), got {reprlib.repr(q)}"
        )
        if arr.shape != (self.nq,):
            raise InvalidArgumentError(
                f"{what} must hold {self.nq} values (one per joint: "
                f"{', '.join(self.joint_names)}); got shape {arr.shape}"
            )
        if not np.isfinite(arr).all():
            raise InvalidArgumentError(f"{what} contains NaN or infinite values: {arr.tolist()}")
        return arr

    def __repr__(self) -> str:
        return (
            f"RobotModel(name={self.name!r}, nq={self.nq}, ee_frame={self.ee_frame!r}, "
            f"kinds={list(self.joint_kinds)})"
        )


_CACHE_KEPT_IN_PICKLES = ("always_in_contact",)
"""The entries of a robot's cache that travel with it when pickled (what it has said)."""


def _frame_id(model: Any, name: str) -> int:
    """Id of frame ``name``, preferring a BODY frame when a joint has the same name."""
    ids = [i for i, f in enumerate(model.frames) if f.name == name]
    for i in ids:
        if model.frames[i].type == pin.FrameType.BODY:
            return i
    return ids[0]


def resolve_robot_path(
    name_or_path: str | os.PathLike[str],
) -> tuple[Path, str | tuple[str, ...] | None]:
    """URDF path and default end-effector frame for a bundled name, an example-robot-data
    name, or a path."""
    s = str(name_or_path)
    if s in BUNDLED:
        fname, frame = BUNDLED[s]
        return bundled_robot_dir() / fname, frame
    if s in EXAMPLE_ROBOTS:
        rel, frames = EXAMPLE_ROBOTS[s]
        return example_robot_data_dir() / rel, frames
    p = Path(s)
    if p.suffix.lower() in (".urdf", ".xml") or p.exists() or os.sep in s:
        return p, None
    files = example_robot_files()
    if s in files:
        return example_robot_data_dir() / files[s], None
    raise unknown("robot", s, [*BUNDLED, *EXAMPLE_ROBOTS, *files])


@keywords_checked
def load_robot(
    name_or_path: str | os.PathLike[str],
    ee_frame: str | Sequence[str] | None = None,
    *,
    srdf: str | os.PathLike[str] | bool | None = None,
    floating_base: bool = False,
    locked: Mapping[str, float] | Sequence[str] | None = None,
    base_box: Any = None,
) -> RobotModel:
    """Load a robot by bundled name, ``example-robot-data`` name, or URDF path.

    Args:
        name_or_path: ``"yumi_left"``, ``"loading_manipulator"``, ``"loading_manipulator_long"``,
            an example-robot-data robot (``"panda"``, ``"ur5"``, ``"baxter"``, …; see
            :func:`robot_names`), or a path to a ``.urdf`` file.
        ee_frame: Goal frame, or a list of goal frames (the model is then the union of the
            root → frame paths, a tree); default: the robot's usual tool frame(s) for named
            robots, the tip of the deepest chain for a file.  A link and a joint of the same
            name (``so100``'s ``gripper``) name the link; the joint's frame is its child
            link's.
        srdf: SRDF whose ``disable_collisions`` pairs the collision goal skips (default: the
            one next to the URDF, if any; ``False``: none).
        floating_base: Give the root link a free flyer (a humanoid, a mobile base): six more
            entries at the head of ``q`` (:data:`FREE_FLYER_ENTRIES`), the position bounded
            by ``base_box`` around the origin, the orientation free (a rotation vector, no
            gimbal lock).
        locked: Joints held out of the problem even on a goal path: a dict name -> value
            (rad or m, within the joint's limits; None: its neutral value) or a list of
            names (held at their neutral value).  The answer keeps them exactly there; mimic
            followers of a locked joint follow it.
        base_box: Half-widths [m] of the floating base's box around the origin (one number or
            three; default :data:`DEFAULT_BASE_BOX`, 2: a standing humanoid's pelvis, a base
            driving a few metres); only with ``floating_base=True``.

    Raises:
        UnknownNameError: a locked joint is not a one-DoF joint of the URDF (they are
            listed).
        InvalidArgumentError: a locked value outside its limits or not finite, a bad
            ``base_box`` or one without a floating base.

    Returns:
        The robot, reduced to the joints between the root and its goal frame(s).

    >>> load_robot("baxter", ["left_gripper", "right_gripper"]).nq
    14
    """
    path, default_frame = resolve_robot_path(name_or_path)
    frames: str | Sequence[str] | None
    if ee_frame is not None:
        frames, reason = ee_frame, "given"
    else:
        frames, reason = default_frame, "the robot's usual tool frame"
    with warnings.catch_warnings(record=True) as said:
        warnings.simplefilter("always")  # (the libraries' warnings silenced, not swarm_ik's own)
        robot = RobotModel.from_urdf(
            path, frames, frame_reason=reason, floating_base=floating_base, locked=locked,
            base_box=base_box,
        )  # fmt: skip
    for w in said:
        if issubclass(w.category, RobotModelWarning):
            warnings.warn(w.message, stacklevel=user_stacklevel())
    if srdf is not None:
        if not isinstance(srdf, (str, os.PathLike, bool)):
            raise InvalidArgumentError(
                f"srdf must be a file path, False or None, got {reprlib.repr(srdf)}"
            )
        if srdf is not False and (srdf is True or not Path(srdf).is_file()):
            raise RobotFileNotFoundError(f"SRDF file not found: {str(srdf)!r}")
        object.__setattr__(robot, "srdf", srdf)
    return robot
