"""IKProblem: a robot, its goals, a scalar cost for the swarm solvers, the search bounds, and
the one success judge.

>>> import swarm_ik
>>> robot = swarm_ik.load_robot("baxter")             # goal frames: both grippers
>>> q = robot.mid_q() + 0.2
>>> left, right = robot.fk_all(q)
>>> problem = swarm_ik.IKProblem(robot, goals=[swarm_ik.goals.Pose("left_gripper", left),
...                                            swarm_ik.goals.Pose("right_gripper", right)])
>>> swarm_ik.solve(problem, seed=0).success
True
"""

from __future__ import annotations

import dataclasses
import functools
import math
import threading
import warnings
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numba
import numpy as np
from numpy.typing import NDArray

from swarm_ik._types import FloatArray
from swarm_ik._validate import keywords_checked, quoted_error, user_stacklevel
from swarm_ik.errors import (
    GoalWarning,
    InvalidArgumentError,
    InvalidTargetError,
    SwarmIKError,
    unknown,
)
from swarm_ik.fitness import FITNESS, get_fitness
from swarm_ik.goals import AvoidCollisions, Goal, Pose, Position, State, kernel_slot, kernels
from swarm_ik.goals import base as goals_base
from swarm_ik.kernels import joints, lm
from swarm_ik.pose import ORTH_TOL, as_pose, check_tolerances, is_finite_nonneg
from swarm_ik.robot import RobotModel

SECONDARY_WEIGHT = 1e-3
"""Weight of the secondary goals' cost (½‖r₂‖²) in the scalar cost of the swarm solvers."""


def _same_details(a: Any, b: Any) -> bool:
    """Whether two goal reports' ``details`` (or errors) are equal: the same object, equal,
    both NaN, or equal arrays (a Python goal's ``met`` may report anything)."""
    if a is b:
        return True
    if isinstance(a, float) and isinstance(b, float):
        return a == b or (math.isnan(a) and math.isnan(b))
    if isinstance(a, dict) and isinstance(b, dict):
        return a.keys() == b.keys() and all(_same_details(a[k], b[k]) for k in a)
    if isinstance(a, (list, tuple)) and type(a) is type(b):
        return len(a) == len(b) and all(map(_same_details, a, b))
    if isinstance(a, np.ndarray) or isinstance(b, np.ndarray):
        try:
            return bool(np.array_equal(a, b, equal_nan=True))
        except TypeError:  # (not numbers: NaN has no meaning there)
            return bool(np.array_equal(a, b))
    try:
        return bool(a == b)
    except (ValueError, TypeError):  # (no single truth value)
        return False


@dataclass(frozen=True, eq=False)
class GoalError:
    """How far one primary goal is from being met, computed with Pinocchio.

    Attributes:
        goal: Label, e.g. ``"Pose(left_gripper)"``.
        position_error: Position error [m] (NaN when the goal has none).
        rotation_error: Angular error [rad] (NaN when the goal has none).
        met: Within the tolerances of the solve (collisions: the exact check finds no
            contact).
        details: Goal-specific report (``AvoidCollisions``: the
            :class:`swarm_ik.collision.CollisionReport` with clearance and pairs in contact).
    """

    goal: str
    position_error: float
    rotation_error: float
    met: bool
    details: Any = None

    def __eq__(self, other: object) -> bool:
        """Equal to a report of the same goal, numbers and verdict (a NaN error, a goal
        without such an error, equal to NaN: two checks of one answer are equal)."""
        if not isinstance(other, GoalError):
            return NotImplemented
        return (
            self.goal == other.goal
            and _same_details(self.position_error, other.position_error)
            and _same_details(self.rotation_error, other.rotation_error)
            and self.met == other.met
            and _same_details(self.details, other.details)
        )

    def __hash__(self) -> int:
        return hash((self.goal, self.met))

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready dict (NaN as None)."""

        def num(v: float) -> float | None:
            return None if math.isnan(v) else float(v)

        out: dict[str, Any] = {
            "goal": self.goal,
            "position_error": num(self.position_error),
            "rotation_error": num(self.rotation_error),
            "met": self.met,
        }
        if self.details is not None and hasattr(self.details, "clearance"):
            out["clearance"] = float(self.details.clearance)
            out["pairs_in_contact"] = [list(p) for p in self.details.pairs_in_contact]
        return out


def largest_errors(goal_errors: Sequence[GoalError]) -> tuple[float, float]:
    """Largest position error [m] and angular error [rad] over checked goals (0 where no goal
    has such an error): the summary figures of a :class:`~swarm_ik.result.Result`."""
    if len(goal_errors) == 1:  # (the common case, on every solve's path: no generators)
        e = goal_errors[0]
        return (
            0.0 if math.isnan(e.position_error) else float(e.position_error),
            0.0 if math.isnan(e.rotation_error) else float(e.rotation_error),
        )
    dp = max(
        (e.position_error for e in goal_errors if not math.isnan(e.position_error)), default=0.0
    )
    dr = max(
        (e.rotation_error for e in goal_errors if not math.isnan(e.rotation_error)), default=0.0
    )
    return float(dp), float(dr)


def _tree_with_frames(
    robot: RobotModel, added: list[tuple[int, tuple[Any, Any, Any]]]
) -> tuple[Any, dict[int, int]]:
    """The robot's tree with the frames goals add (collision bodies, centres of mass) after
    its goal frames, and the index of each adding goal's first frame (by the goal's position
    among the compiled goals): made once per robot and set of added frames, so that problems
    of the same goals share one tree (and with it their route, :func:`swarm_ik.api.route_for`).

    Args:
        robot: The robot.
        added: ``(position, (joint ids (k,), rotations (k, 3, 3), translations (k, 3)))`` per
            goal that adds frames (:meth:`Goal.extra_frames`), in goal order.
    """
    key = tuple((i, *(np.asarray(a).tobytes() for a in extra)) for i, extra in added)
    trees = robot._cache.setdefault("trees", {})
    hit = trees.get(key)
    if hit is None:
        t = robot.tree
        joints, rots, poss = [t.frame_joint], [t.frame_rot], [t.frame_pos]
        frame0 = {}
        for i, extra in added:
            frame0[i] = sum(len(j) for j in joints)
            fj, fr, fp = robot.canonical_frames(*extra)
            joints.append(fj)
            rots.append(fr)
            poss.append(fp)
        tree = t.with_frames(np.concatenate(joints), np.concatenate(rots), np.concatenate(poss))
        if len(trees) >= 32:  # (many scenes or goal sets: keep memory bounded)
            trees.clear()
        hit = trees[key] = (tree, frame0)
    return hit[0], dict(hit[1])


TWIN_RTOL = 1e-6
"""Relative tolerance of :func:`_check_kernel_twin` on the rows (against ``1 +`` their
size)."""


def _probe_q(robot: RobotModel) -> FloatArray:
    """The configuration the goals' checks probe: no two joints alike (a residual that
    vanishes where joints are equal, or at the middle of the ranges, would tell neither
    sign), inside the limits."""
    j = np.arange(1, robot.nq + 1)
    frac = 0.25 + 0.5 * ((0.6180339887 * j) % 1.0)
    return _at_fractions(robot, frac, frac - 0.5)


PROBES = 4
"""Configurations beyond the first where a compiled goal's rows are checked
(:func:`_more_probe_qs`): a kernel writing NaN in part of the joint space (half of a torso's
range, say) passed the one probe and made that part a wall the search never said a word
about, where a Python goal's NaN is refused at once."""


def _more_probe_qs(robot: RobotModel, n: int = PROBES) -> list[FloatArray]:
    """``n`` more configurations spread over the joint ranges (a low-discrepancy sequence,
    every joint at another fraction of its range in each, from 5 % to 95 %), where
    :func:`_check_kernel_twin` checks a compiled goal's rows again."""
    j = np.arange(1, robot.nq + 1)
    out = []
    for k in range(1, n + 1):
        frac = 0.05 + 0.9 * ((0.7548776662 * k + 0.5698402910 * j) % 1.0)
        out.append(_at_fractions(robot, frac, 2.0 * frac - 1.0))
    return out


def _at_fractions(robot: RobotModel, frac: Any, unbounded: Any) -> FloatArray:
    """The joint vector at fractions ``frac`` ``(nq,)`` of the joint ranges, ``unbounded``
    [rad, m] on a joint without finite limits, inside the limits."""
    lo, hi = np.asarray(robot.lower, dtype=float), np.asarray(robot.upper, dtype=float)
    finite = np.isfinite(lo) & np.isfinite(hi)
    q = np.where(finite, lo + frac * np.where(finite, hi - lo, 0.0), unbounded)
    return np.asarray(np.clip(q, lo, hi))


JACOBIAN_STEP = 1e-6
"""Step [rad, m] of the central difference :func:`_check_python_jacobian` compares a Python
goal's ``jacobian`` with."""


JACOBIAN_SCALE = (0.75, 1.5)
"""The share of a Python goal's ``jacobian`` along the residual's central difference
(:func:`_check_python_jacobian`) outside which a :class:`~swarm_ik.errors.GoalWarning` says
that it looks scaled: a UR5 goal whose Jacobian was half its derivative met 0 of 10 targets
in 3,000 evaluations (10 of 10 with the exact one), one ten times it none either.  Only a
warning: an approximate Jacobian (a rotation error's first-order one) may still steer."""


_CHECK_LOCK = threading.RLock()
"""Held while a goal class is checked (:func:`_check_python_jacobian`,
:func:`_check_kernel_twin`): a check marks its class as checked before it runs (the probe
problem it makes would check it again), so a second thread making a problem of the class
at the same time skipped the check and took a goal the first then refused."""


def _check_python_jacobian(robot: RobotModel, goal: Goal) -> None:
    """:func:`_check_python_jacobian_now` under :data:`_CHECK_LOCK`."""
    with _CHECK_LOCK:
        _check_python_jacobian_now(robot, goal)


def _check_python_jacobian_now(robot: RobotModel, goal: Goal) -> None:
    """A goal written in Python, checked once per class and robot: its ``jacobian`` along
    one direction at one configuration against the central difference of its ``residual``
    (three residual calls and one Jacobian call, when the first problem of the class is made:
    not under any solve's clock).  A Jacobian of the other sign (the
    kernels' step convention ``−∂r/∂q`` where the protocol asks ``+∂r/∂q``) or zero where the
    residual changes sent the search the wrong way and ended every solve with the budget's
    reason and no word why.  Only the rows the direction changes are compared (a row at rest
    in a dead zone may keep its Jacobian, as a bounded ``Pose`` does), and only the sign is
    refused: their derivative along the direction must not point against the residual's
    change (a negative inner product) nor vanish; an approximate Jacobian (a rotation
    error's first-order one far from the target) still steers the search and is accepted,
    with a :class:`~swarm_ik.errors.GoalWarning` where its size looks off by a factor
    (:data:`JACOBIAN_SCALE`).  Where
    the residual does not change along the direction nothing can be told.

    Raises:
        InvalidArgumentError: the Jacobian disagrees (the goal, ``q`` and the two
            derivatives named).
    """
    cls = type(goal)
    checked = robot._cache.setdefault("jacobians_checked", set())
    if cls in checked:
        return
    checked.add(cls)
    q = _probe_q(robot)
    span = np.where(np.isfinite(robot.upper - robot.lower), robot.upper - robot.lower, 1.0)
    v = span * np.where(np.arange(q.shape[0]) % 2 == 0, 1.0, -0.7)  # (every joint moves)
    v /= float(np.linalg.norm(v))
    h = JACOBIAN_STEP
    try:
        r_np, j_np = goals_base.search_rows(goal, State(robot, q), want_jac=True)
        r_hi = goals_base.search_rows(goal, State(robot, q + h * v), want_jac=False)[0]
        r_lo = goals_base.search_rows(goal, State(robot, q - h * v), want_jac=False)[0]
    except InvalidArgumentError:  # (rows of the wrong shape, NaN, an exception of the goal's:
        # refused by the search where it meets them, with their own messages)
        checked.discard(cls)
        return
    except BaseException:
        checked.discard(cls)
        raise
    if j_np is None or r_hi.shape != r_np.shape or r_lo.shape != r_np.shape:
        return  # (a goal whose rows change in number: nothing to compare)
    fd = (r_hi - r_lo) / (2.0 * h)
    along = j_np @ v
    # only the rows the direction changes (a row at rest in a dead zone may keep a Jacobian)
    moving = np.abs(fd) > 1e-9 * (1.0 + np.abs(r_np))
    fd, along = fd[moving], along[moving]
    size = float(np.linalg.norm(fd))
    if size <= 1e-6 * (1.0 + float(np.linalg.norm(r_np))):
        return
    dot = float(fd @ along)
    if float(np.linalg.norm(along)) <= 1e-3 * size:
        what = "is zero where the residual changes"
    elif dot < 0.0:
        what = "has the other sign (jacobian(state) is +∂residual/∂q)"
    else:  # (an approximate Jacobian still steers the search: accepted)
        scale = dot / (size * size)  # (its derivative's share along the residual's change)
        if not JACOBIAN_SCALE[0] <= scale <= JACOBIAN_SCALE[1]:
            warnings.warn(
                f"{goal.describe()}.jacobian(state) looks {scale:.3g} times the residual's "
                f"derivative at q = {np.round(q, 6).tolist()} (along a direction it gives "
                f"{np.round(along, 9).tolist()} where the residual changes by "
                f"{np.round(fd, 9).tolist()}): a Jacobian off by a factor (degrees for "
                "radians, a missing ½) slows the search or stalls it (docs/goals.md)",
                GoalWarning,
                stacklevel=user_stacklevel(),
            )
        return
    checked.discard(cls)
    raise InvalidArgumentError(
        f"{goal.describe()}.jacobian(state) {what} at q = {np.round(q, 6).tolist()}: along "
        f"a direction it gives {np.round(along, 9).tolist()} where the residual changes by "
        f"{np.round(fd, 9).tolist()} (docs/goals.md)"
    )


_BOUNDS_CHECKED: dict[int, tuple[Any, Any]] = {}
"""A goal kernel (by ``id``) → ``(the kernel, its copy compiled with numba's bounds
checks)``, made once per kernel for :func:`_kernel_rows`."""


def _bounds_checked(kernel: Any) -> Any:
    """``kernel`` (a ``numba.njit`` dispatcher) compiled again from its Python function with
    ``boundscheck=True`` (numba's public options): an index past an array raises
    ``IndexError`` instead of writing into whatever memory follows."""
    known = _BOUNDS_CHECKED.get(id(kernel))
    if known is None or known[0] is not kernel:
        known = (kernel, numba.njit(boundscheck=True)(kernel.py_func))
        _BOUNDS_CHECKED[id(kernel)] = known
    return known[1]


def _kernel_rows(robot: RobotModel, goal: Goal, q: FloatArray) -> tuple[FloatArray, FloatArray]:
    """The weighted rows ``(m,)`` and step Jacobian ``(m, nq)`` a compiled goal's kernel
    writes at ``q``, its copy with bounds checks (:func:`_bounds_checked`) called on arrays of
    exactly its own size: its rows as its ``encode`` declares them, its two errors, its
    parameter block and the scratch vector.

    Raises:
        InvalidArgumentError: the kernel raised, or indexed past one of those arrays (a write
            past its rows corrupts the rows of the goal after it, or memory: an abort at
            exit; the search itself runs the kernel without bounds checks).
    """
    prob = IKProblem(robot, goals=[goal])
    tab = prob.table(None)
    m, nq = int(tab.nrows[0]), robot.nq
    par = np.ascontiguousarray(tab.par[tab.p0[0] : tab.p0[1]])
    ipar = np.ascontiguousarray(tab.ipar[tab.i0[0] : tab.i0[1]])
    poses, f_jac = prob.tree.fk_jacobian(q)
    f_pos = np.ascontiguousarray(poses[:, :3, 3])
    f_rot = np.ascontiguousarray(poses[:, :3, :3])
    res, jac, err = np.zeros(m), np.zeros((m, nq)), np.full(2, np.nan)
    work = np.zeros(lm.WORK_SIZE)
    try:
        fn = _bounds_checked(goal.kernel_of())
        fn(par, ipar, q, f_pos, f_rot, np.ascontiguousarray(f_jac), True, res, jac, err, work)
    except SwarmIKError:
        raise
    except IndexError as exc:  # (numba's bounds check)
        raise InvalidArgumentError(
            f"{goal.describe()}: its kernel indexes past its {m} row{'s' * (m != 1)} (the rows "
            "its encode() declares), its two errors, its parameter block or its scratch "
            f"({lm.WORK_SIZE} floats) at q = {np.round(q, 6).tolist()}: declare every row it "
            f"writes (docs/goals.md; numba: {quoted_error(exc)})"
        ) from exc
    except Exception as exc:  # (raised inside the compiled kernel)
        raise InvalidArgumentError(
            f"{goal.describe()}: its kernel raised {type(exc).__name__}: "
            f"{quoted_error(exc)} at q = {np.round(q, 6).tolist()}"
        ) from exc
    w = float(tab.weight[0])
    return res * w, jac * w


def _close(a: FloatArray, b: FloatArray) -> bool:
    """Whether a kernel's rows ``a`` equal its twin's ``b`` (:data:`TWIN_RTOL`)."""
    return a.shape == b.shape and bool(np.all(np.abs(a - b) <= TWIN_RTOL * (1.0 + np.abs(b))))


def _check_kernel_twin(robot: RobotModel, goal: Goal, form: tuple[Any, ...] = ()) -> None:
    """:func:`_check_kernel_twin_now` under :data:`_CHECK_LOCK`."""
    with _CHECK_LOCK:
        _check_kernel_twin_now(robot, goal, form)


def _check_kernel_twin_now(robot: RobotModel, goal: Goal, form: tuple[Any, ...] = ()) -> None:
    """A compiled goal written outside swarm_ik, checked once per class, robot and ``form``
    of its parameter block (its sizes, its integers and its rows: a goal whose rows depend on
    its integers is probed for each, since a kernel past its rows corrupts memory): its
    kernel's rows and step Jacobian at one configuration against its own numpy
    ``residual``/``jacobian`` on Pinocchio's state (the Jacobian when it defines one: its
    sign only, on the rows whose twin has a derivative, as a Python goal's is judged), then
    its rows at :data:`PROBES` more configurations (finite, and equal to the residual's).  The
    kernel writes ``r`` as ``residual`` does and the step Jacobian ``J = −∂r/∂q``
    (``r(q + δ) ≈ r − Jδ``);
    a kernel of the other sign, or one disagreeing with its twin, would end every solve with
    the budget's reason and no word why.

    Raises:
        InvalidArgumentError: the two disagree, or the kernel wrote NaN or infinite values
            (named, with the configuration).
    """
    cls = type(goal)
    if str(cls.__module__).startswith("swarm_ik."):
        return
    checked = robot._cache.setdefault("twins_checked", set())
    key = (cls, form)
    if key in checked:
        return
    checked.add(key)  # (before the problem below, which would check it again)
    q = _probe_q(robot)
    try:  # (probed as a primary goal: a secondary one alone makes no problem)
        probe = dataclasses.replace(goal, primary=True) if not goal.is_primary else goal
    except (TypeError, ValueError):
        return
    try:
        _check_kernel_rows(robot, probe, q)
    except BaseException:
        checked.discard(key)
        raise


def _check_kernel_rows(robot: RobotModel, goal: Goal, q: FloatArray) -> None:
    """:func:`_check_kernel_twin_now`'s checks of ``goal`` (primary) at ``q``, then its rows
    at :func:`_more_probe_qs` (finite, and equal to its twin's, up to their sign)."""
    res, jac = _kernel_rows(robot, goal, q)
    _check_finite_rows(goal, q, res, jac)
    twin = type(goal).residual is not Goal.residual
    if twin:
        _check_twin_at(robot, goal, q, res, jac)
    for q_at in _more_probe_qs(robot):
        res_at, jac_at = _kernel_rows(robot, goal, q_at)
        _check_finite_rows(goal, q_at, res_at, jac_at)
        if twin:
            r_at = goals_base.search_rows(goal, State(robot, q_at), want_jac=False)[0]
            if not (_close(res_at, r_at) or _close(res_at, -r_at)):
                raise _rows_differ(goal, res_at, r_at, q_at)


def _rows_differ(
    goal: Goal, res: FloatArray, r_np: FloatArray, q: FloatArray
) -> InvalidArgumentError:
    """The refusal of a kernel whose rows ``res`` differ from its residual's ``r_np`` at
    ``q``."""
    return InvalidArgumentError(
        f"{goal.describe()}: its kernel's rows {np.round(res, 9).tolist()} differ from its "
        f"residual(state) {np.round(r_np, 9).tolist()} at q = {np.round(q, 6).tolist()} "
        "(the kernel writes the residual's rows, weighted alike; docs/goals.md)"
    )


def _check_finite_rows(goal: Goal, q: FloatArray, res: FloatArray, jac: FloatArray) -> None:
    """Refuse a kernel's rows or step Jacobian at ``q`` that are not finite."""
    if not (np.all(np.isfinite(res)) and np.all(np.isfinite(jac))):
        raise InvalidArgumentError(
            f"{goal.describe()}: its kernel wrote NaN or infinite rows or Jacobian entries at "
            f"q = {np.round(q, 6).tolist()} (rows {np.round(res, 9).tolist()}; a goal's rows "
            "are finite wherever the joints may go; docs/goals.md)"
        )


def _check_twin_at(
    robot: RobotModel, goal: Goal, q: FloatArray, res: FloatArray, jac: FloatArray
) -> None:
    """The kernel's rows ``res`` and step Jacobian ``jac`` at ``q`` against the goal's numpy
    ``residual``/``jacobian`` (see :func:`_check_kernel_twin_now`)."""
    cls = type(goal)
    r_np, j_np = goals_base.search_rows(
        goal, State(robot, q), want_jac=cls.jacobian is not Goal.jacobian
    )
    # r may be the residual or its negative (only |r| is judged), its step Jacobian then
    # −∂r/∂q: +jacobian(state) for −residual, −jacobian(state) for +residual
    sign = 1.0 if _close(res, r_np) else -1.0 if _close(res, -r_np) else 0.0
    if _close(res, r_np) and _close(res, -r_np) and j_np is not None:  # (rows of zero: either
        # sign, told by the Jacobian)
        sign = -1.0 if float(np.sum(jac * j_np)) > 0.0 else 1.0
    if sign == 0.0:
        raise _rows_differ(goal, res, r_np, q)
    if j_np is None:
        return
    # only the sign is judged, on the rows whose twin has a derivative (an approximate step
    # Jacobian still steers the search; a row at rest in a dead zone may keep its Jacobian)
    want = -sign * j_np
    live = np.linalg.norm(want, axis=1) > 1e-12 * (1.0 + float(np.abs(want).max(initial=0.0)))
    size = float(np.linalg.norm(want[live]))
    if size == 0.0:
        return
    if float(np.linalg.norm(jac[live])) <= 1e-3 * size:
        what = "is zero where its rows change"
    elif float(np.sum(jac[live] * want[live])) <= 0.0:
        what = "points against −∂r/∂q of its rows (it has the other sign)"
    else:
        return
    raise InvalidArgumentError(
        f"{goal.describe()}: its kernel's step Jacobian {what} at q = "
        f"{np.round(q, 6).tolist()}: the kernel's rows satisfy r(q + δ) ≈ r − Jδ (docs/goals.md)"
    )


def judge(
    errors: FloatArray,
    primary: Sequence[bool] | NDArray[Any],
    tol_pos: float | FloatArray,
    tol_rot: float,
) -> NDArray[np.bool_]:
    """The one success judge: which goals are met.

    Args:
        errors: ``(ng, 2)`` errors ``[position m, angle rad]`` (NaN where a goal has none).
        primary: Which goals are primary, ``(ng,)`` (secondary goals always count as met).
        tol_pos: Position tolerance [m], or one per goal ``(ng,)``
            (:meth:`IKProblem.position_tolerances`).
        tol_rot: Angular tolerance [rad].

    Returns:
        ``(ng,)`` booleans (compiled twin: :func:`swarm_ik.kernels.lm.within_tolerance`).
    """
    e = np.asarray(errors, dtype=float)
    ok_p = ~(e[:, 0] > tol_pos)  # NaN: no such error
    ok_r = ~(e[:, 1] > tol_rot)
    return (ok_p & ok_r) | ~np.asarray(primary, dtype=bool)


def pushed_out(
    q: FloatArray, direction: FloatArray, bounds: lm.Bounds, tol: float = 0.0
) -> NDArray[np.bool_]:
    """The joints at a limit (within ``tol``) that a move along ``direction`` ``(nq,)`` would
    push out of range (continuous joints never): the joints an active-set step holds.  The
    one rule of the numpy polish, its null-space step and :meth:`IKProblem.opposing_goals`
    (the compiled kernels spell it in their loops)."""
    lo = (q <= bounds.lower + tol) & (direction < 0.0)
    hi = (q >= bounds.upper - tol) & (direction > 0.0)
    return ~bounds.wrap & (lo | hi)  # type: ignore[no-any-return]


_ONE_PRIMARY = np.ones(1, dtype=np.bool_)
_ONE_PRIMARY.flags.writeable = False
"""The primary mask of a problem made of a target alone (shared, read-only)."""


REPLACEABLE = frozenset(("fitness", "is_success", "residual_jacobian", "cost"))
"""Methods of :class:`IKProblem` that may be replaced on an instance (e.g. wrapped to record a
trace); a problem with one replaced runs the general Python path of the solvers."""

_W_ROT, _LAM, _MU, _ORTH_TOL = 1.0, 10.0, 1.0, ORTH_TOL
"""The defaults of :class:`IKProblem`'s options."""


def _batch(q_batch: Any) -> FloatArray:
    """Joint vectors as the kernels take them: float64, C-contiguous, writable (a
    :class:`~swarm_ik.result.Result`'s read-only ``q`` copied), at least 2-D ``(pop, nq)``."""
    return np.require(np.atleast_2d(q_batch), dtype=float, requirements=("C", "W"))


class IKProblem:
    """Inverse kinematics of a set of goals.

    Args:
        robot: The robot (see :func:`swarm_ik.load_robot`), loaded with every goal frame.
        target: Shorthand for ``[Pose(robot.ee_frame, target)]`` (``Position`` when
            ``w_rot == 0``): ``(4, 4)`` array [m], ``(position, quaternion xyzw)``, 7 numbers
            ``x y z qx qy qz qw``, or a ``pinocchio.SE3``.
        goals: Goal terms (:mod:`swarm_ik.goals`), after the target's pose if both are given.
        fitness: Scalar cost of the swarm solvers: ``"se3"`` (default: the sum over primary
            goals of their errors, ``‖Δp‖ + w_rot·θ`` for a pose, plus
            ``SECONDARY_WEIGHT·½‖r₂‖²``), or, for a single-pose problem only, the paper forms
            ``"paper-l1"``, ``"euler-zyz"``, ``"paper-pso"`` (see :mod:`swarm_ik.fitness`).
            (For compatibility a fitness name passed as the third positional argument is
            taken as ``fitness``; with ``fitness`` given too, or a string that names no
            fitness, it is refused.)
        w_rot: Weight of angular errors in ``"se3"`` [m/rad]: 0, or between 1e-6 and 1e6
            (a goal weight's range); 0 with ``target`` makes the problem position-only.
        lam: λ of ``"paper-l1"`` (per metre).
        mu: μ of ``"euler-zyz"``.
        orth_tol: Tolerance on the orthonormality of target rotations.
        lower: Optional narrower lower bounds, shape ``(nq,)``; default the joint limits.
        upper: Optional narrower upper bounds, shape ``(nq,)``.

    Attributes:
        robot, goals, target (the first pose target, or None), fitness_name, w_rot, lower,
        upper, nq, position_only (a single Position goal from ``target`` with ``w_rot=0``).

    A problem is read once, when it is made: the search's tables and bounds are built from
    its arrays then.  Do not edit them in place (``problem.target[:] = …``, ``lower``,
    ``upper``, a goal's ``target`` or ``q_ref``): the search would run the old problem and the
    judge check the new one (the answer then reads as failed, never as a false success).  For
    another target make a new problem (``IKProblem(robot, T)``, or an :class:`IKSolver`).
    Making these arrays read-only was weighed and left: numba compiles every kernel again for
    read-only arrays (37 s on a warm cache).
    """

    target: FloatArray | None
    goals: tuple[Goal, ...]
    lower: FloatArray
    upper: FloatArray
    _table_cache: dict[Any, lm.GoalTable]

    @keywords_checked
    def __init__(
        self,
        robot: RobotModel,
        target: Any = None,
        goals: Sequence[Goal] | str | None = None,
        fitness: str | None = None,
        *,
        w_rot: float = _W_ROT,
        lam: float = _LAM,
        mu: float = _MU,
        orth_tol: float = _ORTH_TOL,
        lower: Any = None,
        upper: Any = None,
    ) -> None:
        if not isinstance(robot, RobotModel):
            raise InvalidArgumentError(
                f"robot must be a RobotModel (see swarm_ik.load_robot), got {type(robot).__name__}"
            )
        if (
            goals is None
            and target is not None
            and fitness in (None, "se3")
            and lower is None
            and upper is None
            and w_rot is _W_ROT
            and lam is _LAM
            and mu is _MU
            and orth_tol is _ORTH_TOL
        ):  # a pose target with every default: a copy of the robot's pose problem, retargeted
            template = robot._cache.get("pose_problem")
            if template is None:
                template = object.__new__(IKProblem)
                template._make(robot, robot.fk_pinocchio(robot.mid_q()), None, "se3",
                               w_rot, lam, mu, orth_tol, None, None)  # fmt: skip
                robot._cache["pose_problem"] = template
            template._retarget(self, target, orth_tol)
            self.lower, self.upper = template.lower.copy(), template.upper.copy()  # (its own)
            return
        self._make(robot, target, goals, fitness, w_rot, lam, mu, orth_tol, lower, upper)

    def _make(
        self,
        robot: RobotModel,
        target: Any,
        goals: Sequence[Goal] | str | None,
        fitness: str | None,
        w_rot: float,
        lam: float,
        mu: float,
        orth_tol: float,
        lower: Any,
        upper: Any,
    ) -> None:
        """The constructor's general path (any goals and options)."""
        if isinstance(goals, str):  # IKProblem(robot, target, "paper-l1"): the 0.1 signature
            if goals not in FITNESS:
                raise InvalidArgumentError(
                    f"goals must be a list of goal terms (swarm_ik.goals), got {goals!r} (a "
                    f"string there is read as the fitness, one of {', '.join(FITNESS)})"
                )
            if fitness is not None and fitness != goals:
                raise InvalidArgumentError(
                    f"two fitness names: {goals!r} where the goals go and fitness={fitness!r}; "
                    "give the fitness once, as fitness="
                )
            fitness, goals = goals, None
        fitness = "se3" if fitness is None else fitness
        self.robot = robot
        if not (is_finite_nonneg(w_rot) and is_finite_nonneg(lam) and is_finite_nonneg(mu)):
            label, v = next(
                (k, v) for k, v in (("w_rot", w_rot), ("lam", lam), ("mu", mu))
                if not is_finite_nonneg(v)
            )  # fmt: skip
            raise InvalidArgumentError(f"{label} must be a finite non-negative number, got {v!r}")
        low, high = goals_base.WEIGHT_RANGE  # (0: position only; else a weight's range)
        if float(w_rot) != 0.0 and not low <= float(w_rot) <= high:
            raise InvalidArgumentError(
                "w_rot must be 0 (position only) or between 1e-6 and 1e6 [m/rad] (weights are "
                f"relative), got {float(w_rot):.15g}"
            )
        self.w_rot = float(w_rot)
        terms: list[Goal] = []
        self.target = None
        self.orth_tol = float(orth_tol)
        """The orthonormality tolerance the target's rotation was checked with."""
        if target is not None:
            self.target = as_pose(target, orth_tol=orth_tol)
            if self.w_rot == 0.0:
                terms.append(Position(robot.ee_frame, self.target[:3, 3]))
            else:
                terms.append(Pose.checked(robot.ee_frame, self.target, self.orth_tol))
        if goals is not None:
            if not isinstance(goals, Sequence):
                raise InvalidArgumentError(
                    "goals must be a list of goal terms (swarm_ik.goals), got "
                    f"{type(goals).__name__}"
                    + (" (put it in a list)" if isinstance(goals, Goal) else "")
                )
            for gl in goals:
                if not isinstance(gl, Goal):
                    raise InvalidArgumentError(
                        f"goals must be swarm_ik.goals terms, got {type(gl).__name__}"
                    )
            terms.extend(gl for gl in goals if isinstance(gl, Goal))
        if not terms:
            raise InvalidTargetError(
                "give a target pose or a list of goals; got "
                + ("no target and an empty goal list" if goals is not None else "None")
            )
        if goals is not None and not any(gl.is_primary for gl in terms):  # (a target is)
            raise InvalidArgumentError(
                "at least one goal must be primary (Posture, CenterJoints and "
                "MinimalDisplacement are secondary unless primary=True)"
            )
        self.goals = tuple(terms)
        weights = [gl.weight for gl in terms if gl.is_primary]
        if len(weights) > 1 and max(weights) > goals_base.WEIGHT_SPREAD * min(weights):
            heavy = max(terms, key=lambda gl: gl.weight if gl.is_primary else -1.0)
            light = min(terms, key=lambda gl: gl.weight if gl.is_primary else np.inf)
            warnings.warn(
                f"primary goals' weights {max(weights) / min(weights):.0e} apart "
                f"({heavy.describe()} {heavy.weight:g}, {light.describe()} {light.weight:g}): "
                f"the search may leave the lighter unmet where both can be met (weights "
                f"trade primary goals off only where they conflict; keep them within "
                f"{goals_base.WEIGHT_SPREAD:g} of each other)",
                stacklevel=user_stacklevel(),
            )
        if self.target is None:
            first = next((gl for gl in terms if isinstance(gl, Pose)), None)
            self.target = None if first is None else first.target
        if not isinstance(fitness, str) or fitness not in FITNESS:
            raise unknown("fitness", fitness, FITNESS)
        exact = terms[0].exact  # (a bounded Pose or Position is no single-pose target)
        self.single_pose = len(terms) == 1 and isinstance(terms[0], (Pose, Position)) and exact
        if fitness != "se3" and not (len(terms) == 1 and isinstance(terms[0], Pose) and exact):
            raise InvalidArgumentError(
                f"fitness {fitness!r} is a paper's single-pose form; goal sets use 'se3'"
            )
        self.fitness_name = fitness
        self._fitness = get_fitness(fitness)
        self._weights = {"w_rot": self.w_rot, "lam": float(lam), "mu": float(mu)}
        narrowed = lower is not None or upper is not None
        self.lower = robot.lower.copy() if lower is None else robot.check_q(lower, "lower")
        self.upper = robot.upper.copy() if upper is None else robot.check_q(upper, "upper")
        if narrowed and np.any(self.lower > self.upper):
            raise InvalidArgumentError(
                "lower bounds exceed upper bounds at joints "
                f"{np.flatnonzero(self.lower > self.upper).tolist()}"
            )
        outside: Any = (
            np.flatnonzero((self.lower < robot.lower) | (self.upper > robot.upper))
            if narrowed
            else ()  # (the robot's own limits)
        )
        if len(outside):  # wider bounds would let a "success" break the joint limits
            j = int(outside[0])
            raise InvalidArgumentError(
                f"bounds may only narrow the joint limits; joint {robot.joint_names[j]!r}: "
                f"bounds [{self.lower[j]:g}, {self.upper[j]:g}] exceed its limits "
                f"[{robot.lower[j]:g}, {robot.upper[j]:g}]"
            )
        self.position_only = (
            isinstance(terms[0], Position)  # (the target's goal alone: Pose or Position)
            if goals is None
            else (target is not None and self.w_rot == 0.0 and len(terms) == 1)
            or all(isinstance(gl, Position) for gl in terms if gl.is_primary)
        )
        self.primary: NDArray[np.bool_] = (
            _ONE_PRIMARY
            if goals is None  # the target's goal alone
            else np.array([gl.is_primary for gl in terms], dtype=np.bool_)
        )
        self.has_secondary = not bool(self.primary.all())
        """Whether any goal is secondary."""
        self.tree = robot.tree
        """The kinematic tree the kernels evaluate: the robot's goal frames (first, in order)
        and any frames the goals add (collision bodies)."""
        avoid = [gl for gl in terms if isinstance(gl, AvoidCollisions)]
        if len(avoid) > 1:
            raise InvalidArgumentError("at most one AvoidCollisions goal per problem")
        self._collision_goal = avoid[0] if avoid and avoid[0].is_primary else None
        self.compiled_goals = tuple(gl for gl in terms if gl.compiled)
        """The goals with a compiled kernel, in order (the goal table's entries)."""
        self.python_goals = tuple(gl for gl in terms if not gl.compiled)
        """The goals written in Python (``residual(state)``/``jacobian(state)``)."""
        for gl in self.python_goals:
            missing = [
                m for m in ("residual", "jacobian") if getattr(type(gl), m) is getattr(Goal, m)
            ]
            if missing:
                raise InvalidArgumentError(
                    f"{gl.describe()} has no compiled kernel and defines no "
                    f"{' and no '.join(m + '(state)' for m in missing)}: a goal written in "
                    "Python defines residual(state) -> (m,) and jacobian(state) -> (m, nq) "
                    "(docs/goals.md)"
                )
            gl.own_tolerance()  # (a bad tolerance refused now, not judged as met later)
            _check_python_jacobian(robot, gl)
        self._frame0: dict[int, int] = {}
        """Index of the first frame each frame-adding goal owns (by position in
        ``compiled_goals``)."""
        added = []
        for i, gl in enumerate(self.compiled_goals):
            extra = gl.extra_frames(robot)
            if extra is not None:
                added.append((i, extra))
        if added:
            self.tree, self._frame0 = _tree_with_frames(robot, added)
        # angular errors in the se3 cost: w_rot (m/rad); position errors: 1
        self._table_cache = {}
        self._free: list[IKProblem | None] = []  # (without_collisions, made once)
        if narrowed:
            self.bounds = lm.Bounds(
                np.ascontiguousarray(self.lower),
                np.ascontiguousarray(self.upper),
                np.ascontiguousarray(robot.continuous_mask),
                np.ascontiguousarray(robot.prismatic_mask),
            )
        else:  # the robot's own limits: one Bounds per robot
            cached = robot._cache.get("bounds")
            if cached is None:
                cached = robot._cache["bounds"] = lm.Bounds(
                    np.ascontiguousarray(robot.lower),
                    np.ascontiguousarray(robot.upper),
                    np.ascontiguousarray(robot.continuous_mask),
                    np.ascontiguousarray(robot.prismatic_mask),
                )
            self.bounds = cached
        if not (target is not None and goals is None):  # (the target's Pose is valid as made)
            # every goal checked against the robot now (its kernel and parameter block); the
            # goal table is made when first asked for (a route bound to another problem of
            # the same goals writes these blocks into its own)
            blocks = []
            for i, gl in enumerate(self.compiled_goals):
                enc = goals_base.checked_encoding(gl, functools.partial(self.encode, i, None))
                kernel_slot(gl.kernel_of())
                form = (enc.par.shape[0], enc.ipar.tobytes(), int(enc.rows))
                blocks.append(form[:2])
                cls = type(gl)
                if cls.residual is Goal.residual and cls.errors is Goal.errors:
                    raise InvalidArgumentError(
                        f"{gl.describe()} defines no residual(state) (nor errors(state)): the "
                        "judge checks every answer with them on Pinocchio's state, not with the "
                        "kernel (docs/goals.md)"
                    )
                _check_kernel_twin(robot, gl, form)
            # (the blocks' form: a route rewrites only the floats of another problem's goals,
            # so problems whose integer parameters or block sizes differ take other routes)
            self._blocks = tuple(blocks)

    def __getstate__(self) -> dict[str, Any]:
        """Pickled without its goal tables (their kernel slots are this process's: the
        receiving process encodes the goals again) and its share of a route's key."""
        state = dict(self.__dict__)
        state["_table_cache"] = {}
        state.pop("_route_key_part", None)  # (it names this process's tree by its id)
        return state

    # ------------------------------------------------------------------ goals
    @property
    def nq(self) -> int:
        """Number of joints."""
        return self.robot.nq

    def table(self, q0: FloatArray | None) -> lm.GoalTable:
        """The compiled goal table of the compiled goals (``q0`` fills
        :class:`~swarm_ik.goals.MinimalDisplacement`)."""
        key = None if q0 is None else np.asarray(q0, dtype=float).tobytes()
        tab = self._table_cache.get(key)
        if tab is None:
            enc = [
                goals_base.checked_encoding(gl, functools.partial(self.encode, i, q0))
                for i, gl in enumerate(self.compiled_goals)
            ]
            tab = lm.goal_table(
                [kernel_slot(gl.kernel_of()) for gl in self.compiled_goals],
                [gl.weight for gl in self.compiled_goals],
                [gl.is_primary for gl in self.compiled_goals],
                [e.par for e in enc],
                [e.ipar for e in enc],
                [e.rows for e in enc],
            )
            if len(self._table_cache) > 64:
                self._table_cache.clear()
            self._table_cache[key] = tab
        return tab

    def encode(self, i: int, q0: FloatArray | None) -> goals_base.Encoded:
        """The parameter block of compiled goal ``i`` (a goal that adds frames is told where
        its frames start: ``encode(robot, q0, frame0)``)."""
        gl = self.compiled_goals[i]
        if i in self._frame0:
            return gl.encode(self.robot, q0, frame0=self._frame0[i])  # type: ignore[call-arg]
        return gl.encode(self.robot, q0)

    def with_target(self, target: Any) -> IKProblem:
        """The same single-pose problem with another target (validated), sharing everything
        else: the per-call path of :class:`swarm_ik.IKSolver`."""
        if not self.single_pose or self.target is None:
            raise InvalidArgumentError("with_target needs a single-pose problem")
        new = object.__new__(type(self))
        self._retarget(new, target, ORTH_TOL)
        return new

    def _retarget(self, new: IKProblem, target: Any, orth_tol: float) -> None:
        """Make ``new`` this single-pose problem with another target (validated with
        ``orth_tol``): a shallow copy (``copy.copy``'s protocol costs 6 µs) sharing everything
        but the target."""
        new.__dict__.update(self.__dict__)
        new.target = as_pose(target, orth_tol=orth_tol)
        if isinstance(self.goals[0], Position):
            new.goals = (Position(self.robot.ee_frame, new.target[:3, 3]),)
        else:
            new.goals = (Pose.checked(self.robot.ee_frame, new.target, orth_tol),)
        new.compiled_goals = new.goals
        new._table_cache = {}
        new._free = []

    @classmethod
    def from_q(cls, robot: RobotModel, q: Any, fitness: str = "se3", **kwargs: Any) -> IKProblem:
        """The single-pose problem whose target is the FK of ``q`` (reachable by
        construction; a warning when ``q`` lies outside the joint limits:
        :meth:`RobotModel.target_q`)."""
        return cls(robot, robot.fk(robot.target_q(q)), fitness=fitness, **kwargs)

    # --------------------------------------------------------------- hot path
    def _errors_and_cost2(
        self, q_batch: FloatArray, q0: FloatArray | None
    ) -> tuple[FloatArray, FloatArray]:
        """Errors of every goal ``(pop, ng, 2)`` and the secondary cost ``(pop,)``: the
        compiled goals through the kernels, Python goals on Pinocchio's state."""
        q2 = _batch(q_batch)
        pop = q2.shape[0]
        err = np.empty((pop, len(self.goals), 2))
        cost2 = np.zeros(pop)
        compiled = [i for i, gl in enumerate(self.goals) if gl.compiled]
        if compiled:
            e_c = np.empty((pop, len(compiled), 2))
            lm.errors_batch(q2, self.tree, self.table(q0), kernels(), self.bounds, e_c, cost2)
            err[:, compiled] = e_c
        if self.python_goals:
            for k in range(pop):
                state = State(self.robot, q2[k], q0)
                for i, gl in enumerate(self.goals):
                    if gl.compiled:
                        continue
                    err[k, i] = goals_base.errors_of(gl, state)
                    if not gl.is_primary:
                        r = goals_base.search_rows(gl, state, want_jac=False)[0]
                        cost2[k] += float(r @ r)
        return err, cost2

    def goal_errors(self, q_batch: FloatArray, q0: FloatArray | None = None) -> FloatArray:
        """Errors of every goal, ``(pop, nq) -> (pop, ng, 2)`` ``[m, rad]`` (compiled FK)."""
        return self._errors_and_cost2(q_batch, q0)[0]

    def cost(self, q_batch: FloatArray, q0: FloatArray | None = None) -> FloatArray:
        """The ``"se3"`` scalar cost ``(pop, nq) -> (pop,)``: Σ over primary goals of
        position error + ``w_rot``·angular error, plus ``SECONDARY_WEIGHT``·½‖r₂‖²."""
        err, cost2 = self._errors_and_cost2(q_batch, q0)
        e = np.where(np.isnan(err), 0.0, err)[:, self.primary]
        return e[..., 0].sum(-1) + self.w_rot * e[..., 1].sum(-1) + SECONDARY_WEIGHT * 0.5 * cost2

    def fitness(self, q_batch: FloatArray) -> FloatArray:
        """Batched scalar cost: ``(pop, nq) -> (pop,)`` (the swarm solvers' objective)."""
        if self.fitness_name == "se3":
            return self.cost(q_batch)
        poses = self.robot.fk(np.atleast_2d(q_batch))
        return self._fitness(poses, self.target, **self._weights)

    __call__ = fitness

    def fitness_of_poses(self, poses: FloatArray) -> FloatArray:
        """Fitness of given end-effector poses ``(pop, 4, 4)`` (single-pose problems)."""
        if self.target is None or not self.single_pose:
            raise InvalidArgumentError("fitness_of_poses needs a single-pose problem")
        return self._fitness(poses, self.target, **self._weights)

    def errors(self, q_batch: FloatArray) -> tuple[FloatArray, FloatArray]:
        """Largest primary position error [m] and angular error [rad], each ``(pop,)``."""
        err = self.goal_errors(q_batch)[:, self.primary]
        e = np.where(np.isnan(err), 0.0, err)
        return e[..., 0].max(-1), e[..., 1].max(-1)

    def residual_jacobian(
        self, q_batch: FloatArray, primary: bool = True, q0: FloatArray | None = None
    ) -> tuple[FloatArray, FloatArray, FloatArray]:
        """Fitness, stacked primary residual and its step Jacobian, for Gauss–Newton steps.

        Args:
            q_batch: Joint vectors, shape ``(pop, nq)``.
            primary: The primary stack (default), or the secondary one.
            q0: The solve's start (what ``MinimalDisplacement`` goals hold to), or None.

        Returns:
            ``fitness (pop,)``; ``err (pop, rows)`` with ``r(q + δ) ≈ r − J δ`` (for a pose:
            ``[p* − p; log(R* Rᵀ)]`` in world axes); ``jac (pop, rows, nq)``, so that
            ``q + pinv(jac) @ err`` is the Gauss–Newton step.  The compiled goals' rows come
            first, then the Python goals' (``−∂r/∂q`` of their ``jacobian``).
        """
        q2 = _batch(q_batch)
        res, jac = self.stacked_rows(q2, primary, q0)
        return self.fitness(q2), res, jac

    def stacked_rows(
        self, q_batch: FloatArray, primary: bool = True, q0: FloatArray | None = None
    ) -> tuple[FloatArray, FloatArray]:
        """The stacked residual and step Jacobian of :meth:`residual_jacobian` without the
        fitness (what the numpy polish steps with): ``(pop, rows)``, ``(pop, rows, nq)``."""
        q2 = _batch(q_batch)
        tab = self.table(q0)
        pop, m = q2.shape[0], tab.rows_primary if primary else tab.rows_secondary
        res = np.zeros((pop, m))
        jac = np.zeros((pop, m, self.nq))
        err = np.empty((pop, len(self.compiled_goals), 2))
        if self.compiled_goals:
            lm.residuals_batch(q2, self.tree, tab, kernels(), self.bounds, primary, res, jac, err)
        py = [gl for gl in self.python_goals if gl.is_primary == primary]
        if py and pop:  # (no point: the Python goals' row counts unknown, none given)
            extra_r, extra_j = [], []
            for k in range(pop):
                state = State(self.robot, q2[k], q0)
                rows = [goals_base.search_rows(gl, state) for gl in py]
                extra_r.append(np.concatenate([r for r, _ in rows]))
                extra_j.append(-np.concatenate([j for _, j in rows]))
            res = np.concatenate([res, np.array(extra_r)], axis=1)
            jac = np.concatenate([jac, np.array(extra_j)], axis=1)
        return res, jac

    def opposing_goals(self, q: Any, ratio: float = 0.1) -> str | None:
        """Primary goals that pull against each other at ``q``, if any: their labels.

        Each primary goal pulls on the joints along the gradient of its share of the
        search's cost, ``g_i = w_i² J_iᵀ r_i`` (its rows of :func:`goals.base.search_rows`, on
        Pinocchio's state; goals without a numpy Jacobian, such as ``AvoidCollisions``, are
        left out), over the joints free to move (a joint at a limit that the sum pushes
        outwards is held).  The goals oppose when at least two of them pull with at least
        ``ratio`` of the largest pull ``‖g_i‖`` while the sum ``‖Σ g_i‖`` is at most ``ratio``
        of it: no small step lowers one's residual without raising another's (two goals no
        configuration meets together end so, as may goals stuck against each other at a
        local minimum).  Those pulling that hard are named.

        The same test is made on the pulls of the sum of the goals' norms ``Σ ‖w_i r_i‖``,
        ``g_i / ‖w_i r_i‖``, of the goals whose rows' norm is at least ``ratio`` of the
        largest (a goal met, or nearly, has no share in that sum's pull): the answer a
        search keeps is the one of least summed error, and where two goals ask for values no
        configuration gives together (a distance of 0.3 and of 0.9) every point between
        them has the same sum, so the answer kept may be one where the squares are
        unbalanced (errors 0.51 and 0.09) and their pulls do not cancel, while the pulls of
        the norms do.
        """
        if int(self.primary.sum()) < 2:
            return None
        qv = self.robot.check_q(q, "q")
        state = State(self.robot, qv)
        pulls = []
        norms = []
        for gl in self.goals:
            if not gl.is_primary or type(gl).jacobian is Goal.jacobian:
                continue
            r, jac = goals_base.search_rows(gl, state)
            assert jac is not None
            pulls.append((gl, jac.T @ r))
            norms.append(float(np.linalg.norm(r)))
        if len(pulls) < 2:
            return None
        found = self._opposing(qv, pulls, ratio)
        if found is None:
            least = ratio * max(norms)  # (a goal met, or nearly: no share in the sum)
            unit = [
                (gl, g / n)
                for (gl, g), n in zip(pulls, norms, strict=True)
                if n > 0.0 and n >= least
            ]
            found = self._opposing(qv, unit, ratio) if len(unit) >= 2 else None
        return found

    def _opposing(
        self, q: FloatArray, pulls: list[tuple[Any, FloatArray]], ratio: float
    ) -> str | None:
        """:meth:`opposing_goals`'s test of one set of pulls ``(goal, g_i (nq,))``."""
        total = np.sum([g for _, g in pulls], axis=0)
        free = ~pushed_out(q, -total, self.bounds, 1e-12)  # (the descent moves along −Σg)
        size = [float(np.linalg.norm(g[free])) for _, g in pulls]
        big = max(size)
        if not big > 0.0 or float(np.linalg.norm(total[free])) > ratio * big:
            return None
        names = [gl.describe() for (gl, _), n in zip(pulls, size, strict=True) if n >= ratio * big]
        return " and ".join(names) if len(names) >= 2 else None

    def position_tolerances(self, tol_pos: float) -> float | FloatArray:
        """The position tolerance each goal is judged against: ``tol_pos``, or a Python
        goal's own ``tolerance`` where it has one (as :meth:`Goal.met` judges it), ``(ng,)``
        (``tol_pos`` itself when no goal has its own)."""
        own = [gl.own_tolerance() for gl in self.goals]
        if all(t is None for t in own):
            return tol_pos
        return np.array([tol_pos if t is None else t for t in own])

    def within_bounds(self, q: FloatArray, tol: float = 1e-12) -> bool:
        """Whether ``q`` lies within the problem's bounds (± ``tol``)."""
        q = np.asarray(q, dtype=float)
        if q.shape != self.lower.shape:
            return bool((q >= self.lower - tol).all() and (q <= self.upper + tol).all())
        return bool(joints.in_box(q, self.lower, self.upper, float(tol)))

    @property
    def collision_goal(self) -> Any:
        """The primary ``AvoidCollisions`` goal, if any (found once, when the problem is
        made)."""
        return self._collision_goal

    def is_success(self, q: FloatArray, tol_pos: float, tol_rot: float) -> bool:
        """Every primary goal within tolerance (compiled FK) and ``q`` within the bounds; a
        collision goal is judged by the exact check (coal), not by its spheres."""
        if not self.within_bounds(q):
            return False
        col = self.collision_goal
        if col is None:
            tp = self.position_tolerances(tol_pos)
            return bool(np.all(judge(self.goal_errors(q)[0], self.primary, tp, tol_rot)))
        return self.candidate_cost(q, tol_pos, tol_rot) is not None

    def without_collisions(self) -> IKProblem | None:
        """The same problem without its collision goal (None when no other goal is primary):
        the pose-only polish of the search, whose answers the exact check then judges (made
        once per problem)."""
        if not self._free:
            col = self.collision_goal
            rest = [g for g in self.goals if g is not col]
            self._free.append(
                IKProblem(
                    self.robot, goals=rest, w_rot=self.w_rot, lower=self.lower, upper=self.upper
                )
                if any(g.is_primary for g in rest)
                else None
            )
        return self._free[0]

    def candidate_cost(self, q: FloatArray, tol_pos: float, tol_rot: float) -> float | None:
        """For a problem with a collision goal: when every other primary goal is within
        tolerance at ``q`` and the exact check finds no contact, the cost with the collision
        term measured exactly (0), else None.  The spheres of the search are conservative
        (they stick out of the bodies by up to their fitting tolerance), so a point the
        spheres call in contact may be free; the search offers such points here."""
        col = self.collision_goal
        err = self.goal_errors(q)[0]
        others = self.primary & np.array([g is not col for g in self.goals])
        tp = self.position_tolerances(tol_pos)
        tp = tp[others] if isinstance(tp, np.ndarray) else tp
        if not np.all(judge(err[others], [True] * int(others.sum()), tp, tol_rot)):
            return None
        if col is not None and self.robot.collision_model().collides(
            q, col.scene, col.margin, bool(col.self_collision)
        ):
            return None
        e = np.where(np.isnan(err), 0.0, err)[others]
        return float(e[:, 0].sum() + self.w_rot * e[:, 1].sum())

    # ------------------------------------------------------------ the check
    def verify(
        self, q: Any, tol_pos: float = 1e-5, tol_rot: float = 1e-5, q0: FloatArray | None = None
    ) -> tuple[GoalError, ...]:
        """Errors of every primary goal at ``q`` computed with Pinocchio's own FK (and coal
        for collisions), not the compiled kernels, judged against the tolerances; ``q0``:
        the solve's start, for goals that read it (``MinimalDisplacement``).

        Raises:
            InvalidArgumentError: ``q`` or ``q0`` of the wrong length or not finite, or a
                tolerance that is not a positive number.
        """
        if not (
            type(tol_pos) is float and type(tol_rot) is float
            and 0.0 < tol_pos < math.inf and 0.0 < tol_rot < math.inf
        ):  # fmt: skip
            check_tolerances(tol_pos, tol_rot)  # (anything else is refused there)
        qv = q if self.robot.is_q(q) else self.robot.check_q(q, "q")
        if q0 is not None and not self.robot.is_q(q0):
            q0 = self.robot.check_q(q0, "q0")
        return self.verify_checked(qv, tol_pos, tol_rot, q0)

    def verify_checked(
        self, q: FloatArray, tol_pos: float, tol_rot: float, q0: FloatArray | None = None
    ) -> tuple[GoalError, ...]:
        """:meth:`verify` of arguments it would accept as they are (float64 vectors of the
        robot's length, finite; positive float tolerances): the route's judge, whose answer
        and settings were checked once."""
        state = State(self.robot, q, q0)
        out = []
        for gl, prim in zip(self.goals, self.primary, strict=True):
            if not prim:
                continue
            dp, dr, met, details = gl.met(state, tol_pos, tol_rot)
            out.append(GoalError(gl.describe(), float(dp), float(dr), met, details))
        return tuple(out)

    def __repr__(self) -> str:
        labels = [gl.describe() for gl in self.goals]
        return (
            f"IKProblem(robot={self.robot.name!r}, fitness={self.fitness_name!r}, goals={labels})"
        )
