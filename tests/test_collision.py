"""Robot collision geometry, self-collision pairs (SRDF, adjacency, sampling) and the exact
check against coal called directly."""

from __future__ import annotations

from itertools import combinations

import coal
import numpy as np
import pinocchio as pin
import pytest
from conftest import robot, scene_near_robot

from swarm_ik.collision import RobotCollision, find_srdf, parse_srdf
from swarm_ik.errors import InvalidArgumentError, RobotFileNotFoundError
from swarm_ik.scene import Scene, Sphere

_RC: dict[str, RobotCollision] = {}


def collision(get_robot, name: str) -> RobotCollision:
    if name not in _RC:
        _RC[name] = RobotCollision.from_robot(get_robot(name))
    return _RC[name]


def _key(a: str, b: str) -> tuple[str, str]:
    return (a, b) if a <= b else (b, a)


def test_srdf_found_for_example_robot_data(get_robot) -> None:
    for name, srdf in [("panda", "panda.srdf"), ("ur5", "ur5.srdf"), ("baxter_left", None)]:
        found = find_srdf(get_robot(name).urdf_path)
        if srdf is None:
            assert found is not None and found.name == "baxter_manipulation.srdf"
        else:
            assert found is not None and found.name == srdf


def test_panda_pairs_are_all_minus_adjacent_rigid_and_srdf(get_robot) -> None:
    rc = collision(get_robot, "panda")
    assert rc.pair_rule == "srdf" and rc.srdf_path is not None
    links = sorted(set(rc.body_links))
    srdf = {_key(a, b) for a, b, _ in parse_srdf(rc.srdf_path)}
    adjacent = {_key(f"panda_link{i}", f"panda_link{i + 1}") for i in range(7)}
    adjacent |= {("panda_hand", "panda_link7"), ("panda_hand", "panda_leftfinger")}
    adjacent |= {("panda_hand", "panda_rightfinger")}
    assert set(rc.disabled["adjacent"]) == adjacent
    # fingers are locked: they ride on joint 7 with link 7 and the hand
    assert ("panda_leftfinger", "panda_rightfinger") in rc.disabled["rigid"]
    expected = {
        _key(a, b)
        for a, b in combinations(links, 2)
        if _key(a, b) not in srdf | adjacent | set(rc.disabled["rigid"])
    }
    assert set(rc.self_link_pairs) == expected
    assert ("panda_link1", "panda_link7") in expected  # a pair the SRDF keeps
    assert not srdf & set(rc.self_link_pairs)
    for i, j in rc.self_pairs:  # geometry pairs follow the link pairs
        assert _key(rc.body_links[i], rc.body_links[j]) in expected


def test_bad_srdf_path(get_robot, tmp_path) -> None:
    with pytest.raises(RobotFileNotFoundError, match="nope.srdf"):
        RobotCollision.from_robot(get_robot("ur5"), srdf=tmp_path / "nope.srdf")


def _world_tf(rc: RobotCollision, data, k: int):
    g = rc.geom_model.geometryObjects[k]
    m = data.oMi[g.parentJoint] * g.placement
    return coal.Transform3s(np.array(m.rotation), np.array(m.translation))


def _reference(rc: RobotCollision, q, scene: Scene, margin: float):
    """Contact pairs and smallest distance from coal.collide / coal.distance, pair by pair
    (the bodies no joint moves against no obstacle: their contacts do not depend on q)."""
    robot = rc.robot
    data = robot.model.createData()
    pin.forwardKinematics(robot.model, data, robot.to_pinocchio(q))
    tfs = [_world_tf(rc, data, k) for k in range(rc.nb)]
    geoms = [g.geometry for g in rc.geom_model.geometryObjects]
    pairs = [
        (geoms[i], tfs[i], geoms[j], tfs[j], _key(rc.body_links[i], rc.body_links[j]))
        for i, j in rc.self_pairs
    ]
    for name, obj in scene.coal_objects():
        for k in range(rc.nb):
            if rc.geom_model.geometryObjects[k].parentJoint == 0:
                continue
            pairs.append(
                (
                    geoms[k],
                    tfs[k],
                    obj.collisionGeometry(),
                    obj.getTransform(),
                    (rc.body_links[k], name),
                )
            )
    contact, best = set(), np.inf
    for g1, t1, g2, t2, label in pairs:
        req = coal.CollisionRequest()
        req.security_margin = margin
        res = coal.CollisionResult()
        hit = coal.collide(g1, t1, g2, t2, req, res) > 0
        d = coal.distance(g1, t1, g2, t2, coal.DistanceRequest(), coal.DistanceResult())
        if hit or d < margin:
            contact.add(label)
        best = min(best, d)
    return contact, best


@pytest.mark.parametrize("name", ["panda", "ur5"])
def test_exact_check_equals_coal(get_robot, name) -> None:
    rc = collision(get_robot, name)
    scene = scene_near_robot()
    rng = np.random.default_rng(3)
    free = hit = 0
    for q in rc.robot.random_q(rng, 25):
        for margin in (0.0, 0.03):
            rep = rc.check(q, scene, margin=margin)
            contact, best = _reference(rc, q, scene, margin)
            assert set(rep.pairs_in_contact) == contact
            assert rep.collision_free == (not contact)
            assert rc.collides(q, scene, margin) == (not rep.collision_free)
            if rep.collision_free:
                assert rep.clearance == pytest.approx(best, abs=1e-9)
                assert rep.clearance >= margin
                free += 1
            else:
                assert rep.clearance <= max(margin, 0.0)
                hit += 1
    assert free > 5 and hit > 5  # both outcomes were exercised


def test_self_collision_off_and_empty_scene(get_robot) -> None:
    rc = collision(get_robot, "panda")
    rng = np.random.default_rng(5)
    for q in rc.robot.random_q(rng, 10):
        rep = rc.check(q, Scene(), self_collision=False)
        assert rep.collision_free and rep.clearance == np.inf
    with pytest.raises(InvalidArgumentError, match="margin"):
        rc.check(rc.robot.mid_q(), margin=-0.1)


def test_sampled_rule_without_srdf(get_robot, tmp_path, monkeypatch) -> None:
    """No SRDF: pairs colliding in none (or >= 95 %) of the seeded samples are disabled; the
    classification is recomputed here with coal pair by pair."""
    monkeypatch.setenv("SWARM_IK_CACHE_DIR", str(tmp_path))
    robot = get_robot("ur5")
    n = 150
    rc = RobotCollision.from_robot(robot, srdf=False, samples=n, seed=7)
    assert rc.pair_rule == "sampled" and rc.srdf_path is None
    assert len(list(tmp_path.glob("pairs-*.json"))) == 1
    links = sorted(set(rc.body_links))
    off = set().union(*(set(rc.disabled[k]) for k in ("adjacent", "rigid")))
    candidates = [_key(a, b) for a, b in combinations(links, 2) if _key(a, b) not in off]
    counts = dict.fromkeys(candidates, 0)
    data = robot.model.createData()
    geoms = [g.geometry for g in rc.geom_model.geometryObjects]
    for q in robot.random_q(np.random.default_rng(7), n):
        pin.forwardKinematics(robot.model, data, robot.to_pinocchio(q))
        tfs = [_world_tf(rc, data, k) for k in range(rc.nb)]
        hit = set()
        for i, j in combinations(range(rc.nb), 2):
            key = _key(rc.body_links[i], rc.body_links[j])
            if key in counts and coal.collide(
                geoms[i], tfs[i], geoms[j], tfs[j], coal.CollisionRequest(), coal.CollisionResult()
            ):
                hit.add(key)
        for key in hit:
            counts[key] += 1
    never = {k for k, c in counts.items() if c == 0}
    always = {k for k, c in counts.items() if c >= 0.95 * n}
    assert set(rc.disabled["never"]) == never and set(rc.disabled["always"]) == always
    assert set(rc.self_link_pairs) == set(candidates) - never - always
    assert never and set(rc.self_link_pairs)  # the rule did something, and left pairs
    again = RobotCollision.from_robot(robot, srdf=False, samples=n, seed=7)  # from the cache
    assert again.self_pairs == rc.self_pairs


@pytest.mark.parametrize("margin", [-1.0, float("nan"), float("inf"), "abc", True, None])
def test_bad_margins_are_refused_by_every_check(margin: object) -> None:
    """check, collides and collides_many refuse a margin that is not a finite number >= 0
    with one message (collides let coal fail deep inside Pinocchio on -1 and passed NaN)."""
    r = robot("panda")
    rc = r.collision_model()
    q = r.mid_q()
    scene = Scene([Sphere(0.05, tuple(r.fk(q)[:3, 3] + [0.0, 0.0, 0.3]))])
    for call in (
        lambda: rc.check(q, scene, margin=margin),  # type: ignore[arg-type]
        lambda: rc.collides(q, scene, margin=margin),  # type: ignore[arg-type]
        lambda: rc.collides_many([q], scene, margin=margin),  # type: ignore[arg-type]
    ):
        with pytest.raises(InvalidArgumentError, match="margin must be a finite number >= 0"):
            call()


@pytest.mark.parametrize("shape", ["sphere", "box"])
def test_an_obstacle_wholly_inside_a_link_mesh_is_in_contact(shape: str) -> None:
    """coal's meshes are surfaces: a 2 cm ball or a 4 cm cube at the middle of Panda's
    link 5 touched none of its triangles and was called collision-free (clearance > 0), so a
    solve among it reported success; the winding number of the closed mesh now finds it
    inside, in the fast test, the report, and the solve's verdict."""
    import pinocchio as pin

    import swarm_ik
    from swarm_ik.goals import AvoidCollisions
    from swarm_ik.scene import Box, Scene, Sphere

    robot = swarm_ik.load_robot("panda")
    rc = robot.collision_model()
    q = robot.mid_q()
    data, gd = robot.model.createData(), pin.GeometryData(rc.geom_model)
    pin.forwardKinematics(robot.model, data, robot.to_pinocchio(q))
    pin.updateGeometryPlacements(robot.model, data, rc.geom_model, gd)
    k = [g.name for g in rc.geom_model.geometryObjects].index("panda_link5_0")
    verts = np.array(rc.geom_model.geometryObjects[k].geometry.vertices())
    centre = gd.oMg[k].act(0.5 * (verts.min(axis=0) + verts.max(axis=0)))
    obstacle = Sphere(0.01, list(centre)) if shape == "sphere" else Box([0.03] * 3, list(centre))
    scene = Scene([obstacle])
    report = rc.check(q, scene)
    assert not report.collision_free and report.clearance < 0
    assert rc.collides(q, scene)
    away = Scene([Sphere(0.01, list(centre + [0.0, 0.0, 2.0]))])
    assert rc.check(q, away).collision_free and not rc.collides(q, away)
    res = swarm_ik.solve(
        swarm_ik.IKProblem(robot, robot.fk(q), goals=[AvoidCollisions(scene)]),
        q0=q, seed=0, max_evals=5000,
    )  # fmt: skip
    assert not res.success or rc.check(res.q, scene).collision_free
    assert not np.allclose(res.q, q)  # (the start, inside the obstacle, is not the answer)


def test_a_body_fixed_to_the_world_touching_an_obstacle_is_named_once_and_left_out() -> None:
    """cuRobo's own table (its top at z = 0) touches the Panda's base mesh (3e-5 m below
    z = 0) whatever the joints: one warning names the pair, the check leaves it out (every
    solve failed "local_minima" on it), and a link the joints move still touches the table."""
    import warnings

    import swarm_ik
    from swarm_ik.goals import AvoidCollisions
    from swarm_ik.scene import Box

    r = swarm_ik.load_robot("panda")
    rc = r.collision_model()
    table = Scene([Box((5.0, 5.0, 0.2), (0.0, 0.0, -0.1), name="table")])
    with pytest.warns(UserWarning, match="panda_link0–table: fixed to the world"):
        rep = rc.check(r.mid_q(), table)
    assert rep.collision_free and "panda_link0" not in str(rep.closest_pair)
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # (once per scene: not again)
        q_low = r.mid_q().copy()
        q_low[1], q_low[3] = 1.7, -0.1  # (the arm reached down through the table top)
        assert rc.collides(q_low, table)
    q_true = np.array([0.3, -0.4, 0.1, -2.0, 0.1, 1.8, 0.7])
    prob = swarm_ik.IKProblem(r, r.fk(q_true), goals=[AvoidCollisions(table)])
    res = swarm_ik.solve(prob, seed=0)
    assert res.success and not rc.collides(res.q, table)
