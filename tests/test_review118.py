"""Held-out review 118 (``solve_many``): what it found, pinned as behaviour."""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest

import swarm_ik
from swarm_ik import branches as br


@pytest.mark.parametrize("name", ["ur5", "ur10"])
def test_auto_never_returns_fewer_than_numerical_at_the_ur_home_pose(name: str) -> None:
    """At q = 0 the wrist (q5 = 0, a continuum) and the elbow are straight at once; eaik
    returns two exact points of the continuum and nothing marked the set incomplete, so
    ``auto`` gave 2 where ``numerical`` gives 8."""
    pytest.importorskip("eaik")
    robot = swarm_ik.load_robot(name)
    problem = swarm_ik.IKProblem.from_q(robot, np.zeros(6))
    auto = swarm_ik.solve_many(problem, n=16, seed=0)
    numerical = swarm_ik.solve_many(problem, n=16, method="numerical", seed=0)
    assert len(auto) >= len(numerical) >= 8
    for s in auto:  # every one checked with Pinocchio directly, inside the limits
        np.testing.assert_allclose(robot.fk_pinocchio(s.q), problem.target, atol=1e-9)
        assert robot.within_limits(s.q)
    qs = np.array([s.q for s in auto])
    d = br.branch_distance(qs[:, None], qs[None], br.periodic_mask(robot))
    assert (d + np.eye(len(qs)) * 10 > br.BRANCH_TOL).all()  # each once


def test_a_target_at_the_edge_of_reach_gives_its_point_within_the_tolerances() -> None:
    """0.7 µm beyond the stretched UR5 no exact root exists, yet a point meets 1e-5 m: the
    numerical path returned nothing ("local_minima") where ``solve`` and ``auto`` succeed."""
    robot = swarm_ik.load_robot("ur5")
    target = robot.fk(np.array([0.3, -1.0, 0.0, -0.5, 1.1, 0.2]))
    target[:3, 3] *= 1 + 1e-6
    problem = swarm_ik.IKProblem(robot, target)
    sols = swarm_ik.solve_many(problem, n=4, method="numerical", seed=0, max_evals=3000)
    assert len(sols) == 1 and sols.reason == "converged"
    (s,) = sols
    assert s.success and s.position_error <= 1e-5 and robot.within_limits(s.q)
    pose = robot.fk_pinocchio(s.q)
    assert np.linalg.norm(pose[:3, 3] - target[:3, 3]) <= 1e-5


def test_several_solutions_with_a_named_solver_start_from_random_configurations() -> None:
    """``swarm-ik show --solutions 8 --solver swarm`` showed one solution: each seed started
    from the middle of the ranges and found the same branch."""
    from swarm_ik.viz.views import several_solutions

    robot = swarm_ik.load_robot("ur5")
    problem = swarm_ik.IKProblem.from_q(robot, [0.3, -1.0, 1.2, -0.5, 1.1, 0.2])
    found = several_solutions(problem, 4, solver="swarm", min_distance=0.5, seed=0)
    assert len(found) == 4 and all(r.success for r in found)
    again = several_solutions(problem, 4, solver="swarm", min_distance=0.5, seed=0)
    assert [r.q.tolist() for r in again] == [r.q.tolist() for r in found]  # (seeded)


def test_show_says_when_fewer_solutions_than_asked_were_found(tmp_path) -> None:  # type: ignore[no-untyped-def]
    run = subprocess.run(
        [sys.executable, "-m", "swarm_ik.cli", "show", "--robot", "ur5", "--from-q", "0.3",
         "-1.0", "1.2", "-0.5", "1.1", "0.2", "--solutions", "12", "--html",
         str(tmp_path / "x.html")],
        capture_output=True, text=True, timeout=600,
    )  # fmt: skip
    assert run.returncode == 0, run.stderr[-2000:]
    (line,) = [x for x in run.stderr.splitlines() if "warning" in x]
    assert line.startswith("swarm-ik: warning: found 8 of the 12 solutions asked for")


def test_every_public_module_is_an_attribute_of_the_package() -> None:
    """``dir(swarm_ik)`` lists the modules; ``help(swarm_ik.many)`` needed ``import
    swarm_ik.many`` first."""
    code = (
        "import types, swarm_ik\n"
        "names = ['many', 'result', 'path', 'batch', 'scene', 'branches']\n"
        "assert all(isinstance(getattr(swarm_ik, n), types.ModuleType) for n in names)\n"
        "assert set(names) <= set(dir(swarm_ik))\n"
    )
    run = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300)
    assert run.returncode == 0, run.stderr[-2000:]
