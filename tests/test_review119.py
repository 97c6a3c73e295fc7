"""Held-out review 119 (determinism, seeds, budgets): what it found, pinned as behaviour."""

from __future__ import annotations

import numpy as np
import pytest

import swarm_ik
from swarm_ik.goals import AvoidCollisions
from swarm_ik.scene import Box, Scene, Sphere


@pytest.fixture(scope="module")
def cluttered() -> swarm_ik.IKProblem:
    """A Panda target among four obstacles whose first search without the collision goal
    ends in contact (so the search with the sphere rows runs)."""
    robot = swarm_ik.load_robot("panda")
    scene = Scene(
        [Box([0.6, 0.6, 0.04], [0.55, 0, -0.02]), Box([0.08, 0.08, 0.5], [0.45, 0.25, 0.25]),
         Sphere(0.08, [0.4, -0.2, 0.3]), Box([0.05, 0.5, 0.3], [0.3, 0, 0.6])]
    )  # fmt: skip
    rc = robot.collision_model()
    free = [q for q in robot.random_q(np.random.default_rng(0), 400) if not rc.collides(q, scene)]
    return swarm_ik.IKProblem(robot, robot.fk(free[53]), goals=[AvoidCollisions(scene)])


def test_a_generator_in_one_state_gives_one_answer_with_a_collision_goal(cluttered) -> None:  # type: ignore[no-untyped-def]
    """The collision-free tries drew their random starts from fresh OS entropy when the seed
    was a Generator: four calls with ``default_rng(5)`` gave four answers."""
    runs = [swarm_ik.solve(cluttered, seed=np.random.default_rng(5)) for _ in range(3)]
    assert len({r.q.tobytes() for r in runs}) == 1
    assert len({r.n_evals for r in runs}) == 1
    assert all(r.seed is None for r in runs)  # (a Generator: no integer seed to record)
    rng = np.random.default_rng(5)
    swarm_ik.solve(cluttered, seed=rng)
    assert rng.bit_generator.state != np.random.default_rng(5).bit_generator.state  # advanced


def test_the_largest_seed_is_taken_with_a_collision_goal(cluttered) -> None:  # type: ignore[no-untyped-def]
    """The k-th try used ``seed + k``, past ``2**63 - 1``: refused as a bad seed."""
    res = swarm_ik.solve(cluttered, seed=2**63 - 1, max_evals=3000)
    assert res.seed == 2**63 - 1 and res.n_evals <= 3000


@pytest.mark.parametrize("budget", [1, 2, 3])
def test_max_evals_is_exact_with_a_collision_goal(budget: int) -> None:
    """``max_evals=1`` spent 2: the tries took one and the search after them one more."""
    robot = swarm_ik.load_robot("panda")
    target = robot.fk(robot.random_q(np.random.default_rng(1)))
    problem = swarm_ik.IKProblem(robot, target, goals=[AvoidCollisions()])
    for seed in range(3):
        assert swarm_ik.solve(problem, seed=seed, max_evals=budget).n_evals <= budget
