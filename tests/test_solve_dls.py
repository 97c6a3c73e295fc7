"""`solve` with the DLS baseline, Result semantics, and the CLI."""

from __future__ import annotations

import json

import numpy as np
import pytest
from conftest import robot

import swarm_ik
from swarm_ik.cli import main
from swarm_ik.problem import largest_errors


@pytest.mark.parametrize("name", ["panda", "yumi_left"])
def test_dls_solves_fk_sampled_targets(name: str) -> None:
    r = robot(name)
    rng = np.random.default_rng(7)
    solved = 0
    for i in range(10):
        prob = swarm_ik.IKProblem.from_q(r, r.random_q(rng))
        res = swarm_ik.solve(prob, "dls", seed=i, max_evals=3000)
        assert res.within_limits
        if res.success:
            assert res.position_error <= 1e-5 and res.rotation_error <= 1e-5
            solved += 1
    assert solved >= 9


def test_result_is_frozen_and_verified_with_pinocchio() -> None:
    r = robot("panda")
    prob = swarm_ik.IKProblem.from_q(r, r.mid_q() + 0.3)
    res = swarm_ik.solve(prob, "dls", seed=0)
    with pytest.raises(AttributeError):
        res.q = np.zeros(7)  # type: ignore[misc]
    dp, dr = largest_errors(swarm_ik.verify(prob, res.q))
    assert (dp, dr) == (res.position_error, res.rotation_error)
    assert res.n_evals >= 1 and len(res.history) >= 1
    assert np.all(np.diff(res.history) <= 0)


def test_unreachable_target_is_not_a_success() -> None:
    r = robot("ur5")
    target = np.eye(4)
    target[:3, 3] = [5.0, 0, 0]  # UR5 reaches < 1 m
    res = swarm_ik.solve(swarm_ik.IKProblem(r, target), "dls", max_evals=200)
    assert not res.success
    assert res.position_error > 3.0 and np.isfinite(res.fitness)
    assert res.n_evals == 200


def test_position_only_ik() -> None:
    r = robot("panda")
    q = r.random_q(np.random.default_rng(3))
    target = r.fk(q)
    target[:3, :3] = np.eye(3)  # orientation unreachable together with the position, ignored
    prob = swarm_ik.IKProblem(r, target, w_rot=0.0)
    res = swarm_ik.solve(prob, "dls", max_evals=2000)
    assert res.success and res.position_error <= 1e-5


def test_cli_solve_exit_codes(capsys: pytest.CaptureFixture[str]) -> None:
    q = [0.1, -0.5, 0.3, -2.0, 0.2, 1.5, 0.4]
    rc = main(["solve", "--robot", "panda", "--from-q", *map(str, q), "--json"])
    out = json.loads(capsys.readouterr().out)
    assert rc == 0 and out["success"] and out["position_error"] <= 1e-5
    rc = main(
        [
            "solve",
            "--robot",
            "ur5",
            "--pose",
            "5",
            "0",
            "0",
            "0",
            "0",
            "0",
            "1",
            "--max-evals",
            "100",
        ]
    )
    assert rc == 1
    assert "NOT reached" in capsys.readouterr().out
    rc = main(["solve", "--robot", "nope", "--from-q", "1"])
    err = capsys.readouterr().err
    assert rc == 2 and "unknown robot 'nope'" in err and "panda" in err
    assert "Traceback" not in err
    rc = main(["solve", "--robot", "panda", "--from-q", "1", "2"])
    assert rc == 2 and "7 values" in capsys.readouterr().err
    rc = main(["solve", "--robot", "panda", "--from-q", *map(str, q), "--solver", "bogus"])
    err = capsys.readouterr().err
    assert rc == 2 and "unknown solver 'bogus'" in err and "dls" in err
    rc = main(["robots"])
    assert rc == 0 and "yumi_left" in capsys.readouterr().out
