"""What a viewer sees of the gripping scene (two youBots composed into one model, a sphere,
a table), through the session layer without DDS: /ee_pose and /ee_poses name real links
(checked against Pinocchio's forward kinematics at the logged joint positions), every
logged time is on the step grid in integer nanoseconds, the Rerun recording draws the
sphere in a named frame under ``world`` and the table, and the MCAP carries both as
visualization_msgs/MarkerArray."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pinocchio as pin
import pyarrow as pa
import pytest
import yaml
from mcap.reader import make_reader
from rerun.chunk import RrdReader

from bag_support import read_mcap
from youbot_dynamics.node.simulate import SimulationSession
from youbot_dynamics.scene.schema import load_scene
from youbot_dynamics.sim.simulator import Simulator

RATE = 100.0
STEP_NS = 10_000_000
N = 151                    # samples at t = 0, 0.01, ..., 1.5 s: youBot 1's arm starts turning



def stamp_ns(message: object) -> int:
    return message.header.stamp.sec * 1_000_000_000 + message.header.stamp.nanosec


@pytest.fixture(scope="module")
def gripping(tmp_path_factory: pytest.TempPathFactory) -> dict:
    out = tmp_path_factory.mktemp("gripping")
    scene = load_scene("gripping")
    with SimulationSession(scene, RATE, mcap_path=out / "run.mcap", rrd_path=out / "run.rrd") as session:
        published = [dict(session.step()) for _ in range(N)]
        topics = session.topics
    with (out / "run.mcap").open("rb") as stream:
        summary = make_reader(stream).get_summary()
    qos = {channel.topic: yaml.safe_load(channel.metadata["offered_qos_profiles"])[0]
           for channel in summary.channels.values()}
    return {"scene": scene, "published": published, "topics": topics, "mcap": read_mcap(out / "run.mcap"),
            "qos": qos, "rrd": out / "run.rrd"}


def rerun_rows(path: Path) -> tuple[dict[str, list[dict]], dict[str, list[dict]]]:
    """Temporal and static rows per entity of a .rrd, ``sim_time`` as integer ns."""
    temporal: dict[str, list[dict]] = {}
    static: dict[str, list[dict]] = {}
    for chunk in RrdReader(path).stream():
        batch = chunk.to_record_batch()
        columns = batch.to_pydict()
        if "sim_time" in columns:
            columns["sim_time"] = batch.column("sim_time").cast(pa.int64()).to_pylist()
        rows = [dict(zip(columns, values)) for values in zip(*columns.values())]
        (static if chunk.is_static else temporal).setdefault(chunk.entity_path, []).extend(rows)
    return temporal, static


def palm_poses(scene, names: list[str], q: list[float]) -> dict[str, pin.SE3]:
    """World poses of both palms by Pinocchio's forward kinematics at q given by joint name
    (the locked joints, also on /joint_states, are folded into the scene's reduced model)."""
    robot = scene.robot
    config = pin.neutral(robot.model)
    for name, value in zip(names, q, strict=True):
        if name in robot.locked:
            assert value == robot.locked[name]
            continue
        joint = robot.model.joints[robot.model.getJointId(name)]
        config[joint.idx_q] = value
    data = robot.model.createData()
    pin.framesForwardKinematics(robot.model, data, config)
    return {link: data.oMf[robot.model.getFrameId(link)]
            for link in ("yb1_gripper_palm_link", "yb2_gripper_palm_link")}


def assert_pose(pose, expected: pin.SE3) -> None:
    """position and orientation of a geometry_msgs/Pose equal ``expected``: measured 6.7e-16 m
    and 4.4e-16 (quaternion, up to sign) over the run; bound 1e-12, a margin of 1500."""
    position = [pose.position.x, pose.position.y, pose.position.z]
    quaternion = np.array([pose.orientation.x, pose.orientation.y, pose.orientation.z, pose.orientation.w])
    reference = pin.Quaternion(expected.rotation).coeffs()            # x, y, z, w
    assert position == pytest.approx(expected.translation, abs=1e-12)
    assert min(np.abs(quaternion - reference).max(), np.abs(quaternion + reference).max()) < 1e-12


def test_ee_pose_is_youbot_1s_palm_and_ee_poses_both_palms(gripping) -> None:
    """In the MCAP, every /ee_pose is youBot 1's palm and /ee_poses both palms, in the world
    frame, at the q of /joint_states of the same stamp; the palm moves (not the identity)."""
    assert gripping["topics"] == ("/clock", "/joint_states", "/ee_pose", "/ee_poses", "/free_bodies",
                                  "/free_bodies_markers", "/wrist_wrench",
                                  *(f"/contacts/{pair}/sphere" for pair in ("table", "yb1_plate", "yb2_plate",
                                                                             "yb1_pad_l", "yb1_pad_r", "yb2_pad_l",
                                                                             "yb2_pad_r")),
                                  "/tf", "/diagnostics")
    logged = gripping["mcap"]
    assert len(logged["/ee_pose"]) == len(logged["/ee_poses"]) == len(logged["/joint_states"]) == N
    for state, ee, both in zip(logged["/joint_states"], logged["/ee_pose"], logged["/ee_poses"]):
        assert stamp_ns(state) == stamp_ns(ee) == stamp_ns(both)
        assert ee.header.frame_id == both.header.frame_id == "world"
        palms = palm_poses(gripping["scene"], state.name, state.position)
        assert_pose(ee.pose, palms["yb1_gripper_palm_link"])
        assert_pose(both.poses[0], palms["yb1_gripper_palm_link"])
        assert_pose(both.poses[1], palms["yb2_gripper_palm_link"])
    first, last = logged["/ee_pose"][0].pose.position, logged["/ee_pose"][-1].pose.position
    # upright arm: the palm 0.665 m above the floor, above youBot 1's arm base; then it turns away
    assert [first.x, first.z] == pytest.approx([-0.371, 0.665], abs=1e-3)
    assert np.hypot(last.x - first.x, last.y - first.y) > 0.01


def test_diagnostics_name_the_end_effector_links(gripping) -> None:
    session = SimulationSession(gripping["scene"], RATE)
    try:
        (_, array), = session.diagnostics(1.0)
    finally:
        session.close()
    values = {kv.key: kv.value for kv in array.status[0].values}
    assert values["ee_link"] == "yb1_gripper_palm_link"
    assert values["ee_links"] == "yb1_gripper_palm_link,yb2_gripper_palm_link"


def test_offline_simulator_records_youbot_1s_palm_too() -> None:
    """The simulator's own end-effector pose (Snapshot.ee_pose, recorded ee_position) is the
    first robot's palm, not ``world``."""
    scene = load_scene("gripping")
    simulator = Simulator(scene)
    robot = simulator.robot
    palms = palm_poses(scene, list(robot.joint_names), simulator.q.tolist())
    assert simulator.snapshot().ee_pose == pytest.approx(palms["yb1_gripper_palm_link"].homogeneous, abs=1e-12)


def test_ee_link_parameter_chooses_youbot_2s_palm() -> None:
    scene = load_scene("gripping")
    with SimulationSession(scene, RATE, ee_link="yb2_gripper_palm_link") as session:
        outputs = dict(session.step())
    palms = palm_poses(scene, outputs["/joint_states"].name, outputs["/joint_states"].position)
    assert_pose(outputs["/ee_pose"].pose, palms["yb2_gripper_palm_link"])
    assert_pose(outputs["/ee_poses"].poses[0], palms["yb1_gripper_palm_link"])


def test_every_logged_time_is_on_the_step_grid(gripping) -> None:
    """MCAP stamps and log times and every Rerun sim_time are k * 10 ms exactly (integer ns)."""
    grid = [k * STEP_NS for k in range(N)]
    for topic in ("/clock", "/joint_states", "/ee_pose", "/free_bodies", "/free_bodies_markers"):
        messages = gripping["mcap"][topic]
        stamps = [m.clock.sec * 10**9 + m.clock.nanosec if topic == "/clock" else
                  stamp_ns(m.markers[0] if topic == "/free_bodies_markers" else m) for m in messages]
        assert stamps == grid, topic
    temporal, _ = rerun_rows(gripping["rrd"])
    for entity, rows in temporal.items():
        times = sorted({row["sim_time"] for row in rows})
        assert times == grid, entity


def test_rerun_draws_the_sphere_under_world_and_the_table(gripping) -> None:
    """The sphere: a static ellipsoid in the named frame ``sphere``, moved by one transform
    world -> sphere per sample equal to /free_bodies (float32); the table: a static box
    in the frame ``world`` where the scene puts it; the finger pads in their links'
    frames; the URDF itself rooted at ``world``."""
    temporal, static = rerun_rows(gripping["rrd"])
    (sphere,) = static["/free_bodies/sphere"]
    assert sphere["CoordinateFrame:frame"] == ["sphere"]
    assert sphere["Ellipsoids3D:half_sizes"] == [pytest.approx([0.025] * 3)]
    rows = sorted(temporal["/free_bodies/sphere"], key=lambda row: row["sim_time"])
    assert {(tuple(r["Transform3D:parent_frame"]), tuple(r["Transform3D:child_frame"])) for r in rows} == \
        {(("world",), ("sphere",))}
    poses = [m.poses[0].position for m in gripping["mcap"]["/free_bodies"]]
    assert np.array_equal([r["Transform3D:translation"][0] for r in rows],
                          np.float32([[p.x, p.y, p.z] for p in poses]))
    (table,) = static["/geometry/table"]
    assert table["CoordinateFrame:frame"] == ["world"]
    assert (table["Boxes3D:centers"], table["Boxes3D:half_sizes"]) == \
        ([pytest.approx([0.0, 0.0, 0.365])], [pytest.approx([0.15, 0.15, 0.005])])
    assert static["/geometry/yb2_pad_l"][0]["CoordinateFrame:frame"] == ["yb2_gripper_finger_link_l"]
    assert [r["CoordinateFrame:frame"] for r in static["/composed"] if "CoordinateFrame:frame" in r] == [["world"]]


def test_mcap_markers_draw_the_sphere_and_latch_the_scene(gripping) -> None:
    """/free_bodies_markers: per sample one sphere marker (diameter 0.05 m) at the
    /free_bodies pose in ``world``; /scene_markers: once, latched (transient local, depth 1,
    in the channel's offered QoS), the table in ``world`` and the plates and pads in their
    links' frames (frame-locked)."""
    logged = gripping["mcap"]
    for array, poses in zip(logged["/free_bodies_markers"], logged["/free_bodies"], strict=True):
        (marker,) = array.markers
        assert (marker.header.frame_id, marker.ns, marker.type) == ("world", "sphere", marker.SPHERE)
        assert [marker.scale.x, marker.scale.y, marker.scale.z] == pytest.approx([0.05] * 3)
        assert marker.pose == poses.poses[0]
    (scene,) = logged["/scene_markers"]
    by_name = {m.ns: m for m in scene.markers}
    assert set(by_name) == {"table", "yb1_plate", "yb2_plate", "yb1_pad_l", "yb1_pad_r", "yb2_pad_l", "yb2_pad_r"}
    table = by_name["table"]
    assert (table.header.frame_id, table.type, table.frame_locked) == ("world", table.CUBE, False)
    assert [table.pose.position.z, table.scale.x, table.scale.z] == pytest.approx([0.365, 0.3, 0.01])
    pad = by_name["yb1_pad_l"]
    assert (pad.header.frame_id, pad.frame_locked) == ("yb1_gripper_finger_link_l", True)
    assert [pad.pose.position.y, pad.pose.position.z] == pytest.approx([-0.0145, 0.02])
    qos = gripping["qos"]
    assert (qos["/scene_markers"]["durability"], qos["/scene_markers"]["depth"]) == ("transient_local", 1)
    assert qos["/free_bodies_markers"]["durability"] == "volatile"
