"""Benchmark functions F1..F4 ([MGWO], Table 2): values, minima, domains, errors."""

from __future__ import annotations

import math

import numpy as np
import pytest

from swarm_ik.errors import InvalidArgumentError, UnknownNameError
from swarm_ik.testfunctions import FUNCTIONS, get_function, hartmann3


def test_table_of_functions():
    assert sorted(FUNCTIONS) == ["F1", "F2", "F3", "F4"]
    expected = {  # (dim, lower, upper, f_min), [GWO] / [MGWO] with the F4 fix
        "F1": (30, -100.0, 100.0, 0.0),
        "F2": (30, -10.0, 10.0, 0.0),
        "F3": (30, -5.12, 5.12, 0.0),
        "F4": (3, 0.0, 1.0, -3.86278),
    }
    for key, (dim, lo, hi, fmin) in expected.items():
        tf = FUNCTIONS[key]
        assert (tf.dim, tf.lower, tf.upper, tf.f_min) == (dim, lo, hi, fmin)
        assert len(tf.x_min) == dim
        lower, upper = tf.bounds
        assert lower.shape == upper.shape == (dim,)
        assert np.all(lower <= np.array(tf.x_min)) and np.all(np.array(tf.x_min) <= upper)


@pytest.mark.parametrize("key", ["F1", "F2", "F3", "F4"])
def test_value_at_the_known_minimum(key):
    tf = FUNCTIONS[key]
    f = tf(np.array([tf.x_min]))
    assert f.shape == (1,)
    assert f[0] == pytest.approx(tf.f_min, abs=1e-5)


@pytest.mark.parametrize("key", ["F1", "F2", "F3", "F4"])
def test_known_minimum_is_a_local_minimum(key):
    tf = FUNCTIONS[key]
    rng = np.random.default_rng(7)
    x0 = np.array(tf.x_min)
    lower, upper = tf.bounds
    pts = np.clip(x0 + 1e-3 * rng.standard_normal((200, tf.dim)), lower, upper)
    f0 = tf(x0[None])[0]
    assert np.all(tf(pts) >= f0 - 1e-6)  # x_min of F4 is given to 6 decimals


def test_hand_computed_values():
    x = np.ones((1, 30))
    x[0, :3] = [1.0, -2.0, 0.5]
    # sphere: 1 + 4 + 0.25 + 27
    assert FUNCTIONS["F1"](x)[0] == pytest.approx(32.25)
    # Schwefel 2.22: (1 + 2 + 0.5 + 27) + 1*2*0.5*1
    assert FUNCTIONS["F2"](x)[0] == pytest.approx(31.5)
    # Rastrigin: x = 1 and x = -2 are integers (x^2 - 10 + 10 = x^2); x = 0.5: 0.25 + 20
    assert FUNCTIONS["F3"](x)[0] == pytest.approx(1 + 4 + 20.25 + 27)
    # Hartmann-3 at the origin: -sum_i c_i exp(-sum_j a_ij p_ij^2), written out term by term
    a = [[3, 10, 30], [0.1, 10, 35], [3, 10, 30], [0.1, 10, 35]]
    c = [1.0, 1.2, 3.0, 3.2]
    p = [
        [0.3689, 0.1170, 0.2673],
        [0.4699, 0.4387, 0.7470],
        [0.1091, 0.8732, 0.5547],
        [0.03815, 0.5743, 0.8828],
    ]
    want = -sum(c[i] * math.exp(-sum(a[i][j] * p[i][j] ** 2 for j in range(3))) for i in range(4))
    assert FUNCTIONS["F4"](np.zeros((1, 3)))[0] == pytest.approx(want, rel=1e-12)


@pytest.mark.parametrize("key", ["F1", "F2", "F3", "F4"])
def test_batched_equals_row_by_row(key):
    tf = FUNCTIONS[key]
    rng = np.random.default_rng(1)
    lower, upper = tf.bounds
    x = rng.uniform(lower, upper, size=(7, tf.dim))
    batch = tf(x)
    assert batch.shape == (7,)
    np.testing.assert_allclose(batch, [tf(row[None])[0] for row in x], rtol=1e-13)


def test_errors():
    with pytest.raises(InvalidArgumentError, match="3 coordinates"):
        hartmann3(np.zeros((2, 4)))
    with pytest.raises(UnknownNameError, match="F1, F2, F3, F4"):
        get_function("F5")
    assert get_function("F3") is FUNCTIONS["F3"]
