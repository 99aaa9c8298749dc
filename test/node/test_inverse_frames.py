"""Inverse mode's tf tree (issue 21, REP 105), read as tf2's BufferCore reads it: a recorded
run's /joint_states replayed into an inverse-mode session. With a moving base (mobile_pick:
the wheels drive the base 1 m to the table) the root is odom, odom -> base_footprint is the
wheel odometry (the /odom pose, from the wheel speeds of the input), odom -> world the
identity, and /ee_pose (in odom) equals the palm composed along /tf at its stamp and the
palm the simulation published. With a fixed base the root is the robot's root link, as in
simulate mode, and no odom frame exists."""
from __future__ import annotations

import numpy as np
import pytest

from tf_support import Tree, assert_same, pose_of, stamp_of
from youbot_dynamics.node.inverse_session import InverseSession
from youbot_dynamics.node.simulate import SimulationSession
from youbot_dynamics.ros.conversions import to_cdr
from youbot_dynamics.scene.schema import load_scene

RATE = 100.0


def replayed(scene_name: str, seconds: float, **options) -> tuple[dict, dict[int, dict], dict[int, dict], str]:
    """(the inverse session's latched messages, its outputs by stamp (ns) and topic, the
    simulate session's outputs by stamp and topic, the frame of its /ee_pose link) of a
    simulated run's /joint_states fed, one message at a time, to an inverse-mode session of
    the same scene."""
    scene = load_scene(scene_name)
    simulated: dict[int, dict] = {}
    with SimulationSession(scene, RATE) as simulation:
        for _ in range(round(seconds * RATE) + 1):
            outputs = dict(simulation.step())
            simulated[simulation.stamp_ns] = outputs
    inverse_outputs: dict[int, dict] = {}
    with InverseSession(scene, **options) as inverse:
        latched = dict(inverse.latched)
        ee_frame = inverse.frames.prefix + inverse.frames.links.ee_link
        for stamp, outputs in sorted(simulated.items()):
            state = outputs["/joint_states"]
            for topic, message in inverse.joint_state(list(state.name), state.position, state.velocity, stamp):
                header = message.transforms[0].header if topic == "/tf" else message.header
                inverse_outputs.setdefault(stamp_of(header), {})[topic] = message
    return latched, inverse_outputs, simulated, ee_frame


def checked_trees(latched: dict, outputs: dict[int, dict], root: str, ee_frame: str) -> list[tuple[int, Tree]]:
    """The tree at every stamp with a /tf: one root, ``root``, and one parent per frame;
    /ee_pose (the pose of ``ee_frame``) and /odom, where present, equal to the composed
    transforms."""
    trees = []
    for stamp, sample in sorted(outputs.items()):
        if "/tf" not in sample:
            continue
        tree = Tree(latched["/tf_static"], sample["/tf"], stamp)
        tree.check()
        assert tree.roots == [root]
        ee = sample["/ee_pose"]
        assert ee.header.frame_id == root
        assert_same(pose_of(ee.pose), tree.pose(root, ee_frame), f"/ee_pose at {stamp} ns")
        if "/odom" in sample:
            odom = sample["/odom"]
            assert_same(pose_of(odom.pose.pose), tree.pose(odom.header.frame_id, odom.child_frame_id),
                        f"/odom at {stamp} ns")
        trees.append((stamp, tree))
    return trees


@pytest.mark.parametrize("options, root", [({}, "odom"), ({"frame_id": "map", "frame_prefix": "r1/"}, "map")])
def test_a_moving_base_in_inverse_mode_has_one_tree_rooted_at_odom(options: dict, root: str) -> None:
    latched, outputs, simulated, ee_frame = replayed("mobile_pick", 2.5, **options)
    trees = checked_trees(latched, outputs, root, ee_frame)
    assert len(trees) == round(2.5 * RATE) - 1           # a torque (and its /tf) for every middle sample
    prefix = options.get("frame_prefix", "")
    stamp, tree = trees[-1]
    base = tree.pose(prefix + "odom", prefix + "base_footprint")
    # the base drove 1 m towards the table (the wheel odometry of the replayed speeds), and the
    # world stays where the odometry started
    assert base[0, 3] > -0.6 and np.linalg.norm(base[:2, 3] - [-1.569, 0.0]) > 0.9
    np.testing.assert_array_equal(tree.pose(prefix + "odom", prefix + "world"), np.eye(4))
    # the palm in odom is the simulation's (same kinematics, same odometry of the same wheel
    # speeds; measured 0.0 m); without a frame_id both /ee_pose are in odom
    for stamp, _ in trees:
        published = simulated[stamp]["/ee_pose"]
        if not options:
            assert published.header.frame_id == outputs[stamp]["/ee_pose"].header.frame_id == "odom"
            assert_same(pose_of(outputs[stamp]["/ee_pose"].pose), pose_of(published.pose), "palm against simulate")


@pytest.mark.parametrize("scene_name, root", [("arm_ptp", "base_footprint"), ("gripping", "world")])
def test_a_fixed_base_in_inverse_mode_is_rooted_at_the_robots_root_link(scene_name: str, root: str) -> None:
    latched, outputs, simulated, ee_frame = replayed(scene_name, 0.3)
    assert ee_frame == ("yb1_" if scene_name == "gripping" else "") + "gripper_palm_link"
    trees = checked_trees(latched, outputs, root, ee_frame)
    assert trees and all("odom" not in tree.frames for _, tree in trees)
    for stamp, _ in trees:
        assert_same(pose_of(outputs[stamp]["/ee_pose"].pose), pose_of(simulated[stamp]["/ee_pose"].pose),
                    "palm against simulate")


@pytest.mark.parametrize("size", [7, 64])
def test_a_moving_base_batch_gives_what_one_by_one_gives(size: int) -> None:
    """The odometry previewed through a batch (for the torques' /tf and /ee_pose) is the one
    each sample then publishes: batches give the messages of the samples taken one by one, bit
    for bit, across a velocity step (an implausible torque: the estimate restarts inside the
    batch), a NaN (rejected) and a duplicate."""
    scene = load_scene("mobile_pick")
    with SimulationSession(scene, RATE) as simulation:
        states = [dict(simulation.step())["/joint_states"] for _ in range(150)]
    samples = [[list(s.name), np.array(s.position), np.array(s.velocity), stamp_of(s.header), None] for s in states]
    samples[40][2] = samples[40][2] + 30.0 * (np.array(samples[40][0]) == "arm_joint_2")
    samples[80][1] = np.where(np.array(samples[80][0]) == "arm_joint_1", np.nan, samples[80][1])
    samples.insert(120, list(samples[119]))
    samples = [(names, q.tolist(), v.tolist(), stamp, stamp) for names, q, v, stamp, _ in samples]
    expected, outputs = [], []
    with InverseSession(scene) as single, InverseSession(scene) as batched:
        for sample in samples:
            expected += single.joint_states([sample])[0]
        for start in range(0, len(samples), size):
            outputs += batched.joint_states(samples[start:start + size])[0]
        assert single.counters.rejected == batched.counters.rejected
        assert {"implausible_torque", "non_finite", "duplicate"} <= set(single.counters.rejected)
    assert [topic for topic, _ in outputs] == [topic for topic, _ in expected]
    assert [to_cdr(message) for _, message in outputs] == [to_cdr(message) for _, message in expected]
    assert sum(topic == "/tf" for topic, _ in expected) > 100


@pytest.mark.parametrize("size", [1, 5])
@pytest.mark.parametrize("jump, cause", [("back", "backwards"), ("wall_clock", "gap")])
def test_a_moving_base_holds_its_odometry_over_a_break_in_the_stamps(size: int, jump: str, cause: str) -> None:
    """A stream that breaks: a replay restarting its time base (the last 20 samples stamped
    0.4 s earlier) or a publisher switching to wall-clock stamps (1.8e9 s later) in a
    moving-base scene. Inverse mode goes on (the estimate restarts, counted by its cause),
    the odometry holds its pose over the break instead of integrating a negative time (it
    raised a UserInputError before) or the last wheel speeds over decades, and /odom goes on
    from there."""
    scene = load_scene("mobile_pick")
    with SimulationSession(scene, RATE) as simulation:
        states = [dict(simulation.step())["/joint_states"] for _ in range(120)]
    samples = [(list(s.name), list(s.position), list(s.velocity), stamp_of(s.header), stamp_of(s.header))
               for s in states]
    shift = samples[60][3] - samples[100][3] if jump == "back" else 1_800_000_000 * 10**9
    samples = samples[:100] + [(n, q, v, stamp + shift, log) for n, q, v, stamp, log in samples[100:]]
    odom = []
    with InverseSession(scene) as inverse:
        for start in range(0, len(samples), size):
            odom += [message for topic, message in inverse.joint_states(samples[start:start + size])[0]
                     if topic == "/odom"]
        assert inverse.estimator.restarts[cause] >= 1
    assert len(odom) == len(samples)
    x = np.array([m.pose.pose.position.x for m in odom])
    assert np.isfinite(x).all() and x[99] - x[0] > 0.3      # the base drove towards the table (0.46 m)
    # over the break the pose holds (nothing integrated across it)
    assert x[100] == x[99]
    assert np.all(np.diff(x[100:]) >= -1e-12)        # then it drives on, forwards


def test_a_replay_repeating_its_stamps_in_one_batch_gives_the_one_by_one_messages() -> None:
    """A moving base's /tf and /ee_pose of a batch that holds a jump back in time, so that
    some stamps come twice in it (samples 100-149 restamped as 60-109): each torque takes the
    odometry of its own sample, as one by one (keyed by stamp, the later sample's pose went
    to the earlier torque)."""
    scene = load_scene("mobile_pick")
    with SimulationSession(scene, RATE) as simulation:
        states = [dict(simulation.step())["/joint_states"] for _ in range(150)]
    samples = [(list(s.name), list(s.position), list(s.velocity), stamp_of(s.header), stamp_of(s.header))
               for s in states]
    shift = samples[60][3] - samples[100][3]
    samples = samples[:100] + [(n, q, v, stamp + shift, log) for n, q, v, stamp, log in samples[100:]]
    expected, outputs = [], []
    with InverseSession(scene) as single, InverseSession(scene) as batched:
        for sample in samples:
            expected += single.joint_states([sample])[0]
        outputs += batched.joint_states(samples)[0]
    assert [topic for topic, _ in outputs] == [topic for topic, _ in expected]
    assert [to_cdr(message) for _, message in outputs] == [to_cdr(message) for _, message in expected]
