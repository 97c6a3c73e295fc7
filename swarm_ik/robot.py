"""RobotModel: a URDF loaded into Pinocchio and reduced to the serial chain root → end effector.

>>> import swarm_ik
>>> robot = swarm_ik.load_robot("yumi_left")
>>> robot.nq, robot.ee_frame
(7, 'yumi_tool')
"""

from __future__ import annotations

import os
import reprlib
import sys
import threading
import warnings
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path
from typing import Any

import numpy as np
import pinocchio as pin
from numpy.typing import NDArray

from swarm_ik import urdf
from swarm_ik.errors import InvalidArgumentError, RobotFileNotFoundError, RobotModelError, unknown
from swarm_ik.kinematics import CONTINUOUS, KIND_NAMES, PRISMATIC, REVOLUTE, ChainKinematics

FloatArray = NDArray[np.float64]

BUNDLED: dict[str, tuple[str, str]] = {
    "yumi_left": ("yumi_left.urdf", "yumi_tool"),
    "loading_manipulator": ("loading_manipulator.urdf", "spreader"),
    "loading_manipulator_long": ("loading_manipulator_long.urdf", "spreader"),
}
"""Bundled robots: name -> (file in ``robots/``, end-effector frame)."""

EXAMPLE_ROBOTS: dict[str, tuple[str, str]] = {
    "panda": ("panda_description/urdf/panda.urdf", "panda_hand_tcp"),
    "ur3": ("ur_description/urdf/ur3_robot.urdf", "tool0"),
    "ur5": ("ur_description/urdf/ur5_robot.urdf", "tool0"),
    "ur10": ("ur_description/urdf/ur10_robot.urdf", "tool0"),
    "kinova": ("kinova_description/robots/kinova.urdf", "j2s6s200_end_effector"),
    "xarm7": ("xarm_description/urdf/xarm7.urdf", "link_eef"),
    "z1": ("z1_description/urdf/z1.urdf", "link06"),
    "baxter_left": ("baxter_description/urdf/baxter.urdf", "left_gripper"),
}
"""Arms of the ``example-robot-data`` package: name -> (URDF path under its ``robots/``
folder, default end-effector frame).  Joints off the root → end-effector chain (grippers)
are locked at their neutral value."""


def bundled_robot_dir() -> Path:
    """Folder holding the bundled URDFs (``robots/`` of the repository, installed as
    ``swarm_ik.robots``)."""
    return Path(str(resources.files("swarm_ik.robots")))


def example_robot_data_dir() -> Path:
    """The ``robots`` folder of the installed ``example-robot-data`` package.

    ``$EXAMPLE_ROBOT_DATA_DIR`` overrides the search.

    Raises:
        RobotFileNotFoundError: the package is not installed.
    """
    env = os.environ.get("EXAMPLE_ROBOT_DATA_DIR")
    candidates = [Path(env)] if env else []
    for entry in sys.path:
        candidates.append(Path(entry) / "cmeel.prefix" / "share" / "example-robot-data" / "robots")
    candidates.append(Path(sys.prefix) / "share" / "example-robot-data" / "robots")
    for c in candidates:
        if c.is_dir():
            return c
    raise RobotFileNotFoundError(
        "the example-robot-data package was not found; install it with "
        "`pip install example-robot-data` or set EXAMPLE_ROBOT_DATA_DIR"
    )


def robot_names() -> dict[str, list[str]]:
    """Robots loadable by name: ``{"bundled": [...], "example-robot-data": [...]}``."""
    return {"bundled": sorted(BUNDLED), "example-robot-data": sorted(EXAMPLE_ROBOTS)}


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


@dataclass(frozen=True, eq=False)
class RobotModel:
    """A serial chain from a URDF, with limits, joint kinds and batched kinematics.

    Build it with :func:`load_robot` or :meth:`from_urdf`.

    Attributes:
        name: Robot name (from the URDF).
        urdf_path: The URDF file.
        ee_frame: End-effector frame name.
        model: Pinocchio model of the chain (joints off the chain locked).
        full_model: Pinocchio model of the whole URDF.
        locked_joints: Names of the URDF joints locked (off the chain).
        q_locked: Full-model configuration used for the locked joints.
        joint_names: Names of the chain's joints, shape ``(nq,)``.
        joint_kinds: ``"revolute"``, ``"prismatic"`` or ``"continuous"`` per joint.
        lower: Lower limits (rad or m), shape ``(nq,)``; ``-π`` for continuous joints.
        upper: Upper limits (rad or m), shape ``(nq,)``; ``+π`` for continuous joints.
        chain: The arrays behind the batched FK and Jacobian.
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
    chain: ChainKinematics
    ee_frame_id: int = field(default=0)
    _local: threading.local = field(default_factory=threading.local, repr=False)

    # --------------------------------------------------------------- building
    @classmethod
    def from_urdf(cls, path: str | os.PathLike[str], ee_frame: str | None = None) -> RobotModel:
        """Load a URDF and reduce it to the chain from the root to ``ee_frame``.

        Args:
            path: URDF file.
            ee_frame: End-effector frame (a link or fixed-joint name).  Default: chosen by
                :func:`swarm_ik.urdf.default_ee_frame` (tip of the longest movable chain
                without gripper or mimic joints; the choice and its reason are logged at
                INFO level on the ``swarm_ik`` logger).

        Raises:
            RobotFileNotFoundError: the file does not exist.
            RobotModelError: not a URDF, loops, bad limits, no movable joint on the chain.
            UnknownNameError: ``ee_frame`` is not a frame of the model (the valid ones listed).
        """
        p = Path(path)
        if not p.is_file():
            raise RobotFileNotFoundError(f"URDF file not found: {str(p)!r}")
        full, info = urdf.load_urdf(p)  # decoded, checked, joints renamed, stderr captured
        mimic = info.mimic_drivers
        body_frames = [f.name for f in full.frames if f.type == pin.FrameType.BODY]
        all_frames = [f.name for f in full.frames if f.name != "universe"]
        if ee_frame is None:
            ee_frame, reason = urdf.default_ee_frame(full, info)
            urdf.log.info("%s: %s", p, reason)
        if ee_frame not in all_frames:
            raise unknown("frame", ee_frame, body_frames)
        fid = _frame_id(full, ee_frame)
        parent = full.frames[fid].parentJoint
        chain_ids = [int(j) for j in full.supports[parent] if j != 0]
        if not chain_ids:
            raise RobotModelError(f"{p}: no movable joint between the root and frame {ee_frame!r}")
        locked = [j for j in range(1, full.njoints) if j not in chain_ids]
        q_ref = pin.neutral(full)
        try:
            reduced = pin.buildReducedModel(full, locked, q_ref) if locked else full.copy()
        except Exception as exc:
            raise RobotModelError(f"{p}: could not reduce the model to the chain ({exc})") from None
        rfid = _frame_id(reduced, ee_frame)
        names, kinds, axes, rot_p, pos_p = [], [], [], [], []
        lower, upper = [], []
        for j in range(1, reduced.njoints):
            if reduced.parents[j] != j - 1:
                raise RobotModelError(f"{p}: the reduced model is not a serial chain")
            jm = reduced.joints[j]
            jname = reduced.names[j]
            if jname in mimic:
                raise RobotModelError(
                    f"{p}: joint {jname!r} on the chain to {ee_frame!r} mimics joint "
                    f"{mimic[jname]!r}; mimic joints on the chain are not supported (they would "
                    "be solved as independent joints)"
                )
            try:
                kind, axis = _joint_kind_axis(jm)
            except RobotModelError as exc:
                raise RobotModelError(
                    f"{p}: joint {jname!r} on the chain to {ee_frame!r}: {exc}; supported: "
                    "revolute, continuous, prismatic (and fixed)"
                ) from None
            names.append(reduced.names[j])
            kinds.append(kind)
            axes.append(axis)
            placement = reduced.jointPlacements[j]
            rot_p.append(np.array(placement.rotation))
            pos_p.append(np.array(placement.translation))
            if kind == CONTINUOUS:
                lo, hi = -np.pi, np.pi
            else:
                lo = float(reduced.lowerPositionLimit[jm.idx_q])
                hi = float(reduced.upperPositionLimit[jm.idx_q])
            if not (np.isfinite(lo) and np.isfinite(hi)) or lo > hi:
                raise RobotModelError(
                    f"{p}: joint {reduced.names[j]!r} has invalid limits [{lo}, {hi}]"
                )
            lower.append(lo)
            upper.append(hi)
        frame = reduced.frames[rfid]
        if frame.parentJoint != reduced.njoints - 1:
            raise RobotModelError(f"{p}: frame {ee_frame!r} is not at the end of the chain")
        chain = ChainKinematics.canonical(
            kinds=np.array(kinds, dtype=np.int64),
            axes=np.asarray(axes, dtype=float),
            rot_p=np.asarray(rot_p, dtype=float),
            pos_p=np.asarray(pos_p, dtype=float),
            rot_f=np.asarray(frame.placement.rotation, dtype=float),
            pos_f=np.asarray(frame.placement.translation, dtype=float),
        )
        return cls(
            name=full.name or p.stem,
            urdf_path=p.resolve(),
            ee_frame=ee_frame,
            model=reduced,
            full_model=full,
            locked_joints=tuple(full.names[j] for j in locked),
            q_locked=np.asarray(q_ref, dtype=float),
            joint_names=tuple(names),
            joint_kinds=tuple(KIND_NAMES[k] for k in kinds),
            lower=np.array(lower),
            upper=np.array(upper),
            chain=chain,
            ee_frame_id=rfid,
        )

    # ------------------------------------------------------------- properties
    @property
    def nq(self) -> int:
        """Number of joints of the chain (one value per joint)."""
        return self.chain.nq

    @property
    def continuous_mask(self) -> NDArray[np.bool_]:
        """True for continuous joints, shape ``(nq,)``."""
        return np.array([k == "continuous" for k in self.joint_kinds])

    @property
    def prismatic_mask(self) -> NDArray[np.bool_]:
        """True for prismatic joints, shape ``(nq,)``."""
        return np.array([k == "prismatic" for k in self.joint_kinds])

    # ------------------------------------------------------------- kinematics
    def fk(self, q: FloatArray) -> FloatArray:
        """End-effector pose(s) [m]: ``(nq,) -> (4, 4)`` or ``(pop, nq) -> (pop, 4, 4)``."""
        return self.chain.fk(q)

    def fk_jacobian(self, q: FloatArray) -> tuple[FloatArray, FloatArray]:
        """Pose(s) and LOCAL_WORLD_ALIGNED frame Jacobian(s) ``(…, 6, nq)``, rows ``[v; ω]``."""
        return self.chain.fk_jacobian(q)

    def to_pinocchio(self, q: FloatArray) -> FloatArray:
        """Pinocchio configuration of the chain model for ``q`` (continuous → cos, sin)."""
        q = np.asarray(q, dtype=float).reshape(self.nq)
        if self.model.nq == self.nq:  # no continuous joint: the same vector
            return q.copy()
        out = np.empty(self.model.nq)
        for j in range(1, self.model.njoints):
            jm = self.model.joints[j]
            v = q[j - 1]
            if jm.nq == 2:
                out[jm.idx_q] = np.cos(v)
                out[jm.idx_q + 1] = np.sin(v)
            else:
                out[jm.idx_q] = v
        return out

    def from_pinocchio(self, q_pin: FloatArray) -> FloatArray:
        """Inverse of :meth:`to_pinocchio`: one value per joint."""
        q_pin = np.asarray(q_pin, dtype=float)
        out = np.empty(self.nq)
        for j in range(1, self.model.njoints):
            jm = self.model.joints[j]
            if jm.nq == 2:
                out[j - 1] = np.arctan2(q_pin[jm.idx_q + 1], q_pin[jm.idx_q])
            else:
                out[j - 1] = q_pin[jm.idx_q]
        return out

    def __getstate__(self) -> dict[str, Any]:
        state = dict(self.__dict__)
        state.pop("_local", None)  # per-thread Pinocchio Data: rebuilt on demand
        return state

    def __setstate__(self, state: dict[str, Any]) -> None:
        self.__dict__.update(state)
        object.__setattr__(self, "_local", threading.local())

    def _data(self) -> Any:
        """Pinocchio ``Data`` of the chain model, one per thread (reused between calls)."""
        data = getattr(self._local, "data", None)
        if data is None:
            data = self._local.data = self.model.createData()
        return data

    def fk_pinocchio(self, q: FloatArray) -> FloatArray:
        """Reference FK through ``pinocchio.forwardKinematics`` + ``updateFramePlacements``.

        Slower than :meth:`fk` (one call per pose); used to verify results.

        Args:
            q: Joint values, shape ``(nq,)``.

        Returns:
            Pose, shape ``(4, 4)``.
        """
        data = self._data()
        pin.forwardKinematics(self.model, data, self.to_pinocchio(q))
        pin.updateFramePlacements(self.model, data)
        return np.array(data.oMf[self.ee_frame_id].homogeneous)

    def jacobian_pinocchio(self, q: FloatArray) -> FloatArray:
        """Reference frame Jacobian ``(6, nq)`` from Pinocchio, LOCAL_WORLD_ALIGNED."""
        data = self._data()
        pin.computeJointJacobians(self.model, data, self.to_pinocchio(q))
        pin.updateFramePlacements(self.model, data)
        jac = pin.getFrameJacobian(
            self.model, data, self.ee_frame_id, pin.ReferenceFrame.LOCAL_WORLD_ALIGNED
        )
        return np.array(jac).reshape(6, self.model.nv)  # eigenpy gives (6,) when nv == 1

    # ----------------------------------------------------------------- limits
    def within_limits(self, q: FloatArray, tol: float = 1e-9) -> bool:
        """Whether ``q`` (shape ``(nq,)``) lies within the limits (± ``tol``)."""
        q = np.asarray(q, dtype=float)
        return bool(np.all(q >= self.lower - tol) and np.all(q <= self.upper + tol))

    def wrap(self, q: FloatArray) -> FloatArray:
        """Continuous joints wrapped into ``[-π, π)``; other values unchanged (same shape)."""
        q = np.array(q, dtype=float)
        m = self.continuous_mask
        if m.any():
            q[..., m] = (q[..., m] + np.pi) % (2 * np.pi) - np.pi
        return q

    def random_q(self, rng: np.random.Generator, n: int | None = None) -> FloatArray:
        """Joint vector(s) drawn uniformly within the limits: ``(nq,)`` or ``(n, nq)``."""
        size = self.nq if n is None else (n, self.nq)
        return rng.uniform(self.lower, self.upper, size=size)

    def mid_q(self) -> FloatArray:
        """The middle of the joint ranges, shape ``(nq,)`` (TRAC-IK's benchmark seed)."""
        return 0.5 * (self.lower + self.upper)

    def check_q(self, q: Any, what: str = "q") -> FloatArray:
        """Validate a joint vector: shape ``(nq,)`` and finite; returns it as floats."""
        try:
            arr = np.array(q, dtype=float)
        except (TypeError, ValueError):
            raise InvalidArgumentError(
                f"{what} must be {self.nq} numbers (one per joint), got {reprlib.repr(q)}"
            ) from None
        if arr.shape != (self.nq,):
            raise InvalidArgumentError(
                f"{what} must hold {self.nq} values (one per joint: "
                f"{', '.join(self.joint_names)}); got shape {arr.shape}"
            )
        if not np.all(np.isfinite(arr)):
            raise InvalidArgumentError(f"{what} contains NaN or infinite values: {arr.tolist()}")
        return arr

    def __repr__(self) -> str:
        return (
            f"RobotModel(name={self.name!r}, nq={self.nq}, ee_frame={self.ee_frame!r}, "
            f"kinds={list(self.joint_kinds)})"
        )


def _frame_id(model: Any, name: str) -> int:
    """Id of frame ``name``, preferring a BODY frame when a joint has the same name."""
    ids = [i for i, f in enumerate(model.frames) if f.name == name]
    for i in ids:
        if model.frames[i].type == pin.FrameType.BODY:
            return i
    return ids[0]


def resolve_robot_path(name_or_path: str | os.PathLike[str]) -> tuple[Path, str | None]:
    """URDF path and default end-effector frame for a bundled name, an example-robot-data
    name, or a path."""
    s = str(name_or_path)
    if s in BUNDLED:
        fname, frame = BUNDLED[s]
        return bundled_robot_dir() / fname, frame
    if s in EXAMPLE_ROBOTS:
        rel, frame = EXAMPLE_ROBOTS[s]
        return example_robot_data_dir() / rel, frame
    p = Path(s)
    if p.suffix.lower() in (".urdf", ".xml") or p.exists() or os.sep in s:
        return p, None
    raise unknown("robot", s, [*BUNDLED, *EXAMPLE_ROBOTS])


def load_robot(name_or_path: str | os.PathLike[str], ee_frame: str | None = None) -> RobotModel:
    """Load a robot by bundled name, ``example-robot-data`` name, or URDF path.

    Args:
        name_or_path: ``"yumi_left"``, ``"loading_manipulator"``, ``"loading_manipulator_long"``,
            an example-robot-data arm (``"panda"``, ``"ur5"``, ``"ur10"``, …; see
            :func:`robot_names`), or a path to a ``.urdf`` file.
        ee_frame: End-effector frame; default: the robot's usual tool frame for named robots,
            the tip of the deepest chain for a file.

    Returns:
        The robot, reduced to the serial chain root → ``ee_frame``.
    """
    path, default_frame = resolve_robot_path(name_or_path)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return RobotModel.from_urdf(path, ee_frame or default_frame)
