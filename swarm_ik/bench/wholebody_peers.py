"""Whole-body peers of ``swarm-ik bench wholebody``: Talos targets, a judge, placo and pink.

The problem (one per target): the Talos humanoid (``talos_reduced.urdf`` of
``example-robot-data``, a free-flyer base) must put both soles flat at their poses, both
hands (``gripper_left_base_link``, ``gripper_right_base_link``) at 6-D poses, keep its centre
of mass (CoM) over the support polygon (the convex hull of the two sole rectangles), its
joints within their limits and the torso joints at given (locked) values.

* :func:`talos_wholebody_targets` draws the targets: the torso and arm joints uniformly
  within their limits, the legs in the reference posture (:data:`LEG_POSTURE`), the base
  placed so that both soles lie flat on the ground ``z = 0``; a draw is kept when its CoM's
  ground projection lies inside the support polygon (so a balanced solution exists: the
  generating configuration).
* :func:`judge_wholebody` judges any full configuration with Pinocchio alone.
* :func:`run_placo` solves them with placo's ``KinematicsSolver`` in placo's own virtual
  environment (:func:`placo_env`; placo's wheel pins an older ``pin`` and ``numpy`` than
  swarm_ik's), through the worker script ``_placo_worker.py`` and ``.npz`` files.
* :func:`run_pink` solves them with pink (``pin-pink``, in swarm_ik's own environment: the
  ``bench`` and ``test`` extras already list it).

Every configuration is in Pinocchio's free-flyer convention ``[x y z qx qy qz qw, joints...]``
(``nq = 39`` for Talos), the joints in the order of the model Pinocchio builds from the URDF
with ``JointModelFreeFlyer`` (:attr:`WholebodyTargets.joint_names`).

Measured once (500 targets, seed 1, one start each from the reference posture, judged at
1e-5; 2 shared CPU cores): placo 0.10.2 76.8 % success, median 3.2 ms, p95 11 ms per
target; pink 4.4 (CoM as a limit) 80.0 %, 7.2 ms, 30 ms; pink with a ``ComTask`` 75.2 %,
8.8 ms, 43 ms.  No false claim of convergence by either.  The failures are local: from the
one start, the steps stall with a hand (and, after large steps, a sole) away from its goal.
"""

from __future__ import annotations

import functools
import inspect
import os
import shutil
import subprocess
import sys
import tempfile
import time
import warnings
from dataclasses import dataclass, field
from importlib.metadata import version
from pathlib import Path
from typing import Any

import numpy as np

from swarm_ik.errors import InvalidArgumentError, SwarmIKError
from swarm_ik.paths import cache_dir, example_robot_data_dir

TALOS_URDF = "talos_data/robots/talos_reduced.urdf"
"""The robot, relative to :func:`swarm_ik.paths.example_robot_data_dir`."""
SOLE_FRAMES = ("left_sole_link", "right_sole_link")
"""Sole frames (at the bottom of the feet, z up when flat)."""
HAND_FRAMES = ("gripper_left_base_link", "gripper_right_base_link")
"""Hand frames with 6-D goals."""
LOCKED_JOINTS = ("torso_1_joint", "torso_2_joint")
"""Joints held at their drawn values (the solvers may not move them)."""
ARM_JOINTS = tuple(f"arm_{side}_{i}_joint" for side in ("left", "right") for i in range(1, 8))
"""Arm joints, drawn at random with the torso."""
DRAWN_JOINTS = LOCKED_JOINTS + ARM_JOINTS
"""Joints drawn uniformly within their limits by :func:`talos_wholebody_targets`."""
LEG_POSTURE = {
    f"leg_{side}_{i}_joint": v
    for side in ("left", "right")
    for i, v in zip(range(1, 7), (0.0, 0.0, -0.411354, 0.859395, -0.448041, 0.0), strict=True)
}
"""The legs' posture [rad]: the ``half_sitting`` state of ``talos_data/srdf/talos.srdf``
with the ankle roll (``leg_*_6_joint``) at 0 instead of -0.001708, so that both soles are
exactly flat and level (hip, knee and ankle pitch sum to zero)."""
ARM_POSTURE = {
    "arm_left_1_joint": 0.25847,
    "arm_left_2_joint": 0.173046,
    "arm_left_3_joint": -0.0002,
    "arm_left_4_joint": -0.525366,
    "arm_left_7_joint": 0.1,
    "arm_right_1_joint": -0.25847,
    "arm_right_2_joint": -0.173046,
    "arm_right_3_joint": 0.0002,
    "arm_right_4_joint": -0.525366,
    "arm_right_7_joint": 0.1,
}
"""The arms of ``half_sitting`` [rad] (the start configuration's arms; others at 0)."""
SOLE_SIZE = (0.21, 0.13)
"""Sole rectangle, length (x) by width (y) [m], centred on the sole frame: the foot's box
``0.21 0.13 0.02`` of ``talos_reduced_box.urdf`` (``talos_reduced.urdf`` has a mesh)."""
PLACO_VERSION = "0.10.2"
"""The placo release installed by :func:`placo_env` (the one these adapters were tested
with; its wheel brings ``pin`` 3.8 and ``numpy`` 2.3)."""
_MARKER = ".swarm_ik-placo"


class PeerEnvironmentError(SwarmIKError, RuntimeError):
    """A peer's separate environment cannot be made, or its worker failed."""


# --------------------------------------------------------------------------- model, polygon
def talos_urdf() -> Path:
    """Path of ``talos_reduced.urdf`` in the installed ``example-robot-data``."""
    return example_robot_data_dir() / TALOS_URDF


@functools.lru_cache(maxsize=4)
def _model(path: str) -> Any:
    import pinocchio as pin

    return pin.buildModelFromUrdf(path, pin.JointModelFreeFlyer())


def free_flyer_model(path: str | os.PathLike[str] | None = None) -> Any:
    """The Pinocchio model of a URDF with a free-flyer root (cached; Talos by default)."""
    return _model(str(Path(path) if path is not None else talos_urdf()))


def joint_names(model: Any) -> tuple[str, ...]:
    """The model's joint names after the free flyer, in configuration order."""
    return tuple(str(n) for n in model.names[2:])


def _q_index(model: Any, name: str) -> int:
    if not model.existJointName(name):
        raise InvalidArgumentError(f"no joint {name!r} in the model")
    return int(model.idx_qs[model.getJointId(name)])


def reference_configuration(model: Any | None = None) -> np.ndarray:
    """The reference posture: legs :data:`LEG_POSTURE`, arms :data:`ARM_POSTURE`, the rest 0,
    the base upright with both soles flat on the ground (``z = 0``), the base above the
    origin.

    Returns:
        Configuration ``(nq,)``, free-flyer convention.
    """
    import pinocchio as pin

    model = model if model is not None else free_flyer_model()
    q = pin.neutral(model)
    for name, v in {**LEG_POSTURE, **ARM_POSTURE}.items():
        q[_q_index(model, name)] = v
    data = model.createData()
    pin.framesForwardKinematics(model, data, q)
    q[2] = -float(data.oMf[model.getFrameId(SOLE_FRAMES[0])].translation[2])
    return q


def sole_corners(pose: np.ndarray, size: tuple[float, float] = SOLE_SIZE) -> np.ndarray:
    """Ground projection of a sole rectangle's corners.

    Args:
        pose: Sole frame pose ``(4, 4)``.
        size: Length and width [m].

    Returns:
        Corners ``(4, 2)`` [m].
    """
    hx, hy = 0.5 * size[0], 0.5 * size[1]
    local = np.array([[hx, hy, 0.0], [-hx, hy, 0.0], [-hx, -hy, 0.0], [hx, -hy, 0.0]])
    pose = np.asarray(pose, dtype=float)
    return (local @ pose[:3, :3].T + pose[:3, 3])[:, :2]


def convex_hull(points: np.ndarray) -> np.ndarray:
    """Convex hull of 2-D points, counter-clockwise, no repeated first vertex.

    Args:
        points: ``(m, 2)``.

    Returns:
        Vertices ``(k, 2)``.

    >>> convex_hull(np.array([[0, 0], [1, 0], [1, 1], [0, 1], [0.5, 0.5]])).tolist()
    [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]]
    """
    pts = sorted({(float(x), float(y)) for x, y in np.asarray(points, dtype=float)})
    if len(pts) < 3:
        return np.asarray(pts, dtype=float).reshape(-1, 2)

    def cross(o: tuple[float, float], a: tuple[float, float], b: tuple[float, float]) -> float:
        return (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])

    lower: list[tuple[float, float]] = []
    for p in pts:
        while len(lower) >= 2 and cross(lower[-2], lower[-1], p) <= 0:
            lower.pop()
        lower.append(p)
    upper: list[tuple[float, float]] = []
    for p in reversed(pts):
        while len(upper) >= 2 and cross(upper[-2], upper[-1], p) <= 0:
            upper.pop()
        upper.append(p)
    return np.asarray(lower[:-1] + upper[:-1], dtype=float)


def support_polygon(left_sole: np.ndarray, right_sole: np.ndarray) -> np.ndarray:
    """Support polygon of two flat feet: the convex hull of both sole rectangles
    (:data:`SOLE_SIZE`), counter-clockwise, ``(k, 2)`` [m]."""
    return convex_hull(np.vstack([sole_corners(left_sole), sole_corners(right_sole)]))


def polygon_margin(point: np.ndarray, polygon: np.ndarray) -> float:
    """Signed distance [m] of a 2-D point inside a convex counter-clockwise polygon: the
    smallest distance to an edge's line, positive inside, negative outside.

    >>> polygon_margin(np.array([0.5, 0.25]), np.array([[0, 0], [1, 0], [1, 1], [0, 1]]))
    0.25
    """
    a = np.asarray(polygon, dtype=float)
    e = np.roll(a, -1, axis=0) - a
    n = np.stack([-e[:, 1], e[:, 0]], axis=1) / np.linalg.norm(e, axis=1)[:, None]
    return float(np.min(np.sum(n * (np.asarray(point, dtype=float)[:2] - a), axis=1)))


# --------------------------------------------------------------------------- targets
@dataclass(frozen=True)
class WholebodyTargets:
    """``n`` whole-body problems on one robot.

    Attributes:
        model_path: The URDF (read with a free-flyer root).
        joint_names: Joint order of the configurations' joint part ``(nq - 7,)``.
        left_sole: Left sole goal poses ``(n, 4, 4)`` [m].
        right_sole: Right sole goal poses ``(n, 4, 4)``.
        left_hand: Left hand (``gripper_left_base_link``) goal poses ``(n, 4, 4)``.
        right_hand: Right hand goal poses ``(n, 4, 4)``.
        polygon: Support polygons ``(n, k, 2)`` [m], counter-clockwise.
        locked: Values of :data:`LOCKED_JOINTS` ``(n, 2)`` [rad].
        com: CoM of the generating configurations ``(n, 3)`` [m].
        q_gen: Generating configurations ``(n, nq)`` (one solution each).
        q0: Start configurations ``(n, nq)``: :func:`reference_configuration` with the
            locked joints at their values.
    """

    model_path: str
    joint_names: tuple[str, ...]
    left_sole: np.ndarray
    right_sole: np.ndarray
    left_hand: np.ndarray
    right_hand: np.ndarray
    polygon: np.ndarray
    locked: np.ndarray
    com: np.ndarray
    q_gen: np.ndarray
    q0: np.ndarray

    @property
    def n(self) -> int:
        """Number of targets."""
        return int(self.q0.shape[0])

    def subset(self, index: Any) -> WholebodyTargets:
        """The targets at ``index`` (a slice or an index array)."""
        keep = {"model_path", "joint_names"}
        kw = {
            k: (v if k in keep else np.asarray(v)[index])
            for k, v in self.__dict__.items()
            if not k.startswith("_")
        }
        return WholebodyTargets(**kw)


def talos_wholebody_targets(
    n: int,
    rng: np.random.Generator | int | None = None,
    *,
    com_margin: float = 0.0,
    max_draws: int | None = None,
) -> WholebodyTargets:
    """Draw ``n`` reachable, balanced Talos whole-body problems.

    Each draw: :func:`reference_configuration` with :data:`DRAWN_JOINTS` (torso and arms)
    uniform within their limits; kept when the CoM's ground projection is at least
    ``com_margin`` inside the support polygon.  The draws are one at a time from ``rng``, so
    the first ``k`` targets do not depend on ``n``.

    Args:
        n: Number of targets.
        rng: A ``numpy.random.Generator`` or a seed.
        com_margin: Smallest distance of a kept CoM inside the polygon [m].
        max_draws: Most draws before giving up (default ``100 * n + 100``).

    Returns:
        The targets.

    Raises:
        InvalidArgumentError: ``n < 1``, or too few draws were balanced.
    """
    import pinocchio as pin

    if int(n) < 1:
        raise InvalidArgumentError(f"n must be at least 1, got {n}")
    rng = rng if isinstance(rng, np.random.Generator) else np.random.default_rng(rng)
    path = str(talos_urdf())
    model = free_flyer_model(path)
    data = model.createData()
    q_ref = reference_configuration(model)
    idx = np.array([_q_index(model, j) for j in DRAWN_JOINTS])
    lo, hi = model.lowerPositionLimit[idx], model.upperPositionLimit[idx]
    fids = [model.getFrameId(f) for f in SOLE_FRAMES + HAND_FRAMES]
    limit = int(max_draws) if max_draws is not None else 100 * int(n) + 100
    rows: list[tuple[np.ndarray, list[np.ndarray], np.ndarray, np.ndarray]] = []
    draws = 0
    while len(rows) < int(n):
        if draws >= limit:
            raise InvalidArgumentError(
                f"only {len(rows)} of {draws} draws had their CoM {com_margin} m inside the "
                f"support polygon; {n} asked"
            )
        draws += 1
        q = q_ref.copy()
        q[idx] = rng.uniform(lo, hi)
        pin.framesForwardKinematics(model, data, q)
        com = np.array(pin.centerOfMass(model, data, q, False), dtype=float)
        poses = [np.array(data.oMf[f].homogeneous, dtype=float) for f in fids]
        poly = support_polygon(poses[0], poses[1])
        if polygon_margin(com[:2], poly) >= com_margin:
            rows.append((q, poses, poly, com))
    q_gen = np.stack([r[0] for r in rows])
    lk = np.array([_q_index(model, j) for j in LOCKED_JOINTS])
    q0 = np.tile(q_ref, (len(rows), 1))
    q0[:, lk] = q_gen[:, lk]
    return WholebodyTargets(
        model_path=path,
        joint_names=joint_names(model),
        left_sole=np.stack([r[1][0] for r in rows]),
        right_sole=np.stack([r[1][1] for r in rows]),
        left_hand=np.stack([r[1][2] for r in rows]),
        right_hand=np.stack([r[1][3] for r in rows]),
        polygon=np.stack([r[2] for r in rows]),
        locked=q_gen[:, lk].copy(),
        com=np.stack([r[3] for r in rows]),
        q_gen=q_gen,
        q0=q0,
    )


# --------------------------------------------------------------------------- judge
@dataclass(frozen=True)
class WholebodyJudgement:
    """Per-target verdict of :func:`judge_wholebody` (NaN errors where ``q`` is not finite).

    Attributes:
        success: Every check passed ``(n,)``.
        sole_pos: Sole position errors ``(n, 2)`` [m] (left, right).
        sole_rot: Sole rotation errors ``(n, 2)`` [rad] (angle of ``R_goalᵀ R``).
        hand_pos: Hand position errors ``(n, 2)`` [m].
        hand_rot: Hand rotation errors ``(n, 2)`` [rad].
        com_margin: Signed distance of the CoM's ground projection inside the support
            polygon ``(n,)`` [m] (negative: outside).
        limit_excess: Largest excursion of a joint beyond its limits ``(n,)`` [rad or m]
            (0 when within).
        locked_err: Largest deviation of a locked joint from its value ``(n,)`` [rad].
        quat_err: ``|‖quaternion‖ - 1|`` of the base ``(n,)``.
        tol: The tolerance used.
    """

    success: np.ndarray
    sole_pos: np.ndarray
    sole_rot: np.ndarray
    hand_pos: np.ndarray
    hand_rot: np.ndarray
    com_margin: np.ndarray
    limit_excess: np.ndarray
    locked_err: np.ndarray
    quat_err: np.ndarray
    tol: float


def judge_wholebody(
    model_path: str | os.PathLike[str],
    q_full: np.ndarray,
    targets: WholebodyTargets,
    tol: float = 1e-5,
) -> WholebodyJudgement:
    """Judge full configurations against whole-body targets, with Pinocchio alone.

    A target succeeds when ``q`` is finite, its base quaternion has unit norm (to 1e-6; it is
    normalised before the kinematics), each sole and hand is within ``tol`` of its goal in
    position [m] and rotation angle [rad], the CoM's ground projection is inside the support
    polygon (signed distance ≥ ``-tol``), every joint is within its limits (to ``tol``) and
    each locked joint is within ``tol`` of its value.

    Args:
        model_path: The URDF, read with a free-flyer root; its joint order must be
            ``targets.joint_names``.
        q_full: Configurations ``(n, nq)`` (or one ``(nq,)`` when ``n == 1``), free-flyer
            convention.
        targets: The problems.
        tol: Tolerance [m and rad].

    Returns:
        The verdict per target.

    Raises:
        InvalidArgumentError: Shapes or joint order do not match.
    """
    import pinocchio as pin

    model = free_flyer_model(model_path)
    if joint_names(model) != tuple(targets.joint_names):
        raise InvalidArgumentError("the model's joint order is not the targets' joint order")
    q_all = np.atleast_2d(np.asarray(q_full, dtype=float))
    n = targets.n
    if q_all.shape != (n, model.nq):
        raise InvalidArgumentError(f"q_full has shape {q_all.shape}; expected {(n, model.nq)}")
    data = model.createData()
    fids = [model.getFrameId(f) for f in SOLE_FRAMES + HAND_FRAMES]
    lk = np.array([_q_index(model, j) for j in LOCKED_JOINTS])
    lo, hi = model.lowerPositionLimit[7:], model.upperPositionLimit[7:]
    pos = np.full((n, 4), np.nan)
    rot = np.full((n, 4), np.nan)
    com_m = np.full(n, np.nan)
    excess = np.full(n, np.nan)
    locked_err = np.full(n, np.nan)
    quat_err = np.full(n, np.nan)
    goals = [targets.left_sole, targets.right_sole, targets.left_hand, targets.right_hand]
    for i in range(n):
        q = q_all[i].copy()
        if not np.all(np.isfinite(q)):
            continue
        qn = float(np.linalg.norm(q[3:7]))
        quat_err[i] = abs(qn - 1.0)
        if qn == 0.0:
            continue
        q[3:7] /= qn
        pin.framesForwardKinematics(model, data, q)
        for k, (f, g) in enumerate(zip(fids, goals, strict=True)):
            m = data.oMf[f]
            t = np.asarray(g[i], dtype=float)
            pos[i, k] = np.linalg.norm(m.translation - t[:3, 3])
            rot[i, k] = np.linalg.norm(pin.log3(t[:3, :3].T @ m.rotation))
        com = pin.centerOfMass(model, data, q, False)
        com_m[i] = polygon_margin(np.asarray(com)[:2], targets.polygon[i])
        excess[i] = max(0.0, float(np.max(np.maximum(lo - q[7:], q[7:] - hi))))
        locked_err[i] = float(np.max(np.abs(q[lk] - targets.locked[i])))
    with np.errstate(invalid="ignore"):
        ok = (
            (quat_err <= 1e-6)
            & np.all(pos <= tol, axis=1)
            & np.all(rot <= tol, axis=1)
            & (com_m >= -tol)
            & (excess <= tol)
            & (locked_err <= tol)
        )
    return WholebodyJudgement(
        success=ok,
        sole_pos=pos[:, :2],
        sole_rot=rot[:, :2],
        hand_pos=pos[:, 2:],
        hand_rot=rot[:, 2:],
        com_margin=com_m,
        limit_excess=excess,
        locked_err=locked_err,
        quat_err=quat_err,
        tol=float(tol),
    )


# --------------------------------------------------------------------------- answers
@dataclass(frozen=True)
class PeerAnswers:
    """A peer's answers to :class:`WholebodyTargets`.

    Attributes:
        name: The peer.
        q: Configurations ``(n, nq)``, free-flyer convention, the targets' joint order (NaN
            rows: the peer raised).
        time_s: Wall-clock seconds of each call ``(n,)``: the solver and its tasks built from
            the target, every iteration (the model is loaded once, outside).
        solve_s: Seconds of the iterations alone ``(n,)``.
        converged: The peer's own success flag ``(n,)``.
        iterations: Iterations (QP steps) ``(n,)``.
        errors: The exception text per target (``""`` when none).
        versions: Library versions used.
    """

    name: str
    q: np.ndarray
    time_s: np.ndarray
    solve_s: np.ndarray
    converged: np.ndarray
    iterations: np.ndarray
    errors: tuple[str, ...]
    versions: dict[str, str] = field(default_factory=dict)


def summarize(judged: WholebodyJudgement, answers: PeerAnswers) -> dict[str, float]:
    """Success rate and times of one peer on one set of targets.

    Returns:
        ``n``, ``success`` (fraction judged successful), ``claimed`` (fraction the peer
        called converged), ``false_claims`` (claimed but judged failed), ``median_s`` and
        ``p95_s`` (of :attr:`PeerAnswers.time_s` over every target), ``median_iterations``.
    """
    t = np.asarray(answers.time_s, dtype=float)
    return {
        "n": float(judged.success.size),
        "success": float(np.mean(judged.success)),
        "claimed": float(np.mean(answers.converged)),
        "false_claims": float(np.sum(answers.converged & ~judged.success)),
        "median_s": float(np.nanmedian(t)),
        "p95_s": float(np.nanpercentile(t, 95)),
        "median_iterations": float(np.median(answers.iterations)),
    }


# --------------------------------------------------------------------------- placo
def default_placo_env_dir() -> Path:
    """``$SWARM_IK_PLACO_ENV`` when set, else ``<swarm_ik cache>/placo-<version>-py<major><minor>``
    (:func:`swarm_ik.paths.cache_dir`)."""
    env = os.environ.get("SWARM_IK_PLACO_ENV")
    if env:
        return Path(env)
    v = sys.version_info
    return cache_dir() / f"placo-{PLACO_VERSION}-py{v.major}{v.minor}"


def venv_python(env: Path) -> Path:
    """The Python executable of a virtual environment."""
    if os.name == "nt":  # pragma: no cover
        return Path(env) / "Scripts" / "python.exe"
    return Path(env) / "bin" / "python"


def _ready(env: Path) -> bool:
    marker = env / _MARKER
    return (
        venv_python(env).exists()
        and marker.is_file()
        and marker.read_text().strip() == PLACO_VERSION
    )


def _run_step(cmd: list[str], what: str, env_dir: Path, timeout_s: float) -> None:
    try:
        r = subprocess.run(
            cmd, capture_output=True, text=True, timeout=timeout_s, env=_clean_environ()
        )
    except (OSError, subprocess.TimeoutExpired) as exc:
        raise PeerEnvironmentError(
            f"could not create the placo environment at {env_dir}: {what} failed ({exc})"
        ) from exc
    if r.returncode != 0:
        lines = [ln.strip() for ln in (r.stdout + "\n" + r.stderr).splitlines() if ln.strip()]
        errors = [ln for ln in lines if ln.startswith("ERROR")]
        last = (errors or lines or [f"exit status {r.returncode}"])[-1]
        raise PeerEnvironmentError(
            f"could not create the placo environment at {env_dir}: {what} failed ({last})"
        )


def _clean_environ() -> dict[str, str]:
    """This process's environment without the variables that would mix the main
    environment's packages into another interpreter's."""
    drop = {"PYTHONPATH", "PYTHONHOME", "PYTHONSTARTUP", "VIRTUAL_ENV", "PIP_REQUIRE_VIRTUALENV"}
    return {k: v for k, v in os.environ.items() if k not in drop}


def placo_env(
    path: Path | str | None = None, *, create: bool = True, timeout_s: float = 1800.0
) -> Path:
    """placo's own virtual environment, made on first use and reused after.

    Made with ``python -m venv`` (this interpreter's version) and ``pip install
    placo==PLACO_VERSION`` in a temporary sibling folder, checked (``import placo,
    pinocchio``), marked, then renamed into place, so that a half-made environment is never
    used.  Nothing is installed into swarm_ik's environment.

    Args:
        path: Folder of the environment (default :func:`default_placo_env_dir`).
        create: Make it when missing (else raise).
        timeout_s: Limit of each step (venv, pip, check) [s].

    Returns:
        The environment's folder (its interpreter: :func:`venv_python`).

    Raises:
        PeerEnvironmentError: It is missing and ``create`` is false, or it cannot be made
            (no network, pip failed, no wheel for this platform).
    """
    env = Path(path) if path is not None else default_placo_env_dir()
    if _ready(env):
        return env
    if not create:
        raise PeerEnvironmentError(
            f"no placo environment at {env}; make it with "
            "swarm_ik.bench.wholebody_peers.placo_env() (needs pip and the network)"
        )
    try:
        env.parent.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise PeerEnvironmentError(
            f"could not create the placo environment at {env}: {exc}"
        ) from exc
    tmp = env.parent / f".{env.name}.tmp-{os.getpid()}"
    shutil.rmtree(tmp, ignore_errors=True)
    try:
        _run_step([sys.executable, "-m", "venv", str(tmp)], "python -m venv", env, timeout_s)
        py = str(venv_python(tmp))
        pip = [py, "-m", "pip", "install", "--disable-pip-version-check", "--no-input"]
        _run_step(
            [*pip, f"placo=={PLACO_VERSION}"], f"pip install placo=={PLACO_VERSION}", env, timeout_s
        )
        _run_step([py, "-c", "import placo, pinocchio"], "import placo", env, timeout_s)
        (tmp / _MARKER).write_text(PLACO_VERSION + "\n")
        if env.exists():  # a half-made or older one: replaced
            if _ready(env):  # made meanwhile by another process
                return env
            shutil.rmtree(env)
        try:
            os.rename(tmp, env)
        except OSError:
            if not _ready(env):
                raise
    except OSError as exc:
        raise PeerEnvironmentError(
            f"could not create the placo environment at {env}: {exc}"
        ) from exc
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    return env


def write_problems(
    path: Path,
    targets: WholebodyTargets,
    *,
    time_limit: float,
    max_iterations: int,
    stop_tol: float,
    com_margin: float,
    regularization: float,
) -> Path:
    """Write the worker's input ``.npz`` (see ``_placo_worker.py`` for its arrays)."""
    np.savez(
        path,
        urdf=np.array(str(targets.model_path)),
        joint_names=np.array(targets.joint_names, dtype=str),
        sole_frames=np.array(SOLE_FRAMES, dtype=str),
        hand_frames=np.array(HAND_FRAMES, dtype=str),
        locked_joints=np.array(LOCKED_JOINTS, dtype=str),
        left_sole=targets.left_sole,
        right_sole=targets.right_sole,
        left_hand=targets.left_hand,
        right_hand=targets.right_hand,
        polygon=targets.polygon,
        q0=targets.q0,
        settings=np.array(
            [time_limit, max_iterations, stop_tol, com_margin, regularization], dtype=float
        ),
    )
    return path


def run_placo(
    targets: WholebodyTargets,
    *,
    env: Path | str | None = None,
    time_limit: float = 1.0,
    max_iterations: int = 300,
    stop_tol: float = 1e-6,
    com_margin: float = 0.0,
    regularization: float = 1e-3,
    timeout_s: float | None = None,
) -> PeerAnswers:
    """Solve the targets with placo's ``KinematicsSolver`` in placo's own environment.

    Writes the problems to an ``.npz`` file, runs ``_placo_worker.py`` with the environment's
    Python (settings documented there), reads the answers back.

    Args:
        targets: The problems.
        env: placo's environment (default :func:`placo_env`'s, made when missing).
        time_limit: Time limit of one target [s].
        max_iterations: Most QP steps per target.
        stop_tol: placo stops when every sole and hand error is within it [m, rad].
        com_margin: Margin of placo's CoM polygon constraint [m].
        regularization: Weight of placo's regularisation task (0: none).
        timeout_s: Limit of the whole subprocess [s] (default ``120 + n * (time_limit +
            0.5)``).

    Returns:
        placo's answers (``name = "placo"``).

    Raises:
        PeerEnvironmentError: The environment cannot be made, or the worker failed or ran
            past ``timeout_s``.
    """
    env_dir = placo_env(env)
    worker = Path(__file__).with_name("_placo_worker.py")
    limit = timeout_s if timeout_s is not None else 120.0 + targets.n * (time_limit + 0.5)
    with tempfile.TemporaryDirectory(prefix="swarm_ik-placo-") as d:
        src, dst = Path(d) / "problems.npz", Path(d) / "answers.npz"
        write_problems(
            src,
            targets,
            time_limit=time_limit,
            max_iterations=max_iterations,
            stop_tol=stop_tol,
            com_margin=com_margin,
            regularization=regularization,
        )
        cmd = [str(venv_python(env_dir)), str(worker), str(src), str(dst)]
        try:
            r = subprocess.run(
                cmd, capture_output=True, text=True, timeout=limit, env=_clean_environ(), cwd=d
            )
        except subprocess.TimeoutExpired as exc:
            raise PeerEnvironmentError(f"the placo worker ran past {limit:.0f} s") from exc
        if r.returncode != 0 or not dst.exists():
            lines = [ln for ln in r.stderr.splitlines() if ln.strip()]
            last = lines[-1].strip() if lines else f"exit status {r.returncode}"
            raise PeerEnvironmentError(f"the placo worker failed: {last}")
        with np.load(dst, allow_pickle=False) as f:
            ans = {k: f[k] for k in f.files}
    return PeerAnswers(
        name="placo",
        q=ans["q"],
        time_s=ans["time_s"],
        solve_s=ans["solve_s"],
        converged=ans["converged"].astype(bool),
        iterations=ans["iterations"],
        errors=tuple(str(e) for e in ans["error"]),
        versions={"placo": str(ans["versions"][0]), "pinocchio": str(ans["versions"][1])},
    )


# --------------------------------------------------------------------------- pink
class _CoMPolygonLimit:
    """pink limit keeping the CoM's ground projection in a convex polygon.

    The linearised constraint ``nᵢ·(c + J_c Δq - aᵢ) ≥ margin`` for each edge (``aᵢ`` its
    first vertex, ``nᵢ`` its inward unit normal), returned as pink's ``G Δq ≤ h``.
    """

    def __init__(self, model: Any, polygon: np.ndarray, margin: float) -> None:
        a = np.asarray(polygon, dtype=float)
        e = np.roll(a, -1, axis=0) - a
        self.normals = np.stack([-e[:, 1], e[:, 0]], axis=1) / np.linalg.norm(e, axis=1)[:, None]
        self.offsets = np.sum(self.normals * a, axis=1) + float(margin)
        self.model = model
        self.data = model.createData()

    def compute_qp_inequalities(
        self, configuration: Any, dt: float
    ) -> tuple[np.ndarray, np.ndarray]:
        import pinocchio as pin

        jac = pin.jacobianCenterOfMass(self.model, self.data, configuration.q, False)
        com = self.data.com[0]
        g = -self.normals @ jac[:2]
        h = self.normals @ com[:2] - self.offsets
        return g, h


def _inside_target(com: np.ndarray, polygon: np.ndarray, margin: float) -> np.ndarray:
    """The CoM's ``(x, y)`` moved toward the polygon's vertex mean until it is ``margin``
    inside (unchanged when already inside)."""
    a = np.asarray(polygon, dtype=float)
    e = np.roll(a, -1, axis=0) - a
    n = np.stack([-e[:, 1], e[:, 0]], axis=1) / np.linalg.norm(e, axis=1)[:, None]
    b = np.sum(n * a, axis=1) + margin
    g = a.mean(axis=0)
    d = com[:2] - g
    s = 1.0
    for ni, bi in zip(n, b, strict=True):
        nd = float(ni @ d)
        if nd < 0:
            s = min(s, max(0.0, float(ni @ g - bi)) / -nd)
    return g + s * d


def run_pink(
    targets: WholebodyTargets,
    *,
    time_limit: float = 1.0,
    max_iterations: int = 300,
    stop_tol: float = 1e-6,
    com: str = "limit",
    com_margin: float = 0.0,
    solver: str = "quadprog",
    damping: float = 1e-12,
    config_limit_gain: float = 0.5,
) -> PeerAnswers:
    """Solve the targets with pink (differential IK iterated to convergence).

    Per target: the model reduced with the locked joints fixed at their values
    (``pin.buildReducedModel``: pink has no DoF mask); ``FrameTask``\\ s (position and
    orientation costs 1) on the soles as hard equality ``constraints`` and on the hands as
    costs; pink's ``ConfigurationLimit`` (gain ``config_limit_gain``); the CoM by ``com``:

    * ``"limit"``: a hard inequality keeping the linearised CoM in the polygon (a pink
      ``Limit``: ``compute_qp_inequalities``), as placo's CoM polygon constraint;
    * ``"task"``: pink's ``ComTask`` (cost 1 on x and y, 0 on z) whose target is the CoM
      itself when inside the polygon, else the CoM moved toward the polygon's centre until
      it is inside (updated every step).

    Each step ``solve_ik(dt = 1)`` (quadprog), integrated; it stops when every sole and hand
    error is within ``stop_tol`` and the CoM inside, when the largest error has not fallen by
    0.1 % over 20 steps, or at the iteration or time limit.

    Args:
        targets: The problems.
        time_limit: Time limit of one target [s].
        max_iterations: Most QP steps per target.
        stop_tol: Stop tolerance [m, rad].
        com: ``"limit"`` or ``"task"``.
        com_margin: Margin inside the polygon [m].
        solver: QP solver of ``qpsolvers``.
        damping: pink's Tikhonov damping.
        config_limit_gain: Gain of pink's configuration limit (0, 1].

    Returns:
        pink's answers (``name = "pink"`` or ``"pink-comtask"``).

    Raises:
        InvalidArgumentError: ``com`` is neither ``"limit"`` nor ``"task"``.
        PeerEnvironmentError: pink is older than 3.3 (no hard ``constraints``).
    """
    import pink
    import pinocchio as pin
    from pink.limits import ConfigurationLimit
    from pink.tasks import ComTask, FrameTask

    if com not in ("limit", "task"):
        raise InvalidArgumentError(f"com must be 'limit' or 'task', got {com!r}")
    if "constraints" not in inspect.signature(pink.solve_ik).parameters:
        raise PeerEnvironmentError(
            f"run_pink needs pink >= 3.3 (solve_ik's hard constraints); "
            f"pin-pink {version('pin-pink')} is installed"
        )
    full = free_flyer_model(targets.model_path)
    locked_ids = [full.getJointId(j) for j in LOCKED_JOINTS]
    lk = np.array([_q_index(full, j) for j in LOCKED_JOINTS])
    keep = np.setdiff1d(np.arange(full.nq), lk)
    n = targets.n
    q_out = np.full((n, full.nq), np.nan)
    time_s = np.full(n, np.nan)
    solve_s = np.full(n, np.nan)
    converged = np.zeros(n, dtype=bool)
    iterations = np.zeros(n, dtype=np.int64)
    errors = [""] * n
    frames = SOLE_FRAMES + HAND_FRAMES
    for i in range(n):
        t_call = time.perf_counter()
        q0 = targets.q0[i].copy()
        q0[lk] = targets.locked[i]
        model = pin.buildReducedModel(full, locked_ids, q0)
        data = model.createData()
        goals = [targets.left_sole[i], targets.right_sole[i]]
        goals += [targets.left_hand[i], targets.right_hand[i]]
        tasks = []
        for f, g in zip(frames, goals, strict=True):
            task = FrameTask(f, position_cost=1.0, orientation_cost=1.0)
            task.set_target(pin.SE3(np.asarray(g, dtype=float)))
            tasks.append(task)
        limits: list[Any] = [ConfigurationLimit(model, config_limit_gain)]
        com_task = None
        if com == "limit":
            limits.append(_CoMPolygonLimit(model, targets.polygon[i], com_margin))
        else:
            com_task = ComTask(cost=np.array([1.0, 1.0, 0.0]))
        conf = pink.Configuration(model, data, q0[keep])
        fids = [model.getFrameId(f) for f in frames]
        history: list[float] = []
        steps = 0
        ok = False
        t0 = time.perf_counter()
        try:
            while True:
                err = 0.0
                for fid, g in zip(fids, goals, strict=True):
                    m = conf.data.oMf[fid]
                    err = max(err, float(np.linalg.norm(m.translation - g[:3, 3])))
                    err = max(err, float(np.linalg.norm(pin.log3(g[:3, :3].T @ m.rotation))))
                c = np.asarray(pin.centerOfMass(model, conf.data, conf.q, False))
                inside = polygon_margin(c[:2], targets.polygon[i]) >= com_margin - 1e-9
                if err <= stop_tol and inside:
                    ok = True
                    break
                history.append(err)
                if len(history) > 20 and err > (1 - 1e-3) * history[-21]:
                    break
                if steps >= max_iterations or time.perf_counter() - t0 >= time_limit:
                    break
                cost_tasks = tasks[2:]
                if com_task is not None:
                    xy = _inside_target(c, targets.polygon[i], com_margin)
                    com_task.set_target(np.array([xy[0], xy[1], c[2]]))
                    cost_tasks = [*cost_tasks, com_task]
                with warnings.catch_warnings():
                    warnings.simplefilter("ignore")
                    v = pink.solve_ik(
                        conf,
                        cost_tasks,
                        1.0,
                        solver=solver,
                        damping=damping,
                        limits=limits,
                        constraints=tasks[:2],
                        safety_break=False,
                    )
                conf.integrate_inplace(v, 1.0)
                steps += 1
        except Exception as exc:  # pink's NoSolutionFound, a failed QP: no answer
            errors[i] = f"{type(exc).__name__}: {exc}".replace("\n", " ")[:500]
            time_s[i] = time.perf_counter() - t_call
            iterations[i] = steps
            continue
        solve_s[i] = time.perf_counter() - t0
        q = np.empty(full.nq)
        q[keep] = conf.q
        q[lk] = targets.locked[i]
        q_out[i] = q
        time_s[i] = time.perf_counter() - t_call
        converged[i], iterations[i] = ok, steps
    return PeerAnswers(
        name="pink" if com == "limit" else "pink-comtask",
        q=q_out,
        time_s=time_s,
        solve_s=solve_s,
        converged=converged,
        iterations=iterations,
        errors=tuple(errors),
        versions={"pink": version("pin-pink"), "pinocchio": pin.__version__},
    )
