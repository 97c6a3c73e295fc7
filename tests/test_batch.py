"""Batched IK (solve_batch), target files, reachability maps and the batch/reach CLI."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import swarm_ik
from swarm_ik import batch
from swarm_ik.batch import (
    BatchChain,
    BatchSettings,
    check_targets,
    read_targets,
    solve_batch,
    solve_chunk,
    target_uniforms,
    write_targets,
)
from swarm_ik.cli import main
from swarm_ik.errors import InvalidArgumentError, InvalidTargetError
from swarm_ik.reach import (
    ReachMap,
    chain_reach_bound,
    grid_axes,
    random_rotations,
    reach_map,
)

TOL = 1e-5


def fk_targets(robot: swarm_ik.RobotModel, n: int, seed: int) -> tuple[np.ndarray, np.ndarray]:
    q = robot.random_q(np.random.default_rng(seed), n)
    return q, robot.fk(q)


@pytest.mark.parametrize("name", ["panda", "yumi_left"])
def test_fk_sampled_targets_are_solved_and_pinocchio_agrees(get_robot, name):
    robot = get_robot(name)
    _, targets = fk_targets(robot, 300, seed=7)
    res = solve_batch(robot, targets, seed=0)
    assert res.q.shape == (300, robot.nq)
    assert res.success_rate >= 0.99
    ok = res.success
    assert np.all(res.position_error[ok] <= TOL) and np.all(res.rotation_error[ok] <= TOL)
    assert np.all(res.q >= robot.lower - 1e-12) and np.all(res.q <= robot.upper + 1e-12)
    # an independent check of a sample with Pinocchio's own FK
    for i in np.flatnonzero(ok)[:: max(1, int(ok.sum()) // 12)]:
        dp, dr = swarm_ik.problem.largest_errors(
            swarm_ik.verify(swarm_ik.IKProblem(robot, targets[i]), res.q[i])
        )
        assert dp <= TOL and dr <= TOL
        assert dp == pytest.approx(res.position_error[i], abs=1e-12)


def test_errors_reported_are_those_of_the_answer(get_robot):
    robot = get_robot("panda")
    _, targets = fk_targets(robot, 40, seed=3)
    res = solve_batch(robot, targets, seed=0, max_starts=1, max_iters=3)  # stopped early
    assert not res.success.all()
    pose = robot.fk(res.q)
    dp = np.linalg.norm(pose[:, :3, 3] - targets[:, :3, 3], axis=1)
    np.testing.assert_allclose(res.position_error, dp, atol=1e-12)
    bad = ~res.success
    assert np.all((res.position_error[bad] > TOL) | (res.rotation_error[bad] > TOL))


def test_result_does_not_depend_on_chunking(get_robot):
    robot = get_robot("yumi_left")
    _, targets = fk_targets(robot, 240, seed=11)
    whole = solve_batch(robot, targets, seed=5)
    small = solve_batch(robot, targets, seed=5, chunk_size=17)
    np.testing.assert_array_equal(whole.q, small.q)
    np.testing.assert_array_equal(whole.n_evals, small.n_evals)
    np.testing.assert_array_equal(whole.success, small.success)
    assert (whole.n_starts > 1).any()  # restarts were used, so their streams were compared
    # a chunk solved on its own (as on a worker) gives the rows of the whole batch
    bc = BatchChain.from_robot(robot)
    seeds = np.tile(robot.mid_q(), (60, 1))
    part = solve_chunk(bc, BatchSettings(seed=5), 100, targets[100:160], seeds)
    np.testing.assert_array_equal(part.q, whole.q[100:160])


def test_seed_changes_restarts_only_where_restarts_happen(get_robot):
    robot = get_robot("panda")
    _, targets = fk_targets(robot, 200, seed=2)
    a = solve_batch(robot, targets, seed=0)
    b = solve_batch(robot, targets, seed=1)
    first = (a.n_starts == 1) & (b.n_starts == 1)  # solved from the shared mid-range start
    np.testing.assert_array_equal(a.q[first], b.q[first])
    restarted = (a.n_starts > 1) & (b.n_starts > 1)
    assert restarted.any()
    assert not np.array_equal(a.q[restarted], b.q[restarted])


def test_restart_streams_are_keyed_by_seed_and_index():
    u = target_uniforms(3, 10, 1000)
    assert np.all((u >= 0) & (u < 1)) and abs(u.mean() - 0.5) < 0.05
    np.testing.assert_array_equal(u, target_uniforms(3, 10, 1000))
    assert not np.array_equal(u[:8], target_uniforms(3, 11, 8))
    assert not np.array_equal(u[:8], target_uniforms(4, 10, 8))


def test_unreachable_targets_fail_after_all_starts(get_robot):
    robot = get_robot("yumi_left")
    _, targets = fk_targets(robot, 4, seed=1)
    targets[:2, :3, 3] += 5.0  # 5 m away: out of reach
    res = solve_batch(robot, targets, max_starts=40)
    np.testing.assert_array_equal(res.success, [False, False, True, True])
    np.testing.assert_array_equal(res.n_starts[:2], [40, 40])
    assert np.all(res.position_error[:2] > 4.0)


@pytest.mark.parametrize("max_starts", [1, 2, 3, 12])
def test_max_starts_bounds_every_target_with_the_restart_table(get_robot, max_starts):
    """The seed, the restart table's nearest configurations, the random restarts and the
    patient last start together spend at most ``max_starts`` starts per target, and the
    evaluations of as many starts (the last one ``PATIENT_ITERS`` times as long); unreachable
    targets spend all the starts."""
    robot = get_robot("panda")
    _, targets = fk_targets(robot, 200, seed=6)
    targets[:3, :3, 3] += 5.0  # out of reach
    res = solve_batch(robot, targets, seed=0, max_starts=max_starts)
    assert np.all(res.n_starts <= max_starts) and np.all(res.n_starts >= 1)
    np.testing.assert_array_equal(res.n_starts[:3], [max_starts] * 3)
    long_starts = 0 if max_starts == 1 else batch.PATIENT_ITERS - 1
    assert np.all(res.n_evals <= (max_starts + long_starts) * batch.BATCH_MAX_ITERS)
    assert not res.success[:3].any()
    assert res.success[3:].mean() >= {1: 0.6, 2: 0.75, 3: 0.9, 12: 0.97}[max_starts]


@pytest.mark.parametrize("max_evals", [3, 40, 500])
def test_max_evals_bounds_every_target_over_all_its_passes(get_robot, max_evals):
    """``max_evals`` bounds each target's evaluations over all its starts and passes, as
    ``solve``'s bounds one solve: unreachable targets stop at it, and every success is still
    an answer Pinocchio checks (with a goal of the batch too)."""
    robot = get_robot("panda")
    _, targets = fk_targets(robot, 150, seed=7)
    targets[:3, :3, 3] += 5.0  # out of reach
    for goals in (None, [swarm_ik.goals.CenterJoints(weight=0.1)]):
        res = solve_batch(robot, targets, seed=0, max_evals=max_evals, goals=goals)
        assert int(res.n_evals.max()) <= max_evals
        assert not res.success[:3].any()
        if max_evals >= 40:
            np.testing.assert_array_equal(res.n_evals[:3], [max_evals] * 3)
        for i in np.flatnonzero(res.success):
            assert np.linalg.norm(robot.fk_pinocchio(res.q[i])[:3, 3] - targets[i, :3, 3]) < 1e-5
    plain = solve_batch(robot, targets, seed=0)
    assert plain.success.sum() >= solve_batch(robot, targets, seed=0, max_evals=40).success.sum()


@pytest.mark.parametrize("bad", [0, -5, 2.5, True, "10", 2**63, 10**30])
def test_a_bad_max_evals_is_refused(get_robot, bad):
    with pytest.raises(InvalidArgumentError, match="max_evals must be"):
        solve_batch(get_robot("panda"), np.eye(4)[None], max_evals=bad)


def test_the_last_start_polishes_the_best_point_patiently(get_robot):
    """With two starts, the second polishes the first's end point with up to
    ``PATIENT_ITERS × max_iters`` evaluations and no verdict on slow steps: it solves targets
    the first start gave up on (same first start: the same answer where it was the only)."""
    robot = get_robot("panda")
    _, targets = fk_targets(robot, 200, seed=6)
    one = solve_batch(robot, targets, max_starts=1, max_iters=10)
    two = solve_batch(robot, targets, max_starts=2, max_iters=10)
    first_only = two.n_starts == 1
    np.testing.assert_array_equal(two.q[first_only], one.q[first_only])
    gained = two.success & ~one.success
    assert gained.sum() >= 10
    np.testing.assert_array_equal(two.n_starts[gained], 2)
    second = two.n_evals[gained] - one.n_evals[gained]
    assert np.all(second <= batch.PATIENT_ITERS * 10) and np.any(second > 10)


def test_q0_seeds_each_target(get_robot):
    robot = get_robot("panda")
    q_true, targets = fk_targets(robot, 30, seed=4)
    res = solve_batch(robot, targets, q0=q_true)
    assert res.success.all()
    np.testing.assert_array_equal(res.n_starts, 1)
    assert res.n_evals.max() <= 2  # the seed is already a solution: one check, maybe one step
    with pytest.raises(InvalidArgumentError, match=r"q0 must have shape \(7,\) or \(30, 7\)"):
        solve_batch(robot, targets, q0=q_true[:3])
    with pytest.warns(UserWarning, match="outside the joint limits for 30 target"):
        solve_batch(robot, targets, q0=robot.upper + 1.0, max_starts=2)


def test_continuous_joints_are_wrapped(get_robot):
    robot = get_robot("kinova")
    assert "continuous" in robot.joint_kinds
    _, targets = fk_targets(robot, 100, seed=9)
    res = solve_batch(robot, targets)
    assert res.success_rate >= 0.97
    m = robot.continuous_mask
    assert np.all(np.abs(res.q[:, m]) <= np.pi + 1e-12)


def test_position_only(get_robot):
    robot = get_robot("yumi_left")
    _, targets = fk_targets(robot, 50, seed=6)
    rots = random_rotations(np.random.default_rng(0), 50)
    targets[:, :3, :3] = rots  # orientations the arm mostly cannot take at these points
    res = solve_batch(robot, targets, position_only=True)
    assert res.success.all()
    assert np.all(res.position_error <= TOL)
    assert np.isnan(res.rotation_error).all()  # (the orientations ignored: not measured)
    reached = np.array([robot.fk_pinocchio(q)[:3, :3] for q in res.q])
    assert np.median(np.abs(reached - rots).max(axis=(1, 2))) > 0.1


def test_position_only_takes_points(get_robot):
    """A position-only batch takes ``(N, 3)`` points, with the answers of their poses; a pose
    batch refuses them, naming the shapes it takes."""
    robot = get_robot("yumi_left")
    _, targets = fk_targets(robot, 30, seed=7)
    points = targets[:, :3, 3].copy()
    res = solve_batch(robot, points, position_only=True)
    assert res.success.all()
    reached = np.array([robot.fk_pinocchio(q)[:3, 3] for q in res.q])
    assert np.all(np.linalg.norm(reached - points, axis=1) <= TOL)
    same = solve_batch(robot, targets, position_only=True)
    np.testing.assert_array_equal(res.q, same.q)  # (a point is its pose's position)
    with pytest.raises(InvalidTargetError, match=r"\(N, 4, 4\) or \(N, 7\).*got \(30, 3\)"):
        solve_batch(robot, points)
    bad = points.copy()
    bad[4, 1] = np.nan
    with pytest.raises(InvalidTargetError, match="target 4 contains NaN"):
        solve_batch(robot, bad, position_only=True)


def test_does_not_loop_over_solve(get_robot, monkeypatch):
    def forbidden(*args, **kwargs):
        raise AssertionError("solve_batch must not call swarm_ik.solve")

    # the package's attribute first: swarm_ik imports it lazily from swarm_ik.api, so patching
    # swarm_ik.api first would make monkeypatch remember (and restore) the forbidden one
    monkeypatch.setattr(swarm_ik, "solve", forbidden)
    monkeypatch.setattr(swarm_ik.api, "solve", forbidden)
    robot = get_robot("yumi_left")
    assert solve_batch(robot, fk_targets(robot, 20, 0)[1]).success.all()


def test_empty_batch(get_robot):
    robot = get_robot("yumi_left")
    res = solve_batch(robot, np.empty((0, 4, 4)))
    assert res.q.shape == (0, 7) and res.success.shape == (0,) and res.success_rate == 0.0


def test_settings_are_validated(get_robot):
    robot = get_robot("yumi_left")
    t = robot.fk(robot.mid_q())[None]
    for kwargs, msg in [
        ({"tol_pos": 0.0}, "tol_pos must be a positive"),
        ({"max_starts": 0}, r"max_starts must be an integer in \[1, "),
        ({"seed": -1}, r"seed must be in \[0, 2\*\*63\), got -1"),
        ({"seed": 2**63}, r"seed must be in \[0, 2\*\*63\)"),
        ({"seed": 1.5}, "seed must be a non-negative integer, got 1.5"),
        ({"seed": np.random.default_rng(0)}, r"seed must be an integer in \[0, 2\*\*63\)"),
        ({"chunk_size": 0}, "chunk_size must be a positive integer"),
        ({"scheduler": "udp://x"}, "valid choices: 'none'"),
    ]:
        with pytest.raises(InvalidArgumentError, match=msg):
            solve_batch(robot, t, **kwargs)
    with pytest.raises(InvalidArgumentError, match="RobotModel"):
        solve_batch("panda", t)  # type: ignore[arg-type]
    with pytest.raises(InvalidArgumentError, match="own_start must be a bool, got 'yes'"):
        batch.BatchSettings(own_start="yes")  # type: ignore[arg-type]


def test_check_targets():
    good = np.tile(np.eye(4), (3, 1, 1))
    assert check_targets(good).shape == (3, 4, 4)
    rows = np.array([[0.1, 0.2, 0.3, 0.0, 0.0, np.sin(0.25), np.cos(0.25)]])
    pose = check_targets(rows)[0]
    np.testing.assert_allclose(pose[:3, 3], [0.1, 0.2, 0.3])
    assert np.isclose(np.arctan2(pose[1, 0], pose[0, 0]), 0.5)
    bad = good.copy()
    bad[2, 0, 3] = np.nan
    with pytest.raises(InvalidTargetError, match="target 2 contains NaN"):
        check_targets(bad)
    bad = good.copy()
    bad[1, :3, :3] *= 1.01
    with pytest.raises(InvalidTargetError, match="target 1: rotation is not orthonormal"):
        check_targets(bad)
    bad = good.copy()
    bad[0, 3, 0] = 1.0
    with pytest.raises(InvalidTargetError, match="target 0: bottom row"):
        check_targets(bad)
    with pytest.raises(InvalidTargetError, match=r"shape \(N, 4, 4\) or \(N, 7\)"):
        check_targets(np.zeros((3, 3, 3)))


def test_target_files_round_trip(get_robot, tmp_path):
    robot = get_robot("yumi_left")
    _, targets = fk_targets(robot, 25, seed=1)
    for suffix in (".csv", ".npz"):
        path = write_targets(tmp_path / f"t{suffix}", targets)
        np.testing.assert_allclose(read_targets(path), targets, atol=1e-12)
    # 16 columns, no header; a .npy file; columns in another order
    np.savetxt(tmp_path / "m.csv", targets.reshape(25, 16), delimiter=",")
    np.testing.assert_allclose(read_targets(tmp_path / "m.csv"), targets, atol=1e-12)
    np.save(tmp_path / "t.npy", targets)
    np.testing.assert_allclose(read_targets(tmp_path / "t.npy"), targets)
    (tmp_path / "o.csv").write_text("qw,qx,qy,qz,x,y,z\n1,0,0,0,0.1,0.2,0.3\n")
    np.testing.assert_allclose(read_targets(tmp_path / "o.csv")[0, :3, 3], [0.1, 0.2, 0.3])
    (tmp_path / "h.csv").write_text("a,b,c\n1,2,3\n")
    with pytest.raises(InvalidArgumentError, match="header lacks column"):
        read_targets(tmp_path / "h.csv")
    (tmp_path / "t.txt").write_text("1")
    with pytest.raises(InvalidArgumentError, match="valid suffixes: .csv, .npy, .npz"):
        read_targets(tmp_path / "t.txt")
    with pytest.raises(InvalidArgumentError, match="not found"):
        read_targets(tmp_path / "missing.csv")


def test_position_only_target_files_take_points(tmp_path):
    """With ``positions``, a file of points is read as targets (CSV ``x,y,z`` with or without
    a header, ``(N, 3)`` arrays); without it they are refused, the shapes named."""
    pts = np.array([[0.4, 0.1, 0.5], [0.3, -0.2, 0.4]])
    (tmp_path / "h.csv").write_text("z,x,y\n0.5,0.4,0.1\n0.4,0.3,-0.2\n")
    np.savetxt(tmp_path / "n.csv", pts, delimiter=",")
    np.save(tmp_path / "p.npy", pts)
    for name in ("h.csv", "n.csv", "p.npy"):
        out = read_targets(tmp_path / name, positions=True)
        np.testing.assert_allclose(out[:, :3, 3], pts)
        np.testing.assert_array_equal(out[:, :3, :3], np.broadcast_to(np.eye(3), (2, 3, 3)))
    with pytest.raises(InvalidArgumentError, match="header lacks column"):
        read_targets(tmp_path / "h.csv")
    with pytest.raises(InvalidArgumentError, match="7 columns .* got 3"):
        read_targets(tmp_path / "n.csv")
    with pytest.raises(InvalidTargetError, match=r"\(N, 7\) .*; got \(2, 3\)"):
        read_targets(tmp_path / "p.npy")
    assert main(["batch", "--robot", "panda", "--targets", str(tmp_path / "h.csv"),
                 "--position-only", "--out", str(tmp_path / "r.csv")]) == 0  # fmt: skip


def test_an_interrupted_save_leaves_no_partial_file(get_robot, tmp_path, monkeypatch):
    """A save interrupted while writing (Ctrl-C) leaves the file as it was and no part file:
    the answers are written beside it and renamed into place."""
    robot = get_robot("yumi_left")
    res = solve_batch(robot, fk_targets(robot, 5, seed=1)[1])
    out = tmp_path / "r.csv"
    out.write_text("before\n")

    def interrupted(*args, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr(batch.csv, "writer", interrupted)
    with pytest.raises(KeyboardInterrupt):
        res.save(out)
    assert out.read_text() == "before\n"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["r.csv"]
    monkeypatch.undo()
    res.save(out)
    assert out.read_text().count("\n") == 6


def test_result_files(get_robot, tmp_path):
    robot = get_robot("yumi_left")
    _, targets = fk_targets(robot, 10, seed=1)
    res = solve_batch(robot, targets)
    d = np.load(res.save(tmp_path / "r.npz", targets=targets))
    np.testing.assert_array_equal(d["q"], res.q)
    np.testing.assert_array_equal(d["targets"], targets)
    assert list(d["joint_names"]) == list(robot.joint_names)
    res.save(tmp_path / "r.csv")
    table = np.genfromtxt(tmp_path / "r.csv", delimiter=",", names=True)
    np.testing.assert_array_equal(table[robot.joint_names[0]], res.q[:, 0])
    np.testing.assert_array_equal(table["success"].astype(bool), res.success)
    with pytest.raises(InvalidArgumentError, match="valid: .csv, .npz"):
        res.save(tmp_path / "r.json")


# ---------------------------------------------------------------------------- reach
def test_grid_axes():
    x, y, z = grid_axes([0, 0, 0], [1.0, 0.5, 0.05], 0.1)
    assert (x.size, y.size, z.size) == (10, 5, 1)
    np.testing.assert_allclose(np.diff(x), 0.1)
    assert x[0] == pytest.approx(0.05) and x[-1] == pytest.approx(0.95)


def test_chain_reach_bound_holds(get_robot):
    for name in ("panda", "loading_manipulator"):
        robot = get_robot(name)
        centre, radius = chain_reach_bound(robot)
        pos = robot.fk(robot.random_q(np.random.default_rng(0), 5000))[:, :3, 3]
        dist = np.linalg.norm(pos - centre, axis=1)
        assert dist.max() <= radius
        assert dist.max() > 0.6 * radius  # a bound, but not a vacuous one


def test_reach_map(get_robot, tmp_path):
    robot = get_robot("yumi_left")
    rmap = reach_map(robot, resolution=0.2, n_orientations=4, max_starts=8, seed=1)
    assert rmap.index.shape == (rmap.x.size, rmap.y.size, rmap.z.size)
    np.testing.assert_array_equal(rmap.index, rmap.hits.mean(axis=-1))
    assert np.all(rmap.index[~rmap.solved] == 0)
    assert 0 < (rmap.index > 0).sum() < rmap.solved.sum()
    # a voxel counted reachable in some orientation is reached by the single-pose solver too
    i = np.argwhere(rmap.hits)[0]
    target = np.eye(4)
    target[:3, :3] = rmap.orientations[i[3]]
    target[:3, 3] = rmap.centres[tuple(i[:3])]
    assert swarm_ik.solve(swarm_ik.IKProblem(robot, target), "swarm").success
    # save / load round trip
    back = ReachMap.load(rmap.save(tmp_path / "m.npz"))
    np.testing.assert_array_equal(back.index, rmap.index)
    np.testing.assert_array_equal(back.hits, rmap.hits)
    assert back.robot == rmap.robot and back.n_orientations == 4
    with pytest.raises(InvalidArgumentError, match="coarser resolution"):
        reach_map(robot, resolution=0.01, max_targets=1000)
    with pytest.raises(InvalidArgumentError, match="lower corner"):
        reach_map(robot, bounds=[0, 0, 0, 1, -1, 1])


def test_cli_reach(tmp_path, capsys):
    out = tmp_path / "yumi.npz"
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        code = main(
            [
                "reach",
                "--robot",
                "yumi_left",
                "--resolution",
                "0.25",
                "--orientations",
                "2",
                "--max-starts",
                "4",
                "--out",
                str(out),
                "--scheduler",
                "none",
            ]
        )
    assert code == 0
    assert "reachable voxels" in capsys.readouterr().out
    rmap = ReachMap.load(out)
    assert rmap.n_orientations == 2 and rmap.resolution == 0.25
    assert out.with_suffix(".png").stat().st_size > 10_000
    try:
        import meshcat  # noqa: F401
    except ImportError:  # pragma: no cover
        return
    assert out.with_suffix(".html").is_file()


@pytest.mark.parametrize("position_only", [False, True])
def test_nearest_table_poses_match_a_sort_of_every_distance(position_only: bool) -> None:
    """The restart table's nearest poses: for each target the k poses of least
    ``‖p − p*‖² + L²(3 − tr(RᵀR*))`` (position alone when position-only), nearest first,
    as a full stable sort of the distances orders them; fewer poses than k give them all."""
    from swarm_ik import batch

    robot = swarm_ik.load_robot("ur5")
    rng = np.random.default_rng(7)
    table, targets = robot.fk(robot.random_q(rng, 200)), robot.fk(robot.random_q(rng, 50))
    settings = batch.BatchSettings(position_only=position_only)
    d = ((table[None, :, :3, 3] - targets[:, None, :3, 3]) ** 2).sum(-1)
    if not position_only:
        tr = np.einsum("cab,iab->ic", table[:, :3, :3], targets[:, :3, :3])
        d = d + batch.POSE_LENGTH**2 * (3.0 - tr)
    ref = np.argsort(d, axis=1, kind="stable")
    for k in (1, 8, 200, 300):
        got = batch._nearest_poses(table, targets, k, settings)
        np.testing.assert_array_equal(got, ref[:, : min(k, 200)])
    assert batch._nearest_poses(table[:0], targets, 8, settings).shape == (50, 0)


def test_targets_separated_by_white_space_are_read_as_np_savetxt_writes_them(tmp_path) -> None:
    """``np.savetxt``'s default (spaces, a '#' header) was refused as a bad header."""
    rows = np.array([[0.4, 0.0, 0.3, 0.0, 0.0, 0.0, 1.0], [0.4, 0.1, 0.3, 1.0, 0.0, 0.0, 0.0]])
    path = tmp_path / "t.csv"
    np.savetxt(path, rows, header="x y z qx qy qz qw")
    spaced = read_targets(path)
    np.savetxt(path, rows, delimiter=",")
    np.testing.assert_array_equal(spaced, read_targets(path))
    assert spaced.shape == (2, 4, 4)
