"""Any URDF (issue 16, items 1-7): encodings, empty robots, joint/link name clashes, urdfdom's
stderr, the default end-effector frame, mimic joints and huge joint ranges.

The real-robot cases load example-robot-data's URDFs *by path* (no curated frame) and solve
FK-sampled targets with the batched solver; the others write small URDFs to ``tmp_path``.
"""

from __future__ import annotations

import logging
from pathlib import Path

import numpy as np
import pytest

import swarm_ik
from swarm_ik import InvalidArgumentError, RobotModelError
from swarm_ik.errors import RobotModelWarning
from swarm_ik.robot import EXAMPLE_ROBOTS, example_robot_data_dir
from swarm_ik.urdf import (
    DEFAULT_MAX_SAMPLING_WIDTH,
    MimicJoint,
    decode_xml_bytes,
    frame_name_score,
    is_gripper_joint,
    load_urdf,
    name_words,
    sampling_bounds,
)

LIMIT = '<limit lower="-1" upper="1" effort="1" velocity="1"/>'


def _arm(joint_names: tuple[str, str] = ("j1", "j2"), extra_link: str = "") -> str:
    """A 2-joint arm a -> b -> c (joints named ``joint_names``)."""
    j1, j2 = joint_names
    return (
        '<?xml version="1.0" encoding="UTF-8"?>\n<robot name="arm">'
        f'<link name="a"/><link name="b"/><link name="c"/>{extra_link}'
        f'<joint name="{j1}" type="revolute"><parent link="a"/><child link="b"/>'
        f'<origin xyz="0 0 0.3"/><axis xyz="0 0 1"/>{LIMIT}</joint>'
        f'<joint name="{j2}" type="revolute"><parent link="b"/><child link="c"/>'
        f'<origin xyz="0.4 0 0"/><axis xyz="0 1 0"/>{LIMIT}</joint></robot>'
    )


def _write(tmp_path: Path, data: str | bytes, name: str = "r.urdf") -> Path:
    p = tmp_path / name
    if isinstance(data, str):
        p.write_text(data, encoding="utf-8")
    else:
        p.write_bytes(data)
    return p


# ------------------------------------------------------------------- item 3: reading the text
@pytest.mark.parametrize(
    "encode",
    [
        pytest.param(lambda t: ("\n   \t" + t).encode(), id="whitespace before <?xml"),
        pytest.param(lambda t: b"\xef\xbb\xbf" + t.encode(), id="utf-8 BOM"),
        pytest.param(lambda t: t.replace("UTF-8", "UTF-16").encode("utf-16"), id="utf-16 with BOM"),
        pytest.param(
            lambda t: t.replace("UTF-8", "UTF-16").encode("utf-16-le"), id="utf-16-le no BOM"
        ),
        pytest.param(lambda t: t.replace("UTF-8", "latin-1").encode("latin-1"), id="latin-1"),
    ],
)
def test_urdf_in_any_encoding_or_with_leading_whitespace_loads_silently(
    encode, tmp_path: Path, capfd: pytest.CaptureFixture[str]
) -> None:
    path = _write(tmp_path, encode(_arm()))
    robot = swarm_ik.RobotModel.from_urdf(path)
    assert robot.joint_names == ("j1", "j2") and robot.ee_frame == "c"
    q = np.array([0.3, -0.2])
    np.testing.assert_allclose(robot.fk(q), robot.fk_pinocchio(q), atol=1e-12)
    assert capfd.readouterr().err == ""  # urdfdom said nothing


def test_decode_refuses_bytes_that_are_not_their_declared_encoding() -> None:
    with pytest.raises(RobotModelError, match=r"f.urdf: not valid utf-8 text"):
        decode_xml_bytes(b'<?xml version="1.0"?><robot>\xff\xfe\xfa</robot>', "f.urdf")
    with pytest.raises(RobotModelError, match=r"unknown encoding 'klingon'"):
        decode_xml_bytes(b'<?xml version="1.0" encoding="klingon"?><robot/>', "f.urdf")


# ------------------------------------------------------------------- item 2: empty <robot>
def test_empty_robot_is_called_empty(tmp_path: Path) -> None:
    path = _write(
        tmp_path, '<?xml version="1.0"?>\n<!-- generated -->\n<robot name="ur3">\n</robot>'
    )
    with pytest.raises(RobotModelError, match=r"the URDF is empty: <robot name='ur3'> defines no"):
        swarm_ik.load_robot(path)


def test_example_robot_data_ur3_urdf_is_reported_empty() -> None:
    path = example_robot_data_dir() / "ur_description/urdf/ur3.urdf"
    if not path.is_file():
        pytest.skip("ur3.urdf not shipped by this example-robot-data")
    with pytest.raises(RobotModelError, match="the URDF is empty"):
        swarm_ik.load_robot(path)


# ------------------------------------------------------------------- item 7: urdfdom's stderr
def test_urdfdom_messages_do_not_reach_stderr(
    tmp_path: Path, capfd: pytest.CaptureFixture[str]
) -> None:
    # urdfdom prints three "Error:" lines for a mesh scale of four numbers and loads anyway
    visual = (
        '<link name="d"><visual><geometry><mesh filename="x.stl" scale="1 1 1 1"/></geometry>'
        "</visual></link>"
    )
    text = _arm(extra_link=visual).replace(
        "</robot>",
        '<joint name="fix" type="fixed"><parent link="c"/><child link="d"/></joint></robot>',
    )
    path = _write(tmp_path, text)
    robot = swarm_ik.load_robot(path)
    assert robot.nq == 2
    assert capfd.readouterr().err == ""
    _model, info = load_urdf(path)
    assert any("scale" in m.lower() for m in info.messages)  # captured, not lost


def test_pinocchio_refusal_is_one_line_with_urdfdom_reason(
    tmp_path: Path, capfd: pytest.CaptureFixture[str]
) -> None:
    # a velocity limit that is not a number passes our checks but not urdfdom's, which
    # printed six lines of "Error: ... at line 224 in joint.cpp" before
    path = _write(tmp_path, _arm().replace('velocity="1"', 'velocity="abc"', 1))
    with pytest.raises(RobotModelError) as info:
        swarm_ik.load_robot(path)
    msg = str(info.value)
    assert msg.startswith(f"{path}: Pinocchio could not load it (") and "\n" not in msg
    assert "velocity value (abc) is not a valid float" in msg and "at line" not in msg
    assert capfd.readouterr().err == ""


# ------------------------------------------------------------------- item 1: name clashes
def test_joint_named_like_a_link_is_renamed_in_memory(
    tmp_path: Path, capfd: pytest.CaptureFixture[str]
) -> None:
    # joint "b" (child link b) and joint "c" (child link c): Pinocchio's buildReducedModel
    # refused this ("Several frames match the filter") as soon as a joint had to be locked
    extra = (
        '<link name="f"/><joint name="f" type="prismatic"><parent link="c"/><child link="f"/>'
        f'<axis xyz="1 0 0"/>{LIMIT}<mimic joint="b" multiplier="2" offset="0.1"/></joint>'
    )
    text = _arm(("b", "c")).replace("</robot>", extra + "</robot>")
    path = _write(tmp_path, text)
    robot = swarm_ik.load_robot(path, ee_frame="c")
    assert robot.joint_names == ("b_joint", "c_joint")
    # f mimics b, a solved joint: kept off the chain, driven by b (nothing locked here)
    assert robot.locked_joints == () and robot.mimic == {"f_joint": ("b_joint", 2.0, 0.1)}
    assert robot.ee_frame == "c"
    q = np.array([0.5, -0.4])
    np.testing.assert_allclose(robot.fk(q), robot.fk_pinocchio(q), atol=1e-12)
    # goal b: c_joint is locked (buildReducedModel on renamed joints), f below it still follows b
    short = swarm_ik.load_robot(path, ee_frame="b")
    assert short.joint_names == ("b_joint",) and short.locked_joints == ("c_joint",)
    assert short.mimic == {"f_joint": ("b_joint", 2.0, 0.1)}
    qf = short.full_configuration([0.3])
    assert qf[short.full_model.idx_qs[short.full_model.getJointId("f_joint")]] == 2.0 * 0.3 + 0.1
    _model, info = load_urdf(path)
    assert info.renamed == {"b": "b_joint", "c": "c_joint", "f": "f_joint"}
    assert info.joint_name("b") == "b_joint" and info.joint_name("b_joint") == "b_joint"
    # the mimic reference follows the rename
    assert info.mimic == {"f_joint": MimicJoint("f_joint", "b_joint", 2.0, 0.1)}
    assert capfd.readouterr().err == ""


def test_renamed_joint_does_not_take_an_existing_name(tmp_path: Path) -> None:
    text = _arm(("b", "b_joint"))
    _model, info = load_urdf(_write(tmp_path, text))
    assert info.renamed == {"b": "b_joint2"}


# ------------------------------------------------------------------- item 5: mimic parsed
def test_mimic_joints_are_parsed_with_driver_multiplier_offset(tmp_path: Path) -> None:
    extra = (
        '<link name="f1"/><link name="f2"/>'
        f'<joint name="finger1" type="prismatic"><parent link="c"/><child link="f1"/>'
        f'<axis xyz="1 0 0"/>{LIMIT}</joint>'
        f'<joint name="finger2" type="prismatic"><parent link="c"/><child link="f2"/>'
        f'<axis xyz="1 0 0"/>{LIMIT}<mimic joint="finger1" multiplier="-1.5"/></joint>'
    )
    path = _write(tmp_path, _arm().replace("</robot>", extra + "</robot>"))
    _model, info = load_urdf(path)
    m = info.mimic["finger2"]
    assert (m.driver, m.multiplier, m.offset) == ("finger1", -1.5, 0.0)
    np.testing.assert_allclose(m.follower_value([0.0, 0.2]), [0.0, -0.3])
    # the default frame skips the fingers: the tip of the arm
    assert swarm_ik.load_robot(path).ee_frame == "c"


def test_mimic_with_a_non_numeric_multiplier_is_refused(tmp_path: Path) -> None:
    text = _arm().replace(
        f"{LIMIT}</joint></robot>", f'{LIMIT}<mimic joint="j1" multiplier="x"/></joint></robot>'
    )
    with pytest.raises(RobotModelError, match=r"joint 'j2': <mimic multiplier='x'> must be a"):
        swarm_ik.load_robot(_write(tmp_path, text))


def test_mimic_on_the_chain_is_driven_by_its_driver(tmp_path: Path) -> None:
    text = _arm().replace(f"{LIMIT}</joint></robot>", f'{LIMIT}<mimic joint="j1"/></joint></robot>')
    robot = swarm_ik.load_robot(_write(tmp_path, text), ee_frame="c")
    assert robot.joint_names == ("j1",) and robot.mimic == {"j2": ("j1", 1.0, 0.0)}


# ------------------------------------------------------------------- item 4: default frame
def test_name_words_and_scores() -> None:
    assert name_words("panda_hand_tcp") == ["panda", "hand", "tcp"]
    assert name_words("gripperMover") == ["gripper", "mover"]
    assert name_words("tool0") == ["tool"]
    assert frame_name_score("tool0") > frame_name_score("ee_link") > frame_name_score("link6")
    assert frame_name_score("j2s6s200_end_effector") == frame_name_score("link_eef") > 0
    assert frame_name_score("left_knee") == 0  # "ee" is a word, not a substring
    assert frame_name_score("left_hand_camera") < 0
    assert is_gripper_joint("panda_finger_joint1") and is_gripper_joint("gripperMover")
    assert is_gripper_joint("joint7", "left_finger_link")
    assert not is_gripper_joint("wrist_roll", "gripper")  # a link named gripper is its body
    assert not is_gripper_joint("elbow_flex", "lower_arm")


ROBOT_FILES = {
    # file under example-robot-data's robots/ -> acceptable default frames
    "anymal_c": ("anymal_c_simple_description/urdf/anymal.urdf", None),
    "so100": ("so_arm_description/urdf/so100.urdf", {"gripper"}),
    "b1-z1": ("b1_description/urdf/b1-z1.urdf", {"gripperStator", "link06"}),
    "panda": ("panda_description/urdf/panda.urdf", {"panda_hand_tcp"}),
    "baxter": ("baxter_description/urdf/baxter.urdf", {"left_gripper", "right_gripper"}),
    "romeo": ("romeo_description/urdf/romeo.urdf", None),
    "talos_full": ("talos_data/robots/talos_full_v2.urdf", None),
}


@pytest.mark.parametrize("name", list(ROBOT_FILES))
def test_real_robot_by_path_loads_with_a_sensible_frame_and_solves(
    name: str, caplog: pytest.LogCaptureFixture, capfd: pytest.CaptureFixture[str]
) -> None:
    rel, frames = ROBOT_FILES[name]
    path = example_robot_data_dir() / rel
    if not path.is_file():
        pytest.skip(f"{rel} not shipped by this example-robot-data")
    with caplog.at_level(logging.INFO, logger="swarm_ik"):
        robot = swarm_ik.load_robot(path)
    # the choice is said, with its reason
    said = [
        r.getMessage() for r in caplog.records if "default end-effector frame" in r.getMessage()
    ]
    assert said and repr(robot.ee_frame) in said[0] and "longest movable chain" in said[0]
    if frames is not None:
        assert robot.ee_frame in frames
    _model, info = load_urdf(path)
    # no mimic joint, mimic driver or finger on the chosen chain
    drivers = {m.driver for m in info.mimic.values()}
    for j in robot.joint_names:
        assert j not in info.mimic and j not in drivers
        assert not is_gripper_joint(j)
    assert robot.nq >= 2
    # FK of the batched kernel equals Pinocchio's, and FK-sampled targets are solved
    rng = np.random.default_rng(7)
    q = robot.random_q(rng, 20)
    np.testing.assert_allclose(robot.fk(q[0]), robot.fk_pinocchio(q[0]), atol=1e-10)
    res = swarm_ik.solve_batch(robot, robot.fk(q), seed=0)
    assert res.success.all(), f"{name}: {res.n - res.success.sum()} of 20 not solved"
    assert capfd.readouterr().err == ""


@pytest.mark.parametrize("name", ["panda", "ur5", "kinova", "xarm7"])
def test_default_frame_by_path_equals_the_curated_frame(name: str) -> None:
    rel, frame = EXAMPLE_ROBOTS[name]
    path = example_robot_data_dir() / rel
    assert swarm_ik.load_robot(path).ee_frame == frame


def test_joint_link_clash_robots_load_by_name_of_a_locked_branch() -> None:
    # anymal_c: every foot joint is named like its link; choosing one leg locks the others
    path = example_robot_data_dir() / "anymal_c_simple_description/urdf/anymal.urdf"
    robot = swarm_ik.load_robot(path, ee_frame="RH_FOOT")
    assert robot.nq == 3 and all(j.startswith("RH_") for j in robot.joint_names)


# ------------------------------------------------------------------- item 6: huge ranges
def test_sampling_bounds_narrows_only_huge_ranges_around_the_seed() -> None:
    lower = np.array([-999999.0, -999999.0, -np.pi, -2 * np.pi, 0.0])
    upper = np.array([999999.0, 999999.0, np.pi, 2 * np.pi, 1e6])
    seed = np.array([3.0, -999998.0, 0.5, 0.0, 10.0])
    lo, hi = sampling_bounds(lower, upper, seed)
    w = DEFAULT_MAX_SAMPLING_WIDTH
    np.testing.assert_allclose(lo, [3.0 - w / 2, -999999.0, -np.pi, -2 * np.pi, 0.0])
    np.testing.assert_allclose(hi, [3.0 + w / 2, -999999.0 + w, np.pi, 2 * np.pi, w])
    assert np.all(lower <= lo) and np.all(hi <= upper)
    # UR-style ±2π joints keep their whole range; no seed: centred on the middle
    lo, hi = sampling_bounds(lower, upper, None, max_width=7.0)
    np.testing.assert_allclose(lo[:2], [-3.5, -3.5])
    np.testing.assert_allclose([lo[2], hi[2]], [-np.pi, np.pi])  # 2π < 7: kept
    np.testing.assert_allclose([lo[3], hi[3]], [-3.5, 3.5])  # 4π > 7: narrowed
    # a draw from these bounds lands near the seed, not a million metres away
    rng = np.random.default_rng(0)
    draws = rng.uniform(*sampling_bounds(lower, upper, seed), size=(1000, 5))
    assert np.abs(draws[:, 0] - 3.0).max() <= w / 2


@pytest.mark.parametrize(
    "kwargs, message",
    [
        ({"max_width": 0.0}, "max_width must be a positive finite number"),
        ({"max_width": float("nan")}, "max_width must be a positive finite number"),
        ({"max_width": "a"}, "max_width must be a positive finite number"),
        ({"seed_q": [0.0]}, "seed_q must be 2 finite numbers"),
        ({"seed_q": [0.0, np.nan]}, "seed_q must be 2 finite numbers"),
    ],
)
def test_sampling_bounds_refuses_bad_input(kwargs: dict, message: str) -> None:
    with pytest.raises(InvalidArgumentError, match=message):
        sampling_bounds([-1.0, -1.0], [1.0, 1.0], **kwargs)


def _fixed_chain(n: int, wide: bool) -> str:
    links = "".join(f'<link name="l{i}"/>' for i in range(n + 2))
    joints = (
        '<joint name="j" type="revolute"><parent link="l0"/><child link="l1"/>'
        '<axis xyz="0 0 1"/><limit lower="-2" upper="2" effort="1" velocity="1"/></joint>'
    )
    joints += "".join(
        f'<joint name="f{i}" type="fixed"><parent link="l{1 if wide else i + 1}"/>'
        f'<child link="l{i + 2}"/></joint>'
        for i in range(n)
    )
    return f'<robot name="big">{links}{joints}</robot>'


@pytest.mark.parametrize(
    ("n", "wide", "words"),
    [(140_000, True, "at most 10000 are read"), (5000, False, "a chain of")],
)
def test_huge_or_deep_urdf_refused_at_once(n: int, wide: bool, words: str, tmp_path: Path) -> None:
    """140k fixed links (quadratic checks once took minutes) and a 5000-deep chain (which
    crashes Pinocchio's parser) are refused in about a second, naming the limit."""
    import time

    path = tmp_path / "big.urdf"
    path.write_text(_fixed_chain(n, wide))
    t0 = time.perf_counter()
    with pytest.raises(RobotModelError, match=words):
        swarm_ik.load_robot(path)
    assert time.perf_counter() - t0 < 20.0


def test_mimic_multiplier_zero_refused(tmp_path: Path) -> None:
    text = _fixed_chain(0, False).replace(
        "</robot>",
        '<link name="m"/><joint name="jm" type="revolute"><parent link="l1"/>'
        '<child link="m"/><axis xyz="0 1 0"/><limit lower="-1" upper="1" effort="1" '
        'velocity="1"/><mimic joint="j" multiplier="0" offset="0.1"/></joint></robot>',
    )
    path = tmp_path / "mimic0.urdf"
    path.write_text(text)
    with pytest.raises(RobotModelError, match="multiplier=0"):
        swarm_ik.load_robot(path, "m")


def test_too_many_degrees_of_freedom_refused_naming_the_limit(tmp_path: Path) -> None:
    """Pinocchio's Data for 300 joints takes 1.7 GB (nv³ tensors): refused before it is made."""
    links = "".join(f'<link name="l{i}"/>' for i in range(301))
    joints = "".join(
        f'<joint name="j{i}" type="revolute"><parent link="l{i}"/><child link="l{i + 1}"/>'
        '<origin xyz="0 0 0.01"/><axis xyz="0 1 0"/>'
        '<limit lower="-1" upper="1" effort="1" velocity="1"/></joint>'
        for i in range(300)
    )
    path = tmp_path / "j300.urdf"
    path.write_text(f'<robot name="r">{links}{joints}</robot>')
    with pytest.raises(RobotModelError, match="at most 150 are solved"):
        swarm_ik.load_robot(path, "l300")
    robot = swarm_ik.load_robot(path, "l300", locked=[f"j{i}" for i in range(160)])
    assert robot.nq == 140


def test_a_mimic_of_a_joint_not_in_the_file_loads_as_an_independent_joint_with_a_warning(
    tmp_path: Path,
) -> None:
    """With the default frame the follower was dropped without a word (a 1-joint chain); with
    its frame named, the same file was refused, and so was example-robot-data's
    alex_psyonic_hands for every frame (review 98): the follower moves on its own, as
    Pinocchio loads it, and one warning names it, whatever the frame."""
    text = _arm().replace(
        f"{LIMIT}</joint></robot>", f'{LIMIT}<mimic joint="nope"/></joint></robot>'
    )
    path = _write(tmp_path, text)
    for frames in (None, "c"):
        with pytest.warns(RobotModelWarning, match=r"'j2' → 'nope'.*independent joints"):
            robot = swarm_ik.load_robot(path, frames)
        assert robot.nq == 2 and robot.joint_names[-1] == "j2"
