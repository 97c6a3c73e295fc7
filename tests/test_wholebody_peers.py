"""The whole-body peers' side (swarm_ik.bench.wholebody_peers): Talos targets, the judge,
pink, and placo in its own environment.

The placo round trip needs placo's virtual environment (made by ``placo_env()``: pip and the
network, about 40 s once).  It runs when that environment exists (``$SWARM_IK_PLACO_ENV`` or
the default folder in swarm_ik's cache), or is made first when ``SWARM_IK_TEST_PLACO=1``;
otherwise it is skipped, so that a machine without network still passes.
"""

from __future__ import annotations

import os
import re
import sys
from pathlib import Path

import numpy as np
import pytest

from swarm_ik.bench import wholebody_peers as wb


@pytest.fixture(scope="module")
def targets() -> wb.WholebodyTargets:
    return wb.talos_wholebody_targets(6, np.random.default_rng(7))


def test_generated_targets_are_solved_by_their_configuration(targets):
    j = wb.judge_wholebody(targets.model_path, targets.q_gen, targets)
    assert j.success.all()
    assert np.nanmax(j.hand_pos) < 1e-12 and np.nanmax(j.sole_rot) < 1e-12
    assert (j.com_margin >= 0).all()
    # both soles flat on the ground, the support polygon a convex CCW hull of 4 or more corners
    for soles in (targets.left_sole, targets.right_sole):
        np.testing.assert_allclose(soles[:, 2, 3], 0.0, atol=1e-12)
        np.testing.assert_allclose(
            soles[:, :3, :3], np.broadcast_to(np.eye(3), (6, 3, 3)), atol=1e-12
        )
    poly = targets.polygon[0]
    e = np.roll(poly, -1, axis=0) - poly
    f = np.roll(e, -1, axis=0)
    assert len(poly) >= 4 and (e[:, 0] * f[:, 1] - e[:, 1] * f[:, 0] > 0).all()
    # the start configuration holds the locked torso but not the hands
    j0 = wb.judge_wholebody(targets.model_path, targets.q0, targets)
    assert not j0.success.any() and np.nanmax(j0.locked_err) == 0.0


def test_targets_do_not_depend_on_n():
    a = wb.talos_wholebody_targets(2, np.random.default_rng(3))
    b = wb.talos_wholebody_targets(4, np.random.default_rng(3))
    np.testing.assert_array_equal(a.q_gen, b.q_gen[:2])
    assert b.subset(slice(0, 2)).q_gen.shape == (2, 39)


def test_judge_refuses_perturbed_configurations(targets):
    model = wb.free_flyer_model(targets.model_path)
    q = targets.q_gen.copy()
    arm = model.idx_qs[model.getJointId("arm_left_4_joint")]
    torso = model.idx_qs[model.getJointId("torso_2_joint")]
    knee = model.idx_qs[model.getJointId("leg_right_4_joint")]
    q[0, arm] += 1e-3  # hand off by about a millimetre
    q[1, torso] += 1e-4  # locked joint moved
    q[2, 2] += 1e-4  # whole robot lifted: soles off
    q[3, knee] = model.lowerPositionLimit[knee] - 1e-3  # beyond a limit
    q[4] = np.nan
    j = wb.judge_wholebody(targets.model_path, q, targets)
    assert j.success.tolist() == [False, False, False, False, False, True]
    assert j.hand_pos[0, 0] > 1e-5 and j.locked_err[1] > 1e-5
    assert j.sole_pos[2].min() > 1e-5 and j.limit_excess[3] > 1e-5
    assert np.isnan(j.hand_pos[4]).all()
    # the CoM outside the polygon: the same configuration judged against a shifted polygon
    moved = wb.WholebodyTargets(**{**targets.__dict__, "polygon": targets.polygon + [0.5, 0.0]})
    assert not wb.judge_wholebody(targets.model_path, targets.q_gen, moved).success.any()


def test_pink_round_trip(targets):
    pytest.importorskip("pink")
    pytest.importorskip("quadprog")
    sub = targets.subset(slice(0, 3))
    try:
        a = wb.run_pink(sub)
    except wb.PeerEnvironmentError as exc:  # pink older than 3.3
        pytest.skip(str(exc))
    j = wb.judge_wholebody(sub.model_path, a.q, sub)
    assert a.q.shape == (3, 39) and (a.time_s > 0).all()
    assert (j.success == a.converged).all()  # its own flag is the judge's verdict
    assert j.success.sum() >= 2


def test_placo_worker_imports_no_swarm_ik():
    src = (Path(wb.__file__).with_name("_placo_worker.py")).read_text()
    imports = re.findall(r"^\s*(?:import|from)\s+([\w.]+)", src, flags=re.M)
    assert not [m for m in imports if m.split(".")[0] == "swarm_ik"]


def test_placo_env_missing_is_one_clear_error(tmp_path):
    with pytest.raises(wb.PeerEnvironmentError, match="no placo environment") as info:
        wb.placo_env(tmp_path / "none", create=False)
    assert "\n" not in str(info.value)


@pytest.mark.slow
def test_placo_env_pip_failure_is_one_clear_error(tmp_path, monkeypatch):
    """pip finding nothing (here: no index, an empty folder of wheels) fails with one line."""
    monkeypatch.setenv("PIP_NO_INDEX", "1")
    monkeypatch.setenv("PIP_FIND_LINKS", str(tmp_path))
    with pytest.raises(wb.PeerEnvironmentError, match="pip install placo") as info:
        wb.placo_env(tmp_path / "env")
    assert "\n" not in str(info.value)
    assert not (tmp_path / "env").exists()  # nothing half-made left in place


def _placo_env_or_skip() -> Path:
    try:
        return wb.placo_env(create=os.environ.get("SWARM_IK_TEST_PLACO") == "1")
    except wb.PeerEnvironmentError as exc:
        pytest.skip(f"placo environment unavailable ({exc}); set SWARM_IK_TEST_PLACO=1 to make it")


@pytest.mark.skipif(sys.platform == "win32", reason="placo has no Windows wheel")
def test_placo_round_trip(targets):
    env = _placo_env_or_skip()
    sub = targets.subset(slice(0, 3))
    a = wb.run_placo(sub, env=env)
    assert a.name == "placo" and a.versions["placo"] == wb.PLACO_VERSION
    j = wb.judge_wholebody(sub.model_path, a.q, sub)
    assert a.q.shape == (3, 39) and (a.time_s > 0).all()
    assert (j.success == a.converged).all()
    assert j.success.sum() >= 2
    np.testing.assert_array_equal(a.q[:, [19, 20]][j.success], sub.locked[j.success])
