"""One contract, every registered solver (nevergrad's parametrised optimizer test)."""

from __future__ import annotations

import numpy as np
import pytest

import swarm_ik
from swarm_ik import solvers

NAMES = solvers.search_names()
Q_STAR = np.array([0.7, 1.1])  # positive angles: even basic FOA (S > 0) can reach them


@pytest.fixture(scope="module")
def planar(planar2_urdf: str) -> swarm_ik.RobotModel:
    return swarm_ik.load_robot(planar2_urdf, ee_frame="tip")


def _problem(planar: swarm_ik.RobotModel) -> swarm_ik.IKProblem:
    return swarm_ik.IKProblem.from_q(planar, Q_STAR)


def test_registry_lists_the_solvers_and_refuses_duplicates() -> None:
    assert "dls" in NAMES
    spec = solvers.get("dls")
    with pytest.raises(swarm_ik.InvalidArgumentError, match="already registered"):
        solvers.register("dls", spec.run)
    with pytest.raises(swarm_ik.UnknownNameError, match="valid solvers: .*dls"):
        solvers.get("nope")


@pytest.mark.parametrize("name", NAMES)
def test_budget_is_respected_exactly(name: str, planar: swarm_ik.RobotModel) -> None:
    res = swarm_ik.solve(_problem(planar), name, seed=1, max_evals=437, stop_on_success=False)
    assert 1 <= res.n_evals <= 437
    assert len(res.history) >= 1


@pytest.mark.parametrize("name", NAMES)
def test_result_within_bounds_and_finite(name: str, get_robot) -> None:
    r = get_robot("loading_manipulator")
    x_star = np.array([np.pi / 4, np.pi / 6, np.pi / 4, 0.8, 1, 1, np.pi / 6, -np.pi / 4])
    target = r.fk(x_star)  # outside this robot's limits: unreachable
    res = swarm_ik.solve(swarm_ik.IKProblem(r, target, "euler-zyz"), name, seed=0, max_evals=600)
    assert res.within_limits
    assert np.all(res.q >= r.lower) and np.all(res.q <= r.upper)
    assert not res.success and np.isfinite(res.fitness) and np.isfinite(res.position_error)


@pytest.mark.parametrize("name", NAMES)
def test_same_seed_same_result_other_seed_other_run(name: str, get_robot) -> None:
    # an unreachable target, so that every solver keeps searching (restarts, swarms)
    r = get_robot("loading_manipulator")
    x_star = np.array([np.pi / 4, np.pi / 6, np.pi / 4, 0.8, 1, 1, np.pi / 6, -np.pi / 4])
    prob = swarm_ik.IKProblem(r, r.fk(x_star), "euler-zyz")
    a = swarm_ik.solve(prob, name, seed=3, max_evals=500, stop_on_success=False)
    b = swarm_ik.solve(prob, name, seed=3, max_evals=500, stop_on_success=False)
    c = swarm_ik.solve(prob, name, seed=4, max_evals=500, stop_on_success=False)
    assert a.q.tobytes() == b.q.tobytes() and a.n_evals == b.n_evals
    np.testing.assert_array_equal(a.history, b.history)
    assert a.q.tobytes() != c.q.tobytes() or not np.array_equal(a.history, c.history)


@pytest.mark.parametrize("name", NAMES)
def test_converges_on_a_two_link_arm(name: str, planar: swarm_ik.RobotModel) -> None:
    prob = _problem(planar)
    res = swarm_ik.solve(prob, name, seed=0, max_evals=20000, tol_pos=1e-4, tol_rot=1e-4)
    assert res.position_error < 1e-2, res
    assert res.rotation_error < 1e-2, res


class _NaNProblem(swarm_ik.IKProblem):
    """Returns NaN fitness wherever q[0] > 1.0 (a third of the first joint's range)."""

    def _poison(self, q: np.ndarray, f: np.ndarray) -> np.ndarray:
        return np.where(np.atleast_2d(q)[:, 0] > 1.0, np.nan, f)

    def fitness(self, q_batch):  # type: ignore[override]
        return self._poison(q_batch, super().fitness(q_batch))

    def residual_jacobian(self, q_batch):  # type: ignore[override]
        f, err, jac = super().residual_jacobian(q_batch)
        return self._poison(q_batch, f), err, jac


@pytest.mark.parametrize("name", NAMES)
def test_survives_nan_fitness(name: str, planar: swarm_ik.RobotModel) -> None:
    prob = _NaNProblem(planar, planar.fk(Q_STAR))
    res = swarm_ik.solve(prob, name, seed=0, max_evals=2000)
    assert res.within_limits and np.all(np.isfinite(res.q))
    assert np.isfinite(res.position_error)
