"""Sphere approximation: coverage of the collision geometry, obstacle SDFs, the compiled
penetration residual and its Jacobian (finite differences on Pinocchio kinematics)."""

from __future__ import annotations

import coal
import numpy as np
import pinocchio as pin
import pytest
from conftest import scene_near_robot

from swarm_ik import spheres as S
from swarm_ik.collision import RobotCollision
from swarm_ik.kernels import spheres as K
from swarm_ik.scene import Mesh

_SM: dict[str, S.SphereModel] = {}


def model(get_robot, name: str) -> S.SphereModel:
    if name not in _SM:
        rc = RobotCollision.from_robot(get_robot(name))
        _SM[name] = S.SphereModel.from_collision(rc, scene_near_robot())
    return _SM[name]


# ----------------------------------------------------------------- surface sampling
def _on_triangles(v, f, n, rng):
    tri = v[f]
    area = np.linalg.norm(np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]), axis=1)
    k = rng.choice(len(tri), n, p=area / area.sum())
    u = rng.random((n, 2))
    flip = u.sum(axis=1) > 1.0
    u[flip] = 1.0 - u[flip]
    t = tri[k]
    return t[:, 0] + u[:, :1] * (t[:, 1] - t[:, 0]) + u[:, 1:] * (t[:, 2] - t[:, 0])


def _unit(rng, n):
    v = rng.normal(size=(n, 3))
    return v / np.linalg.norm(v, axis=1, keepdims=True)


def surface_points(geo, n: int, rng) -> np.ndarray:
    """Random points on the true surface of a coal geometry (body frame)."""
    if isinstance(geo, coal.BVHModelBase):
        v, f = S.mesh_arrays(geo)
        return np.vstack([v, _on_triangles(v, f, n, rng)])
    if isinstance(geo, coal.Sphere):
        return geo.radius * _unit(rng, n)
    if isinstance(geo, coal.Box):
        h = np.asarray(geo.halfSide)
        p = rng.uniform(-h, h, size=(n, 3))
        axis = rng.integers(0, 3, n)
        p[np.arange(n), axis] = np.where(rng.random(n) < 0.5, -1.0, 1.0) * h[axis]
        return p
    r, hl = geo.radius, geo.halfLength
    a = rng.uniform(0.0, 2.0 * np.pi, n)
    side = np.column_stack([r * np.cos(a), r * np.sin(a), rng.uniform(-hl, hl, n)])
    if isinstance(geo, coal.Capsule):
        u = _unit(rng, n)
        caps = r * u + np.outer(np.sign(u[:, 2]), [0.0, 0.0, hl])
        return np.vstack([side, caps])
    rad = r * np.sqrt(rng.random(n))
    disc = np.column_stack(
        [rad * np.cos(a), rad * np.sin(a), np.where(rng.random(n) < 0.5, -hl, hl)]
    )
    rim = np.column_stack([r * np.cos(a), r * np.sin(a), np.full(n, hl)])
    return np.vstack([side, disc, rim])


def _excess(points, centres, radii) -> np.ndarray:
    """How far each point lies outside every sphere [m] (<= 0: covered)."""
    d = np.linalg.norm(points[:, None, :] - centres[None, :, :], axis=2) - radii[None, :]
    return d.min(axis=1)


@pytest.mark.parametrize("name", ["panda", "ur5"])
def test_spheres_cover_every_collision_body(get_robot, name) -> None:
    sm = model(get_robot, name)
    rng = np.random.default_rng(0)
    for b, g in enumerate(sm.collision.geom_model.geometryObjects):
        sl = slice(sm.arrays.body_start[b], sm.arrays.body_start[b + 1])
        pts = surface_points(g.geometry, 4000, rng)
        assert _excess(pts, sm.arrays.sph_local[sl], sm.arrays.sph_radius[sl]).max() <= 1e-9, g.name
        # and not absurdly inflated: within the body's bounding box grown by 2.5 tolerances
        lo, hi = pts.min(axis=0), pts.max(axis=0)
        ext_lo = (sm.arrays.sph_local[sl] - sm.arrays.sph_radius[sl, None]).min(axis=0)
        ext_hi = (sm.arrays.sph_local[sl] + sm.arrays.sph_radius[sl, None]).max(axis=0)
        assert np.all(ext_lo >= lo - 2.5 * sm.tolerance) and np.all(
            ext_hi <= hi + 2.5 * sm.tolerance
        )


@pytest.mark.parametrize(
    "geo",
    [
        coal.Box(0.3, 0.05, 0.02),
        coal.Cylinder(0.04, 0.3),
        coal.Cylinder(0.2, 0.02),
        coal.Capsule(0.03, 0.4),
        coal.Sphere(0.07),
    ],
    ids=["box", "cylinder", "disc", "capsule", "sphere"],
)
def test_primitives_are_covered(geo) -> None:
    c, r = S.fit_spheres(geo, 0.01)
    pts = surface_points(geo, 5000, np.random.default_rng(1))
    assert _excess(pts, c, r).max() <= 1e-9
    assert 1 <= len(r) < 1000  # a 2 cm thick disc of 0.4 m takes hundreds at 1 cm


def test_mesh_obstacle_is_covered(tmp_path) -> None:
    import trimesh

    path = tmp_path / "ring.stl"
    trimesh.creation.annulus(r_min=0.1, r_max=0.2, height=0.05).export(path)
    pose = np.eye(4)
    pose[:3, 3] = [0.5, 0.1, 0.3]
    mesh = Mesh(path, pose, scale=1.5)
    from swarm_ik.scene import coal_geometry

    geo = coal_geometry(mesh)
    c, r = S.fit_spheres(geo, 0.01)
    pts = surface_points(geo, 4000, np.random.default_rng(2))
    assert _excess(pts, c, r).max() <= 1e-9
    assert np.max(np.linalg.norm(pts[:, :2], axis=1)) == pytest.approx(0.3, rel=1e-3)


def test_a_fine_mesh_is_covered_within_the_inside_test_budget(monkeypatch) -> None:
    """A mesh of many triangles gets a coarser grid of interior candidates (a 327,680-triangle
    ball took 250 s in the inside test), and its cover stays complete and tight."""
    import trimesh

    ball = trimesh.creation.icosphere(subdivisions=4, radius=0.1)  # 5,120 triangles
    v, f = np.asarray(ball.vertices), np.asarray(ball.faces)
    full = S.fit_mesh(v, f, 0.02)
    monkeypatch.setattr(S, "WINDING_PAIRS", 5e4)  # (about 10 interior candidates)
    coarse = S.fit_mesh(v, f, 0.02)
    rng = np.random.default_rng(3)
    pts = np.vstack([v, _on_triangles(v, f, 4000, rng)])
    for c, r in (full, coarse):
        assert _excess(pts, c, r).max() <= 1e-9
        assert np.max(np.linalg.norm(c, axis=1) + r) <= 0.1 + 2.5 * 0.02


# ------------------------------------------------------------------------------ SDFs
@pytest.mark.parametrize("shape", scene_near_robot().obstacles, ids=lambda o: o.kind)
def test_obstacle_sdf_matches_coal(shape) -> None:
    """Signed distance of points to each primitive = coal's signed distance to a tiny
    sphere (plus its radius); the gradient is the finite difference of the SDF."""
    from swarm_ik.scene import coal_object

    obj = coal_object(shape)
    kinds = {"sphere": K.SPHERE, "box": K.BOX, "capsule": K.CAPSULE, "cylinder": K.CYLINDER}
    pose = np.array(shape.pose)
    if shape.kind == "sphere":
        dims = np.array([shape.radius, 0.0, 0.0])
    elif shape.kind == "box":
        dims = 0.5 * np.array(shape.size)
    else:
        dims = np.array([shape.radius, 0.5 * shape.length, 0.0])
    rng = np.random.default_rng(4)
    probe = coal.Sphere(1e-4)
    lo, hi = pose[:3, 3] - 0.8, pose[:3, 3] + 0.8
    inside = 0
    for p in np.vstack([rng.uniform(lo, hi, (150, 3)), pose[:3, 3] + rng.normal(0, 0.03, (50, 3))]):
        d, gx, gy, gz = K.obstacle_sdf(kinds[shape.kind], pose[:3, :3], pose[:3, 3], dims, p)
        req = coal.DistanceRequest()
        req.enable_signed_distance = True
        ref = (
            coal.distance(
                obj.collisionGeometry(),
                obj.getTransform(),
                probe,
                coal.Transform3s(np.eye(3), p),
                req,
                coal.DistanceResult(),
            )
            + 1e-4
        )
        assert d == pytest.approx(ref, abs=2e-6)
        inside += d < 0
        h = 1e-7
        fd = [
            (
                K.obstacle_sdf(kinds[shape.kind], pose[:3, :3], pose[:3, 3], dims, p + h * e)[0]
                - K.obstacle_sdf(kinds[shape.kind], pose[:3, :3], pose[:3, 3], dims, p - h * e)[0]
            )
            / (2 * h)
            for e in np.eye(3)
        ]
        np.testing.assert_allclose([gx, gy, gz], fd, atol=1e-5)
    assert inside > 5


# ----------------------------------------------------------------- kinematics, residual
@pytest.mark.parametrize("name", ["panda", "ur5"])
def test_body_kinematics_match_pinocchio(get_robot, name) -> None:
    sm = model(get_robot, name)
    robot = sm.collision.robot
    rng = np.random.default_rng(1)
    gm = sm.collision.geom_model
    for q in robot.random_q(rng, 5):
        rot, pos, jac = sm.body_kinematics(q)
        data, gd = robot.model.createData(), pin.GeometryData(gm)
        pin.forwardKinematics(robot.model, data, robot.to_pinocchio(q))
        pin.updateGeometryPlacements(robot.model, data, gm, gd)
        for b in range(sm.nb):
            np.testing.assert_allclose(rot[b], gd.oMg[b].rotation, atol=1e-12)
            np.testing.assert_allclose(pos[b], gd.oMg[b].translation, atol=1e-12)
        h = 1e-6
        for k in range(robot.nq):
            e = np.zeros(robot.nq)
            e[k] = h
            rp, pp, _ = sm.body_kinematics(q + e)
            rm, pm, _ = sm.body_kinematics(q - e)
            np.testing.assert_allclose((pp - pm) / (2 * h), jac[:, :3, k], atol=1e-7)
            for b in range(sm.nb):
                w = pin.log3(rp[b] @ rm[b].T) / (2 * h)
                np.testing.assert_allclose(w, jac[b, 3:, k], atol=1e-7)


@pytest.mark.parametrize("name", ["panda", "ur5"])
def test_penetration_jacobian_by_finite_differences(get_robot, name) -> None:
    sm = model(get_robot, name)
    robot = sm.collision.robot
    rng = np.random.default_rng(2)
    h, compared, obstacle_rows = 1e-6, 0, 0
    for q in robot.random_q(rng, 12):
        res, jac, pairs = sm.evaluate(q, margin=0.05, max_rows=512)
        assert np.all(res > 0) and np.all(np.diff(res) <= 0)
        keys = [tuple(p) for p in pairs]
        obstacle_rows += sum(p[1] < 0 for p in keys)
        for k in range(robot.nq):
            e = np.zeros(robot.nq)
            e[k] = h
            rp, _, pp = sm.evaluate(q + e, margin=0.05, max_rows=512)
            rm, _, pm = sm.evaluate(q - e, margin=0.05, max_rows=512)
            plus = dict(zip(map(tuple, pp), rp, strict=True))
            minus = dict(zip(map(tuple, pm), rm, strict=True))
            for row, key in enumerate(keys):
                if key in plus and key in minus:
                    fd = (plus[key] - minus[key]) / (2 * h)
                    assert jac[row, k] == pytest.approx(fd, abs=1e-6), (key, k)
                    compared += 1
    assert compared > 200 and obstacle_rows > 5


def test_max_rows_keeps_the_largest(get_robot) -> None:
    sm = model(get_robot, "panda")
    robot = sm.collision.robot
    rng = np.random.default_rng(6)
    checked = 0
    for q in robot.random_q(rng, 30):
        res, jac, pairs = sm.evaluate(q, margin=0.08, max_rows=512)
        if len(res) <= 4:
            continue
        r4, j4, p4 = sm.evaluate(q, margin=0.08, max_rows=4)
        np.testing.assert_allclose(r4, res[:4])
        full = {tuple(p): j for p, j in zip(pairs, jac, strict=True)}
        for p, j in zip(p4, j4, strict=True):
            np.testing.assert_allclose(j, full[tuple(p)])
        total, worst = sm.cost(q, margin=0.08)
        assert total == pytest.approx(float(np.sum(res**2))) and worst == pytest.approx(res[0])
        checked += 1
    assert checked > 5


@pytest.mark.parametrize("name", ["panda", "ur5"])
def test_sphere_free_implies_exact_free(get_robot, name) -> None:
    """Conservative: wherever the spheres are clear (cost 0) coal finds no contact."""
    sm = model(get_robot, name)
    rc, robot, scene = sm.collision, sm.collision.robot, scene_near_robot()
    rng = np.random.default_rng(8)
    clear = 0
    for q in robot.random_q(rng, 150):
        for margin in (0.0, 0.02):
            if sm.cost(q, margin)[0] == 0.0:
                clear += 1
                coarse = {tuple(sorted(p)) for p in sm.coarse_pairs}
                free_pairs = set(rc.self_link_pairs) - coarse
                rep = rc.check(q, scene, margin=margin)
                contact = {
                    p for p in rep.pairs_in_contact if p in free_pairs or p[1] in scene.names
                }
                assert not contact, (q, contact)
    assert clear > 20


def test_ur5_ee_link_box_is_a_coarse_pair(get_robot) -> None:
    sm = model(get_robot, "ur5")
    assert {frozenset(p) for p in sm.coarse_pairs} == {frozenset(("ee_link", "wrist_2_link"))}
    assert model(get_robot, "panda").coarse_pairs == ()


def test_triangle_owners_is_the_least_growth_sphere_of_each_triangle() -> None:
    """The compiled owner of each triangle against the brute-force numpy argmin over every
    sphere of ``max_v |v − c| − nominal_c`` (the first on ties, as ``np.argmin``)."""
    from swarm_ik.kernels.mesh import triangle_owners

    rng = np.random.default_rng(7)
    tri = rng.uniform(-1.0, 1.0, (400, 3, 3))
    centres = rng.uniform(-1.0, 1.0, (60, 3))
    nominal = rng.uniform(0.0, 0.5, 60)
    nominal[7] = nominal[3]
    centres[7] = centres[3]  # a tie: the first sphere keeps the triangle
    owner = np.empty(len(tri), dtype=np.int64)
    need = np.empty(len(tri))
    triangle_owners(tri, centres, nominal, owner, need)
    d = np.sqrt(((tri[:, None, :, :] - centres[None, :, None, :]) ** 2).sum(axis=-1)).max(axis=2)
    want = np.argmin(d - nominal[None, :], axis=1)
    np.testing.assert_array_equal(owner, want)
    np.testing.assert_array_equal(need, d[np.arange(len(tri)), want])
    assert 7 not in owner
