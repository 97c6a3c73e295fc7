"""Peer IK solvers behind one interface, for the benchmarks.

Every adapter is built for one :class:`~swarm_ik.RobotModel` (the same chain: URDF root link
to the model's end-effector frame, the same joint order and limits) and answers
``solve(target, q0, seed) -> Answer``:

* ``q``: the answer in the model's joint order, continuous joints wrapped into ``[-π, π)``
  (``None``: the peer returned nothing);
* ``claimed``: the peer's own success flag (what a user of that library would be told);
* ``call_s``: the **user-facing call**: wall-clock seconds from the 4x4 target (and ``q0``)
  to the answer, every conversion the library needs included (our ``IKProblem``, TRAC-IK's
  quaternion, pink's ``SE3``, …);
* ``own_s``: the **solver's own time**: the library's inner solve (our ``Result.time_s``;
  the ``pytracik.ik`` call; rtb's compiled ``IK_*_c`` function; pink's ``solve_ik`` calls;
  ikpy's optimiser).

Adapters (:data:`PEERS`; the optional ones need ``pip install 'swarm_ik[bench]'``):

==============  ==============================================================================
``swarm``       ``swarm_ik.solve(IKProblem(robot, T), "swarm", time_limit=budget)``
``ik-solver``   ``swarm_ik.IKSolver(robot, time_limit=budget).solve(T)`` (when the package has
                ``IKSolver``)
``dls``         ``swarm_ik.solve(IKProblem(robot, T), "dls", time_limit=budget)``
``tracik-1e-5`` TRAC-IK (``pytracik``), Speed mode, timeout = budget, eps 1e-5 (its own test:
                every twist component ≤ eps, in its own frame)
``tracik-1e-6`` the same with eps 1e-6 (both named by their eps, whatever ``--tol``: with eps
                1e-5 a claimed success may miss the Euclidean 1e-5 check, 24 of 200 Panda
                targets in review 99; the table reports both)
``tracik``      the same with eps ``tol/√3`` (follows ``--tol``: every component within it puts
                each error's norm within ``tol``, as ``rtb-lm``'s ``½ tol²`` does)
``rtb-lm``      roboticstoolbox-python ``ETS.ik_LM`` (C++, Chan's λ), the ETS read from the
                same URDF; tolerance on its ``E = ½ eᵀe`` set to ``½ tol²`` (so that a claimed
                success has ‖e‖ ≤ tol: the 6-vector's norm, where our check takes ‖Δp‖ and
                the angle each within tol, up to √2·tol together; at most one more iteration
                of rtb's); no time limit (its iteration and search limits)
``rtb-gn``      ``ETS.ik_GN`` (Gauss-Newton), the same settings
``rtb-nr``      ``ETS.ik_NR`` (Newton-Raphson), the same settings
``pink``        pink (``pin-pink``): a ``FrameTask`` per frame, ``solve_ik`` (QP with the
                configuration limits, quadprog) iterated with ``dt = 1`` until every frame's
                error is within tol or the budget is spent; several frames / targets accepted
``ikpy``        ikpy ``Chain.inverse_kinematics_frame`` (SciPy least squares, orientation
                ``all``); no time limit
==============  ==============================================================================

Each adapter also exposes ``fk(q)`` through the peer's own kinematics where it has one, so
the tests can check that the peer's chain is the model's (to 1e-9 on random ``q``).
"""

from __future__ import annotations

import functools
import io
import math
import time
import xml.etree.ElementTree as ET
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any, Protocol

import numpy as np

from swarm_ik.bench._placo_worker import geometry_free_urdf
from swarm_ik.bench.common import quiet_c_output, urdf_link_of_frame, urdf_root_link
from swarm_ik.errors import InvalidArgumentError

EXTRA_HINT = "pip install 'swarm_ik[bench]'"
"""How to install the optional peers."""


@dataclass(frozen=True)
class Answer:
    """One peer call.

    Attributes:
        q: Joint values ``(nq,)`` in the model's order, wrapped; ``None`` when no answer.
        claimed: The peer's own success flag.
        call_s: User-facing call time [s] (conversions included).
        own_s: The solver's own time [s] (NaN when it cannot be separated).
        iterations: Iterations or evaluations the peer reports (NaN when it does not).
    """

    q: np.ndarray | None
    claimed: bool
    call_s: float
    own_s: float
    iterations: float = math.nan


class Peer(Protocol):
    """What the benchmarks need of a peer adapter."""

    name: str

    def solve(
        self, target: np.ndarray, q0: np.ndarray, seed: int
    ) -> Answer: ...  # pragma: no cover


@dataclass(frozen=True)
class PeerInfo:
    """A registered peer.

    Attributes:
        name: Adapter name (CSV ``solver`` column).
        package: Python module it needs (``None``: only swarm_ik).
        what: One line for reports.
        factory: ``(robot, budget_s, tol) -> Peer``.
    """

    name: str
    package: str | None
    what: str
    factory: Callable[[Any, float, float], Peer]

    def available(self) -> bool:
        """Whether the module it needs imports (and, for ``ik-solver``, exists)."""
        if self.name == "ik-solver":
            import swarm_ik

            return hasattr(swarm_ik, "IKSolver")
        if self.package is None:
            return True
        return _importable(self.package)


@functools.cache
def _importable(module: str) -> bool:
    import importlib

    try:
        importlib.import_module(module)
    except ImportError:
        return False
    return True


def _need(module: str, peer: str) -> Any:
    import importlib

    try:
        return importlib.import_module(module)
    except ImportError:
        raise InvalidArgumentError(
            f"peer {peer!r} needs the optional package {module!r}: {EXTRA_HINT}"
        ) from None


# --------------------------------------------------------------------------- ours
class OursSolve:
    """``swarm_ik.solve(IKProblem(robot, T), solver, …)``: our public one-shot call."""

    def __init__(self, robot: Any, budget_s: float, tol: float, solver: str) -> None:
        import swarm_ik

        self._sik = swarm_ik
        self.robot = robot
        self.name = solver
        self.solver = solver
        self.budget_s = float(budget_s)
        self.tol = float(tol)
        swarm_ik.solvers.get(solver)  # an unknown name is refused with the list

    def solve(self, target: np.ndarray, q0: np.ndarray, seed: int) -> Answer:
        sik = self._sik
        t0 = time.perf_counter()
        res = sik.solve(
            sik.IKProblem(self.robot, target),
            self.solver,
            seed=seed,
            q0=q0,
            time_limit=self.budget_s,
            tol_pos=self.tol,
            tol_rot=self.tol,
        )
        dt = time.perf_counter() - t0
        return Answer(res.q, bool(res.success), dt, float(res.time_s), float(res.n_evals))

    def fk(self, q: np.ndarray) -> np.ndarray:
        return np.asarray(self.robot.fk(q), dtype=float)


class OursIKSolver:
    """``swarm_ik.IKSolver(robot, …).solve(T)``: the reusable solver (bound once per robot)."""

    def __init__(self, robot: Any, budget_s: float, tol: float) -> None:
        import swarm_ik

        self.name = "ik-solver"
        self.robot = robot
        self._ik = swarm_ik.IKSolver(  # type: ignore[attr-defined]
            robot, solver="swarm", tol_pos=tol, tol_rot=tol, time_limit=budget_s
        )

    def solve(self, target: np.ndarray, q0: np.ndarray, seed: int) -> Answer:
        t0 = time.perf_counter()
        res = self._ik.solve(target, q0=q0, seed=seed)
        dt = time.perf_counter() - t0
        return Answer(res.q, bool(res.success), dt, float(res.time_s), float(res.n_evals))


# --------------------------------------------------------------------------- TRAC-IK
class TracIK:
    """TRAC-IK (``pytracik``, Speed mode) on the model's chain.

    Args:
        robot: The robot (URDF root link → end-effector link is the chain).
        budget_s: TRAC-IK's timeout [s].
        eps: TRAC-IK's own tolerance (per twist component).
        name: Adapter name.

    Raises:
        InvalidArgumentError: ``pytracik`` is missing, or its chain is not the model's.
    """

    def __init__(self, robot: Any, budget_s: float, eps: float, name: str = "tracik") -> None:
        pt = _need("pytracik", name)
        self._pt = pt
        self.name = name
        self.robot = robot
        ee = urdf_link_of_frame(robot.urdf_path, robot.ee_frame)
        with quiet_c_output():
            self._solver = pt.TRAC_IK(
                urdf_root_link(robot.urdf_path),
                ee,
                robot.urdf_path.read_text(),
                float(budget_s),
                float(eps),
                pt.SolveType.Speed,
            )
        dof = pt.get_num_joints(self._solver)
        if dof != robot.nq:
            raise InvalidArgumentError(
                f"TRAC-IK's chain of {robot.name} has {dof} joints, the model {robot.nq}"
            )
        pt.set_joint_limits(self._solver, list(robot.lower), list(robot.upper))

    def solve(self, target: np.ndarray, q0: np.ndarray, seed: int) -> Answer:
        t0 = time.perf_counter()
        p = target[:3, 3]
        qx, qy, qz, qw = _quaternion(target)  # (scipy's conversion took 50-160 µs of the call)
        t1 = time.perf_counter()
        out = self._pt.ik(self._solver, q0, p[0], p[1], p[2], qx, qy, qz, qw)
        t2 = time.perf_counter()
        ok = out[0] >= 0
        q = self.robot.wrap(np.asarray(out[1:], dtype=float)) if ok else None
        dt = time.perf_counter() - t0
        return Answer(q, bool(ok), dt, t2 - t1)

    def fk(self, q: np.ndarray) -> np.ndarray:
        from scipy.spatial.transform import Rotation

        out = np.asarray(self._pt.fk(self._solver, np.asarray(q, dtype=float)), dtype=float)
        if out.shape == (4, 4):
            return out
        t = np.eye(4)  # (x, y, z, qx, qy, qz, qw)
        t[:3, 3] = out[:3]
        t[:3, :3] = Rotation.from_quat(out[3:7]).as_matrix()
        return t


def _quaternion(target: np.ndarray) -> tuple[float, float, float, float]:
    """The unit quaternion ``(x, y, z, w)`` of a pose's rotation (Shepperd's method, on the
    nine Python floats: what a user hands TRAC-IK, at a few µs)."""
    (a, b, c), (d, e, f), (g, h, i) = (row[:3] for row in target[:3].tolist())
    tr = a + e + i
    if tr > 0.0:
        s = 2.0 * math.sqrt(tr + 1.0)
        return (h - f) / s, (c - g) / s, (d - b) / s, 0.25 * s
    if a >= e and a >= i:
        s = 2.0 * math.sqrt(1.0 + a - e - i)
        return 0.25 * s, (b + d) / s, (c + g) / s, (h - f) / s
    if e >= i:
        s = 2.0 * math.sqrt(1.0 + e - a - i)
        return (b + d) / s, 0.25 * s, (f + h) / s, (c - g) / s
    s = 2.0 * math.sqrt(1.0 + i - a - e)
    return (c + g) / s, (f + h) / s, 0.25 * s, (d - b) / s


# --------------------------------------------------------------------------- rtb
@functools.lru_cache(maxsize=16)
def _rtb_ets(urdf: str, root: str, ee: str) -> Any:
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        rtb = _need("roboticstoolbox", "rtb")
        from roboticstoolbox.models.URDF.URDFRobot import URDF_file

        elinks, name, _ = URDF_file(io.StringIO(urdf))
        robot = rtb.Robot(elinks, name=name)
    return robot.ets(start=root, end=ee)


class _Timed:
    """Wraps a function, remembering the duration of its last call [s]."""

    def __init__(self, fn: Callable[..., Any]) -> None:
        self.fn = fn
        self.last = math.nan

    def __call__(self, *args: Any, **kwargs: Any) -> Any:
        t0 = time.perf_counter()
        try:
            return self.fn(*args, **kwargs)
        finally:
            self.last = time.perf_counter() - t0


_RTB_METHODS = {
    "rtb-lm": ("ik_LM", "IK_LM_c"),
    "rtb-gn": ("ik_GN", "IK_GN_c"),
    "rtb-nr": ("ik_NR", "IK_NR_c"),
}


class RtbIK:
    """roboticstoolbox-python's numerical IK (``ETS.ik_LM`` / ``ik_GN`` / ``ik_NR``, C++).

    The ETS is read from the model's URDF (meshes dropped) from the root link to the
    end-effector link.  The compiled function is wrapped once to time the solver's own part.

    Args:
        robot: The robot.
        tol: Strict tolerance [m and rad]; rtb's ``tol`` (on ``E = ½ eᵀe``) is ``½ tol²``.
        name: ``rtb-lm``, ``rtb-gn`` or ``rtb-nr``.
    """

    def __init__(self, robot: Any, tol: float, name: str = "rtb-lm") -> None:
        if name not in _RTB_METHODS:
            raise InvalidArgumentError(
                f"unknown rtb method {name!r}; valid: {sorted(_RTB_METHODS)}"
            )
        rtb = _need("roboticstoolbox", name)
        method, cfun = _RTB_METHODS[name]
        namespace = getattr(rtb.ETS, method).__globals__  # the module calling the C function
        timed = namespace[cfun]
        if not isinstance(timed, _Timed):
            timed = _Timed(timed)
            namespace[cfun] = timed
        self._timed = timed
        self.name = name
        self.robot = robot
        self.ets = _rtb_ets(
            geometry_free_urdf(robot.urdf_path),
            urdf_root_link(robot.urdf_path),
            urdf_link_of_frame(robot.urdf_path, robot.ee_frame),
        )
        if self.ets.n != robot.nq:
            raise InvalidArgumentError(
                f"rtb's chain of {robot.name} has {self.ets.n} joints, the model {robot.nq}"
            )
        self._call = getattr(self.ets, method)
        self.rtb_tol = 0.5 * float(tol) ** 2

    def solve(self, target: np.ndarray, q0: np.ndarray, seed: int) -> Answer:
        t0 = time.perf_counter()
        sol = self._call(target, q0=q0, tol=self.rtb_tol, joint_limits=True)
        dt = time.perf_counter() - t0
        q = self.robot.wrap(np.asarray(sol.q, dtype=float))
        return Answer(q, bool(sol.success), dt, self._timed.last, float(sol.iterations))

    def fk(self, q: np.ndarray) -> np.ndarray:
        return np.asarray(self.ets.fkine(np.asarray(q, dtype=float)), dtype=float)


# --------------------------------------------------------------------------- pink
class PinkIK:
    """pink (``pin-pink``): differential IK iterated to convergence, one or several frames.

    Each step solves pink's QP (``solve_ik``: a ``FrameTask`` per frame, the configuration
    limits, quadprog) for a velocity and integrates it with ``dt = 1`` (a full Gauss-Newton
    step); it stops when every frame's position and rotation errors are within ``tol`` or the
    budget is spent.

    Args:
        model: Pinocchio model (e.g. ``robot.model`` of a :class:`~swarm_ik.RobotModel`, or a
            whole two-arm robot's model).
        frames: Frame names, one per target.
        budget_s: Time budget of one call [s].
        tol: Tolerance per frame [m and rad].
        to_pin: Our joint vector → Pinocchio configuration (default: identity).
        from_pin: Pinocchio configuration → our joint vector (default: identity).
        name: Adapter name.
        solver: QP solver name for ``qpsolvers``.
        max_steps: Most QP steps per call.
    """

    def __init__(
        self,
        model: Any,
        frames: Sequence[str],
        budget_s: float,
        tol: float,
        to_pin: Callable[[np.ndarray], np.ndarray] | None = None,
        from_pin: Callable[[np.ndarray], np.ndarray] | None = None,
        name: str = "pink",
        solver: str = "quadprog",
        max_steps: int = 200,
    ) -> None:
        self._pink = _need("pink", name)
        import qpsolvers

        if solver not in qpsolvers.available_solvers:
            raise InvalidArgumentError(
                f"pink needs the QP solver {solver!r}; available: {qpsolvers.available_solvers}"
            )
        if not frames:
            raise InvalidArgumentError("pink: give at least one frame")
        for f in frames:
            if not model.existFrame(f):
                raise InvalidArgumentError(f"pink: no frame {f!r} in the model")
        self.name = name
        self.model = model
        self.data = model.createData()
        self.frames = list(frames)
        self.budget_s = float(budget_s)
        self.tol = float(tol)
        self.solver = solver
        self.max_steps = int(max_steps)
        self._to_pin = to_pin or (lambda q: np.asarray(q, dtype=float))
        self._from_pin = from_pin or (lambda q: np.asarray(q, dtype=float))
        self._fids = [model.getFrameId(f) for f in self.frames]
        self.robot: Any = None  # set by for_robot: answers are then wrapped

    @classmethod
    def for_robot(cls, robot: Any, budget_s: float, tol: float) -> PinkIK:
        """The adapter on a :class:`~swarm_ik.RobotModel`'s chain and end-effector frame."""
        out = cls(
            robot.model,
            [robot.ee_frame],
            budget_s,
            tol,
            to_pin=robot.to_pinocchio,
            from_pin=robot.from_pinocchio,
        )
        out.robot = robot
        return out

    def solve_frames(
        self, targets: Sequence[np.ndarray], q0: np.ndarray
    ) -> tuple[np.ndarray, bool, float, int]:
        """Solve several frame targets at once.

        Returns:
            ``(q, converged, seconds inside solve_ik, steps)``; ``q`` in our joint order.
        """
        import pinocchio as pin

        pink = self._pink
        t_start = time.perf_counter()
        conf = pink.Configuration(self.model, self.data, self._to_pin(q0))
        tasks = []
        for f, t in zip(self.frames, targets, strict=True):
            task = pink.FrameTask(f, position_cost=1.0, orientation_cost=1.0)
            task.set_target(pin.SE3(np.asarray(t, dtype=float)))
            tasks.append(task)
        own = 0.0
        steps = 0
        ok = self._converged(conf, targets)
        while not ok and steps < self.max_steps:
            if time.perf_counter() - t_start >= self.budget_s:
                break
            t0 = time.perf_counter()
            v = pink.solve_ik(conf, tasks, 1.0, solver=self.solver, safety_break=False)
            own += time.perf_counter() - t0
            conf.integrate_inplace(v, 1.0)
            steps += 1
            ok = self._converged(conf, targets)
        return self._from_pin(np.array(conf.q)), ok, own, steps

    def _converged(self, conf: Any, targets: Sequence[np.ndarray]) -> bool:
        import pinocchio as pin

        for fid, t in zip(self._fids, targets, strict=True):
            m = conf.data.oMf[fid]
            dp = float(np.linalg.norm(m.translation - t[:3, 3]))
            dr = float(np.linalg.norm(pin.log3(m.rotation.T @ t[:3, :3])))
            if dp > self.tol or dr > self.tol:
                return False
        return True

    def solve(self, target: np.ndarray, q0: np.ndarray, seed: int) -> Answer:
        t0 = time.perf_counter()
        q, ok, own, steps = self.solve_frames([target], q0)
        dt = time.perf_counter() - t0
        if self.robot is not None:
            q = self.robot.wrap(q)
        return Answer(q, ok, dt, own, float(steps))

    def fk(self, q: np.ndarray) -> np.ndarray:
        import pinocchio as pin

        pin.framesForwardKinematics(self.model, self.data, self._to_pin(q))
        return np.array(self.data.oMf[self._fids[0]].homogeneous)


# --------------------------------------------------------------------------- ikpy
def _urdf_chain_elements(path: Any, ee_link: str) -> list[str]:
    """``[root link, joint, link, …, ee link]`` of the URDF path to ``ee_link``."""
    root = ET.parse(path).getroot()
    parent_of: dict[str, tuple[str, str]] = {}
    for j in root.findall("joint"):
        child = j.find("child").get("link")  # type: ignore[union-attr]
        par = j.find("parent").get("link")  # type: ignore[union-attr]
        parent_of[str(child)] = (str(j.get("name")), str(par))
    out = [ee_link]
    while out[-1] in parent_of:
        joint, par = parent_of[out[-1]]
        out += [joint, par]
    return out[::-1]


class IkpyIK:
    """ikpy's ``Chain.inverse_kinematics_frame`` (SciPy least squares, full orientation).

    The chain is read from the URDF along the path root link → end-effector link; fixed
    joints are inactive links.  ikpy has no time limit.
    """

    def __init__(self, robot: Any, tol: float) -> None:
        import warnings

        chain_mod = _need("ikpy.chain", "ikpy")
        self.name = "ikpy"
        self.robot = robot
        ee = urdf_link_of_frame(robot.urdf_path, robot.ee_frame)
        elems = _urdf_chain_elements(robot.urdf_path, ee)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            chain = chain_mod.Chain.from_urdf_file(
                str(robot.urdf_path),
                base_elements=elems,
                symbolic=False,
                jax_precompile=False,
            )
            mask = [link.joint_type != "fixed" for link in chain.links]
            chain = chain_mod.Chain.from_urdf_file(
                str(robot.urdf_path),
                base_elements=elems,
                active_links_mask=mask,
                symbolic=False,
                jax_precompile=False,
            )
        self.chain = chain
        self._active = np.flatnonzero(mask)
        if self._active.size != robot.nq:
            raise InvalidArgumentError(
                f"ikpy's chain of {robot.name} has {self._active.size} joints, the model {robot.nq}"
            )
        self.tol = float(tol)

    def _full(self, q: np.ndarray) -> np.ndarray:
        full = np.zeros(len(self.chain.links))
        full[self._active] = q
        return full

    def solve(self, target: np.ndarray, q0: np.ndarray, seed: int) -> Answer:
        t0 = time.perf_counter()
        init = self._full(np.asarray(q0, dtype=float))
        t1 = time.perf_counter()
        full = self.chain.inverse_kinematics_frame(
            np.asarray(target, dtype=float), initial_position=init, orientation_mode="all"
        )
        t2 = time.perf_counter()
        q = self.robot.wrap(np.asarray(full, dtype=float)[self._active])
        call = time.perf_counter() - t0  # (the claim below is ours, not an ikpy user's)
        # ikpy reports no success flag: its claim is its own FK within tol
        got = self.chain.forward_kinematics(full)
        dp = float(np.linalg.norm(got[:3, 3] - target[:3, 3]))
        c = np.clip((np.trace(got[:3, :3].T @ target[:3, :3]) - 1.0) / 2.0, -1.0, 1.0)
        ok = dp <= self.tol and math.acos(c) <= self.tol
        return Answer(q, bool(ok), call, t2 - t1)

    def fk(self, q: np.ndarray) -> np.ndarray:
        return np.asarray(self.chain.forward_kinematics(self._full(q)), dtype=float)


# --------------------------------------------------------------------------- registry
def tracik_eps(tol: float) -> float:
    """TRAC-IK's eps for a Euclidean tolerance ``tol``: its test bounds each twist component,
    so ``tol/√3`` puts each error's norm within ``tol`` (its claim then implies our check)."""
    return tol / math.sqrt(3.0)


PEERS: dict[str, PeerInfo] = {
    p.name: p
    for p in (
        PeerInfo(
            "swarm",
            None,
            "swarm_ik.solve(IKProblem(robot, T), 'swarm', time_limit=budget)",
            lambda r, b, t: OursSolve(r, b, t, "swarm"),
        ),
        PeerInfo(
            "ik-solver",
            None,
            "swarm_ik.IKSolver(robot, time_limit=budget).solve(T), bound once per robot",
            lambda r, b, t: OursIKSolver(r, b, t),
        ),
        PeerInfo(
            "dls",
            None,
            "swarm_ik.solve(IKProblem(robot, T), 'dls', time_limit=budget): Pinocchio DLS",
            lambda r, b, t: OursSolve(r, b, t, "dls"),
        ),
        PeerInfo(
            "tracik-1e-5",
            "pytracik",
            "TRAC-IK (pytracik), Speed, timeout = budget, eps 1e-5 per twist component",
            lambda r, b, t: TracIK(r, b, 1e-5, "tracik-1e-5"),
        ),
        PeerInfo(
            "tracik-1e-6",
            "pytracik",
            "TRAC-IK (pytracik), Speed, timeout = budget, eps 1e-6 per twist component",
            lambda r, b, t: TracIK(r, b, 1e-6, "tracik-1e-6"),
        ),
        PeerInfo(
            "tracik",
            "pytracik",
            "TRAC-IK (pytracik), Speed, timeout = budget, eps = tol/√3 per twist component "
            "(follows --tol; its claim then implies the Euclidean check)",
            lambda r, b, t: TracIK(r, b, tracik_eps(t), "tracik"),
        ),
        PeerInfo(
            "rtb-lm",
            "roboticstoolbox",
            "roboticstoolbox-python ETS.ik_LM (C++), tol ½·tol² on ½eᵀe, no time limit",
            lambda r, b, t: RtbIK(r, t, "rtb-lm"),
        ),
        PeerInfo(
            "rtb-gn",
            "roboticstoolbox",
            "roboticstoolbox-python ETS.ik_GN (C++), the same settings",
            lambda r, b, t: RtbIK(r, t, "rtb-gn"),
        ),
        PeerInfo(
            "rtb-nr",
            "roboticstoolbox",
            "roboticstoolbox-python ETS.ik_NR (C++), the same settings",
            lambda r, b, t: RtbIK(r, t, "rtb-nr"),
        ),
        PeerInfo(
            "pink",
            "pink",
            "pink FrameTask + solve_ik (quadprog) iterated with dt = 1 until within tol",
            lambda r, b, t: PinkIK.for_robot(r, b, t),
        ),
        PeerInfo(
            "ikpy",
            "ikpy",
            "ikpy inverse_kinematics_frame (SciPy least squares), no time limit",
            lambda r, b, t: IkpyIK(r, t),
        ),
    )
}
"""Every adapter, by name."""


def get(name: str) -> PeerInfo:
    """A peer by name.

    Raises:
        InvalidArgumentError: unknown name (the valid ones listed).
    """
    if name not in PEERS:
        raise InvalidArgumentError(f"unknown peer {name!r}; valid: {', '.join(PEERS)}")
    return PEERS[name]


def available() -> list[str]:
    """Names of the peers that can be built here (their packages import)."""
    return [n for n, p in PEERS.items() if p.available()]


def make(name: str, robot: Any, budget_s: float, tol: float) -> Peer:
    """Build peer ``name`` for ``robot``.

    Raises:
        InvalidArgumentError: unknown name, missing package, or the peer cannot build the
            model's chain.
    """
    info = get(name)
    if not info.available():
        raise InvalidArgumentError(
            f"peer {name!r} is not available here"
            + (f" (needs {info.package!r}: {EXTRA_HINT})" if info.package else "")
        )
    return info.factory(robot, float(budget_s), float(tol))
