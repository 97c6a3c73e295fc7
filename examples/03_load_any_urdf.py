"""Load any URDF: from a file path, or by name from ``example-robot-data``.

``swarm_ik.load_robot`` reduces the URDF to the serial chain from the root to the end-effector
frame; joints off that chain (grippers, other arms) are locked at their neutral value.  This
script writes a small 3-joint arm (two revolute joints and a prismatic one) to a temporary
file and solves a position-only target with it, then loads the UR5 from example-robot-data
both by name and by its file path with a chosen end-effector frame.

Run: ``python examples/03_load_any_urdf.py``.
"""

from __future__ import annotations

import tempfile
from pathlib import Path

import numpy as np

import swarm_ik
from swarm_ik.robot import example_robot_data_dir

ARM_URDF = """<?xml version="1.0"?>
<robot name="scara_like">
  <link name="base"/>
  <link name="arm1"/>
  <link name="arm2"/>
  <link name="quill"/>
  <link name="tip"/>
  <joint name="shoulder" type="revolute"><parent link="base"/><child link="arm1"/>
    <origin xyz="0 0 0.4"/><axis xyz="0 0 1"/>
    <limit lower="-2.5" upper="2.5" effort="10" velocity="2"/></joint>
  <joint name="elbow" type="revolute"><parent link="arm1"/><child link="arm2"/>
    <origin xyz="0.35 0 0"/><axis xyz="0 0 1"/><dynamics damping="0.05"/>
    <limit lower="-2.5" upper="2.5" effort="10" velocity="2"/></joint>
  <joint name="lift" type="prismatic"><parent link="arm2"/><child link="quill"/>
    <origin xyz="0.3 0 0"/><axis xyz="0 0 -1"/>
    <limit lower="0" upper="0.3" effort="10" velocity="0.5"/></joint>
  <joint name="tool" type="fixed"><parent link="quill"/><child link="tip"/>
    <origin xyz="0 0 -0.05"/></joint>
</robot>
"""


def main() -> None:
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "scara_like.urdf"
        path.write_text(ARM_URDF)
        arm = swarm_ik.load_robot(path, ee_frame="tip")
        print(arm, "joint kinds:", arm.joint_kinds)
        target = arm.fk(np.array([0.4, -0.9, 0.12]))
        # 3 joints cannot set a full orientation: ask for the position only (w_rot=0)
        problem = swarm_ik.IKProblem(arm, target, w_rot=0.0)
        res = swarm_ik.solve(problem, seed=0)
        print(
            f"position-only target: success={res.success}, "
            f"position error {res.position_error:.2e} m, q = {np.round(res.q, 4).tolist()}"
        )

    by_name = swarm_ik.load_robot("ur5")
    print("\nby name:", by_name)
    ur5_file = example_robot_data_dir() / "ur_description" / "urdf" / "ur5_robot.urdf"
    by_path = swarm_ik.load_robot(ur5_file, ee_frame="wrist_3_link")
    print("by path:", by_path, "from", ur5_file.name)
    q = np.array([0.2, -1.2, 1.4, -0.6, 1.1, 0.3])
    res = swarm_ik.solve(swarm_ik.IKProblem(by_path, by_path.fk(q)), seed=0)
    print(
        f"UR5 to wrist_3_link: success={res.success}, position error "
        f"{res.position_error:.2e} m, rotation error {res.rotation_error:.2e} rad"
    )

    try:  # a wrong frame name is refused with the list of valid ones
        swarm_ik.load_robot("ur5", ee_frame="tool1")
    except swarm_ik.UnknownNameError as exc:
        print("\nrefused:", str(exc)[:110], "...")


if __name__ == "__main__":
    main()
