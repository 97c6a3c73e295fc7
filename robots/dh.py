"""Denavit–Hartenberg tables and joint chains turned into URDF text.

Two entry points build a serial-chain URDF:

* :func:`chain_to_urdf` takes a list of :class:`ChainStep` -- "fixed transform, then one
  joint (axis, type, limits)" -- and is general enough for chains that are not standard DH
  (the loading manipulator of the MGWO paper, ``robots/generate.py``).
* :func:`dh_to_urdf` takes a standard DH table (:class:`DHRow`) and is implemented on top of
  :func:`chain_to_urdf`.

Standard DH convention (eq. 1 of the HLFOA paper), metres and radians::

    T_i = Rz(theta_i) . Tz(d_i) . Tx(a_i) . Rx(alpha_i)

* revolute / continuous row: ``theta_i = q_i + theta_offset_i``, ``d_i`` constant;
* prismatic row: ``d_i = d + q_i``, ``theta_i = theta_offset_i`` constant.

``q_i`` is the URDF joint value: **the joint value is the DH variable, the offset lives inside
the URDF** (folded into the joint origin as ``Rz(theta_offset)``), and the joint limits of a
row apply to ``q_i``.  :func:`dh_fk` evaluates the DH product directly and is what the URDF
reproduces (Pinocchio FK of the URDF equals ``dh_fk`` to ~1e-15).

How a DH row becomes a URDF joint: each row splits into a part before the joint motion and a
part after it, ``T_i = pre_i . M(q_i) . post_i``:

* revolute: ``pre = Rz(theta_offset)``, ``M = Rz(q)``, ``post = Tz(d) Tx(a) Rx(alpha)``;
* prismatic: ``pre = Rz(theta_offset) Tz(d)``, ``M = Tz(q)``, ``post = Tx(a) Rx(alpha)``.

URDF joint ``i`` then has origin ``post_{i-1} . pre_i`` (``post_0`` = identity) and axis
``+z``; the last row's ``post_n`` (times an optional extra tool transform) becomes a fixed
joint to the end-effector link.

Visual geometry is schematic (a cylinder from each joint to the next, a thinner rod along the
stroke of each prismatic joint, a small box at the tool) and every moving link gets a small
inertial so that viewers, KDL and simulators load the file without complaint.  The base link
has no inertial (KDL warns about a root link with inertia).
"""

from __future__ import annotations

import math
import re
from collections.abc import Sequence
from dataclasses import dataclass, fields
from typing import TYPE_CHECKING, Literal, TypedDict

import numpy as np
from numpy.typing import ArrayLike, NDArray

from swarm_ik.errors import InvalidArgumentError

if TYPE_CHECKING:  # typing.Unpack is Python 3.11+
    from typing_extensions import Unpack

JointKind = Literal["revolute", "prismatic", "continuous"]
"""Joint types a chain step / DH row may have."""

JOINT_KINDS: tuple[str, ...] = ("revolute", "prismatic", "continuous")

_NAME_RE = re.compile(r"^[A-Za-z_][A-Za-z0-9_.\-]*$")


# --------------------------------------------------------------------------------------------
# Small transform helpers (4x4 homogeneous matrices, metres and radians)
# --------------------------------------------------------------------------------------------


def rot_x(angle: float) -> NDArray[np.float64]:
    """Homogeneous rotation about x by ``angle`` (rad); shape (4, 4)."""
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[1.0, 0, 0, 0], [0, c, -s, 0], [0, s, c, 0], [0, 0, 0, 1]])


def rot_y(angle: float) -> NDArray[np.float64]:
    """Homogeneous rotation about y by ``angle`` (rad); shape (4, 4)."""
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[c, 0, s, 0], [0, 1.0, 0, 0], [-s, 0, c, 0], [0, 0, 0, 1]])


def rot_z(angle: float) -> NDArray[np.float64]:
    """Homogeneous rotation about z by ``angle`` (rad); shape (4, 4)."""
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[c, -s, 0, 0], [s, c, 0, 0], [0, 0, 1.0, 0], [0, 0, 0, 1]])


def translation(x: float = 0.0, y: float = 0.0, z: float = 0.0) -> NDArray[np.float64]:
    """Homogeneous translation by ``(x, y, z)`` (m); shape (4, 4)."""
    out = np.eye(4)
    out[:3, 3] = (x, y, z)
    return out


def dh_transform(d: float, theta: float, a: float, alpha: float) -> NDArray[np.float64]:
    """One standard DH link transform ``Rz(theta) Tz(d) Tx(a) Rx(alpha)`` (eq. 1, HLFOA paper).

    Args:
        d: Offset along the previous z axis (m).
        theta: Total rotation about the previous z axis (rad), offset included.
        a: Length along the new x axis (m).
        alpha: Twist about the new x axis (rad).

    Returns:
        The (4, 4) homogeneous transform from frame i-1 to frame i.
    """
    ct, st = math.cos(theta), math.sin(theta)
    ca, sa = math.cos(alpha), math.sin(alpha)
    return np.array(
        [
            [ct, -ca * st, sa * st, a * ct],
            [st, ca * ct, -sa * ct, a * st],
            [0.0, sa, ca, d],
            [0.0, 0.0, 0.0, 1.0],
        ]
    )


# --------------------------------------------------------------------------------------------
# Data types
# --------------------------------------------------------------------------------------------


def _check_kind(kind: str) -> None:
    if kind not in JOINT_KINDS:
        raise InvalidArgumentError(
            f"unknown joint type {kind!r}; valid joint types: {', '.join(JOINT_KINDS)}"
        )


def _check_limits(kind: str, lower: float, upper: float, effort: float, velocity: float) -> None:
    for label, value in (("effort", effort), ("velocity", velocity)):
        if not (math.isfinite(value) and value > 0):
            raise InvalidArgumentError(f"joint {label} must be finite and > 0, got {value!r}")
    if kind == "continuous":
        return
    if not (math.isfinite(lower) and math.isfinite(upper) and lower < upper):
        raise InvalidArgumentError(
            f"{kind} joint limits must be finite with lower < upper, got [{lower!r}, {upper!r}]"
        )


def _check_name(label: str, name: str | None) -> None:
    if name is not None and not _NAME_RE.match(name):
        raise InvalidArgumentError(
            f"{label} {name!r} is not a valid URDF name (letters, digits, '_', '-', '.')"
        )


@dataclass(frozen=True, kw_only=True, eq=False)
class JointSpec:
    """What a :class:`DHRow` and a :class:`ChainStep` say of their joint besides its motion:
    limits and names, keyword-only.

    Attributes:
        lower: Lower limit of the joint value ``q`` (rad, or m for prismatic); ignored for
            continuous joints.
        upper: Upper limit of ``q`` (rad or m); ignored for continuous joints.
        effort: URDF effort limit (N m or N).
        velocity: URDF velocity limit (rad/s or m/s).
        joint_name: URDF joint name; default ``joint{i}`` (1-based).
        link_name: URDF name of the link this joint moves; default ``link{i}``.
    """

    lower: float = -math.pi
    upper: float = math.pi
    effort: float = 100.0
    velocity: float = 1.0
    joint_name: str | None = None
    link_name: str | None = None

    def joint_spec(self) -> dict[str, float | str | None]:
        """The :class:`JointSpec` fields by name (to pass on to another row or step)."""
        return {f.name: getattr(self, f.name) for f in fields(JointSpec)}

    def _check_joint(self, kind: str) -> None:
        """The limits and names, for a joint of ``kind`` (already checked)."""
        _check_limits(kind, self.lower, self.upper, self.effort, self.velocity)
        _check_name("joint name", self.joint_name)
        _check_name("link name", self.link_name)


@dataclass(frozen=True)
class DHRow(JointSpec):
    """One row of a standard DH table (``Rz(theta) Tz(d) Tx(a) Rx(alpha)``).

    Attributes:
        kind: ``"revolute"``, ``"continuous"`` (variable ``theta = q + theta_offset``) or
            ``"prismatic"`` (variable ``d + q``).
        d: Link offset (m); for a prismatic row the value at ``q = 0``.
        theta_offset: Constant added to the joint value to give DH theta (rad).
        a: Link length (m).
        alpha: Link twist (rad).
        lower, upper, effort, velocity, joint_name, link_name: As :class:`JointSpec`
            (keyword-only).
    """

    kind: JointKind
    d: float
    theta_offset: float
    a: float
    alpha: float

    def __post_init__(self) -> None:
        _check_kind(self.kind)  # a bad kind is the first thing to name
        for label in ("d", "theta_offset", "a", "alpha"):
            value = getattr(self, label)
            if not math.isfinite(value):
                raise InvalidArgumentError(f"DH parameter {label} must be finite, got {value!r}")
        self._check_joint(self.kind)


@dataclass(frozen=True, eq=False)
class ChainStep(JointSpec):
    """A fixed transform followed by one joint: the building block of :func:`chain_to_urdf`.

    The link moved by this joint has, at joint value ``q``, the pose
    ``parent_pose . origin . M(q)`` where ``M`` is a rotation by ``q`` about ``axis``
    (revolute, continuous) or a translation by ``q * axis`` (prismatic), ``axis`` being
    expressed in the frame reached after ``origin``.

    Attributes:
        origin: Fixed (4, 4) homogeneous transform from the previous joint's frame (or the base
            link) to this joint's frame; translation in m. Stored read-only.
        kind: ``"revolute"``, ``"prismatic"`` or ``"continuous"``.
        axis: Joint axis in the joint frame (unit-normalised on construction); shape (3,).
        lower, upper, effort, velocity, joint_name, link_name: As :class:`JointSpec`
            (keyword-only).
    """

    origin: NDArray[np.float64]
    kind: JointKind
    axis: tuple[float, float, float] = (0.0, 0.0, 1.0)

    def __post_init__(self) -> None:
        origin = np.array(self.origin, dtype=np.float64)
        _check_transform("origin", origin)
        origin.setflags(write=False)
        object.__setattr__(self, "origin", origin)
        _check_kind(self.kind)  # a bad kind is the first thing to name
        axis = np.asarray(self.axis, dtype=np.float64)
        norm = float(np.linalg.norm(axis)) if axis.shape == (3,) else 0.0
        if not (math.isfinite(norm) and norm > 1e-12):
            raise InvalidArgumentError(
                f"joint axis must be a finite non-zero 3-vector, got {self.axis!r}"
            )
        unit = axis / norm
        object.__setattr__(self, "axis", (float(unit[0]), float(unit[1]), float(unit[2])))
        self._check_joint(self.kind)


def _check_transform(label: str, mat: NDArray[np.float64]) -> None:
    if mat.shape != (4, 4) or not np.all(np.isfinite(mat)):
        raise InvalidArgumentError(f"{label} must be a finite (4, 4) transform, got {mat!r}")
    rot = mat[:3, :3]
    if (
        np.abs(rot.T @ rot - np.eye(3)).max() > 1e-9
        or abs(np.linalg.det(rot) - 1.0) > 1e-9
        or np.abs(mat[3] - (0, 0, 0, 1)).max() > 0
    ):
        raise InvalidArgumentError(f"{label} is not a rigid transform: {mat!r}")


# --------------------------------------------------------------------------------------------
# DH forward kinematics and the DH -> chain split
# --------------------------------------------------------------------------------------------


def dh_fk(table: Sequence[DHRow], q: ArrayLike) -> NDArray[np.float64]:
    """Evaluate the DH product ``T_1(q_1) ... T_n(q_n)`` directly with numpy.

    Args:
        table: The DH rows, base to flange.
        q: Joint values, shape (n,): rad for revolute/continuous rows (DH theta minus the
            row's offset), m for prismatic rows (DH d minus the row's ``d``).

    Returns:
        The (4, 4) pose of the flange frame (frame n) in the base frame; metres.
    """
    q_arr = np.asarray(q, dtype=np.float64)
    if q_arr.shape != (len(table),):
        raise InvalidArgumentError(
            f"q must have shape ({len(table)},) for this DH table, got {q_arr.shape}"
        )
    out = np.eye(4)
    for row, qi in zip(table, q_arr, strict=True):
        if row.kind == "prismatic":
            out = out @ dh_transform(row.d + qi, row.theta_offset, row.a, row.alpha)
        else:
            out = out @ dh_transform(row.d, qi + row.theta_offset, row.a, row.alpha)
    return out


def _dh_to_chain(
    table: Sequence[DHRow], tool: NDArray[np.float64]
) -> tuple[list[ChainStep], NDArray[np.float64]]:
    """Split each DH row into pre . motion . post and regroup into chain steps + tool."""
    steps: list[ChainStep] = []
    post_prev = np.eye(4)
    for row in table:
        if row.kind == "prismatic":
            pre = rot_z(row.theta_offset) @ translation(z=row.d)
            post = translation(x=row.a) @ rot_x(row.alpha)
        else:
            pre = rot_z(row.theta_offset)
            post = translation(z=row.d) @ translation(x=row.a) @ rot_x(row.alpha)
        steps.append(ChainStep(post_prev @ pre, row.kind, **row.joint_spec()))  # type: ignore[arg-type]
        post_prev = post
    return steps, post_prev @ tool


# --------------------------------------------------------------------------------------------
# URDF writing
# --------------------------------------------------------------------------------------------


def _clean(x: float) -> float:
    """Snap float noise (sin(pi) ~ 1e-16, 0.3000000000000004) to the nearby short value."""
    x = float(x)
    if abs(x) < 1e-15:
        return 0.0
    quarter = round(x / (math.pi / 2))
    if quarter != 0 and abs(x - quarter * (math.pi / 2)) < 2e-15:
        return quarter * (math.pi / 2)
    short = round(x, 12)
    if abs(short - x) < 1e-15:
        return short
    return x


def _fmt(*values: float) -> str:
    """Full precision (shortest round-trip repr): kinematic numbers."""
    return " ".join(repr(_clean(v)) for v in values)


def _fmt_short(*values: float) -> str:
    """Six significant digits: schematic visuals and inertials only."""
    return " ".join(f"{_clean(v):.6g}" for v in values)


def _rpy(rot: NDArray[np.float64]) -> tuple[float, float, float]:
    """URDF roll-pitch-yaw with ``rot = Rz(yaw) Ry(pitch) Rx(roll)``, well conditioned.

    Yaw comes from the first column; pitch and roll are then read from ``Rz(yaw)^T rot``,
    which stays accurate at and near pitch = +-pi/2 (gimbal lock, then yaw = 0).
    """
    if math.hypot(rot[0, 0], rot[1, 0]) < 1e-14:
        yaw = 0.0
    else:
        yaw = math.atan2(rot[1, 0], rot[0, 0])
    rest = rot_z(-yaw)[:3, :3] @ rot
    pitch = math.atan2(-rest[2, 0], rest[0, 0])
    roll = math.atan2(-rest[1, 2], rest[1, 1])
    return roll, pitch, yaw


def _origin_xml(mat: NDArray[np.float64], short: bool = False) -> str:
    roll, pitch, yaw = _rpy(mat[:3, :3])
    fmt = _fmt_short if short else _fmt
    return f'<origin xyz="{fmt(*mat[:3, 3])}" rpy="{fmt(roll, pitch, yaw)}"/>'


def _z_to(vec: NDArray[np.float64]) -> NDArray[np.float64]:
    """A rotation (3, 3) taking +z onto the unit vector ``vec``."""
    z = vec / np.linalg.norm(vec)
    helper = np.array([1.0, 0.0, 0.0]) if abs(z[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    x = np.cross(helper, z)
    x /= np.linalg.norm(x)
    y = np.cross(z, x)
    return np.column_stack([x, y, z])


def _cylinder_xml(
    start: NDArray[np.float64], end: NDArray[np.float64], radius: float, material: str
) -> str:
    vec = end - start
    pose = np.eye(4)
    pose[:3, :3] = _z_to(vec)
    pose[:3, 3] = (start + end) / 2
    return (
        f"    <visual>\n      {_origin_xml(pose, short=True)}\n"
        f'      <geometry><cylinder radius="{_fmt_short(radius)}" '
        f'length="{_fmt_short(float(np.linalg.norm(vec)))}"/></geometry>\n'
        f'      <material name="{material}"/>\n    </visual>\n'
    )


def _inertial_xml(mass: float, inertia: float) -> str:
    return (
        "    <inertial>\n"
        '      <origin xyz="0 0 0" rpy="0 0 0"/>\n'
        f'      <mass value="{_fmt_short(mass)}"/>\n'
        f'      <inertia ixx="{_fmt_short(inertia)}" ixy="0" ixz="0" iyy="{_fmt_short(inertia)}" '
        f'iyz="0" izz="{_fmt_short(inertia)}"/>\n'
        "    </inertial>\n"
    )


class _UrdfNames(TypedDict):
    robot_name: str
    base_link: str
    ee_link: str


class UrdfOptions(_UrdfNames, total=False):
    """The keyword-only arguments of :func:`chain_to_urdf`, also taken by :func:`dh_to_urdf`.

    ``robot_name``, ``base_link`` and ``ee_link`` are required; see :func:`chain_to_urdf`.
    """

    tool: ArrayLike | None
    link_radius: float | None
    link_mass: float
    comment: str | None


def chain_to_urdf(
    steps: Sequence[ChainStep],
    *,
    robot_name: str,
    base_link: str,
    ee_link: str,
    tool: ArrayLike | None = None,
    link_radius: float | None = None,
    link_mass: float = 0.1,
    comment: str | None = None,
) -> str:
    """Write a serial chain of "fixed transform + joint" steps as URDF text.

    Joint ``i`` connects link ``i-1`` (the base link for ``i = 1``) to link ``i``, with
    ``<origin>`` = ``steps[i].origin`` and ``<axis>`` = ``steps[i].axis``; a fixed joint
    ``{ee_link}_joint`` with origin ``tool`` connects the last link to ``ee_link``.  So the
    pose of ``ee_link`` is ``origin_1 M_1(q_1) ... origin_n M_n(q_n) tool``.

    Args:
        steps: The joints, base to tip (at least one).
        robot_name: ``<robot name=...>``.
        base_link: Name of the root link (no inertial, no joint above it).
        ee_link: Name of the end-effector link, fixed to the last joint's link.
        tool: Fixed (4, 4) transform from the last joint's frame to ``ee_link``; identity if
            omitted.
        link_radius: Radius (m) of the schematic link cylinders; default 2 % of the summed
            joint-to-joint distances (at least 5 mm).
        link_mass: Mass (kg) given to every moving link (a small, schematic inertial).
        comment: Optional text written as an XML comment at the top (e.g. the source).

    Returns:
        The URDF document as a string (deterministic: same input, same text).

    Raises:
        InvalidArgumentError: on an empty chain, a non-rigid ``tool``, bad or repeated names.
    """
    if len(steps) == 0:
        raise InvalidArgumentError("a chain needs at least one joint step, got none")
    for label, name in (("robot name", robot_name), ("base link", base_link), ("ee link", ee_link)):
        if not _NAME_RE.match(name):
            raise InvalidArgumentError(f"{label} {name!r} is not a valid URDF name")
    tool_mat = np.eye(4) if tool is None else np.array(tool, dtype=np.float64)
    _check_transform("tool", tool_mat)
    if not (math.isfinite(link_mass) and link_mass > 0):
        raise InvalidArgumentError(f"link_mass must be finite and > 0 (kg), got {link_mass!r}")

    joint_names = [s.joint_name or f"joint{i + 1}" for i, s in enumerate(steps)]
    link_names = [s.link_name or f"link{i + 1}" for i, s in enumerate(steps)]
    all_links = [base_link, *link_names, ee_link]
    all_joints = [*joint_names, f"{ee_link}_joint"]
    for kind, names in (("link", all_links), ("joint", all_joints)):
        repeated = sorted({x for x in names if names.count(x) > 1})
        if repeated:
            raise InvalidArgumentError(f"repeated {kind} names {repeated}; {kind}s: {names}")

    # Offsets from each link frame to the next joint (or to the tool) draw the links.
    next_offsets = [s.origin[:3, 3] for s in steps[1:]] + [tool_mat[:3, 3]]
    total = float(np.linalg.norm(steps[0].origin[:3, 3])) + sum(
        float(np.linalg.norm(v)) for v in next_offsets
    )
    radius = round(max(0.005, 0.02 * total), 3) if link_radius is None else float(link_radius)
    if not (math.isfinite(radius) and radius > 0):
        raise InvalidArgumentError(f"link_radius must be finite and > 0 (m), got {link_radius!r}")
    inertia = link_mass * radius**2

    out: list[str] = ['<?xml version="1.0"?>\n']
    if comment:
        safe = comment.replace("--", "- -")
        out.append(f"<!-- {safe} -->\n")
    out.append(f'<robot name="{robot_name}">\n')
    out.append('  <material name="link_grey"><color rgba="0.6 0.6 0.65 1"/></material>\n')
    out.append('  <material name="joint_blue"><color rgba="0.2 0.4 0.8 1"/></material>\n')
    out.append('  <material name="tool_orange"><color rgba="0.95 0.5 0.1 1"/></material>\n')

    # Base link: a cylinder up to the first joint, no inertial.
    out.append(f'  <link name="{base_link}">\n')
    first = steps[0].origin[:3, 3]
    if np.linalg.norm(first) > 1e-9:
        out.append(_cylinder_xml(np.zeros(3), first, radius, "link_grey"))
    out.append("  </link>\n")

    for i, step in enumerate(steps):
        parent = all_links[i]
        child = link_names[i]
        axis = np.asarray(step.axis)
        out.append(f'  <joint name="{joint_names[i]}" type="{step.kind}">\n')
        out.append(f'    <parent link="{parent}"/>\n    <child link="{child}"/>\n')
        out.append(f"    {_origin_xml(step.origin)}\n")
        out.append(f'    <axis xyz="{_fmt(*axis)}"/>\n')
        if step.kind == "continuous":
            out.append(
                f'    <limit effort="{_fmt(step.effort)}" velocity="{_fmt(step.velocity)}"/>\n'
            )
        else:
            out.append(
                f'    <limit lower="{_fmt(step.lower)}" upper="{_fmt(step.upper)}" '
                f'effort="{_fmt(step.effort)}" velocity="{_fmt(step.velocity)}"/>\n'
            )
        out.append("  </joint>\n")

        out.append(f'  <link name="{child}">\n')
        out.append(_inertial_xml(link_mass, inertia))
        # The joint itself: a short cylinder along its axis (revolute) ...
        half = axis * radius * 1.5
        if step.kind == "prismatic":
            # ... or a thinner rod over the stroke behind the moving frame (telescope stage).
            stroke = min(step.upper - step.lower, 10 * radius + total)
            out.append(_cylinder_xml(-axis * stroke, np.zeros(3), radius * 0.6, "joint_blue"))
        else:
            out.append(_cylinder_xml(-half, half, radius * 1.2, "joint_blue"))
        offset = next_offsets[i]
        if np.linalg.norm(offset) > 1e-9:
            out.append(_cylinder_xml(np.zeros(3), offset, radius, "link_grey"))
        out.append("  </link>\n")

    out.append(f'  <joint name="{all_joints[-1]}" type="fixed">\n')
    out.append(f'    <parent link="{link_names[-1]}"/>\n    <child link="{ee_link}"/>\n')
    out.append(f"    {_origin_xml(tool_mat)}\n")
    out.append("  </joint>\n")
    box = _fmt_short(*(np.full(3, 2.0 * radius)))
    out.append(f'  <link name="{ee_link}">\n')
    out.append(_inertial_xml(link_mass, inertia))
    out.append(
        "    <visual>\n"
        '      <origin xyz="0 0 0" rpy="0 0 0"/>\n'
        f'      <geometry><box size="{box}"/></geometry>\n'
        '      <material name="tool_orange"/>\n'
        "    </visual>\n"
    )
    out.append("  </link>\n")
    out.append("</robot>\n")
    return "".join(out)


def dh_to_urdf(table: Sequence[DHRow], **options: Unpack[UrdfOptions]) -> str:
    """Write a standard DH table as URDF text whose FK equals :func:`dh_fk`.

    The URDF joint value is the DH variable (``theta_i = q_i + theta_offset_i`` for
    revolute/continuous rows, ``d_i + q_i`` for prismatic rows); offsets are folded into the
    joint origins, and each row's limits are the URDF limits of ``q_i``.  The frame after the
    last row (the flange) times ``tool`` is the pose of ``ee_link``.

    Args:
        table: DH rows, base to flange (metres, radians).
        **options: The keyword-only arguments of :func:`chain_to_urdf` (:class:`UrdfOptions`:
            ``robot_name``, ``base_link`` = DH frame 0, ``ee_link``, ``link_radius``,
            ``link_mass``, ``comment``); here ``tool`` is the optional fixed (4, 4)
            flange-to-tool transform (identity if omitted).

    Returns:
        The URDF document as a string.

    Example:
        >>> import math
        >>> rows = [DHRow("revolute", d=0.1, theta_offset=0.0, a=0.2, alpha=math.pi / 2)]
        >>> text = dh_to_urdf(rows, robot_name="one", base_link="base", ee_link="tool")
        >>> text.count("<joint ")
        2
    """
    if len(table) == 0:
        raise InvalidArgumentError("a DH table needs at least one row, got none")
    tool = options.get("tool")
    tool_mat = np.eye(4) if tool is None else np.array(tool, dtype=np.float64)
    _check_transform("tool", tool_mat)
    steps, options["tool"] = _dh_to_chain(table, tool_mat)  # the flange-to-ee transform
    return chain_to_urdf(steps, **options)


__all__ = [
    "JOINT_KINDS",
    "ChainStep",
    "DHRow",
    "JointKind",
    "UrdfOptions",
    "chain_to_urdf",
    "dh_fk",
    "dh_to_urdf",
    "dh_transform",
    "rot_x",
    "rot_y",
    "rot_z",
    "translation",
]
