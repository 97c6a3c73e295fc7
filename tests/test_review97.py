"""Review 97 (the multi-target calls, held out): reach_map's refusals and seed, and one order
of solve_many's solutions whichever method found them."""

from __future__ import annotations

import numpy as np
import pytest

import swarm_ik
from swarm_ik.errors import InvalidArgumentError
from swarm_ik.reach import reach_map


@pytest.mark.parametrize("bounds", ["abc", ([0, 0, 0], [1, 1]), [0, 0, 0, 1, 1, "x"], [None] * 6])
def test_reach_map_refuses_bounds_that_are_not_six_numbers(bounds: object) -> None:
    robot = swarm_ik.load_robot("ur5")
    with pytest.raises(InvalidArgumentError, match="bounds must be 6 finite numbers"):
        reach_map(robot, bounds=bounds, resolution=0.5)


def test_reach_map_takes_seed_none_as_zero() -> None:
    robot = swarm_ik.load_robot("ur5")
    kw = dict(resolution=0.4, position_only=True, bounds=[-0.4, -0.4, 0.0, 0.4, 0.4, 0.4])
    a = reach_map(robot, seed=None, **kw)
    b = reach_map(robot, seed=0, **kw)
    assert np.array_equal(a.hits, b.hits) and a.seed == b.seed == 0


def test_solve_many_orders_by_the_distance_of_the_returned_q_whichever_method() -> None:
    robot = swarm_ik.load_robot("ur5")
    problem = swarm_ik.IKProblem(robot, robot.fk(robot.random_q(np.random.default_rng(10))))
    q0 = robot.random_q(np.random.default_rng(510))
    orders = {}
    for method in ("auto", "numerical"):
        sols = swarm_ik.solve_many(problem, n=16, q0=q0, method=method)
        d = [float(np.linalg.norm(s.q - q0)) for s in sols]
        assert len(sols) == 8 and d == sorted(d), (method, d)
        orders[method] = np.round([s.q for s in sols], 6)
    assert np.array_equal(orders["auto"], orders["numerical"])
