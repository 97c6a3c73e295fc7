"""Determinism and isolation: same seed → bit-identical result, in this process, in another
process, in threads and in a process pool; solving leaves no trace in global state.

Determinism holds for an evaluation budget (``max_evals``) or the solvers' own iteration
counts; a ``time_limit`` makes the result depend on the machine's speed.
"""

from __future__ import annotations

import json
import multiprocessing
import os
import random
import subprocess
import sys
import warnings
from concurrent.futures import ProcessPoolExecutor, ThreadPoolExecutor

import numpy as np
import pytest

import swarm_ik

SOLVERS = swarm_ik.solvers.search_names()
BUDGET = 400
Q_REACH = [0.3, -0.8, 0.5, 0.4, -0.6, 0.9, -0.2]


def fingerprint(res: swarm_ik.Result) -> tuple[str, str, int, str, bool]:
    """Everything a run produces, as exact text (floats as hex, arrays as raw bytes)."""
    return (
        res.q.tobytes().hex(),
        float(res.fitness).hex(),
        res.n_evals,
        np.asarray(res.history, dtype=float).tobytes().hex(),
        res.success,
    )


def problems(robot: swarm_ik.RobotModel) -> dict[str, swarm_ik.IKProblem]:
    far = robot.fk(robot.mid_q())
    far[:3, 3] += [0.6, -0.4, 0.5]  # out of reach: every solver spends its whole budget
    return {
        "reachable": swarm_ik.IKProblem.from_q(robot, Q_REACH),
        "unreachable": swarm_ik.IKProblem(robot, far),
    }


def run(problem: swarm_ik.IKProblem, solver: str, seed: int) -> swarm_ik.Result:
    return swarm_ik.solve(problem, solver, seed=seed, max_evals=BUDGET)


@pytest.fixture(scope="module")
def yumi() -> swarm_ik.RobotModel:
    return swarm_ik.load_robot("yumi_left")


# ------------------------------------------------------------------------ in this process
@pytest.mark.parametrize("solver", SOLVERS)
def test_same_seed_is_bit_identical_even_on_a_freshly_loaded_robot(
    solver: str, yumi: swarm_ik.RobotModel
) -> None:
    other = swarm_ik.load_robot("yumi_left")  # a second, independent model object
    for label, prob in problems(yumi).items():
        twin = problems(other)[label]
        a, b, c = run(prob, solver, 7), run(prob, solver, 7), run(twin, solver, 7)
        assert fingerprint(a) == fingerprint(b) == fingerprint(c), (solver, label)


def test_an_integer_seed_equals_a_generator_built_from_it(yumi: swarm_ik.RobotModel) -> None:
    """For the solvers that draw from a Generator (the swarm solver's compiled search is keyed
    by the integer itself: see test_search)."""
    prob = problems(yumi)["unreachable"]
    for solver in ("pso", "dls"):
        by_int = swarm_ik.solve(prob, solver, seed=11, max_evals=BUDGET)
        gen = np.random.default_rng(11)
        by_gen = swarm_ik.solve(prob, solver, seed=gen, max_evals=BUDGET)
        assert fingerprint(by_int) == fingerprint(by_gen), solver
        assert by_int.seed == 11 and by_gen.seed is None
    # None means seed 0, not "random"
    assert fingerprint(swarm_ik.solve(prob, "gwo", seed=None, max_evals=BUDGET)) == fingerprint(
        swarm_ik.solve(prob, "gwo", seed=0, max_evals=BUDGET)
    )


# -------------------------------------------------------------------- in another process
_CHILD = """
import json, sys
import numpy as np
import swarm_ik
sys.path.insert(0, {here!r})
from test_determinism import fingerprint, problems, run, SOLVERS
robot = swarm_ik.load_robot("yumi_left")
out = {{}}
for label, prob in problems(robot).items():
    for solver in SOLVERS:
        out[label + "/" + solver] = list(fingerprint(run(prob, solver, 3)))
print(json.dumps(out))
"""


def test_same_seed_is_bit_identical_in_a_fresh_process(yumi: swarm_ik.RobotModel) -> None:
    here = os.path.dirname(os.path.abspath(__file__))
    env = {**os.environ, "PYTHONHASHSEED": "4242"}  # other set/dict orders than this process
    proc = subprocess.run(
        [sys.executable, "-c", _CHILD.format(here=here)],
        capture_output=True,
        text=True,
        env=env,
        timeout=300,
        check=False,
    )
    assert proc.returncode == 0, proc.stderr
    child = json.loads(proc.stdout.strip().splitlines()[-1])
    mine = {
        f"{label}/{solver}": list(fingerprint(run(prob, solver, 3)))
        for label, prob in problems(yumi).items()
        for solver in SOLVERS
    }
    assert child.keys() == mine.keys()
    for key in mine:
        assert child[key] == mine[key], key


# ---------------------------------------------------------------- threads and processes
def _tasks() -> list[tuple[str, str, int]]:
    return [
        (label, solver, seed)
        for label in ("reachable", "unreachable")
        for solver in ("swarm", "dls", "gwo", "hlfoa", "cs-newton", "pso-improved")
        for seed in (0, 1)
    ]


def test_threads_give_the_sequential_results(yumi: swarm_ik.RobotModel) -> None:
    probs = problems(yumi)  # one problem object shared by every thread
    tasks = _tasks()
    sequential = [fingerprint(run(probs[lab], s, seed)) for lab, s, seed in tasks]
    with ThreadPoolExecutor(max_workers=4) as pool:
        threaded = list(pool.map(lambda t: fingerprint(run(probs[t[0]], t[1], t[2])), tasks))
    assert threaded == sequential


def test_a_process_pool_gives_the_sequential_results(yumi: swarm_ik.RobotModel) -> None:
    probs = problems(yumi)  # problems are pickled to the workers
    tasks = _tasks()[::3]
    sequential = [fingerprint(run(probs[lab], s, seed)) for lab, s, seed in tasks]
    ctx = multiprocessing.get_context("spawn")  # fresh interpreters, nothing inherited
    with ProcessPoolExecutor(max_workers=2, mp_context=ctx) as pool:
        futures = [
            pool.submit(swarm_ik.solve, probs[lab], s, seed=seed, max_evals=BUDGET)
            for lab, s, seed in tasks
        ]
        pooled = [fingerprint(f.result(timeout=300)) for f in futures]
    assert pooled == sequential


# ------------------------------------------------------------------------- global state
def test_solving_neither_reads_nor_writes_global_random_state(yumi: swarm_ik.RobotModel) -> None:
    prob = problems(yumi)["unreachable"]
    np.random.seed(1)  # noqa: NPY002 - the legacy global state is what is tested
    random.seed(1)
    np_state, py_state = np.random.get_state(), random.getstate()  # noqa: NPY002
    first = {s: fingerprint(run(prob, s, 5)) for s in SOLVERS}
    after = np.random.get_state()  # noqa: NPY002
    assert isinstance(np_state, tuple) and isinstance(after, tuple)
    assert np_state[0] == after[0] and np.array_equal(np_state[1], after[1])
    assert np_state[2:] == after[2:]
    assert random.getstate() == py_state
    np.random.seed(999)  # noqa: NPY002 - a different global state changes nothing
    random.seed(999)
    assert {s: fingerprint(run(prob, s, 5)) for s in SOLVERS} == first


def test_one_solve_does_not_influence_the_next(yumi: swarm_ik.RobotModel, tmp_path) -> None:
    probs = problems(yumi)
    planar_urdf = tmp_path / "planar.urdf"
    planar_urdf.write_text(
        '<?xml version="1.0"?><robot name="p"><link name="a"/><link name="b"/><link name="c"/>'
        '<joint name="j1" type="revolute"><parent link="a"/><child link="b"/>'
        '<axis xyz="0 0 1"/><limit lower="-3" upper="3" effort="1" velocity="1"/></joint>'
        '<joint name="j2" type="prismatic"><parent link="b"/><child link="c"/>'
        '<origin xyz="1 0 0"/><axis xyz="1 0 0"/>'
        '<limit lower="0" upper="0.5" effort="1" velocity="1"/></joint></robot>'
    )
    planar = swarm_ik.load_robot(planar_urdf)
    other = swarm_ik.IKProblem(planar, swarm_ik.make_pose([0.0, 1.2, 0.0], [0, 0, 0, 1]), w_rot=0.0)
    for solver in SOLVERS:
        alone = fingerprint(run(probs["reachable"], solver, 2))
        run(other, solver, 9)  # another robot, dimension, fitness mode in between
        run(probs["unreachable"], solver, 4)
        assert fingerprint(run(probs["reachable"], solver, 2)) == alone, solver


def test_solving_does_not_modify_its_inputs(yumi: swarm_ik.RobotModel) -> None:
    target = yumi.fk(np.asarray(Q_REACH)) + 0.0
    target_copy = target.copy()
    q0 = yumi.mid_q() + 0.05
    q0_copy = q0.copy()
    prob = swarm_ik.IKProblem(yumi, target)
    arrays = {
        "problem.target": prob.target,
        "problem.lower": prob.lower,
        "problem.upper": prob.upper,
        "robot.lower": yumi.lower,
        "robot.upper": yumi.upper,
        "tree.frame_pos": yumi.tree.frame_pos,
        "tree.pos_p": yumi.tree.pos_p,
        "tree.rot_p": yumi.tree.rot_p,
    }
    before = {k: v.copy() for k, v in arrays.items()}
    names_before = swarm_ik.solvers.names()
    params_before = {s: dict(swarm_ik.solvers.get(s).params) for s in SOLVERS}
    filters_before = list(warnings.filters)
    for solver in SOLVERS:
        swarm_ik.solve(prob, solver, seed=0, q0=q0, max_evals=BUDGET)
    swarm_ik.load_robot("yumi_left")  # silences its own warnings without leaking the filter
    np.testing.assert_array_equal(target, target_copy)
    np.testing.assert_array_equal(q0, q0_copy)
    for k, v in arrays.items():
        np.testing.assert_array_equal(v, before[k], err_msg=k)
    assert swarm_ik.solvers.names() == names_before
    assert {s: dict(swarm_ik.solvers.get(s).params) for s in SOLVERS} == params_before
    assert list(warnings.filters) == filters_before
    # the target is copied: changing the caller's array later does not move the problem's
    target[0, 3] += 1.0
    assert prob.target[0, 3] == target_copy[0, 3]
