"""placo's side of the whole-body benchmark, run by the placo environment's Python.

Not run inside swarm_ik's process: :func:`swarm_ik.bench.wholebody_peers.run_placo` runs this
file as ``<placo env>/bin/python _placo_worker.py PROBLEMS.npz ANSWERS.npz`` (placo's wheel pins
an older ``pin`` and ``numpy`` than swarm_ik's, so it lives in its own virtual environment).  It
imports only the standard library, numpy, placo and that environment's pinocchio (placo and
pinocchio inside :func:`main`, so that the main environment can import this module without
them: for its doctests, and for :func:`geometry_free_urdf`, which
:mod:`swarm_ik.bench.peers` uses too).

Input (``PROBLEMS.npz``, written by ``run_placo``; ``n`` targets, ``nq = 7 + len(joint_names)``):

==================  =========================================================================
``urdf``            0-d str: the robot's URDF path (its geometry is stripped before loading)
``joint_names``     ``(nj,)`` str: the order of the joint part of every ``q`` in and out
``sole_frames``     ``(2,)`` str: left, right sole frames (held at their poses, hard)
``hand_frames``     ``(2,)`` str: left, right hand frames (6-D goals, soft)
``locked_joints``   ``(m,)`` str: joints held at their start values (masked DoFs)
``left_sole`` ...   ``(n, 4, 4)`` world poses: ``left_sole``, ``right_sole``, ``left_hand``,
                    ``right_hand``
``polygon``         ``(n, k, 2)`` support polygon on the ground, counter-clockwise [m]
``q0``              ``(n, nq)`` start configurations, Pinocchio free-flyer convention
                    ``[x y z qx qy qz qw, joints...]``, joints in ``joint_names`` order
``settings``        ``(5,)`` float: time limit per target [s], most iterations, stop
                    tolerance [m, rad], CoM margin [m], regularisation weight
==================  =========================================================================

Output (``ANSWERS.npz``): ``q`` ``(n, nq)`` (same convention and joint order; NaN where placo
raised), ``time_s`` ``(n,)`` (the whole call per target: solver and tasks built, iterations;
the model is loaded once, outside), ``solve_s`` ``(n,)`` (the iterations alone),
``converged`` ``(n,)`` bool (placo's own view: every sole and hand error within the stop
tolerance and the CoM inside the polygon), ``iterations`` ``(n,)`` int, ``error`` ``(n,)``
str (the exception's text, ``""`` when none), ``versions`` ``(2,)`` str (placo, pinocchio).

Settings of placo's ``KinematicsSolver`` (one built per target):

* soles: ``add_frame_task`` configured ``"hard"`` (equality constraints: the feet are
  contacts and do not slide);
* hands: ``add_frame_task`` configured ``"soft"``, position and orientation weights 1.0
  (errors in m and rad weighted alike; hard tasks would make the QP infeasible whenever a
  linearised step cannot meet them within the joint limits);
* CoM: ``add_com_polygon_constraint(polygon clockwise, margin)`` configured ``"hard"``;
* locked joints: ``mask_dof`` (their step is zero, so they stay at their start values);
* joint limits: ``enable_joint_limits(True)`` (placo's default); velocity limits off and
  ``dt = 0`` (a static problem);
* a regularisation task of weight ``settings[4]`` (``run_placo``'s default 1e-3: it keeps
  the QP well posed in the redundant directions and damps the first, large steps; it
  penalises the step, not the goal, so the iterations still converge to the goals.  On 50
  targets, weights 1e-6, 1e-4, 1e-3, 3e-3, 1e-2, 1e-1 gave 70, 74, 80, 82, 76, 62 % success
  with 10, 8, 9, 12, 22, 76 median iterations; an error-scaled (Levenberg-Marquardt) weight
  and velocity limits as a trust region (``dt`` 0.05, 0.1) did no better).

Each iteration: ``robot.update_kinematics()``, ``solver.solve(True)`` (one QP step,
integrated into ``robot.state.q``).  It stops when every sole and hand error (position [m],
rotation angle [rad], read from placo's own kinematics) is within the stop tolerance and the
CoM is inside the polygon, when the largest error has not fallen by 0.1 % over 20 iterations
(stalled), or at the iteration or time limit.
"""

from __future__ import annotations

import importlib.metadata
import os
import sys
import time
import xml.etree.ElementTree as ET

import numpy as np

STALL_WINDOW = 20
"""Iterations over which the largest error must fall by ``STALL_RATIO`` to go on."""
STALL_RATIO = 1e-3
"""Relative fall of the largest error over ``STALL_WINDOW`` iterations below which a run
has stalled."""


def geometry_free_urdf(path: str | os.PathLike[str]) -> str:
    """The URDF's text without ``<visual>`` and ``<collision>`` elements (kinematics and
    inertias unchanged; no mesh has to be found)."""
    root = ET.parse(path).getroot()
    for link in root.iter("link"):
        for tag in ("visual", "collision"):
            for el in link.findall(tag):
                link.remove(el)
    return ET.tostring(root, encoding="unicode")


def _index_map(model, joint_names) -> np.ndarray:  # type: ignore[no-untyped-def]
    """Indices into placo's ``q`` of ``[free flyer (7), joint_names...]`` (one-DoF joints)."""
    idx = list(range(7))
    for name in joint_names:
        if not model.existJointName(str(name)):
            raise KeyError(f"no joint {name!r} in placo's model")
        j = model.getJointId(str(name))
        if model.nqs[j] != 1:
            raise ValueError(f"joint {name!r} has {model.nqs[j]} coordinates; expected 1")
        idx.append(int(model.idx_qs[j]))
    if len(set(idx)) != model.nq:
        raise ValueError(f"the joint names cover {len(set(idx))} of placo's {model.nq} coordinates")
    return np.asarray(idx, dtype=np.int64)


def _errors(robot, pin, frames, targets) -> float:  # type: ignore[no-untyped-def]
    """Largest position [m] or rotation-angle [rad] error of ``frames`` against ``targets``."""
    worst = 0.0
    for f, t in zip(frames, targets, strict=True):
        m = robot.get_T_world_frame(f)
        dp = float(np.linalg.norm(m[:3, 3] - t[:3, 3]))
        dr = float(np.linalg.norm(pin.log3(t[:3, :3].T @ m[:3, :3])))
        worst = max(worst, dp, dr)
    return worst


def _com_inside(com_xy: np.ndarray, polygon_ccw: np.ndarray, margin: float) -> bool:
    a = polygon_ccw
    e = np.roll(a, -1, axis=0) - a
    n = np.stack([-e[:, 1], e[:, 0]], axis=1)
    n /= np.linalg.norm(n, axis=1, keepdims=True)
    return bool(np.min(np.sum(n * (com_xy - a), axis=1)) >= margin - 1e-9)


def solve_one(placo, pin, robot, prob: dict, i: int, perm: np.ndarray):  # type: ignore[no-untyped-def]
    """Solve target ``i``; returns ``(q in placo order, solve_s, converged, iterations)``."""
    time_limit, max_iter, stop_tol, margin, reg = (float(x) for x in prob["settings"])
    sole_frames = [str(s) for s in prob["sole_frames"]]
    hand_frames = [str(s) for s in prob["hand_frames"]]
    soles = [prob["left_sole"][i], prob["right_sole"][i]]
    hands = [prob["left_hand"][i], prob["right_hand"][i]]
    polygon = np.asarray(prob["polygon"][i], dtype=float)

    q = np.empty(robot.model.nq)
    q[perm] = prob["q0"][i]
    robot.state.q = q
    robot.update_kinematics()

    solver = placo.KinematicsSolver(robot)
    solver.enable_joint_limits(True)
    solver.enable_velocity_limits(False)
    solver.dt = 0.0
    for f, t in zip(sole_frames, soles, strict=True):
        task = solver.add_frame_task(f, np.asarray(t, dtype=float))
        task.configure(f, "hard", 1.0, 1.0)
    for f, t in zip(hand_frames, hands, strict=True):
        task = solver.add_frame_task(f, np.asarray(t, dtype=float))
        task.configure(f, "soft", 1.0, 1.0)
    com = solver.add_com_polygon_constraint(
        [np.asarray(p, dtype=float) for p in polygon[::-1]], margin
    )
    com.configure("com_polygon", "hard")
    for name in prob["locked_joints"]:
        solver.mask_dof(str(name))
    if reg > 0:
        solver.add_regularization_task(reg)

    frames = sole_frames + hand_frames
    goals = soles + hands
    history: list[float] = []
    t0 = time.perf_counter()
    iterations = 0
    converged = False
    while True:
        err = _errors(robot, pin, frames, goals)
        inside = _com_inside(np.asarray(robot.com_world())[:2], polygon, margin)
        if err <= stop_tol and inside:
            converged = True
            break
        history.append(err)
        if len(history) > STALL_WINDOW and err > (1 - STALL_RATIO) * history[-1 - STALL_WINDOW]:
            break
        if iterations >= max_iter or time.perf_counter() - t0 >= time_limit:
            break
        solver.solve(True)
        robot.update_kinematics()
        iterations += 1
    return np.array(robot.state.q, dtype=float), time.perf_counter() - t0, converged, iterations


def main(argv: list[str]) -> int:
    """``_placo_worker.py PROBLEMS.npz ANSWERS.npz``: solve every problem, write answers."""
    if len(argv) != 2:
        print("usage: _placo_worker.py PROBLEMS.npz ANSWERS.npz", file=sys.stderr)
        return 2
    import pinocchio as pin
    import placo

    with np.load(argv[0], allow_pickle=False) as f:
        prob = {k: f[k] for k in f.files}
    urdf = str(prob["urdf"])
    robot = placo.RobotWrapper(
        os.path.dirname(urdf), placo.Flags.ignore_collisions, geometry_free_urdf(urdf)
    )
    perm = _index_map(robot.model, prob["joint_names"])
    n, nq = prob["q0"].shape
    q_out = np.full((n, nq), np.nan)
    time_s = np.full(n, np.nan)
    solve_s = np.full(n, np.nan)
    converged = np.zeros(n, dtype=bool)
    iterations = np.zeros(n, dtype=np.int64)
    errors = [""] * n
    for i in range(n):
        t0 = time.perf_counter()
        try:
            q, s, ok, it = solve_one(placo, pin, robot, prob, i, perm)
        except Exception as exc:  # a QP failure is an answer too (no q)
            time_s[i] = time.perf_counter() - t0
            errors[i] = f"{type(exc).__name__}: {exc}".replace("\n", " ")
            continue
        time_s[i] = time.perf_counter() - t0
        q_out[i] = q[perm]
        solve_s[i], converged[i], iterations[i] = s, ok, it
    versions = np.array([importlib.metadata.version("placo"), pin.__version__])
    np.savez(
        argv[1],
        q=q_out,
        time_s=time_s,
        solve_s=solve_s,
        converged=converged,
        iterations=iterations,
        error=np.array(errors, dtype=str),
        versions=versions,
    )
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
