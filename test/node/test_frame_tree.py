"""The tf check of issue 21 for every scene of config/scenes/ (fixed, kinematic and dynamic
base, composed): the tree tf2's BufferCore would build from /tf_static and the /tf of one
stamp has one root and one parent per frame, and every pose the session publishes equals
the composed transform at the same stamp (<= 1e-9 m and 1e-9 rad), its header frame
honoured: /ee_pose, /ee_poses, /free_bodies, /free_bodies_markers, /scene_markers, /odom and
/base_pose_ground_truth. Against the simulator's own state: the free bodies and the world
geometry relative to the robot's root link are the simulated ones (world poses and the true
base pose), so the tree is not only consistent but true. The moving-base scenes drive 3 s
(base_square has moved 1 m, mobile_pick has reached the table)."""
from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation
from tf_support import Tree, assert_same, pose_of, stamp_of

from youbot_dynamics.io import messages
from youbot_dynamics.node.simulate import SimulationSession
from youbot_dynamics.scene.schema import load_scene, scene_dir

SCENES = sorted(path.stem for path in scene_dir().glob("*.yaml"))
DRIVEN = {"base_square": 3.0, "mobile_pick": 3.0, "base_spin_arm": 3.0}
"""Simulated seconds checked: moving bases drive 3 s, the other scenes 0.5 s."""
def _planar(x: float, y: float, yaw: float) -> np.ndarray:
    pose = np.eye(4)
    pose[:3, :3] = Rotation.from_euler("z", yaw).as_matrix()
    pose[:2, 3] = x, y
    return pose


def _check_sample(session: SimulationSession, latched: dict, sample: dict) -> None:
    stamp = session.stamp_ns
    tree = Tree(latched["/tf_static"], sample["/tf"], stamp)
    tree.check()
    prefix, links = session.frames.prefix, session.frames.links
    for topic, names in (("/ee_pose", [links.ee_link]), ("/ee_poses", links.ee_links),
                         ("/free_bodies", [spec.body.name for spec in session.scene.free_bodies])):
        if topic not in sample:
            continue
        message = sample[topic]
        assert stamp_of(message.header) == stamp
        poses = [message.pose] if topic == "/ee_pose" else message.poses
        assert len(poses) == len(names)
        for name, pose in zip(names, poses):
            assert_same(pose_of(pose), tree.pose(message.header.frame_id, prefix + name), f"{topic} {name}")
    for topic in ("/odom", "/base_pose_ground_truth"):
        if topic in sample:
            message = sample[topic]
            assert_same(pose_of(message.pose.pose), tree.pose(message.header.frame_id, message.child_frame_id), topic)
    _check_world_things(session, tree, latched, sample)


def _check_world_things(session: SimulationSession, tree: Tree, latched: dict, sample: dict) -> None:
    """The free bodies (and their markers) and the world geometry relative to the robot's
    root link, from the tree, equal the simulation's: world poses composed with the true
    base pose (identity for a fixed base: the root link is the world's origin)."""
    snapshot, base = session.snapshot, session.frames.prefix + session.robot.root_link
    world_base = np.eye(4) if snapshot.base is None else _planar(*snapshot.base[:3])
    if "/base_pose_ground_truth" in sample:
        assert_same(pose_of(sample["/base_pose_ground_truth"].pose.pose), world_base, "/base_pose_ground_truth")
    in_base = np.linalg.inv(world_base)
    geometry = {g.name: g for g in session.scene.geometries}
    for name, world_pose in snapshot.bodies.items():
        assert_same(tree.pose(base, session.frames.prefix + name), in_base @ world_pose, f"/tf {name}")
    markers = [*(m for m in sample.get("/free_bodies_markers", messages.marker_array([])).markers),
               *(m for m in latched.get("/scene_markers", messages.marker_array([])).markers)]
    for marker in markers:
        g = geometry[marker.ns]
        owner = snapshot.bodies[g.name] if g.owner == "body" else np.eye(4) if g.owner == "world" else None
        local = next(m for m in messages.shape_markers(0, "", g.name, g.shape, g.placement, (1, 1, 1, 1))
                     if m.id == marker.id)
        in_tree = tree.pose(base, marker.header.frame_id) @ pose_of(marker.pose)
        if owner is None:      # on a link: the link's frame
            assert_same(in_tree, tree.pose(base, session.frames.prefix + g.owner_name) @ pose_of(local.pose),
                         f"marker {g.name}")
        else:
            assert_same(in_tree, in_base @ owner @ pose_of(local.pose), f"marker {g.name}")


def _run(scene_name: str, seconds: float, **options) -> None:
    scene = load_scene(scene_name)
    rate = scene.outputs.rate
    with SimulationSession(scene, rate, **options) as session:
        latched = dict(session.latched)
        for k in range(round(seconds * rate) + 1):
            sample = dict(session.step())
            assert session.failure is None, session.failure
            if k % 5 == 0 or k == round(seconds * rate):
                _check_sample(session, latched, sample)
        assert session.t == pytest.approx(seconds)


@pytest.mark.parametrize("scene_name", SCENES)
def test_one_tree_and_every_pose_topic_equals_its_transform(scene_name: str) -> None:
    _run(scene_name, DRIVEN.get(scene_name, 0.5))


@pytest.mark.parametrize("scene_name, options", [
    ("mobile_pick", {"frame_id": "map", "frame_prefix": "r1/"}),
    ("gripping", {"frame_id": "world", "frame_prefix": "r1/"}),
    ("base_square", {"frame_prefix": "r2/"})])
def test_the_tree_holds_with_a_root_frame_and_a_prefix(scene_name: str, options: dict) -> None:
    _run(scene_name, 0.4, **options)


@pytest.mark.parametrize("scene_name, frame_id", [("mobile_pick", "base_footprint"), ("mobile_pick", "world"),
                                                  ("gripping", "yb1_arm_link_5"), ("gripping", "sphere")])
def test_a_root_frame_inside_the_tree_is_refused(scene_name: str, frame_id: str) -> None:
    with pytest.raises(Exception, match="frame_id|rename") as caught:
        SimulationSession(load_scene(scene_name), 50.0, frame_id=frame_id)
    assert frame_id in str(caught.value)


def test_rerun_recording_holds_the_same_tree(tmp_path) -> None:
    """mobile_pick's .rrd: odom -> base_footprint and odom -> world per sample equal to /tf
    (float32), the end effector in odom equal to /ee_pose, the sphere under world and the
    table in world: the recording carries the tree's numbers, not the base-relative ones."""
    from test_viewers import rerun_rows
    scene, rate = load_scene("mobile_pick"), 50.0
    with SimulationSession(scene, rate, rrd_path=tmp_path / "run.rrd") as session:
        samples = [dict(session.step()) for _ in range(101)]
    temporal, static = rerun_rows(tmp_path / "run.rrd")
    last = samples[-1]
    edges = {(t.header.frame_id, t.child_frame_id): t.transform for t in last["/tf"].transforms}
    for child in ("base_footprint", "world"):
        row = max(temporal[f"/base_frames/{child}"], key=lambda r: r["sim_time"])
        assert (row["Transform3D:parent_frame"], row["Transform3D:child_frame"]) == (["odom"], [child])
        moved = edges[("odom", child)].translation
        assert np.array_equal(row["Transform3D:translation"][0], np.float32([moved.x, moved.y, moved.z]))
    ee = max(temporal["/ee/position"], key=lambda r: r["sim_time"])
    palm = last["/ee_pose"].pose.position
    assert np.array_equal(ee["Points3D:positions"][0], np.float32([palm.x, palm.y, palm.z]))
    assert palm.x > -1.0          # the palm over the table in odom, 1 m from where the base started
    sphere = max(temporal["/free_bodies/sphere"], key=lambda r: r["sim_time"])
    assert sphere["Transform3D:parent_frame"] == ["world"]
    assert static["/geometry/table"][0]["CoordinateFrame:frame"] == ["world"]
    assert static["/ee/position"][0]["CoordinateFrame:frame"] == ["odom"]


def test_mobile_picks_robot_description_has_one_root_for_robot_state_publisher() -> None:
    """The composed URDF of a moving-base scene is rooted at base_footprint (no world link
    welded to it), so robot_state_publisher's tree of it joins odom -> base_footprint."""
    from xml.etree import ElementTree
    root = ElementTree.fromstring(load_scene("mobile_pick").urdf)
    links = {link.get("name") for link in root.iter("link")}
    children = {joint.find("child").get("link") for joint in root.iter("joint")}
    assert links - children == {"base_footprint"}


@pytest.mark.parametrize("scene_name", ["arm_ptp", "mobile_pick"])
def test_frames_of_many_samples_equal_each_samples_frames(scene_name: str) -> None:
    """LinkFrames.at_many (one compiled pass for them all) gives each sample's frames to the
    bit."""
    from youbot_dynamics.node.frames import LinkFrames
    robot = load_scene(scene_name).robot
    links = LinkFrames(robot)
    rng = np.random.default_rng(4)
    q = rng.uniform(-1.0, 1.0, (6, robot.nq))
    batch = links.at_many(q)
    assert len(batch) == len(q) and len(list(batch)) == len(q)
    tail = batch[2:]
    assert len(tail) == len(q) - 2 and np.array_equal(tail[0].ee, batch[2].ee) and np.array_equal(tail.poses,
                                                                                                   batch.poses[2:])
    for many, one in zip([*batch, batch[-1]], [*(links.at(row) for row in q), links.at(q[-1])]):
        assert many.edges == one.edges and many.ee_index == one.ee_index and many.ee_count == one.ee_count
        assert np.array_equal(many.link_poses, one.link_poses) and np.array_equal(many.ee, one.ee)


def test_frames_of_many_samples_refuse_rows_of_another_size() -> None:
    """The compiled kinematics pass reads q unchecked: rows not of nq values, or not rows,
    are a UserInputError naming the shape needed."""
    from youbot_dynamics.errors import UserInputError
    from youbot_dynamics.node.frames import LinkFrames
    links = LinkFrames(load_scene("arm_ptp").robot)
    for q in (np.zeros((3, links.robot.nq + 1)), np.zeros(links.robot.nq)):
        with pytest.raises(UserInputError, match="nq"):
            links.at_many(q)


def test_ee_rows_of_a_batch_equal_each_samples_composition() -> None:
    """ee_rows composes a moving base's odometry pose with every sample's end effectors in one
    call; each row equals, to the bit, end_effector_row's product of that sample alone (the
    reference the Rerun sample took one by one) and the kinematics' own rows without a base.
    A batch that fell back to LinkFrames.at (no compiled form) carries the same rows."""
    from youbot_dynamics.node.frames import LinkFrames, end_effector_row, ee_rows, planar_row
    links = LinkFrames(load_scene("mobile_pick").robot)
    rng = np.random.default_rng(11)
    q = rng.uniform(-1.0, 1.0, (7, links.robot.nq))
    batch = links.at_many(q)
    base = np.array([[planar_row(*rng.uniform(-2.0, 2.0, 3)), planar_row(0.0, 0.0, 0.0)] for _ in q])
    composed = ee_rows(batch, base)
    for k, sample in enumerate(batch):
        assert np.array_equal(composed[k, sample.ee_index], end_effector_row(sample, base[k]))
        assert np.array_equal(ee_rows(batch)[k], sample.ee)
    links._tree = None                                     # the row-by-row fallback
    fallback = links.at_many(q)
    assert np.array_equal(fallback.poses, batch.poses) and fallback.moving == batch.moving


def test_pose_matrices_keep_matrix_from_quaternion_roundings() -> None:
    """The compiled pose_matrices gives, bit for bit, the rotation of the numpy formula
    (lie.matrix_from_quaternion, unnormalised quaternions included) and the translation, in
    any batch shape, and matches scipy's rotation to round-off."""
    from youbot_dynamics.model.lie import matrix_from_quaternion
    from youbot_dynamics.node.frames import pose_matrices

    rows = np.random.default_rng(7).normal(size=(3, 5, 7)) * [1, 1, 1, 2, 2, 2, 2]
    matrices = pose_matrices(rows)
    assert matrices.shape == (3, 5, 4, 4)
    assert np.array_equal(matrices[..., :3, :3], matrix_from_quaternion(rows[..., 3:]))
    assert np.array_equal(matrices[..., :3, 3], rows[..., :3])
    assert np.array_equal(matrices[..., 3, :], np.broadcast_to([0.0, 0.0, 0.0, 1.0], (3, 5, 4)))
    assert pose_matrices(rows[0, 0]).shape == (4, 4)
    reference = Rotation.from_quat(rows[..., 3:].reshape(-1, 4)).as_matrix()     # measured 4e-16, bound 1e-14
    assert np.abs(matrices[..., :3, :3].reshape(-1, 3, 3) - reference).max() < 1e-14
