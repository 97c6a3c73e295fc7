"""Defects a held-out review of this stop's own fixes found (each failed on the code before)."""

from __future__ import annotations

import copy
import pickle
import sys
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pytest

import swarm_ik
from swarm_ik.errors import InvalidArgumentError, SwarmIKError
from swarm_ik.goals import Axis, Goal


@dataclass(frozen=True)
class _OnPlane(Goal):
    """The frame origin at height ``height`` [m], within a tolerance of its own."""

    frame: str
    height: float = 0.3
    tolerance: float = 1e-3

    def residual(self, state):
        return np.array([state.pose(self.frame)[2, 3] - self.height])

    def jacobian(self, state):
        return state.jacobian(self.frame)[2:3]


def test_solve_many_keeps_solutions_within_a_python_goals_own_tolerance() -> None:
    """The plane's rows leave slack up to 0.9 of its tolerance: solve_many judged every
    goal by tol_pos and returned 0-1 solutions after its whole limit."""
    robot = swarm_ik.load_robot("ur5")
    ee = robot.ee_frame
    problem = swarm_ik.IKProblem(robot, goals=[_OnPlane(ee), Axis(ee, [0, 0, 1], [0, 0, -1])])
    sols = swarm_ik.solve_many(problem, n=4, seed=0, time_limit=3.0)
    assert len(sols) == 4
    for r in sols:
        assert all(e.met for e in problem.verify(r.q))


def test_a_follower_of_a_follower_is_refused_whatever_the_file_order(tmp_path: Path) -> None:
    """A mimic of an off-chain mimic follower, written before its driver in the file, loaded
    frozen at 0 (after it, it was refused)."""
    sys.path.insert(0, str(Path(__file__).parent))
    from test_urdf_review46 import _counterweight

    base = _counterweight()
    cw2 = (
        '<link name="cw2"/><joint name="cw2_joint" type="revolute"><parent link="l1"/>'
        '<child link="cw2"/><axis xyz="0 1 0"/><limit lower="-1.5" upper="1.5" effort="1" '
        'velocity="1"/><mimic joint="cw_joint"/></joint>'
    )
    i = base.index('<joint name="j1"')
    for k, text in enumerate(
        (base[:i] + cw2 + base[i:], base.replace("</robot>", cw2 + "</robot>"))
    ):
        path = tmp_path / f"ff{k}.urdf"
        path.write_text(text)
        with pytest.raises(SwarmIKError, match="cw2_joint.*itself a mimic joint"):
            swarm_ik.load_robot(str(path), "tool")


def test_closed_form_held_back_at_a_singular_target_falls_back_to_the_search() -> None:
    """A straight wrist on the joint-limited UR5: eaik's least-squares points do not polish
    into solutions within the +-pi limits, so solve_many (auto) returned 0 where the
    numerical path finds 8; the set is now marked incomplete and the search added."""
    robot = swarm_ik.load_robot("ur5_joint_limited_robot")
    q = np.array([1.11, -2.76, 0.349, -1.436, 0.0, -2.738])
    problem = swarm_ik.IKProblem.from_q(robot, q)
    auto = swarm_ik.solve_many(problem, n=16)
    numerical = swarm_ik.solve_many(problem, n=16, method="numerical")
    assert len(auto) >= len(numerical) > 0


def test_batch_and_path_results_stay_read_only_through_pickle_and_deepcopy() -> None:
    robot = swarm_ik.load_robot("panda")
    q = robot.random_q(np.random.default_rng(4), 3)
    batch = swarm_ik.solve_batch(robot, robot.fk(q))
    path = swarm_ik.solve_path(robot, [robot.fk(q[0]), robot.fk(q[0])], q0=q[0])
    for res in (batch, path):
        for twin in (pickle.loads(pickle.dumps(res)), copy.deepcopy(res)):
            assert not twin.q.flags.writeable
            np.testing.assert_array_equal(twin.q, res.q)


def test_a_mesh_with_nan_or_far_vertices_is_refused_when_made(tmp_path: Path) -> None:
    """Mesh vertices are bounded as the other shapes' sizes: NaN made every configuration
    'in contact' with Eigen's complaints on stderr; a vertex 100 km away was accepted."""
    from swarm_ik.scene import Mesh

    tri = "v 0 0 0\nv {x} 0 0\nv 0 1 0\nf 1 2 3\n"
    (tmp_path / "nan.obj").write_text(tri.format(x="nan"))
    (tmp_path / "far.obj").write_text(tri.format(x="1e5"))
    (tmp_path / "ok.obj").write_text(tri.format(x="1"))
    with pytest.raises(InvalidArgumentError, match="NaN or infinite"):
        Mesh(str(tmp_path / "nan.obj"))
    with pytest.raises(InvalidArgumentError, match="MAX_LENGTH"):
        Mesh(str(tmp_path / "far.obj"))
    with pytest.raises(InvalidArgumentError, match="MAX_LENGTH"):
        Mesh(str(tmp_path / "ok.obj"), scale=2e4)
    Mesh(str(tmp_path / "ok.obj"))


def test_lock_of_a_mimic_follower_gets_the_loaders_reason(capsys) -> None:
    """--lock on a mimic follower outside its limits was refused for its limits, where the
    real refusal (lock its driver instead) is what a value within them gets."""
    from swarm_ik.cli import main

    rc = main(["solve", "--robot", "panda", "--lock", "panda_finger_joint2=0.5", "--pose",
               "0.4", "0.1", "0.5", "1", "0", "0", "0"])  # fmt: skip
    err = capsys.readouterr().err.strip()
    assert rc == 2 and len(err.splitlines()) == 1
    assert "outside its limits" not in err and "driver" in err, err
