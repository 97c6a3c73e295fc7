"""The bundled robots (robots/*.urdf) and their DH/chain -> URDF generator (robots/dh.py).

Every kinematic check goes through Pinocchio's own URDF parser, independently of
swarm_ik.robot, against the papers' equations written out literally in numpy here.
"""

from __future__ import annotations

import importlib.util
import math
import xml.etree.ElementTree as ET
from pathlib import Path
from types import ModuleType

import numpy as np
import pinocchio as pin
import pytest
from numpy.typing import NDArray
from scipy.optimize import least_squares
from swarm_ik.robots.dh import ChainStep, DHRow, chain_to_urdf, dh_fk, dh_to_urdf

from swarm_ik.errors import InvalidArgumentError

ROBOTS = Path(__file__).resolve().parents[1] / "robots"


def _load_generator() -> ModuleType:
    spec = importlib.util.spec_from_file_location("_robots_generate", ROBOTS / "generate.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


gen = _load_generator()


def _model(path_or_text: str | Path) -> pin.Model:
    if isinstance(path_or_text, Path):
        return pin.buildModelFromUrdf(str(path_or_text))
    return pin.buildModelFromXML(path_or_text)


def _frame_pose(model: pin.Model, frame: str, q: NDArray[np.float64]) -> NDArray[np.float64]:
    data = model.createData()
    pin.forwardKinematics(model, data, q)
    pin.updateFramePlacements(model, data)
    assert model.existFrame(frame), frame
    return np.asarray(data.oMf[model.getFrameId(frame)].homogeneous)


def _config(model: pin.Model, values: NDArray[np.float64]) -> NDArray[np.float64]:
    """Pinocchio configuration from one value per joint (continuous joints take cos, sin)."""
    q = pin.neutral(model)
    for joint, value in zip(model.joints[1:], values, strict=True):
        if joint.nq == 2:
            q[joint.idx_q : joint.idx_q + 2] = (math.cos(value), math.sin(value))
        else:
            q[joint.idx_q] = value
    return q


def _joint_kinds(path: Path) -> list[tuple[str, str]]:
    root = ET.parse(path).getroot()
    return [(j.get("name", ""), j.get("type", "")) for j in root.iter("joint")]


# --------------------------------------------------------------------------------------------
# YuMi left arm (HLFOA paper, Table 1)
# --------------------------------------------------------------------------------------------

YUMI = ROBOTS / "yumi_left.urdf"
# Table 1 of the HLFOA paper, copied independently of robots/generate.py: limits in degrees.
YUMI_LIMITS_DEG = [
    (-168.5, 168.5),
    (-143.5, 43.5),
    (-123.5, 80.0),
    (-290.0, 290.0),
    (-88.0, 138.0),
    (-229.0, 229.0),
    (-168.5, 168.5),
]
# Printed target of the Table 2 experiment (mm) and the q (deg) bounded least
# squares finds against it (robots/README.md).
YUMI_PRINTED_TARGET_MM = np.array(
    [
        [-0.53812, -0.17516, 0.82447, 21.84134],
        [0.77431, 0.28371, 0.56565, 72.69408],
        [-0.33299, 0.94278, -0.01704, 234.75475],
        [0.0, 0.0, 0.0, 1.0],
    ]
)
YUMI_LSQ_Q_DEG = np.array([-135.4, -99.5, 13.8, 97.9, -70.8, 188.3, 166.4])


def _hlfoa_fitness(pose_m: NDArray[np.float64], target_mm: NDArray[np.float64]) -> float:
    """Eq. 3 of the HLFOA paper: 1e-2 * L1 position error (mm) + L1 rotation-entry error."""
    dp = pose_m[:3, 3] * 1000.0 - target_mm[:3, 3]
    return float(1e-2 * np.abs(dp).sum() + np.abs(pose_m[:3, :3] - target_mm[:3, :3]).sum())


def test_yumi_urdf_fk_equals_dh_product() -> None:
    model = _model(YUMI)
    table = gen.yumi_left_dh()
    rng = np.random.default_rng(0)
    lo, hi = model.lowerPositionLimit, model.upperPositionLimit
    for k in range(60):
        # 50 within limits, 10 well outside them (FK does not care about limits).
        q = rng.uniform(lo, hi) if k < 50 else rng.uniform(-2 * np.pi, 2 * np.pi, 7)
        np.testing.assert_allclose(
            _frame_pose(model, "yumi_tool", q), dh_fk(table, q), rtol=0, atol=1e-12
        )


def test_yumi_table_joints_and_limits_match_paper() -> None:
    model = _model(YUMI)
    assert model.nq == model.nv == 7
    assert [n for n in model.names[1:]] == [f"yumi_joint_{j}" for j in range(1, 8)]
    assert [t for _, t in _joint_kinds(YUMI)] == ["revolute"] * 7 + ["fixed"]
    np.testing.assert_allclose(
        np.degrees(model.lowerPositionLimit), [lo for lo, _ in YUMI_LIMITS_DEG], atol=1e-12
    )
    np.testing.assert_allclose(
        np.degrees(model.upperPositionLimit), [up for _, up in YUMI_LIMITS_DEG], atol=1e-12
    )
    table = gen.yumi_left_dh()
    as_printed = [
        (r.d * 1e3, math.degrees(r.theta_offset), r.a * 1e3, math.degrees(r.alpha)) for r in table
    ]
    expected = [
        (166, 0, -30, -90),
        (0, 0, 30, 90),
        (251.5, 0, 40.5, -90),
        (0, -90, 40.5, -90),
        (265, 180, 27, -90),
        (0, 0, -27, 90),
        (36, 0, 0, 0),
    ]
    np.testing.assert_allclose(as_printed, expected, atol=1e-9)
    assert model.existFrame("yumi_base") and model.existFrame("yumi_tool")


def test_yumi_reproduces_paper_target_with_offset_inside_urdf() -> None:
    """The least-squares q (DH variable, offset excluded) lands on the paper's printed target."""
    model = _model(YUMI)
    q = np.radians(YUMI_LSQ_Q_DEG)
    assert np.all(q >= model.lowerPositionLimit) and np.all(q <= model.upperPositionLimit)
    pose = _frame_pose(model, "yumi_tool", q)
    # q is rounded to 0.1 deg, so sub-millimetre / 1e-3 agreement is all one can ask.
    assert np.abs(pose[:3, 3] * 1e3 - YUMI_PRINTED_TARGET_MM[:3, 3]).max() < 0.2
    assert np.abs(pose[:3, :3] - YUMI_PRINTED_TARGET_MM[:3, :3]).max() < 2e-3
    assert _hlfoa_fitness(pose, YUMI_PRINTED_TARGET_MM) < 1e-2

    # The other reading (joint value includes the offset) is far away: the convention matters.
    offsets = np.array([r.theta_offset for r in gen.yumi_left_dh()])
    assert _hlfoa_fitness(_frame_pose(model, "yumi_tool", q - offsets), YUMI_PRINTED_TARGET_MM) > 1

    # Polishing within the limits reaches the rounding floor of the printed matrix (~1.55e-5)
    # and no lower: the printed rotation is not orthonormal.
    def residual(x: NDArray[np.float64]) -> NDArray[np.float64]:
        p = _frame_pose(model, "yumi_tool", x)
        return np.concatenate(
            [1e-2 * (p[:3, 3] * 1e3 - YUMI_PRINTED_TARGET_MM[:3, 3]),
             (p[:3, :3] - YUMI_PRINTED_TARGET_MM[:3, :3]).ravel()]
        )  # fmt: skip

    sol = least_squares(
        residual, q, bounds=(model.lowerPositionLimit, model.upperPositionLimit), xtol=1e-14
    )
    best = _hlfoa_fitness(_frame_pose(model, "yumi_tool", sol.x), YUMI_PRINTED_TARGET_MM)
    assert 1.0e-5 < best < 2.0e-5


# --------------------------------------------------------------------------------------------
# Loading manipulator (MGWO paper, eqs. 1-8)
# --------------------------------------------------------------------------------------------

LM = ROBOTS / "loading_manipulator.urdf"
LM_LONG = ROBOTS / "loading_manipulator_long.urdf"
L1, L2, L3, L4 = 1.74, 2.5, 3.0, 2.0
X_STAR = np.array([np.pi / 4, np.pi / 6, np.pi / 4, 0.8, 1.0, 1.0, np.pi / 6, -np.pi / 4])


def paper_fk(x: NDArray[np.float64]) -> NDArray[np.float64]:
    """Eq. 9 of the MGWO paper: the product of eqs. 1-8, entries exactly as printed."""
    t1, t2, t3, d4, d5, d6, t7, t8 = x
    c, s = np.cos, np.sin
    T01 = np.array([[c(t1), -s(t1), 0, 0], [s(t1), c(t1), 0, 0], [0, 0, 1, L1], [0, 0, 0, 1]])
    T12 = np.array([[c(t2), -s(t2), 0, 0], [0, 0, -1, 0], [s(t2), c(t2), 0, 0], [0, 0, 0, 1]])
    T23 = np.array([[c(t3), -s(t3), 0, L2], [s(t3), c(t3), 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]])
    T34 = np.array([[1, 0, 0, 0], [0, 0, -1, -L3 - d4], [0, 1, 0, 0], [0, 0, 0, 1]])
    T45 = np.array([[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, d5], [0, 0, 0, 1]])
    T56 = np.array([[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, d6], [0, 0, 0, 1]])
    T67 = np.array([[c(t7), 0, s(t7), 0], [0, 1, 0, 0], [-s(t7), 0, c(t7), 0], [0, 0, 0, 1]])
    T78 = np.array([[c(t8), s(t8), 0, 0], [-s(t8), c(t8), 0, 0], [0, 0, 1, L4], [0, 0, 0, 1]])
    return np.asarray(T01 @ T12 @ T23 @ T34 @ T45 @ T56 @ T67 @ T78, dtype=np.float64)


@pytest.mark.parametrize("path", [LM, LM_LONG], ids=lambda p: p.stem)
def test_loading_manipulator_fk_equals_paper_equations(path: Path) -> None:
    model = _model(path)
    rng = np.random.default_rng(1)
    lo, hi = model.lowerPositionLimit, model.upperPositionLimit
    for k in range(60):
        x = rng.uniform(lo, hi) if k < 40 else rng.uniform(lo - 2.0, hi + 2.0)
        np.testing.assert_allclose(_frame_pose(model, "spreader", x), paper_fk(x), atol=1e-12)
    np.testing.assert_allclose(_frame_pose(model, "spreader", X_STAR), paper_fk(X_STAR), atol=1e-12)


@pytest.mark.parametrize(("path", "stroke"), [(LM, 0.5), (LM_LONG, 1.5)], ids=["paper", "long"])
def test_loading_manipulator_joints_and_limits(path: Path, stroke: float) -> None:
    model = _model(path)
    assert model.nq == model.nv == 8
    names = ["theta1", "theta2", "theta3", "d4", "d5", "d6", "theta7", "theta8"]
    assert list(model.names[1:]) == names
    kinds = dict(_joint_kinds(path))
    assert [kinds[n] for n in names] == ["revolute"] * 3 + ["prismatic"] * 3 + ["revolute"] * 2
    a2, a3 = math.radians(45.89), math.radians(35.45)
    pi = math.pi
    np.testing.assert_allclose(
        model.lowerPositionLimit, [-pi, -a2, -a3, 0, 0, 0, -pi, -pi], rtol=0, atol=1e-15
    )
    np.testing.assert_allclose(
        model.upperPositionLimit, [pi, a2, a3, stroke, stroke, stroke, pi, pi], rtol=0, atol=1e-15
    )
    assert model.existFrame("base") and model.existFrame("spreader")


def test_loading_manipulator_joint_directions() -> None:
    """d4 extends along -y of frame 3; theta8 turns about -z of frame 7 (eqs. 4 and 8).

    At x = 0 frame 3 is Rx(+90 deg) of the base, so -y of frame 3 is -z of the base, and
    frame 7 has the orientation of the spreader frame.
    """
    model = _model(LM)
    home = _frame_pose(model, "spreader", np.zeros(8))
    x = np.zeros(8)
    x[3] = 0.25
    moved = _frame_pose(model, "spreader", x)
    np.testing.assert_allclose(moved[:3, 3] - home[:3, 3], [0, 0, -0.25], atol=1e-12)
    x = np.zeros(8)
    x[7] = 0.3
    rel = np.linalg.inv(home) @ _frame_pose(model, "spreader", x)
    c, s = math.cos(0.3), math.sin(0.3)
    expected = np.array([[c, s, 0.0], [-s, c, 0.0], [0.0, 0.0, 1.0]])
    np.testing.assert_allclose(rel[:3, :3], expected, atol=1e-12)
    np.testing.assert_allclose(rel[:3, 3], 0, atol=1e-12)


def test_mgwo_target_violates_paper_limits_and_is_out_of_reach() -> None:
    """x* breaks theta3 and d4..d6 limits; its wrist centre is beyond the published reach.

    The spreader origin is l4 along the spreader z axis from the frame-6 origin (the wrist
    centre), whose distance r from the shoulder (0, 0, l1) obeys
    r^2 = l2^2 + D^2 + 2 l2 D sin(theta3), with D = l3 + d4 + d5 + d6.
    """
    paper, long = _model(LM), _model(LM_LONG)
    outside = (X_STAR < paper.lowerPositionLimit) | (X_STAR > paper.upperPositionLimit)
    assert list(np.flatnonzero(outside)) == [2, 3, 4, 5]  # theta3, d4, d5, d6
    outside_long = (X_STAR < long.lowerPositionLimit) | (X_STAR > long.upperPositionLimit)
    assert list(np.flatnonzero(outside_long)) == [2]  # theta3 only

    target = _frame_pose(paper, "spreader", X_STAR)
    np.testing.assert_allclose(target, _frame_pose(long, "spreader", X_STAR), atol=1e-15)
    wrist = target[:3, 3] - L4 * target[:3, 2]
    r_needed = float(np.linalg.norm(wrist - [0, 0, L1]))

    def reach(model: pin.Model) -> float:
        d_max = L3 + 3 * model.upperPositionLimit[3]
        t3 = model.upperPositionLimit[2]
        return math.sqrt(L2**2 + d_max**2 + 2 * L2 * d_max * math.sin(t3))

    # The reach formula bounds sampled configurations of the URDF itself.
    rng = np.random.default_rng(2)
    for model in (paper, long):
        for _ in range(200):
            x = rng.uniform(model.lowerPositionLimit, model.upperPositionLimit)
            pose = _frame_pose(model, "spreader", x)
            r = np.linalg.norm(pose[:3, 3] - L4 * pose[:3, 2] - [0, 0, L1])
            assert r <= reach(model) + 1e-9
    assert reach(paper) < r_needed - 1.4  # out of reach by more than 1.4 m
    assert reach(long) > r_needed


def test_mgwo_target_is_reachable_in_long_variant() -> None:
    model = _model(LM_LONG)
    target = pin.SE3(_frame_pose(model, "spreader", X_STAR))
    data = model.createData()
    fid = model.getFrameId("spreader")

    def residual(x: NDArray[np.float64]) -> NDArray[np.float64]:
        pin.framesForwardKinematics(model, data, x)
        return np.asarray(pin.log6(target.actInv(data.oMf[fid])).vector)

    lo, hi = model.lowerPositionLimit, model.upperPositionLimit
    rng = np.random.default_rng(0)
    best = min(
        (least_squares(residual, rng.uniform(lo, hi), bounds=(lo, hi)) for _ in range(6)),
        key=lambda s: float(np.linalg.norm(s.fun)),
    )
    assert np.linalg.norm(best.fun) < 1e-7
    assert np.all(best.x >= lo) and np.all(best.x <= hi)


# --------------------------------------------------------------------------------------------
# Generated files and the generator
# --------------------------------------------------------------------------------------------


def test_committed_urdfs_equal_generator_output() -> None:
    generated = gen.generate_all()
    assert sorted(generated) == [
        "loading_manipulator.urdf",
        "loading_manipulator_long.urdf",
        "yumi_left.urdf",
    ]
    for name, text in generated.items():
        assert (ROBOTS / name).read_text() == text, f"{name} is stale: python robots/generate.py"


@pytest.mark.parametrize("path", [YUMI, LM, LM_LONG], ids=lambda p: p.stem)
def test_urdf_has_visuals_and_inertials(path: Path) -> None:
    model = _model(path)
    visual = pin.buildGeomFromUrdf(model, str(path), pin.GeometryType.VISUAL)
    assert visual.ngeoms >= model.njoints
    root = ET.parse(path).getroot()
    links = list(root.iter("link"))
    for link in links[1:]:  # every link but the root has a positive mass
        mass = link.find("inertial/mass")
        assert mass is not None and float(mass.get("value", "0")) > 0
    assert links[0].find("inertial") is None  # KDL warns about an inertial on the root


def _random_table(rng: np.random.Generator, n: int) -> list[DHRow]:
    kinds = ["revolute", "prismatic", "continuous"]
    specials = [0.0, np.pi / 2, -np.pi / 2, np.pi]  # exercise gimbal-lock rpy extraction
    rows = []
    for i in range(n):
        kind = kinds[rng.integers(3)] if i else "revolute"
        pick = rng.random(2) < 0.5
        rows.append(
            DHRow(
                kind,  # type: ignore[arg-type]
                d=float(rng.uniform(-0.5, 0.5)),
                theta_offset=float(rng.choice(specials) if pick[0] else rng.uniform(-4, 4)),
                a=float(rng.uniform(-0.5, 0.5)),
                alpha=float(rng.choice(specials) if pick[1] else rng.uniform(-4, 4)),
                lower=-1.0,
                upper=1.0,
            )
        )
    return rows


def test_dh_to_urdf_matches_dh_fk_on_random_tables() -> None:
    rng = np.random.default_rng(3)
    for _ in range(12):
        n = int(rng.integers(1, 9))
        table = _random_table(rng, n)
        tool = pin.SE3.Random().homogeneous if rng.random() < 0.5 else None
        text = dh_to_urdf(table, robot_name="rand", base_link="b", ee_link="tip", tool=tool)
        model = _model(text)
        assert model.njoints == n + 1
        for _ in range(8):
            q = rng.uniform(-3, 3, n)
            expected = dh_fk(table, q) @ (np.eye(4) if tool is None else tool)
            got = _frame_pose(model, "tip", _config(model, q))
            np.testing.assert_allclose(got, expected, rtol=0, atol=1e-12)


def test_chain_to_urdf_general_axes() -> None:
    """Arbitrary fixed transforms and axes: pose = prod(origin_i * M_i(q_i)) * tool."""
    rng = np.random.default_rng(4)
    steps = []
    for i in range(6):
        kind = ["revolute", "prismatic", "continuous"][i % 3]
        axis = rng.normal(size=3)
        steps.append(ChainStep(pin.SE3.Random().homogeneous, kind, tuple(axis)))  # type: ignore[arg-type]
    tool = pin.SE3.Random().homogeneous
    model = _model(chain_to_urdf(steps, robot_name="r", base_link="b", ee_link="e", tool=tool))
    for _ in range(10):
        q = rng.uniform(-2, 2, 6)
        expected = np.eye(4)
        for step, qi in zip(steps, q, strict=True):
            u = np.asarray(step.axis)
            motion = pin.SE3(pin.exp3(u * qi), np.zeros(3))
            if step.kind == "prismatic":
                motion = pin.SE3(np.eye(3), u * qi)
            expected = expected @ step.origin @ motion.homogeneous
        got = _frame_pose(model, "e", _config(model, q))
        np.testing.assert_allclose(got, expected @ tool, rtol=0, atol=1e-12)


def test_dh_fk_prismatic_variable_is_d() -> None:
    row = DHRow("prismatic", d=0.2, theta_offset=0.3, a=0.1, alpha=0.4, lower=0, upper=1)
    pose = dh_fk([row], [0.5])
    expected_p = [0.1 * math.cos(0.3), 0.1 * math.sin(0.3), 0.7]
    np.testing.assert_allclose(pose[:3, 3], expected_p, atol=1e-15)


def test_limits_and_names_are_keyword_only_and_carried_into_the_urdf() -> None:
    with pytest.raises(TypeError):
        DHRow("revolute", 0.1, 0.0, 0.2, 0.0, -1.0, 1.0)  # type: ignore[misc]
    spec = {"lower": -1.0, "upper": 1.5, "effort": 7.0, "velocity": 2.0,
            "joint_name": "j_a", "link_name": "l_a"}  # fmt: skip
    row = DHRow("revolute", d=0.1, theta_offset=0.0, a=0.2, alpha=0.0, **spec)  # type: ignore[arg-type]
    assert row.joint_spec() == spec
    assert ChainStep(np.eye(4), "prismatic", **row.joint_spec()).joint_spec() == spec  # type: ignore[arg-type]
    a, b = ChainStep(np.eye(4), "revolute"), ChainStep(np.eye(4), "prismatic", (1.0, 0.0, 0.0))
    assert a != b and a == a and len({a, b}) == 2  # steps compare by identity
    assert row == DHRow("revolute", d=0.1, theta_offset=0.0, a=0.2, alpha=0.0, **spec)  # type: ignore[arg-type]
    assert row != DHRow("revolute", d=0.2, theta_offset=0.0, a=0.2, alpha=0.0, **spec)  # type: ignore[arg-type]
    text = dh_to_urdf([row], robot_name="r", base_link="b", ee_link="e")
    assert '<joint name="j_a" type="revolute">' in text and '<child link="l_a"/>' in text
    assert '<limit lower="-1.0" upper="1.5" effort="7.0" velocity="2.0"/>' in text


@pytest.mark.parametrize(
    ("make", "message"),
    [
        (lambda: DHRow("spherical", 0, 0, 0, 0), "valid joint types: revolute, prismatic"),  # type: ignore[arg-type]
        (lambda: DHRow("revolute", 0, 0, 0, 0, lower=1, upper=-1), "lower < upper"),
        (lambda: DHRow("revolute", math.nan, 0, 0, 0), "d must be finite"),
        (lambda: ChainStep(np.eye(4), "revolute", (0, 0, 0)), "non-zero 3-vector"),
        (lambda: ChainStep(2 * np.eye(4), "revolute"), "not a rigid transform"),
        (lambda: ChainStep(np.eye(3), "revolute"), "(4, 4) transform"),
        (lambda: DHRow("revolute", 0, 0, 0, 0, joint_name="bad name"), "not a valid URDF name"),
        (lambda: dh_fk([DHRow("revolute", 0, 0, 0, 0)], [0.0, 1.0]), "shape (1,)"),
        (lambda: dh_to_urdf([], robot_name="r", base_link="b", ee_link="e"), "at least one"),
        (
            lambda: chain_to_urdf(
                [ChainStep(np.eye(4), "revolute", link_name="e")],
                robot_name="r",
                base_link="b",
                ee_link="e",
            ),
            "repeated link names ['e']",
        ),
    ],
)
def test_errors_name_the_bad_value(make: object, message: str) -> None:
    with pytest.raises(InvalidArgumentError) as info:
        make()  # type: ignore[operator]
    assert message in str(info.value)
