"""The goal protocol: a goal is a residual with its Jacobian, a weight and a priority.

A goal is a frozen dataclass deriving from :class:`Goal`, written one way or the other:

* **Compiled**: the class names a numba kernel of
  :data:`swarm_ik.kernels.lm.GOAL_SIGNATURE` in its ``kernel`` class attribute and encodes
  itself with :meth:`Goal.encode` as its own parameter block (floats, integers) and its row
  count.  The kernel is registered once (:func:`kernel_slot`); the LM kernel calls it through
  its slot and never learns the goal's name.  Built-in goals also give :meth:`Goal.residual`
  and :meth:`Goal.jacobian` in numpy: the reference the kernel is tested against.
* **Python**: the class defines :meth:`Goal.residual` ``(state) -> (m,)`` and
  :meth:`Goal.jacobian` ``(state) -> (m, nq)`` (the derivative of the residual with respect
  to ``q``) on a :class:`State` computed by Pinocchio.  Such a goal mixes with compiled ones in
  one problem (the solve then runs the Python path of the solvers: slower, still exact), and
  is judged by the norm of its residual against its ``tolerance`` (default: the solve's
  position tolerance).

Both are judged by :meth:`Goal.errors` on a Pinocchio :class:`State` (the independent check
of every answer).  ``docs/goals.md`` writes a Python goal step by step.
"""

from __future__ import annotations

import contextlib
import difflib
import functools
import math
import os
import reprlib
import threading
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, ClassVar, NamedTuple

import numba
import numpy as np
import pinocchio as pin
from numpy.typing import NDArray

from swarm_ik._validate import floats_or, quoted_error
from swarm_ik.errors import InvalidArgumentError, SwarmIKError, UnknownNameError
from swarm_ik.kernels import loaded_despite_damage
from swarm_ik.kernels.lm import GOAL_SIGNATURE, kernel_list
from swarm_ik.pose import FLOAT64, is_finite_nonneg, project_to_se3

if TYPE_CHECKING:
    from swarm_ik.robot import RobotModel

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]


# --------------------------------------------------------------------------- kernels
_KERNELS: list[Any] = []
_SLOTS: dict[int, int] = {}
_GENERATION = [0]
"""Registrations so far: a thread's typed list of kernels made before the last one is made
again (:func:`kernels`)."""


class _ThreadLists(threading.local):
    """This thread's typed list of the kernels, with the generation it was made at."""

    made: tuple[int, Any] | None = None


_LISTS = _ThreadLists()
_REGISTRY = threading.Lock()
"""Held while a kernel is registered and while the typed list is made: threads that first
meet a goal type together raced for its slot (two kernels in one slot, or a list made
before the last registration: IndexError inside the compiled search, for good)."""


def kernel_slot(kernel: Any) -> int:
    """The slot of a compiled goal kernel in the list the LM kernel calls it through,
    registering it on first use: it is compiled then (or loaded from numba's cache) for
    :data:`swarm_ik.kernels.lm.GOAL_SIGNATURE`, so only the kernels of goals in use compile.

    Args:
        kernel: A ``numba.njit`` function of the goal protocol's arguments.

    Raises:
        InvalidArgumentError: ``kernel`` is not a numba function, or cannot be compiled for
            that signature.
    """
    slot = _SLOTS.get(id(kernel))
    if slot is not None:
        return slot
    with _REGISTRY:
        slot = _SLOTS.get(id(kernel))  # (registered by another thread meanwhile)
        if slot is not None:
            return slot
        if not callable(getattr(kernel, "py_func", None)):
            raise InvalidArgumentError(
                "a compiled goal's kernel must be a numba.njit function of the arguments of "
                f"swarm_ik.kernels.lm.GOAL_SIGNATURE, got {reprlib.repr(kernel)}"
            )
        try:
            # the kernel of exactly this signature (compiled now, or loaded from numba's
            # cache): typed as a first-class function, so the list of kernels built from it is
            # one cached type whatever the kernels are
            # (cached on disk when its source is a file: a kernel typed at a prompt, in
            # `python -c` or exec'd has nowhere numba can keep a cache, and compiles each time)
            source = getattr(getattr(kernel.py_func, "__code__", None), "co_filename", "")
            cache = os.path.isfile(source)

            def compiled() -> Any:
                try:
                    return numba.njit(GOAL_SIGNATURE, cache=cache)(kernel.py_func)
                except OSError:  # numba's cache could not be written (a full disk): the
                    if not cache:  # kernel compiled again and kept in memory only, so that
                        raise  # a broken cache never stops a solve
                    return numba.njit(GOAL_SIGNATURE, cache=False)(kernel.py_func)

            ours = str(getattr(kernel.py_func, "__module__", "")).startswith("swarm_ik.")
            # (a damaged cache of swarm_ik's own kernels is removed and compiled again; a
            # user's kernel is the user's, its errors reported as they are)
            typed = loaded_despite_damage(compiled, mark=True) if ours else compiled()
        except Exception as exc:  # numba's typing errors have no public base class
            first = str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
            raise InvalidArgumentError(
                f"goal kernel {getattr(kernel, '__name__', kernel)!r} does not compile for "
                f"swarm_ik.kernels.lm.GOAL_SIGNATURE: {first}"
            ) from None
        slot = len(_KERNELS)
        _KERNELS.append(typed)
        _GENERATION[0] += 1
        _SLOTS[id(kernel)] = slot  # (last: a thread that reads it finds the kernel listed)
        return slot


def kernels() -> Any:
    """The typed list of every registered goal kernel, one per thread (made again after a
    registration).  Every LM run takes a reference to the list, an atomic increment and
    decrement of its count: two threads solving chunks of one batch on a shared list fought
    for that count's cache line, 10-15 % of their speed (90,000 against 104,000 Panda
    poses/s on two threads, interleaved)."""
    with _REGISTRY:
        made = _LISTS.made
        if made is None or made[0] != _GENERATION[0]:  # (its builder is a compiled call
            # too: a cache damaged inside, removed)
            made = (
                _GENERATION[0],
                loaded_despite_damage(lambda: kernel_list(list(_KERNELS)), mark=True),
            )
            _LISTS.made = made
        return made[1]


# --------------------------------------------------------------------------- kept values
KEPT_POINTS = 4096
"""Most joint vectors whose Python-goal values one scope of :func:`reuse_goal_values` keeps
(the oldest dropped first)."""


class _Kept(threading.local):
    """The values of the Python goals kept on this thread: the open scope's table (None: no
    scope open) and the table parked by a scope for the next one that resumes it."""

    table: dict[Any, dict[Any, Any]] | None = None
    parked: dict[Any, dict[Any, Any]] | None = None


_KEPT = _Kept()


@contextlib.contextmanager
def reuse_goal_values(
    active: bool = True, *, park: bool = False, resume: bool = False
) -> Iterator[None]:
    """A scope within which each Python goal's residual, Jacobian and errors at one joint
    vector (and start ``q0``) are computed once: a later :class:`State` of the same robot at
    the same ``q`` and ``q0`` is served the values already computed (the polish's rows and its
    errors, the stop test, the fitness and the judge of the answer all read one evaluation of
    a slow goal).  Compiled goals are always computed.  A scope opened inside another one
    shares the outer scope's values.

    The values are kept only while the scope is open (a goal whose inputs change between two
    solves is evaluated again); at most :data:`KEPT_POINTS` joint vectors are kept.

    Args:
        active: False: no scope (the values are not kept; a problem without Python goals).
        park: At the end of the scope (without an error), park its values on this thread for
            the next scope opened with ``resume`` (the search's values for the judge).
        resume: Start from the values parked on this thread, if any (they are dropped either
            way: a parked table serves one scope at most).
    """
    if not active or _KEPT.table is not None:  # (no scope, or the outer one serves)
        yield
        return
    parked, _KEPT.parked = _KEPT.parked, None
    table: dict[Any, dict[Any, Any]] = parked if resume and parked is not None else {}
    _KEPT.table = table
    done = False
    try:
        yield
        done = True
    finally:
        _KEPT.table = None
        if park and done:
            _KEPT.parked = table


def _values_at(robot: Any, q: FloatArray, q0: FloatArray | None) -> dict[Any, Any] | None:
    """The dict of kept values of the open scope at ``(robot, q, q0)`` (None when no scope is
    open: each asker computes)."""
    table = _KEPT.table
    if table is None:
        return None
    key = (id(robot), q.tobytes(), None if q0 is None else q0.tobytes())
    values = table.get(key)
    if values is None:
        if len(table) >= KEPT_POINTS:
            del table[next(iter(table))]
        values = table[key] = {}
    return values


def _kept(goal: Goal, state: State, kind: str, compute: Callable[[State], Any]) -> Any:
    """``compute(state)`` for a Python goal, computed once per state's point in a scope of
    :func:`reuse_goal_values` (``kind``: which value); a compiled goal's is always computed."""
    values = getattr(state, "_values", None)
    if values is None or goal.compiled:
        return compute(state)
    hit = values.get((id(goal), kind))
    if hit is not None and hit[0] is goal:
        return hit[1]
    value = compute(state)
    values[(id(goal), kind)] = (goal, value)  # (the goal kept: its id stays its own)
    return value


def built_in(goal: Goal) -> bool:
    """Whether ``goal``'s class is one of swarm_ik's own: an exception raised in its methods is
    a defect of swarm_ik and propagates as it is, where one of a goal written outside the
    package is reported naming the goal and the method."""
    return str(type(goal).__module__).startswith("swarm_ik.")


def _real(goal: Goal, state: State, what: str) -> FloatArray:
    """What ``goal.<what>(state)`` returns, as a float array.  An exception raised inside a
    Python goal's method is reported naming the goal and the method
    (:class:`~swarm_ik.errors.InvalidArgumentError`, the goal's own exception chained);
    anything but real numbers (complex values, which numpy would cut to their real parts
    with a warning; ``None``, text) is refused naming the goal."""
    try:
        value = getattr(goal, what)(state)
    except NotImplementedError:
        raise
    except SwarmIKError as exc:  # (a state's own refusal, say an unknown frame: its class
        # kept, the goal and the method named)
        if built_in(goal):
            raise
        try:
            named = type(exc)(f"{goal.describe()}.{what}(state): {exc}")
        except Exception:  # (a subclass that takes other arguments)
            named = InvalidArgumentError(f"{goal.describe()}.{what}(state): {exc}")
        raise named from exc
    except Exception as exc:  # (the user's code: any error it raises)
        if built_in(goal):
            raise
        raise InvalidArgumentError(
            f"{goal.describe()}.{what}(state) raised {type(exc).__name__}: "
            f"{quoted_error(exc)} at q = {np.round(state.q, 6).tolist()}"
        ) from exc
    arr = np.asarray(value)
    if np.iscomplexobj(arr):
        raise InvalidArgumentError(
            f"{goal.describe()}.{what}(state) must return real numbers, got complex values"
        )
    if arr.dtype.kind not in "biuf":
        raise InvalidArgumentError(
            f"{goal.describe()}.{what}(state) must return an array of numbers, got "
            f"{reprlib.repr(value)}"
        )
    return np.array(arr, dtype=float)


def residual_of(goal: Goal, state: State) -> Any:
    """``goal.residual(state)`` as a float array (computed once per point in a scope of
    :func:`reuse_goal_values`)."""
    return _kept(goal, state, "r", lambda s: _real(goal, s, "residual"))


def jacobian_of(goal: Goal, state: State) -> Any:
    """``goal.jacobian(state)`` as a float array (computed once per point in a scope of
    :func:`reuse_goal_values`)."""
    return _kept(goal, state, "j", lambda s: _real(goal, s, "jacobian"))


def _users(goal: Goal, what: str, call: Callable[[], Any]) -> Any:
    """``call()`` of a goal's optional method ``what`` (``infeasible``, ``pin``): an
    exception of a goal written outside swarm_ik reported naming the goal and the method
    (:class:`~swarm_ik.errors.InvalidArgumentError`, its own exception chained)."""
    try:
        return call()
    except SwarmIKError:
        raise
    except Exception as exc:
        if built_in(goal):
            raise
        raise InvalidArgumentError(
            f"{goal.describe()}.{what} raised {type(exc).__name__}: {quoted_error(exc)}"
        ) from exc


def preferred_start_of(goals: Any, robot: RobotModel) -> Any:
    """The first start a solve without ``q0`` takes from its goals: the first
    :meth:`Goal.preferred_start` that is not None (an exception of a goal written outside
    swarm_ik named with its goal), or None."""
    for goal in goals:
        q = _users(goal, "preferred_start()", functools.partial(goal.preferred_start, robot))
        if q is not None:
            return goal, q
    return None


def kernel_error(goals: Any, exc: Exception) -> Exception:
    """What an exception raised inside a compiled call becomes: with compiled goals written
    outside swarm_ik among ``goals`` (whose kernels may raise: numba's ``raise``), an
    :class:`~swarm_ik.errors.InvalidArgumentError` naming them, the exception chained by the
    caller; else the exception itself (a defect of swarm_ik's)."""
    listed = goals if isinstance(goals, (list, tuple)) else []
    users = [
        gl.describe()
        for gl in listed
        if isinstance(gl, Goal) and gl.compiled and not type(gl).__module__.startswith("swarm_ik.")
    ]
    if isinstance(exc, SwarmIKError) or not users:
        return exc
    return InvalidArgumentError(
        f"a compiled goal's kernel raised {type(exc).__name__}: {str(exc)[:200]!r} (goals "
        f"written outside swarm_ik: {', '.join(users)})"
    )


class kernel_errors_named:  # noqa: N801 (used as a function: ``with kernel_errors_named(...)``)
    """Context manager: an exception a user's compiled kernel raises in the body, named
    (:func:`kernel_error`, the exception chained); ``goals_of()`` gives the goals that ran
    (read only when something was raised).  A class rather than a generator: it wraps every
    search, and entering it costs no generator."""

    __slots__ = ("goals_of",)

    def __init__(self, goals_of: Callable[[], Any]) -> None:
        self.goals_of = goals_of

    def __enter__(self) -> None:
        return None

    def __exit__(self, kind: Any, exc: BaseException | None, tb: Any) -> None:
        if not isinstance(exc, Exception):
            return  # (nothing raised, or KeyboardInterrupt and the like: passed on)
        try:
            goals = self.goals_of()
        except Exception:
            goals = None
        err = kernel_error(goals, exc)
        if err is not exc:
            raise err from exc


def names_kernel_errors(goals_of: Callable[..., Any]) -> Callable[[Any], Any]:
    """Decorator of an entry point that runs compiled goals: :func:`kernel_errors_named`
    around it, ``goals_of(*args, **kwargs)`` giving the call's goals."""

    def wrap(func: Any) -> Any:
        @functools.wraps(func)
        def named(*args: Any, **kwargs: Any) -> Any:
            with kernel_errors_named(lambda: goals_of(*args, **kwargs)):
                return func(*args, **kwargs)

        return named

    return wrap


def infeasible_of(goal: Goal, robot: RobotModel, tol_pos: float, tol_rot: float) -> str | None:
    """``goal.infeasible(robot, tol_pos, tol_rot)``, checked: None or a text.

    Raises:
        InvalidArgumentError: the method raised, or returned anything else (the goal named).
    """
    why = _users(goal, "infeasible()", lambda: goal.infeasible(robot, tol_pos, tol_rot))
    if why is not None and not isinstance(why, str):
        raise InvalidArgumentError(
            f"{goal.describe()}.infeasible() must return None or a text (why no configuration "
            f"meets the goal), got {reprlib.repr(why)}"
        )
    return why


PIN_ORTH_TOL = 1e-3
"""Largest ``max |RᵀR − I|`` of a pin's rotation that :func:`pin_of` takes (projected onto
the nearest rotation); a goal accepted with a looser ``orth_tol`` gives no pin."""


def pin_of(goal: Goal, robot: RobotModel | None = None) -> Pin | None:
    """``goal.pin()``, checked: None or a :class:`Pin` of finite arrays of the right shapes,
    its rotation the nearest proper rotation to the one given (a target rounded to a few
    digits, as [HLFOA] prints it, passed ``IKProblem(..., orth_tol=1e-4)`` and was then
    refused here: ``swarm-ik bench paper`` failed); None for a rotation further than
    :data:`PIN_ORTH_TOL` from one that the goal's own ``orth_tol`` accepted; refused further
    than both.

    Raises:
        InvalidArgumentError: the method raised, or returned anything else (the goal named).
        UnknownNameError: the pin names a frame ``robot`` (when given) does not have.
    """
    held = _users(goal, "pin()", goal.pin)
    if held is None:
        return None
    if robot is not None and isinstance(getattr(held, "frame", None), str):
        if not robot.model.existFrame(held.frame):  # (a typo: no proof drawn, silently)
            names = [f.name for f in robot.model.frames]
            raise UnknownNameError(
                f"{goal.describe()}.pin() names unknown frame {held.frame!r}; "
                + _frames_hint(held.frame, names)
            )
    shapes = {"point": (3,), "rotation": (3, 3), "axis": (3,), "direction": (3,), "look_at": (3,)}
    ok = isinstance(held, Pin) and isinstance(held.frame, str)
    fixed = {}
    for name, shape in shapes.items():
        value = getattr(held, name, None) if ok else None
        if value is None:
            continue
        arr: FloatArray | None
        if type(value) is np.ndarray and value.dtype == np.float64:
            arr = value  # (a goal's own float array: read, never written; a subclass, such
            # as np.matrix, is made a plain array below)
        else:
            arr = np.asarray(value, dtype=float) if _numbers(value) else None
        if arr is None or arr.shape != shape or not np.isfinite(arr).all():
            ok = False
            break
        fixed[name] = arr
    for name in ("axis", "direction"):  # (unit vectors; a zero one says nothing)
        if ok and name in fixed:
            norm = float(np.linalg.norm(fixed[name]))
            ok = norm > 1e-12
            fixed[name] = fixed[name] / norm if ok else fixed[name]
    rot = fixed.get("rotation")
    if ok and rot is not None:
        gram = rot.T @ rot
        gram.flat[::4] -= 1.0
        off = float(np.abs(gram).max())
        accepted = getattr(goal, "orth_tol", 0.0)  # (what the goal itself took as a rotation)
        ok = _det3(rot) > 0.0 and off <= max(PIN_ORTH_TOL, float(accepted))
        if ok and off > PIN_ORTH_TOL:  # (a rotation block accepted with a loose orth_tol
            return None  # says too little for a proof: none is drawn from this goal)
        if ok and off > 1e-12:  # (a rounded rotation, as a paper prints it: the nearest
            # one; a rotation off by round-off, a target made by FK, is one already)
            block = np.eye(4)
            block[:3, :3] = rot
            fixed["rotation"] = project_to_se3(block)[:3, :3]
    slacks = (held.point_slack, held.rotation_slack) if ok else ()
    if not ok or not all(is_finite_nonneg(s) for s in slacks):
        raise InvalidArgumentError(
            f"{goal.describe()}.pin() must return None or a swarm_ik.goals.Pin (a frame name, "
            "finite points and non-zero directions (3,), a rotation matrix (3, 3), slacks "
            ">= 0), got "
            f"{reprlib.repr(held)}"
        )
    return held._replace(**fixed)


def _det3(m: FloatArray) -> float:
    """The determinant of a ``(3, 3)`` matrix (the rule of Sarrus, in Python floats)."""
    (a, b, c), (d, e, f), (g, h, i) = m.tolist()
    return a * (e * i - f * h) - b * (d * i - f * g) + c * (d * h - e * g)


def _numbers(value: Any) -> bool:
    """Whether ``value`` reads as an array of real numbers."""
    try:
        arr = np.asarray(value)
    except Exception:
        return False
    return arr.dtype.kind in "biuf"


def errors_of(goal: Goal, state: State) -> tuple[float, float]:
    """``goal.errors(state)`` (computed once per point in a scope of
    :func:`reuse_goal_values`).

    Raises:
        InvalidArgumentError: a goal written outside swarm_ik whose ``errors`` raises (the
            goal and the method named, its exception chained) or returns anything but two
            real numbers.
    """
    return _kept(goal, state, "e", lambda s: _errors_pair(goal, s))  # type: ignore[no-any-return]


def _errors_pair(goal: Goal, state: State) -> tuple[float, float]:
    """``goal.errors(state)`` checked: ``(position error, angular error)`` as floats."""
    value = _users(goal, "errors(state)", lambda: goal.errors(state))
    try:
        pair = np.asarray(value)
    except Exception:  # (ragged nesting)
        pair = np.asarray(None)
    if pair.shape != (2,) or pair.dtype.kind not in "iuf":  # (two real numbers, any container)
        raise InvalidArgumentError(
            f"{goal.describe()}.errors(state) must return (position error [m], angular error "
            f"[rad]), two numbers (NaN where none), got {reprlib.repr(value)}"
        )
    return float(pair[0]), float(pair[1])


def _frames_hint(frame: Any, names: list[str], most: int = 40) -> str:
    """The frames of a robot for a message about an unknown ``frame``: all of them when few,
    else the closest names and how to list them all."""
    if len(names) <= most:
        return f"frames of this robot: {', '.join(names)}"
    close = difflib.get_close_matches(str(frame), names, n=5, cutoff=0.5)
    return (
        f"closest frames: {', '.join(close)}; " if close else ""
    ) + f"the robot has {len(names)} frames ([f.name for f in robot.model.frames])"


# --------------------------------------------------------------------------- state
class _Holders(threading.local):
    """Per thread: which :class:`State` each shared ``Data`` (by ``id``) holds the kinematics
    of."""

    def __init__(self) -> None:
        self.of: dict[int, Any] = {}


_STATE_HOLDER = _Holders()


def _read_only(q: Any) -> FloatArray:
    """A read-only view of ``q`` as float64: a goal reads the state's joint vectors, and one
    that wrote into them (a finite difference in place, say) changed the search's own
    array, and so a Result's ``q`` after its errors were judged.  One that is already a
    read-only float64 array (the route's answer) is kept as it is."""
    if type(q) is np.ndarray and q.dtype is FLOAT64 and not q.flags.writeable:
        return q
    view = np.asarray(q, dtype=float).view()
    view.flags.writeable = False
    return view


class State:
    """What a Python goal sees: the joint vector and Pinocchio's kinematics at it.

    Read it while the goal is evaluated (it reuses a Pinocchio ``Data`` of the robot and the
    calling thread kept for states, so a goal may run Pinocchio's FK at other joint values,
    e.g. through :meth:`RobotModel.fk_pinocchio`, without changing what the state reads; a
    second state made meanwhile, at ``q ± h`` for a finite difference say, takes that
    ``Data`` over, and this one computes its kinematics again when it is next read).

    Attributes:
        robot: The robot.
        q: Joint vector ``(nq,)`` (rad / m), read-only (copy it to change it).
        q0: The solve's start ``(nq,)``, or None (read-only too).
    """

    def __init__(self, robot: RobotModel, q: Any, q0: Any = None) -> None:
        self.robot = robot
        self.q = _read_only(q)
        self.q0 = None if q0 is None else _read_only(q0)
        self._q_pin = robot.to_pinocchio(self.q, copy=False)  # (read only)
        self._data = robot._data("state")  # (one Data per thread for states, reused)
        self._values = _values_at(robot, self.q, self.q0)  # (the Python goals' values here)
        self._jacobians = False
        self._hold()

    def _hold(self) -> Any:
        """The shared ``Data``, holding this state's kinematics (computed again when another
        state of the thread computed its own there since)."""
        data = self._data
        if _STATE_HOLDER.of.get(id(data)) is not self:
            pin.forwardKinematics(self.robot.model, data, self._q_pin)  # (frames: as asked)
            _STATE_HOLDER.of[id(data)] = self
            self._jacobians = False
        return data

    def frame_id(self, frame: str) -> int:
        """Pinocchio's id of a frame of the robot's (reduced) model.

        Raises:
            UnknownNameError: no such frame (the frames listed).
        """
        ids = self.robot._cache.setdefault("frame_id", {})
        fid = ids.get(frame) if isinstance(frame, str) else None
        if fid is None:
            model = self.robot.model
            if not isinstance(frame, str) or not model.existFrame(frame):
                names = [f.name for f in model.frames]
                raise UnknownNameError(f"unknown frame {frame!r}; " + _frames_hint(frame, names))
            fid = ids[frame] = int(model.getFrameId(frame))
        return int(fid)

    def pose(self, frame: str) -> FloatArray:
        """World pose of ``frame``, ``(4, 4)`` [m]."""
        placement = pin.updateFramePlacement(self.robot.model, self._hold(), self.frame_id(frame))
        return placement.homogeneous  # type: ignore[no-any-return]  # (a new array)

    def jacobian(self, frame: str) -> FloatArray:
        """LOCAL_WORLD_ALIGNED Jacobian of ``frame`` ``(6, nq)``: linear rows [m/rad] first,
        then angular; columns in the order of ``q`` (mimic columns summed into their
        drivers')."""
        robot = self.robot
        data = self._hold()
        if not self._jacobians:
            pin.computeJointJacobians(robot.model, data, self._q_pin)
            self._jacobians = True
        jac = pin.getFrameJacobian(
            robot.model, data, self.frame_id(frame), pin.ReferenceFrame.LOCAL_WORLD_ALIGNED
        )
        return robot.velocity_to_q(np.array(jac).reshape(6, robot.model.nv), self.q)


# --------------------------------------------------------------------------- goals
class Pin(NamedTuple):
    """What a goal holds its frame to, for the proofs made before a search
    (:func:`swarm_ik.api.unreachable_goal`, :func:`swarm_ik.api.conflicting_goals`): a point
    beyond the frame's reach, or two goals that no pose meets together, end a solve at once
    without knowing either goal's type.  Every field but ``frame`` may be None.

    Attributes:
        frame: The goal's frame.
        point: Its origin held at this world point ``(3,)`` [m]…
        point_slack: …to within this distance [m] (a bounded goal's region; 0: exact).
        rotation: Its rotation held at this world rotation ``(3, 3)``…
        rotation_slack: …to within this angle [rad].
        axis: A unit axis of the frame ``(3,)``, held along ``direction`` (a unit world
            vector ``(3,)``) or towards the world point ``look_at`` [m] from the origin.
        direction: See ``axis``.
        look_at: See ``axis``.
    """

    frame: str
    point: FloatArray | None = None
    point_slack: float = 0.0
    rotation: FloatArray | None = None
    rotation_slack: float = 0.0
    axis: FloatArray | None = None
    direction: FloatArray | None = None
    look_at: FloatArray | None = None


class Encoded(NamedTuple):
    """A compiled goal as the table holds it.

    Attributes:
        par: Float parameters, ``(P,)``.
        ipar: Integer parameters (frame indices…), ``(I,)``.
        rows: Residual rows.
    """

    par: FloatArray
    ipar: IntArray
    rows: int


def checked_encoding(goal: Goal, encode: Callable[[], Any]) -> Encoded:
    """``encode()`` of a compiled ``goal``, checked once when a problem's goal table is made
    (the per-call paths then read ``.par`` of the same goal's blocks): an :class:`Encoded`
    of float parameters, integer parameters and rows; anything else (a plain tuple
    included), or a goal with a kernel but no ``encode``, is refused naming the goal.

    Raises:
        InvalidArgumentError: no ``encode``, or a block that is not ``(par (P,) floats,
            ipar (I,) integers, rows >= 1)``.
    """
    form = (
        "encode(robot, q0) must return goals.base.Encoded(par, ipar, rows): float "
        "parameters (P,), integer parameters (I,) and the number of residual rows "
        "(docs/goals.md)"
    )
    try:
        block = encode()
    except NotImplementedError:
        if type(goal).encode is Goal.encode:
            raise InvalidArgumentError(
                f"{goal.describe()} names a compiled kernel but defines no encode: {form}"
            ) from None
        raise
    except SwarmIKError:
        raise
    except Exception as exc:  # (the goal's own code: any error it raises)
        raise InvalidArgumentError(
            f"{goal.describe()}.encode(robot, q0) raised {type(exc).__name__}: {quoted_error(exc)}"
        ) from exc
    if not isinstance(block, Encoded):
        raise InvalidArgumentError(f"{goal.describe()}: {form}, got {reprlib.repr(block)}")
    par, ipar, rows = block
    try:
        par = np.ascontiguousarray(par, dtype=np.float64).reshape(-1)
        ipar_arr = np.asarray(ipar)
        if ipar_arr.size and not np.issubdtype(ipar_arr.dtype, np.integer):
            raise TypeError("integer parameters that are not integers")
        ipar = np.ascontiguousarray(ipar_arr, dtype=np.int64).reshape(-1)
    except (TypeError, ValueError) as exc:
        raise InvalidArgumentError(f"{goal.describe()}: {form} ({exc})") from None
    if isinstance(rows, bool) or not isinstance(rows, (int, np.integer)) or rows < 1:
        raise InvalidArgumentError(f"{goal.describe()}: {form}; rows = {rows!r}")
    if np.isnan(par).any():  # (a field given as NaN: the search would run its whole budget)
        raise InvalidArgumentError(
            f"{goal.describe()}: encode(robot, q0) gave NaN parameters "
            f"{reprlib.repr(par.tolist())}: a goal's numbers must be numbers"
        )
    if block.par is par and block.ipar is ipar:
        return block
    return Encoded(par, ipar, int(rows))


WEIGHT_SPREAD = 100.0
"""The largest ratio of two primary goals' weights a problem takes without a warning: the
search's damping follows the heaviest goal's rows, so a goal lighter by more than this may be
left unmet where it could be met (a Panda ``Orientation`` of weight 1 with a ``Position`` of
weight 1e-3: 10 of 12 reachable pairs met in 0.2 s each, at 1e-4: 1 of 6 in 0.5 s; at 1e-2:
every one).  Weights trade primary goals off only where they conflict."""

WEIGHT_RANGE = (1e-6, 1e6)
"""The weights a goal takes, and the nonzero ``w_rot`` of a problem: ``[1e-6, 1e6]``.
Weights are relative (the default is 1); beyond this range the squared weighted residuals
overflow (``1e308``) or the damped least squares of the search is ill-conditioned."""


def weight_value(value: Any, what: str = "weight") -> float:
    """A positive finite number, or :class:`InvalidArgumentError` naming ``what``."""
    if isinstance(value, (bool, str)):
        raise InvalidArgumentError(f"{what} must be a positive number, got {value!r}")
    try:
        w = float(value)
    except (TypeError, ValueError, OverflowError):
        raise InvalidArgumentError(f"{what} must be a positive number, got {value!r}") from None
    if not (np.isfinite(w) and w > 0.0):
        raise InvalidArgumentError(f"{what} must be a positive finite number, got {value!r}")
    return w


def goal_weight(value: Any, what: str = "weight") -> float:
    """A weight within :data:`WEIGHT_RANGE`, or :class:`InvalidArgumentError` naming ``what``
    and the range."""
    w = weight_value(value, what)
    low, high = WEIGHT_RANGE
    if not low <= w <= high:
        raise InvalidArgumentError(
            f"{what} must be between 1e-6 and 1e6 (weights are relative), got {w:.15g}"
        )
    return w


def non_negative(value: Any, what: str) -> float:
    """A finite number ``>= 0`` (a margin [m]), or :class:`InvalidArgumentError` naming
    ``what``."""
    try:
        m = float(value)
    except (TypeError, ValueError):
        m = float("nan")
    if isinstance(value, (bool, str)) or not (np.isfinite(m) and m >= 0.0):
        raise InvalidArgumentError(f"{what} must be >= 0 [m], got {value!r}")
    return m


def vec3(value: Any, what: str, *, unit: bool = False) -> FloatArray:
    """3 finite numbers as a float array (normalised when ``unit``), or
    :class:`InvalidArgumentError` naming ``what``."""
    if isinstance(value, (str, bytes)):
        raise InvalidArgumentError(f"{what} must be 3 numbers, got {value!r}")
    arr = floats_or(value, lambda: f"{what} must be 3 numbers, got {reprlib.repr(value)}")
    if arr.shape != (3,):
        raise InvalidArgumentError(f"{what} must be 3 numbers, got shape {arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise InvalidArgumentError(f"{what} must be finite, got {arr.tolist()}")
    if unit:
        scale = np.max(np.abs(arr))
        if scale == 0.0:
            raise InvalidArgumentError(f"{what} must not be the zero vector")
        arr = arr / scale
        arr = arr / np.linalg.norm(arr)
    return arr


class _GoalType(type):
    """The type of every goal class: a call with arguments the goal does not take (an unknown
    keyword, a missing field) is refused with :class:`InvalidArgumentError` naming the valid
    fields (Python's ``TypeError`` of the dataclass's ``__init__`` before), as a goals file's
    unknown field is."""

    def __call__(cls, *args: Any, **kwargs: Any) -> Any:
        try:
            return super().__call__(*args, **kwargs)
        except TypeError as exc:
            import dataclasses
            import inspect

            try:  # (the arguments against __init__'s signature: a TypeError raised inside a
                # goal's own code is left as it is)
                inspect.signature(cls.__init__).bind(None, *args, **kwargs)  # type: ignore[misc]
            except TypeError:
                fields = [f for f in dataclasses.fields(cls) if f.init]  # type: ignore[arg-type]
                valid = [f.name for f in fields if not f.kw_only]  # (positional first, as
                valid += [f.name for f in fields if f.kw_only]  # goal_to_dict lists them)
                raise InvalidArgumentError(
                    f"goal {cls.__name__}: {exc}; valid fields: {', '.join(valid)}"
                ) from None
            raise


@dataclass(frozen=True)
class Goal(metaclass=_GoalType):
    """Base of every goal (see the module docstring for the protocol).

    Attributes:
        weight: Weight of the goal's residual rows (dimensionless; a Pose's rotation rows are
            in radians, its position rows in metres); keyword-only, between 1e-6 and 1e6
            (:data:`WEIGHT_RANGE`; weights are relative to each other, default 1).
        primary: Must be met to tolerance (True) or optimised after the primary goals in
            their null space (False); keyword-only (default True, False for the joint-space
            preferences).
    """

    weight: float = field(default=1.0, kw_only=True)
    primary: bool = field(default=True, kw_only=True)
    kernel: ClassVar[Any] = None
    """The compiled residual kernel (None: a Python goal)."""
    units: ClassVar[tuple[str, ...]] = ()
    """Fields that are directions: 3 finite numbers, not zero, stored normalised."""
    vectors: ClassVar[tuple[str, ...]] = ()
    """Fields that are points or vectors: 3 finite numbers, stored as a float array."""

    def __post_init__(self) -> None:
        name = type(self).__name__
        frame = getattr(self, "frame", None)
        if frame is not None and not isinstance(frame, str):
            raise InvalidArgumentError(
                f"{name}.frame must be a frame name (a string), got {reprlib.repr(frame)}"
            )
        for label in self.units:
            object.__setattr__(
                self, label, vec3(getattr(self, label), f"{name}.{label}", unit=True)
            )
        for label in self.vectors:
            object.__setattr__(self, label, vec3(getattr(self, label), f"{name}.{label}"))
        object.__setattr__(self, "weight", goal_weight(self.weight, f"{name}.weight"))
        if not isinstance(self.primary, (bool, np.bool_)):
            raise InvalidArgumentError(
                f"{name}.primary must be true or false, got {self.primary!r}"
            )
        object.__setattr__(self, "primary", bool(self.primary))

    @property
    def compiled(self) -> bool:
        """Whether the goal has a compiled kernel."""
        return type(self).kernel is not None

    def kernel_of(self) -> Any:
        """The compiled kernel of this goal: the class's ``kernel`` (a goal whose form
        changes its rows, such as a bounded :class:`~swarm_ik.goals.Pose`, may name another
        per instance, so each form compiles only when used)."""
        return type(self).kernel

    @property
    def exact(self) -> bool:
        """Whether the goal asks for a point, not a region (a ``Pose`` with a
        ``tolerance`` or a ``Position`` with a ``radius`` does not: it encodes other rows and
        flags, is judged against its bounds, and is no single-pose target)."""
        return True

    @property
    def is_primary(self) -> bool:
        """The goal's ``primary`` field."""
        return bool(self.primary)

    def frame_name(self) -> str | None:
        """The goal frame (None for goals without one)."""
        return getattr(self, "frame", None)

    def describe(self) -> str:
        """Short label for reports, e.g. ``Pose(left_gripper)``."""
        f = self.frame_name()
        return f"{type(self).__name__}({f})" if f else type(self).__name__

    # ------------------------------------------------------------- compiled goals
    def encode(self, robot: RobotModel, q0: FloatArray | None) -> Encoded:
        """The goal's parameter block for its kernel (compiled goals)."""
        raise NotImplementedError(f"{type(self).__name__} is not a compiled goal")

    def extra_frames(self, robot: RobotModel) -> tuple[Any, Any, Any] | None:
        """Frames the goal needs beyond the robot's goal frames (appended to the problem's
        tree): ``(joint ids of robot.model, rotations, translations)``, or None.  A goal that
        adds frames takes a third argument ``frame0`` in :meth:`encode`: the index of its
        first frame in the tree."""
        return None

    # ------------------------------------------------------------- every goal
    def residual(self, state: State) -> FloatArray:
        """The unweighted residual ``(m,)`` at ``state`` (zero when the goal is met)."""
        raise NotImplementedError(f"{type(self).__name__} defines no residual(state)")

    def jacobian(self, state: State) -> FloatArray:
        """``∂residual/∂q`` ``(m, nq)`` at ``state``."""
        raise NotImplementedError(f"{type(self).__name__} defines no jacobian(state)")

    def errors(self, state: State) -> tuple[float, float]:
        """``(position error [m], angular error [rad])`` at ``state`` (NaN where none) that
        the tolerances judge; by default the norm of the residual as a position error."""
        # (math.hypot: no overflow where a huge residual's squares would overflow)
        return math.hypot(*residual_of(self, state).tolist()), float("nan")

    def met(self, state: State, tol_pos: float, tol_rot: float) -> tuple[float, float, bool, Any]:
        """The independent check at ``state``: ``(position error, angular error, met,
        details)``; a Python goal's own ``tolerance`` attribute, when it has one, replaces
        ``tol_pos``."""
        dp, dr = self.errors(state) if self.compiled else errors_of(self, state)
        own = self.own_tolerance()
        if own is not None:
            tol_pos = own
        met = not (dp > tol_pos) and not (dr > tol_rot)
        if math.isnan(dp) and math.isnan(dr):
            met = False  # nothing measured: never a vacuous success
        return float(dp), float(dr), bool(met), None

    def preferred_start(self, robot: RobotModel) -> Any:
        """A configuration ``(nq,)`` the search may start from when the solve has no ``q0``
        (``Posture``: its reference), or None (the default: no opinion; the first goal that
        names one is used, else the middle of the ranges)."""
        return None

    def pin(self) -> Pin | None:
        """What this goal holds its frame to (:class:`Pin`), for the proofs before a search;
        None (the default) when it says nothing of the kind (such a goal is still solved and
        judged; only those early proofs cannot see it)."""
        return None

    def infeasible(self, robot: RobotModel, tol_pos: float, tol_rot: float) -> str | None:
        """Why no configuration of ``robot`` can meet this goal within the tolerances, found
        from the goal's data alone before any search (a joint value beyond the joint's
        limits, a centre-of-mass margin deeper than its polygon), or None when that is not
        known.  A primary goal that says so ends its solve ``"unreachable"`` at once
        (:func:`swarm_ik.api.unreachable_goal`); a goal that is not primary is never asked."""
        return None

    def own_tolerance(self) -> float | None:
        """A Python goal's own position tolerance (its ``tolerance`` attribute), which
        replaces the solve's ``tol_pos`` wherever this goal is judged; None for a goal without
        one and for compiled goals (their kernel's rows say how far they may be off, as a
        bounded :class:`~swarm_ik.goals.Pose`'s do; a field of that name means what the goal
        says, :class:`~swarm_ik.goals.AvoidCollisions`'s is its sphere fit's).

        Raises:
            InvalidArgumentError: a tolerance that is not a positive finite number (NaN would
                judge every error as met).
        """
        tol = None if self.compiled else getattr(self, "tolerance", None)
        if tol is None:
            return None
        if isinstance(tol, bool) or not isinstance(tol, (int, float, np.integer, np.floating)):
            raise InvalidArgumentError(
                f"{self.describe()}: tolerance must be a positive number, got {reprlib.repr(tol)}"
            )
        if not (math.isfinite(tol) and tol > 0):
            raise InvalidArgumentError(
                f"{self.describe()}: tolerance must be a positive finite number, got {tol!r}"
            )
        return float(tol)

    def rows(self, robot: RobotModel, state: State | None = None) -> int:
        """Number of residual rows (a Python goal: the length of its residual)."""
        if self.compiled:
            return checked_encoding(self, lambda: self.encode(robot, None)).rows
        if state is None:
            state = State(robot, robot.mid_q())
        return int(np.size(self.residual(state)))


@dataclass(frozen=True)
class StandIn(Goal):
    """A Python goal that costs next to nothing: one joint held at a value (``residual =
    q[joint] − value``).  It stands in for a problem's own Python goals where only the code
    around them must run: :func:`swarm_ik.api.warm_up` loads the compiled kernels of a route
    before its clock starts without calling a user's goals (which may take milliseconds a
    call).

    Attributes:
        joint: Index of the joint in ``q``.
        value: The value it is held at (rad / m).
    """

    joint: int = 0
    value: float = 0.0

    def residual(self, state: State) -> FloatArray:
        """``[q[joint] − value]``."""
        return np.array([state.q[self.joint] - self.value])

    def jacobian(self, state: State) -> FloatArray:
        """The unit row of ``joint``, ``(1, nq)``."""
        jac = np.zeros((1, state.q.shape[0]))
        jac[0, self.joint] = 1.0
        return jac


def stand_ins(goals: Any, lower: FloatArray, upper: FloatArray) -> list[Goal]:
    """``goals`` with each Python goal replaced by a :class:`StandIn` of the same weight and
    priority: a primary one holds the first joint at 70 % of its range (met by a few polish
    steps from the middle), a secondary one the last joint at 20 % of its range (so that a
    descent in the primary goals' null space has work to do).  Compiled goals are kept."""
    lo, hi = np.asarray(lower, dtype=float), np.asarray(upper, dtype=float)
    last = lo.shape[0] - 1
    out: list[Goal] = []
    for gl in goals:
        if gl.compiled:
            out.append(gl)
            continue
        j, share = (0, 0.7) if gl.is_primary else (last, 0.2)
        span = hi[j] - lo[j]
        value = lo[j] + share * span if np.isfinite(span) else np.clip(0.0, lo[j], hi[j])
        out.append(StandIn(j, float(value), weight=gl.weight, primary=gl.is_primary))
    return out


def search_rows(
    goal: Goal, state: State, want_jac: bool = True
) -> tuple[FloatArray, FloatArray | None]:
    """A goal's weighted rows as the search stacks them, from its numpy ``residual`` and
    ``jacobian``: ``(w·r (m,), w·∂r/∂q (m, nq) or None)``.  The search drives them to zero.
    A Python goal's own ``tolerance`` ``t`` (which judges the answer, :meth:`Goal.met`)
    leaves slack to the other goals: its rows are the norm dead zone
    ``r·max(1 − s/‖r‖, 0)`` with ``s =`` :data:`SLACK_SHARE`·``t``, zero while ``‖r‖ ≤ s``,
    and their Jacobian ``(1 − s/‖r‖)·J + s·r rᵀJ/‖r‖³`` (as a bounded ``Pose`` and
    ``Position(radius=…)`` leave slack in their compiled rows).  A one-row goal may return
    its Jacobian as ``(nq,)``.

    Raises:
        InvalidArgumentError: a Python goal without ``residual``/``jacobian``, returning
            arrays of another shape than ``(m,)`` and ``(m, nq)`` (the goal and the shapes
            named), NaN or infinite values, or values beyond :data:`ROW_LIMIT` once
            weighted (the goal and ``q`` named).
    """
    nq = state.q.shape[0]
    try:
        r = residual_of(goal, state)
        jac = jacobian_of(goal, state) if want_jac else None
    except NotImplementedError as exc:
        raise InvalidArgumentError(
            f"{exc}: a goal written in Python defines residual(state) -> (m,) and "
            "jacobian(state) -> (m, nq) (docs/goals.md)"
        ) from None
    except InvalidArgumentError:
        raise  # (named already: complex values)
    except (TypeError, ValueError) as exc:
        if built_in(goal):
            raise
        raise InvalidArgumentError(
            f"{goal.describe()}: residual(state) and jacobian(state) must return arrays of "
            f"numbers ({type(exc).__name__}: {quoted_error(exc)})"
        ) from None
    if r.ndim > 1:
        raise InvalidArgumentError(
            f"{goal.describe()}.residual(state) must have shape (m,), got {r.shape}"
        )
    r = np.atleast_1d(r)
    if r.shape[0] == 0:
        raise InvalidArgumentError(
            f"{goal.describe()}.residual(state) returned no rows: a goal measures at least one "
            "number (zero when it is met)"
        )
    if jac is not None and jac.shape != (r.shape[0], nq):
        if jac.shape == (nq,) and r.shape[0] == 1:
            jac = jac[None]
        else:
            raise InvalidArgumentError(
                f"{goal.describe()}.jacobian(state) must have shape ({r.shape[0]}, {nq}) (one "
                f"row per residual entry, one column per joint), got {jac.shape}"
            )
    if not (np.isfinite(r).all() and (jac is None or np.isfinite(jac).all())):
        which = "residual" if not np.isfinite(r).all() else "jacobian"
        raise InvalidArgumentError(
            f"{goal.describe()}.{which}(state) returned NaN or infinite values at "
            f"q = {np.round(state.q, 6).tolist()}: a goal's rows must be finite wherever the "
            "search may go (within the joint limits)"
        )
    w = goal.weight
    own = goal.own_tolerance()
    if own is not None:
        r, jac = dead_zone(r, jac, SLACK_SHARE * own)
    r, jac = w * r, (None if jac is None else w * jac)
    big = max(float(np.abs(r).max()), 0.0 if jac is None else float(np.abs(jac).max()))
    if big > ROW_LIMIT:  # (the search squares the rows: beyond this they overflow)
        raise InvalidArgumentError(
            f"{goal.describe()}: its weighted rows reach {big:.3g} at q = "
            f"{np.round(state.q, 6).tolist()}; the search squares them, so each value of "
            f"weight·residual(state) and weight·jacobian(state) must stay within {ROW_LIMIT:g} "
            "(scale the goal's rows down)"
        )
    return r, jac


ROW_LIMIT = 1e100
"""Largest magnitude of a Python goal's weighted residual and Jacobian entries
(:func:`search_rows`): the search forms ``JᵀJ`` and ``rᵀr``, which overflowed float64 at
rows of 1e160 (a NaN step, and the goal blamed for NaN at a NaN ``q``)."""


SLACK_SHARE = 0.9
"""Share of a Python goal's own ``tolerance`` its search rows leave as slack
(:func:`search_rows`): the rows vanish within 0.9 of the tolerance, so another goal may pull
the residual anywhere up to there (a plane goal with a 1 mm tolerance beside a point 0.5 mm
off the plane: the point is met exactly; a slack of a quarter left the least-squares
compromise of the two at 0.125 mm from the point on some robots).  The numpy polish stops
such a goal at its tolerance itself (:class:`swarm_ik.solvers.python_lm.PythonPolisher`: its
errors are the judge's, on Pinocchio's state), beyond where its rows vanish."""


def dead_zone(
    r: FloatArray, jac: FloatArray | None, slack: float
) -> tuple[FloatArray, FloatArray | None]:
    """The norm dead zone of a residual: ``r·(1 − s/‖r‖)`` beyond ``‖r‖ > s``, zero within,
    and its Jacobian ``(1 − s/‖r‖)·J + s·r (rᵀJ)/‖r‖³`` (the derivative of ``r − s·r/‖r‖``).

    Args:
        r: Residual ``(m,)``.
        jac: Its Jacobian ``∂r/∂q`` ``(m, nq)``, or None.
        slack: ``s`` ≥ 0, in the residual's units.

    Returns:
        ``(r', J')`` of the same shapes (``J'`` None when ``jac`` is).
    """
    norm = float(np.sqrt(r @ r))
    if norm <= slack:
        return np.zeros_like(r), (None if jac is None else np.zeros_like(jac))
    scale = 1.0 - slack / norm
    if jac is None:
        return scale * r, None
    return scale * r, scale * jac + (slack / norm**3) * np.outer(r, r @ jac)


def frame_index(goal: Goal, robot: RobotModel, frame: str | None = None) -> int:
    """Index of the goal's frame (or of ``frame``, a second frame the goal names) among the
    robot's goal frames (the tree's frames).

    Raises:
        UnknownNameError: not a goal frame of the robot (they are listed).
    """
    frame = goal.frame_name() if frame is None else frame
    if frame not in robot.frames:
        full = robot.full_model
        if not isinstance(frame, str) or not full.existFrame(frame):  # (no frame of the URDF)
            names = [f.name for f in full.frames if f.name != "universe"]
            raise UnknownNameError(
                f"{goal.describe()}: unknown frame {frame!r}; " + _frames_hint(frame, names)
            )
        raise UnknownNameError(
            f"{goal.describe()}: {frame!r} is not a goal frame of this robot; goal frames: "
            f"{', '.join(robot.frames)} (load the robot with every goal frame: "
            f"load_robot(name, ee_frame=[...]); on the command line, add --frame {frame})"
        )
    return robot.frames.index(frame)


def skew(v: FloatArray) -> FloatArray:
    """``[v]×`` (3, 3)."""
    return np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])
