"""``bench path`` reports each greedy peer both ways: by our Pinocchio check and by the peer's
own success flag at every waypoint."""

from __future__ import annotations

import argparse

import numpy as np

import swarm_ik
from swarm_ik.bench.path import judge, peer_tracking, summarize
from swarm_ik.bench.peers import Answer


class _Honest:
    """A peer that answers with the exact joint values of each waypoint and claims success,
    except at the waypoints listed in ``denied`` (where it answers right but says it failed)."""

    def __init__(self, qs: np.ndarray, denied: set[int]) -> None:
        self.qs, self.denied = qs, denied

    def solve(self, pose: np.ndarray, q0: np.ndarray, i: int) -> Answer:
        return Answer(self.qs[i].copy(), i not in self.denied, 0.0, 0.0)


def test_a_peers_claim_is_its_flag_at_every_waypoint_and_is_reported_beside_our_check() -> None:
    robot = swarm_ik.load_robot("ur5")
    rng = np.random.default_rng(3)
    qs = np.array([robot.random_q(rng) for _ in range(4)])
    poses = np.array([robot.fk(q) for q in qs])
    q, claimed, _ = peer_tracking(_Honest(qs, set()), robot, poses)
    assert claimed and judge(robot, poses, q)[0]
    q, claimed, _ = peer_tracking(_Honest(qs, {2}), robot, poses)
    assert not claimed and judge(robot, poses, q)[0]  # (right answers, a denied claim)
    row = dict(arm="ur5", kind="line", ref_exists="", ours_success=1, ours_jump_free=1,
               ours_verified=1, ours_claims_proof=0, proof_rechecked="", tracik_success=1,
               tracik_claimed=0, rtb_success=0, rtb_claimed=1, ours_ms=1.0)  # fmt: skip
    args = argparse.Namespace(waypoints=4, n=1, quick=False)
    text = summarize([row], args, "test")
    line = next(x for x in text.splitlines() if x.startswith("| ur5 | line | 100 % (1/1) | 0 %"))
    assert line.endswith("| 0 % (0/1) | 100 % (1/1) |")
