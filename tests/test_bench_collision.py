"""``swarm-ik bench collision``: its scenes, targets, judging, solvers and report."""

from __future__ import annotations

import argparse
import json

import numpy as np
import pytest
from conftest import robot

import swarm_ik
from swarm_ik import goals as G
from swarm_ik.bench import collision as C
from swarm_ik.bench import common
from swarm_ik.scene import Scene, Sphere


def _inside_obstacle(scene: Scene, p: np.ndarray) -> str | None:
    return G.AvoidCollisions(scene).obstacle_containing(p)


def test_scenes_are_seeded_and_shaped_as_described() -> None:
    for name in C.SCENES:
        assert C.make_scene(name, 3).scene == C.make_scene(name, 3).scene
        assert C.make_scene(name, 3).scene != C.make_scene(name, 4).scene
    table = C.make_scene("table", 0).scene
    assert [o.kind for o in table].count("box") == 4 and [o.kind for o in table].count(
        "sphere"
    ) == 3
    for o in table:  # everything rests on the table top (z = 0) or is the top itself
        if o.kind == "sphere":
            assert o.center[2] == pytest.approx(o.radius)
        elif o.name != "table":
            assert np.array(o.pose)[2, 3] == pytest.approx(o.size[2] / 2)
    cubby = C.make_scene("cubby", 0)
    assert len(cubby.scene) == 5 and cubby.inside is not None
    lo, hi = cubby.inside
    mid = 0.5 * (lo + hi)
    assert _inside_obstacle(cubby.scene, mid) is None  # hollow
    # closed on five sides: just beyond each inner face lies a wall, except towards the robot
    for axis, side, wall in ((2, lo, "floor"), (2, hi, "ceiling"), (0, hi, "back"),
                             (1, hi, "wall_left"), (1, lo, "wall_right")):  # fmt: skip
        p = mid.copy()
        p[axis] = side[axis] + (0.01 if side is hi else -0.01)
        assert _inside_obstacle(cubby.scene, p) == wall
    p = mid.copy()
    p[0] = lo[0] - 0.01
    assert _inside_obstacle(cubby.scene, p) is None  # open towards -x (the robot)
    with pytest.raises(swarm_ik.SwarmIKError, match="valid: table, shelf, cubby"):
        C.make_scene("kitchen", 0)


def test_clutter_scenes_are_seeded_nested_and_leave_the_base_free() -> None:
    scenes = {k: C.make_scene(f"clutter{k}", 0).scene for k in C.CLUTTER_COUNTS}
    for k, sc in scenes.items():
        assert len(sc) == k and all(o.kind == "box" for o in sc)
        assert sc == C.make_scene(f"clutter{k}", 0).scene != C.make_scene(f"clutter{k}", 1).scene
    assert list(scenes[60])[:20] == list(scenes[20])  # nested: more boxes only add obstacles
    for o in scenes[60]:
        c = np.array(o.pose)[:3, 3]
        half = 0.5 * float(np.linalg.norm(o.size))
        assert np.hypot(c[0], c[1]) - half >= C.CLUTTER_BASE_CLEAR  # the base column is free
    narrow = C.make_scene("shelf-narrow", 0)
    assert narrow.inside is not None and len(narrow.scene) == 8
    gaps = np.diff(sorted(np.array(o.pose)[2, 3] for o in narrow.scene if "board" in o.name))
    assert np.all((gaps >= 0.18) & (gaps <= 0.22))  # narrower than the shelf's 0.28-0.34 m


@pytest.mark.parametrize("scene", ["shelf", "cubby", "shelf-narrow", "clutter60"])
def test_targets_are_collision_free_fk_of_in_limit_q(scene: str) -> None:
    r = robot("ur5")
    bs = C.make_scene(scene, 0)
    q, targets = C.collision_free_targets(r, bs, 6, np.random.default_rng(0))
    rc = r.collision_model()
    for qi, t in zip(q, targets, strict=True):
        assert r.within_limits(qi)
        np.testing.assert_allclose(r.fk_pinocchio(qi), t, atol=1e-12)
        assert rc.check(qi, bs.scene).collision_free
        if bs.inside is not None:
            assert np.all(t[:3, 3] > bs.inside[0]) and np.all(t[:3, 3] < bs.inside[1])


def test_judge_flags_pose_errors_and_contacts() -> None:
    r = robot("ur5")
    rng = np.random.default_rng(1)
    rc = r.collision_model()
    q = next(qi for qi in r.random_q(rng, 50) if not rc.collides(qi))
    t = r.fk(q)
    empty = Scene([])
    assert C.judge(r, empty, t, q)["success"]
    off = t.copy()
    off[0, 3] += 1e-4
    v = C.judge(r, empty, off, q)
    assert not v["success"] and not v["pose_ok"] and v["collision_free"]
    on_tool = Scene([Sphere(0.05, t[:3, 3])])
    v = C.judge(r, on_tool, t, q)
    assert not v["success"] and v["pose_ok"] and not v["collision_free"]
    assert v["clearance"] <= 0.0
    assert not C.judge(r, empty, t, None)["success"]


def test_no_solver_reports_a_colliding_success() -> None:
    r = robot("ur5")
    bs = C.make_scene("cubby", 0)
    rows, missing = C.run_scene(r, bs, 4, 0.02, 0, ("ours+goal", "ours-reject"))
    assert not missing and len(rows) == 8
    for row in rows:
        assert row["claimed_colliding"] == 0
        if row["success"]:
            assert row["pose_ok"] and row["collision_free"] and row["within_limits"]
    # every row's verdict is the benchmark's own: a success passes the exact check again
    assert {row["solver"] for row in rows} == {"ours+goal", "ours-reject"}


def test_rejection_loop_rejects_colliding_answers() -> None:
    """A scene where the plain answer from the middle of the ranges collides: the loop must
    reject it (or never find a free one) and never return it as a success."""
    r = robot("ur5")
    rng = np.random.default_rng(2)
    q = r.random_q(rng)
    t = r.fk(q)
    from swarm_ik.bench import peers

    plain = peers.make("swarm", r, 0.02, C.TOL)
    a = plain.solve(t, r.mid_q(), 0)
    assert a.claimed
    _rot, pos = r.collision_model().body_placements(a.q)
    scenes = [Scene([Sphere(0.03, 0.5 * (pos[k] + pos[k + 1]))]) for k in range(1, len(pos) - 1)]
    scene = next(s for s in scenes if r.collision_model().collides(a.q, s))  # on the arm
    solvers, _ = C.make_solvers(r, scene, 0.01, ["ours-reject"])
    out = solvers[0].solve(t, np.random.default_rng(0))
    if out.claimed:
        assert not r.collision_model().collides(out.q, scene)
    assert out.attempts >= 1


def test_targets_inside_obstacles_are_reported_unreachable() -> None:
    r = robot("panda")  # (its tool frame lies in its own geometry: ur5's tool0 does not)
    rows = C.unreachable(r, C.make_scene("cubby", 0), 0.005, 0, per_obstacle=1)
    assert len(rows) == 5
    assert all(row["reason"] == "unreachable" and row["success"] == 0 for row in rows)


def test_report_judges_the_targets_from_the_csv_rows() -> None:
    def row(scene: str, solver: str, i: int, ok: bool, ms: float) -> dict[str, str]:
        base = dict.fromkeys(C.FIELDS, "0")
        base.update(robot="panda", scene=scene, solver=solver, target_id=str(i),
                    success=str(int(ok)), time_ms=str(ms), own_ms=str(ms / 2), attempts="1",
                    reason="")  # fmt: skip
        return base

    rows = [row("table", "ours+goal", i, i < 99, 1.0 if i < 99 else 20.0) for i in range(100)]
    rows += [row("cubby", "ours+goal", i, i < 90, 3.0) for i in range(100)]
    rows += [row("cubby", "ours-reject", i, 85 <= i < 95, 1.0) for i in range(100)]
    text = C.report(rows, [], [], [], {"n": 100, "budget_ms": 20, "seed": 0})
    assert "| panda | table | 99.0 (99) | 1.00 | 99.0 | met |" in text
    # cubby: 90 % alone, 95 % with the rejection loop's targets added
    assert (
        "| panda | cubby | 90.0 (97) | 3.00 | 95.0 | missed: success 7.0 points short, "
        "median 1.50x the target |" in text
    )


def test_cli_writes_csvs_and_a_summary_from_them(tmp_path) -> None:
    parser = argparse.ArgumentParser()
    C.add_arguments(parser)
    out = tmp_path / "bc"
    args = parser.parse_args(["--n", "2", "--robots", "ur5", "--scenes", "table",
                              "--solvers", "ours+goal,ours-reject", "--out", str(out)])  # fmt: skip
    assert C.run(args) == 0
    rows = common.read_csv(out / "collision.csv")
    assert len(rows) == 4 and {r["solver"] for r in rows} == {"ours+goal", "ours-reject"}
    assert len(common.read_csv(out / "batch.csv")) == 2
    assert json.loads((out / "run.json").read_text())["command"] == "collision"
    assert Scene.from_json(out / "scenes" / "table.json") == C.make_scene("table", 0).scene
    summary = (out / "summary.md").read_text()
    assert summary == C.write_report(out)  # the report is a function of the files
    assert "| ur5 | table | ours+goal | 2 |" in summary


@pytest.mark.parametrize(
    "argv,message",
    [(["--scenes", "kitchen"], "valid: table, shelf, cubby"),
     (["--solvers", "magic"], "valid: ours\\+goal")],
)  # fmt: skip
def test_bad_options_are_refused(argv: list[str], message: str, tmp_path) -> None:
    parser = argparse.ArgumentParser()
    C.add_arguments(parser)
    with pytest.raises(swarm_ik.SwarmIKError, match=message):
        C.run(parser.parse_args([*argv, "--out", str(tmp_path / "x")]))


@pytest.mark.parametrize(
    "argv,message",
    [(["--n", "0"], "argument --n: must be an integer from 1"),
     (["--budget-ms", "-1"], "argument --budget-ms: must be a finite number > 0"),
     (["--seed", "-1"], "argument --seed: a seed must be in")],
)  # fmt: skip
def test_bad_numbers_are_refused_when_parsed(
    argv: list[str], message: str, capsys: pytest.CaptureFixture[str]
) -> None:
    parser = argparse.ArgumentParser()
    C.add_arguments(parser)
    with pytest.raises(SystemExit) as info:
        parser.parse_args(argv)
    assert info.value.code == 2 and message in capsys.readouterr().err


def test_diagnosis_finds_the_generating_branch_collision_free() -> None:
    """Every target comes from a collision-free q, so some closed-form branch of the UR5 is
    collision-free by the exact check; the spheres (conservative) can only find fewer."""
    r = robot("ur5")
    rows = C.diagnose(r, C.make_scene("cubby", 0), 4, 0.01, 0, variants=((0.02, 1.0),))
    got = {row["metric"]: row["value"] for row in rows}
    assert set(got) == {"exact_free_branch", "q_true_sphere_contact", "sphere_free_branch",
                        "success"}  # fmt: skip
    assert got["exact_free_branch"] == 1.0
    assert 0.0 <= got["sphere_free_branch"] <= got["exact_free_branch"]
    assert all(0.0 <= v <= 1.0 for v in got.values())


def test_quick_clutter_run_with_the_ablation(tmp_path) -> None:
    """One clutter scene, a few targets, the main solvers and the ablation's variants: rows
    judged by the benchmark, the memory seeding after the first solved target, a summary
    section from the CSV."""
    parser = argparse.ArgumentParser()
    C.add_arguments(parser)
    out = tmp_path / "bc"
    argv = ["--n", "3", "--robots", "ur5", "--scenes", "clutter20", "--solvers", "ours+goal",
            "--ablation", "--out", str(out)]  # fmt: skip
    args = parser.parse_args(argv)
    assert C.run(args) == 0
    rows = common.read_csv(out / "ablation.csv")
    names = [v.name for v in C.ABLATION_VARIANTS]
    assert len(rows) == 3 * len(names) and {r["variant"] for r in rows} == set(names)
    scene = C.make_scene("clutter20", 0).scene
    assert Scene.from_json(out / "scenes" / "clutter20.json") == scene
    for r in rows:
        assert not (r["claimed"] == "1" and r["collision_free"] == "0")
        if r["variant"] in ("uniform", "default"):
            assert r["seeded"] == "0"
        if r["target_id"] == "0":
            assert r["seeded"] == "0"  # the memory starts empty
    solved_first = {r["variant"] for r in rows if r["target_id"] == "0" and r["claimed"] == "1"}
    for r in rows:
        if r["target_id"] == "1" and r["variant"] in solved_first and "memory" in r["variant"]:
            assert r["seeded"] == "1"
    assert json.loads((out / "run.json").read_text())["ablation_budget_ms"] == 50.0
    summary = (out / "summary.md").read_text()
    assert summary == C.write_report(out)
    assert "## Ablation of the default search" in summary
    assert "| ur5 | clutter20 | uniform | 3 |" in summary


def test_hard_scene_group_expands() -> None:
    assert C._names("hard", C.SCENES, "scenes", {"hard": C.HARD_SCENES}) == list(C.HARD_SCENES)
    assert C._names("table,hard,table", C.SCENES, "scenes", {"hard": C.HARD_SCENES})[0] == "table"
