"""Review 46: mimic joints off the goal paths follow their solved drivers (the full
configuration, the bodies they carry in the centre of mass and the collision checks, the
driver's range); an in-chain mimic joint does not cut the default end-effector chain; locked
joints by their URDF name after a rename; robots/README.md's claims."""

from __future__ import annotations

import logging
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest
from conftest import cli_json
from test_center_of_mass import _kernel_rows

import swarm_ik
from swarm_ik import goals
from swarm_ik.errors import InvalidArgumentError, RobotModelError, UnknownNameError
from swarm_ik.goals import AvoidCollisions, CenterOfMass
from swarm_ik.goals.base import State
from swarm_ik.paths import example_robot_data_dir
from swarm_ik.scene import Scene, Sphere
from swarm_ik.solvers.hybrid import Polisher
from swarm_ik.urdf import default_ee_frame, load_urdf

ROOT = Path(__file__).resolve().parents[1]
INERTIA = '<inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"/>'


def _counterweight(cw_limit: str = 'lower="-1.5" upper="1.5"', mimic: str = "") -> str:
    """An arm j1 (yaw), j2 (shoulder), j3 (elbow) → tool, with a 10 kg counterweight hung on
    l1 whose joint mimics the shoulder j2 (a parallelogram), off the tool chain."""
    mimic = mimic or '<mimic joint="j2" multiplier="1" offset="0"/>'
    return f"""<?xml version="1.0"?>
<robot name="counterweight_arm">
  <link name="base"/>
  <link name="l1"/>
  <link name="upper_arm"><collision><origin xyz="0.15 0 0"/><geometry><box size="0.3 0.04 0.04"/></geometry></collision>
    <inertial><origin xyz="0.15 0 0"/><mass value="1"/>{INERTIA}</inertial></link>
  <link name="forearm"/>
  <link name="tool"/>
  <link name="counterweight"><collision><origin xyz="-0.3 0 0"/><geometry><sphere radius="0.04"/></geometry></collision>
    <inertial><origin xyz="-0.3 0 0"/><mass value="10"/>{INERTIA}</inertial></link>
  <joint name="j1" type="revolute"><parent link="base"/><child link="l1"/><origin xyz="0 0 0.1"/><axis xyz="0 0 1"/><limit lower="-3" upper="3" effort="1" velocity="1"/></joint>
  <joint name="j2" type="revolute"><parent link="l1"/><child link="upper_arm"/><origin xyz="0 0 0.1"/><axis xyz="0 1 0"/><limit lower="-1.5" upper="1.5" effort="1" velocity="1"/></joint>
  <joint name="cw_joint" type="revolute"><parent link="l1"/><child link="counterweight"/><origin xyz="0 0 0.1"/><axis xyz="0 1 0"/><limit {cw_limit} effort="1" velocity="1"/>{mimic}</joint>
  <joint name="j3" type="revolute"><parent link="upper_arm"/><child link="forearm"/><origin xyz="0.3 0 0"/><axis xyz="0 1 0"/><limit lower="-2" upper="2" effort="1" velocity="1"/></joint>
  <joint name="j4" type="fixed"><parent link="forearm"/><child link="tool"/><origin xyz="0.3 0 0"/></joint>
</robot>
"""  # noqa: E501


def _write(tmp_path: Path, text: str, name: str = "arm.urdf") -> Path:
    path = tmp_path / name
    path.write_text(text)
    return path


@pytest.fixture()
def arm(tmp_path: Path) -> swarm_ik.RobotModel:
    return swarm_ik.load_robot(_write(tmp_path, _counterweight()), "tool")


def _by_hand(robot: swarm_ik.RobotModel, q: np.ndarray) -> np.ndarray:
    """The full model's configuration with the follower set by hand from the URDF's
    ``<mimic>`` (cw_joint = 1·j2 + 0), the other joints read from ``q`` (j1, j2, j3)."""
    full = robot.full_model
    out = pin.neutral(full)
    for name, v in zip(("j1", "j2", "j3"), q, strict=True):
        out[full.idx_qs[full.getJointId(name)]] = v
    out[full.idx_qs[full.getJointId("cw_joint")]] = 1.0 * q[1] + 0.0
    return out


def _counterweight_centre(robot: swarm_ik.RobotModel, q_full: np.ndarray) -> np.ndarray:
    full = robot.full_model
    data = full.createData()
    pin.framesForwardKinematics(full, data, q_full)
    return np.asarray(data.oMf[full.getFrameId("counterweight")].act(np.array([-0.3, 0.0, 0.0])))


# ------------------------------------------------------------------ 1: off-path mimic
def test_off_path_follower_follows_its_solved_driver(arm: swarm_ik.RobotModel) -> None:
    assert arm.joint_names == ("j1", "j2", "j3")
    assert arm.mimic == {"cw_joint": ("j2", 1.0, 0.0)} and "cw_joint" not in arm.locked_joints
    full = arm.full_model
    i_cw = full.idx_qs[full.getJointId("cw_joint")]
    rng = np.random.default_rng(0)
    for q in [np.array([0.0, 1.0, 0.0]), *arm.random_q(rng, 5)]:
        qf = arm.full_configuration(q)
        assert qf[i_cw] == pytest.approx(q[1], abs=1e-15)
        np.testing.assert_allclose(qf, _by_hand(arm, q), atol=1e-15)
        np.testing.assert_allclose(arm.from_full_configuration(qf), q, atol=1e-15)
        # the reduced model (behind the kernels, collisions and the CoM) moves it too
        data = arm.model.createData()
        pin.framesForwardKinematics(arm.model, data, arm.to_pinocchio(q))
        m = data.oMf[arm.model.getFrameId("counterweight")]
        np.testing.assert_allclose(
            m.act(np.array([-0.3, 0.0, 0.0])), _counterweight_centre(arm, _by_hand(arm, q)),
            atol=1e-12,
        )  # fmt: skip
    # j2 = 1: the counterweight swings up with the shoulder (its neutral place was (-0.3, 0, 0.2))
    c = _counterweight_centre(arm, arm.full_configuration([0.0, 1.0, 0.0]))
    np.testing.assert_allclose(c, [-0.3 * np.cos(1.0), 0.0, 0.2 + 0.3 * np.sin(1.0)], atol=1e-12)


def test_off_path_follower_narrows_its_drivers_range(tmp_path: Path) -> None:
    robot = swarm_ik.load_robot(
        _write(tmp_path, _counterweight('lower="-0.5" upper="0.8"')), "tool"
    )
    assert (robot.lower[1], robot.upper[1]) == pytest.approx((-0.5, 0.8))
    mimic = '<mimic joint="j2" multiplier="-2" offset="0.1"/>'
    robot = swarm_ik.load_robot(_write(tmp_path, _counterweight(mimic=mimic)), "tool")
    # -1.5 <= -2·j2 + 0.1 <= 1.5  ⇔  -0.7 <= j2 <= 0.8
    assert (robot.lower[1], robot.upper[1]) == pytest.approx((-0.7, 0.8))
    q = np.array([0.2, 0.5, -0.3])
    full = robot.full_model
    assert robot.full_configuration(q)[full.idx_qs[full.getJointId("cw_joint")]] == pytest.approx(
        -2.0 * 0.5 + 0.1
    )
    bad = _counterweight('lower="2.0" upper="2.5"')  # no j2 in [-1.5, 1.5] gives that
    with pytest.raises(RobotModelError, match="'cw_joint' cannot stay within its limits"):
        swarm_ik.load_robot(_write(tmp_path, bad), "tool")


def test_centre_of_mass_moves_with_the_counterweight(arm: swarm_ik.RobotModel) -> None:
    full = arm.full_model
    goal = CenterOfMass(point=[0.1, -0.2, 0.3], axes="xyz")
    rng = np.random.default_rng(1)

    def com(q: np.ndarray) -> np.ndarray:
        return np.array(pin.centerOfMass(full, full.createData(), _by_hand(arm, q)))

    for q in [np.array([0.0, 1.0, 0.0]), *arm.random_q(rng, 4)]:
        c_ref = com(q)
        np.testing.assert_allclose(goal.center(arm, q), c_ref, atol=1e-12)
        np.testing.assert_allclose(goal.residual(State(arm, q)), goal.point - c_ref, atol=1e-12)
        res, jac, _err = _kernel_rows(arm, goal, q)  # (the compiled kernel's bodies)
        np.testing.assert_allclose(res, goal.point - c_ref, atol=1e-12)
        h = 1e-6
        num = np.stack([(com(q + h * e) - com(q - h * e)) / (2 * h) for e in np.eye(3)], axis=1)
        np.testing.assert_allclose(jac, num, atol=1e-7)
        np.testing.assert_allclose(-jac, goal.jacobian(State(arm, q)), atol=1e-12)
    # at j2 = 1 the reviewer's numbers: (-0.14, 0, 0.418), not the frozen (-0.2654, 0, 0.1885)
    np.testing.assert_allclose(goal.center(arm, [0.0, 1.0, 0.0]), [-0.14, 0.0, 0.418], atol=1e-3)


def test_an_obstacle_on_the_real_counterweight_is_a_collision(arm: swarm_ik.RobotModel) -> None:
    q = np.array([0.0, 1.0, 0.0])
    real = _counterweight_centre(arm, _by_hand(arm, q))
    scene = Scene([Sphere(0.05, real.tolist())])
    rc = arm.collision_model()
    rep = rc.check(q, scene)
    assert not rep.collision_free
    assert [p[0] for p in rep.pairs_in_contact] == ["counterweight"]
    assert rc.collides(q, scene, 0.0, False)
    prob = swarm_ik.IKProblem(arm, arm.fk(q), goals=[AvoidCollisions(scene, self_collision=False)])
    met = {e.goal: e.met for e in swarm_ik.verify(prob, q)}
    assert met["AvoidCollisions"] is False
    # the sphere model (the compiled collision rows) sees the penetration too
    pol = Polisher.from_problem(prob)
    rows = pol.residual(q)[0][6:]
    assert rows.size and rows.min() < -0.01
    # at the counterweight's frozen (neutral) place there is no obstacle any more
    frozen = _counterweight_centre(arm, _by_hand(arm, np.zeros(3)))
    assert np.linalg.norm(frozen - real) > 0.2


def test_no_colliding_success_with_the_obstacle_on_the_counterweights_path(
    arm: swarm_ik.RobotModel,
) -> None:
    """The tool pose of q_hit has one solution, which puts the counterweight into the
    obstacle: no success (it was a collision-free success while the counterweight stayed
    frozen); its tool position alone has an elbow-flipped solution, which keeps it clear
    (checked on the full model, the follower set by hand)."""
    q_hit = np.array([0.0, 1.0, -1.2])
    centre = _counterweight_centre(arm, _by_hand(arm, q_hit))
    scene = Scene([Sphere(0.05, centre.tolist())])
    goal = AvoidCollisions(scene, self_collision=False)
    for seed in range(2):
        res = swarm_ik.solve(swarm_ik.IKProblem(arm, arm.fk(q_hit), goals=[goal]), seed=seed)
        assert not res.success
    position = goals.Position("tool", arm.fk(q_hit)[:3, 3])
    ok = 0
    for seed in range(3):
        res = swarm_ik.solve(swarm_ik.IKProblem(arm, goals=[position, goal]), seed=seed)
        if res.success:
            ok += 1
            gap = np.linalg.norm(_counterweight_centre(arm, _by_hand(arm, res.q)) - centre)
            assert gap > 0.09 - 1e-9  # (the radii 0.04 + 0.05)
    assert ok >= 1


def test_follower_of_a_locked_or_off_path_driver_is_held_consistently(tmp_path: Path) -> None:
    path = _write(tmp_path, _counterweight())
    held = swarm_ik.load_robot(path, "tool", locked={"j2": 0.4})
    assert held.joint_names == ("j1", "j3") and "cw_joint" in held.locked_joints
    full = held.full_model
    qf = held.full_configuration([0.1, 0.2])
    assert qf[full.idx_qs[full.getJointId("cw_joint")]] == pytest.approx(0.4)
    # goal l1 (j1 only): j2 off the paths at its neutral value, its follower with it
    short = swarm_ik.load_robot(path, "l1")
    assert short.joint_names == ("j1",) and not short.mimic
    qf = short.full_configuration([0.3])
    assert qf[full.idx_qs[full.getJointId("cw_joint")]] == qf[full.idx_qs[full.getJointId("j2")]]


def test_tree_whose_other_arm_mimics_a_solved_joint(tmp_path: Path) -> None:
    """The right shoulder mimics the left one (multiplier -1); solving for the left hand, the
    right arm (its other joints locked) swings with it."""
    link = f'<link name="{{n}}"><inertial><mass value="1"/>{INERTIA}</inertial></link>'
    joint = (
        '<joint name="{n}" type="revolute"><parent link="{p}"/><child link="{c}"/>'
        '<origin xyz="{o}"/><axis xyz="0 1 0"/><limit lower="-2" upper="2" effort="1" '
        'velocity="1"/>{m}</joint>'
    )
    parts = [link.format(n=n) for n in ("base", "torso", "la", "lh", "ra", "rh")]
    parts += [
        joint.format(n="torso_yaw", p="base", c="torso", o="0 0 0.5", m=""),
        joint.format(n="left_j1", p="torso", c="la", o="0 0.2 0.3", m=""),
        joint.format(n="left_j2", p="la", c="lh", o="0 0 -0.3", m=""),
        joint.format(n="right_j1", p="torso", c="ra", o="0 -0.2 0.3",
                     m='<mimic joint="left_j1" multiplier="-1"/>'),
        joint.format(n="right_j2", p="ra", c="rh", o="0 0 -0.3", m=""),
    ]  # fmt: skip
    path = _write(tmp_path, '<robot name="t">' + "".join(parts) + "</robot>")
    robot = swarm_ik.load_robot(path, "lh")
    assert robot.joint_names == ("torso_yaw", "left_j1", "left_j2")
    assert robot.mimic == {"right_j1": ("left_j1", -1.0, 0.0)}
    assert robot.locked_joints == ("right_j2",)
    full = robot.full_model
    q = np.array([0.3, 0.7, -0.2])
    by_hand = pin.neutral(full)
    for name, v in [("torso_yaw", 0.3), ("left_j1", 0.7), ("left_j2", -0.2), ("right_j1", -0.7)]:
        by_hand[full.idx_qs[full.getJointId(name)]] = v
    np.testing.assert_allclose(robot.full_configuration(q), by_hand, atol=1e-15)
    d_full, d_red = full.createData(), robot.model.createData()
    pin.framesForwardKinematics(full, d_full, by_hand)
    pin.framesForwardKinematics(robot.model, d_red, robot.to_pinocchio(q))
    for frame in ("rh", "lh"):
        np.testing.assert_allclose(
            d_red.oMf[robot.model.getFrameId(frame)].homogeneous,
            d_full.oMf[full.getFrameId(frame)].homogeneous,
            atol=1e-12,
        )
    np.testing.assert_allclose(
        CenterOfMass(point=[0, 0, 0]).center(robot, q),
        pin.centerOfMass(full, full.createData(), by_hand),
        atol=1e-12,
    )


def test_continuous_off_path_follower_of_a_solved_joint_is_refused(tmp_path: Path) -> None:
    text = _counterweight().replace(
        '<joint name="cw_joint" type="revolute">', '<joint name="cw_joint" type="continuous">'
    )
    with pytest.raises(RobotModelError, match="mimic joint 'cw_joint'.* is continuous"):
        swarm_ik.load_robot(_write(tmp_path, text), "tool")


def test_off_path_follower_of_a_follower_is_refused_and_not_a_default(tmp_path: Path) -> None:
    """cw2 mimics cw_joint, itself a follower of j2 (a chain of mimic joints): refused as on
    the chain, naming both, instead of a second counterweight frozen in place; the default
    frame avoids the chain whose driver carries it."""
    extra = (
        '<link name="cw2"/><joint name="cw2_joint" type="revolute"><parent link="l1"/>'
        '<child link="cw2"/><axis xyz="0 1 0"/><limit lower="-1.5" upper="1.5" effort="1" '
        'velocity="1"/><mimic joint="cw_joint"/></joint></robot>'
    )
    path = _write(tmp_path, _counterweight().replace("</robot>", extra))
    with pytest.raises(RobotModelError, match="'cw2_joint' mimics 'cw_joint', itself a mimic"):
        swarm_ik.load_robot(path, "tool")
    full, info = load_urdf(path)
    frame, _ = default_ee_frame(full, info)
    assert frame != "tool"
    swarm_ik.load_robot(path)  # (the default frame loads)


# ------------------------------------------------------------- 2: default frame with mimic
def _six_joint_arm_with_mimic() -> str:
    """The reviewer's arm: j3 mimics j2 (a parallelogram), fingers mimic each other."""
    body = (
        '<inertial><mass value="1"/>' + INERTIA + "</inertial><collision><geometry>"
        '<cylinder radius="0.03" length="0.1"/></geometry></collision>'
    )
    links = "".join(
        f'<link name="{n}">{body}</link>'
        for n in ("l0", "l1", "l2", "l3", "l4", "l5", "l6", "hand", "finger_l", "finger_r", "tcp")
    )
    rev = (
        '<joint name="{n}" type="revolute"><parent link="{p}"/><child link="{c}"/>'
        '<origin xyz="{o}"/><axis xyz="{a}"/><limit lower="-{r}" upper="{r}" effort="10" '
        'velocity="1"/>{m}</joint>'
    )
    joints = "".join([
        rev.format(n="j1", p="l0", c="l1", o="0 0 0.1", a="0 0 1", r=3, m=""),
        rev.format(n="j2", p="l1", c="l2", o="0 0 0.1", a="0 1 0", r=2, m=""),
        rev.format(n="j3", p="l2", c="l3", o="0.3 0 0", a="0 1 0", r=1,
                   m='<mimic joint="j2" multiplier="-0.5" offset="0.2"/>'),
        rev.format(n="j4", p="l3", c="l4", o="0.3 0 0", a="1 0 0", r=3, m=""),
        rev.format(n="j5", p="l4", c="l5", o="0.1 0 0", a="0 1 0", r=2, m=""),
        rev.format(n="j6", p="l5", c="l6", o="0.1 0 0", a="1 0 0", r=3, m=""),
        '<joint name="hand_j" type="fixed"><parent link="l6"/><child link="hand"/>'
        '<origin xyz="0.05 0 0"/></joint>',
        '<joint name="finger_l_joint" type="prismatic"><parent link="hand"/><child '
        'link="finger_l"/><origin xyz="0.05 0.01 0"/><axis xyz="0 1 0"/><limit lower="0" '
        'upper="0.04" effort="10" velocity="1"/></joint>',
        '<joint name="finger_r_joint" type="prismatic"><parent link="hand"/><child '
        'link="finger_r"/><origin xyz="0.05 -0.01 0"/><axis xyz="0 -1 0"/><limit lower="0" '
        'upper="0.04" effort="10" velocity="1"/><mimic joint="finger_l_joint"/></joint>',
        '<joint name="tcp_j" type="fixed"><parent link="hand"/><child link="tcp"/>'
        '<origin xyz="0.1 0 0"/></joint>',
    ])  # fmt: skip
    return f'<?xml version="1.0"?><robot name="r">{links}{joints}</robot>'


def test_in_chain_mimic_does_not_cut_the_default_chain(
    tmp_path: Path, caplog: pytest.LogCaptureFixture
) -> None:
    path = _write(tmp_path, _six_joint_arm_with_mimic(), "mimic.urdf")
    with caplog.at_level(logging.INFO, logger="swarm_ik"):
        robot = swarm_ik.load_robot(path)
    assert robot.ee_frame == "tcp"  # (was 'l1', a one-joint chain)
    assert robot.joint_names == ("j1", "j2", "j4", "j5", "j6")
    assert robot.mimic == {"j3": ("j2", -0.5, 0.2)}
    assert "5 joints and 1 mimic joint they drive" in robot.ee_frame_reason
    assert any("'tcp'" in r.getMessage() for r in caplog.records)
    q = robot.mid_q() + 0.1
    np.testing.assert_allclose(robot.fk(q[None])[0], robot.fk_pinocchio(q), atol=1e-12)


def test_unnamed_mimic_gripper_is_still_not_the_tip(tmp_path: Path) -> None:
    """Fingers named j7/j8 (no finger word), j8 mimicking j7, on a hand after a 3-joint arm:
    a mimic group that carries no arm joint is a gripper; the tip is the hand's tool."""
    text = (
        _six_joint_arm_with_mimic().replace("finger_l_joint", "j7").replace("finger_r_joint", "j8")
    )
    text = text.replace("finger_l", "a7").replace("finger_r", "a8")
    full, info = load_urdf(_write(tmp_path, text))
    assert info.mimic["j8"].driver == "j7"
    assert default_ee_frame(full, info)[0] == "tcp"


def test_chain_with_a_follower_whose_driver_is_elsewhere_is_not_chosen(tmp_path: Path) -> None:
    """A follower whose driver is on another branch: that chain would be refused, so the
    default frame is on the other one."""
    link = '<link name="{n}"/>'
    joint = (
        '<joint name="{n}" type="revolute"><parent link="{p}"/><child link="{c}"/>'
        '<origin xyz="0 0 0.1"/><axis xyz="0 1 0"/><limit lower="-2" upper="2" effort="1" '
        'velocity="1"/>{m}</joint>'
    )
    parts = [link.format(n=n) for n in ("b", "t", "la", "lb", "ra", "rb", "rc")]
    parts += [
        joint.format(n="yaw", p="b", c="t", m=""),
        joint.format(n="l1", p="t", c="la", m=""),
        joint.format(n="l2", p="la", c="lb", m=""),
        joint.format(n="r1", p="t", c="ra", m='<mimic joint="l1"/>'),
        joint.format(n="r2", p="ra", c="rb", m=""),
        joint.format(n="r3", p="rb", c="rc", m=""),
    ]
    path = _write(tmp_path, '<robot name="t">' + "".join(parts) + "</robot>")
    full, info = load_urdf(path)
    frame, _ = default_ee_frame(full, info)
    assert frame == "lb"  # (rc's chain holds r1, whose driver l1 is not on it)
    robot = swarm_ik.load_robot(path)
    assert robot.ee_frame == "lb" and robot.mimic == {"r1": ("l1", 1.0, 0.0)}


# the default frames of the URDFs whose mimic joints the rule must still judge as grippers
MIMIC_URDFS = {
    "panda_description/urdf/panda.urdf": "panda_hand_tcp",
    "baxter_description/urdf/baxter.urdf": "left_gripper",
    "pr2_description/urdf/pr2.urdf": "l_gripper_tool_frame",
    "romeo_description/urdf/romeo.urdf": "l_gripper",
    "talos_data/robots/talos_full_v2.urdf": "gripper_left_base_link",
    "talos_data/robots/talos_left_arm.urdf": "gripper_left_inner_double_link",
    "tiago_pro_description/robots/tiago_pro.urdf": "arm_left_tool_link",
}


@pytest.mark.parametrize("rel", list(MIMIC_URDFS))
def test_default_frames_of_robots_with_mimic_grippers_unchanged(rel: str) -> None:
    path = example_robot_data_dir() / rel
    if not path.is_file():
        pytest.skip(f"{rel} not shipped by this example-robot-data")
    full, info = load_urdf(path)
    assert info.mimic  # (the rule is exercised)
    assert default_ee_frame(full, info)[0] == MIMIC_URDFS[rel]


@pytest.mark.parametrize(
    ("name", "frames", "nq"),
    [
        ("panda", ("panda_hand_tcp",), 7),
        ("baxter", ("left_gripper", "right_gripper"), 14),
        ("talos", ("gripper_left_base_link", "gripper_right_base_link"), 16),
        ("z1", ("link06",), 6),
        ("pr2", ("l_gripper_tool_frame",), 8),
        ("tiago_pro", ("arm_left_tool_link",), 8),
    ],
)
def test_named_robots_keep_their_frames(name: str, frames: tuple[str, ...], nq: int) -> None:
    robot = swarm_ik.load_robot(name)
    assert robot.frames == frames and robot.nq == nq and not robot.mimic


# ------------------------------------------------------------ 3: locked by a renamed name
def test_lock_a_renamed_joint_by_its_urdf_name(capsys: pytest.CaptureFixture[str]) -> None:
    _full, info = load_urdf(swarm_ik.load_robot("so100").urdf_path)
    assert info.renamed.get("gripper") == "gripper_joint"  # (a link is named gripper too)
    by_old = swarm_ik.load_robot("so100", locked=["gripper"])
    by_new = swarm_ik.load_robot("so100", locked=["gripper_joint"])
    assert by_old.held == by_new.held and "gripper_joint" in by_old.held
    valued = swarm_ik.load_robot("so100", locked={"gripper": 0.1})
    assert valued.held["gripper_joint"] == pytest.approx(0.1)
    with pytest.raises(InvalidArgumentError, match="given twice, as 'gripper' and 'gripper_joint'"):
        swarm_ik.load_robot("so100", locked={"gripper": 0.1, "gripper_joint": 0.2})
    with pytest.raises(UnknownNameError, match="unknown joint 'grip'"):
        swarm_ik.load_robot("so100", locked=["grip"])
    out = cli_json(capsys, "solve", "--robot", "so100", "--lock", "gripper", "--from-q",
                   "0", "0", "0", "0", "0")  # fmt: skip
    assert out["success"] is True


# ---------------------------------------------------------------------- 4: the README
def test_robots_readme_claims_hold() -> None:
    text = (ROOT / "robots" / "README.md").read_text()
    assert "not offered by name" not in text
    assert "so100" in swarm_ik.robot_names()["example-robot-data"]
    assert swarm_ik.load_robot("so100").nq == 5
    assert "## Licences" in text and "BSD-2-Clause" in text
