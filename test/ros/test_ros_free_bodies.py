"""Free bodies through the dynamics node: the ball_drop sphere (a scene without a robot) on
/tf and /free_bodies, in the MCAP and the Rerun recording, checked against the simulator's
own offline run; contact events in /diagnostics; box_slide's rotated box on /tf."""
from __future__ import annotations

import importlib.util
from pathlib import Path

import numpy as np
import pytest
from rerun.chunk import RrdReader

from bag_support import read_mcap
from ros_support import Collector, diagnostic_values, ros_context, spinning, stamp_ns, wait_until

pytestmark = [pytest.mark.ros, pytest.mark.timeout(240)]

from rclpy.node import Node  # noqa: E402
from rclpy.parameter import Parameter  # noqa: E402

from youbot_dynamics.errors import UserInputError  # noqa: E402
from youbot_dynamics.model.lie import quaternion_from_matrix  # noqa: E402
from youbot_dynamics.node.inverse_session import InverseSession  # noqa: E402
from youbot_dynamics.node.simulate import SimulationSession  # noqa: E402
from youbot_dynamics.ros.conversions import from_rclpy, rclpy_class  # noqa: E402
from youbot_dynamics.ros.dynamics_node import DynamicsNode  # noqa: E402
from youbot_dynamics.ros.qos import LATCHED  # noqa: E402
from youbot_dynamics.scene.schema import load_scene  # noqa: E402
from youbot_dynamics.sim.simulator import Simulator  # noqa: E402

RATE, DURATION = 100.0, 1.0
STEP_NS = 10_000_000
N = 101                                  # samples at t = 0, 0.01, ..., 1.0 s
TOPICS = {"/free_bodies": "geometry_msgs/msg/PoseArray", "/clock": "rosgraph_msgs/msg/Clock",
          "/diagnostics": "diagnostic_msgs/msg/DiagnosticArray",
          "/free_bodies_markers": "visualization_msgs/msg/MarkerArray"}



def rerun_rows(path: Path) -> tuple[dict[str, list[dict]], dict[str, list[dict]]]:
    """Temporal and static rows per entity of a .rrd."""
    temporal: dict[str, list[dict]] = {}
    static: dict[str, list[dict]] = {}
    for chunk in RrdReader(path).stream():
        columns = chunk.to_record_batch().to_pydict()
        rows = [dict(zip(columns, values)) for values in zip(*columns.values())]
        (static if chunk.is_static else temporal).setdefault(chunk.entity_path, []).extend(rows)
    return temporal, static


def xyz(point) -> list[float]:
    return [point.x, point.y, point.z]


def xyzw(quaternion) -> list[float]:
    return [quaternion.x, quaternion.y, quaternion.z, quaternion.w]


@pytest.fixture(scope="module")
def ball_drop_run(tmp_path_factory: pytest.TempPathFactory) -> dict:
    """The node on ball_drop for 1 s of simulated time at 100 Hz, one integrator run over
    the whole second (solve_horizon = duration), with a subscriber on its topics."""
    out = tmp_path_factory.mktemp("ball_drop")
    paths = {"mcap_path": str(out / "run.mcap"), "rrd_path": str(out / "run.rrd")}
    with ros_context(20) as (context, _):
        node = DynamicsNode(context=context, parameter_overrides=[Parameter(k, value=v) for k, v in dict(
            scene="ball_drop", publish_rate=RATE, duration=DURATION, solve_horizon=DURATION, time_scale=0.0,
            wait_for_subscribers=1, **paths).items()])
        collector = Collector(context, TOPICS)
        with spinning(context, node, collector) as executor:
            wait_until(lambda: node.finished, what="the node to finish")
            wait_until(lambda: all(collector.count(topic) == N for topic in ("/free_bodies", "/free_bodies_markers",
                                                                             "/clock"))
                       and any(float(diagnostic_values(m)["sim_time"]) == DURATION
                               for m in collector.messages("/diagnostics")),
                       what=f"{N} samples on each topic and the closing /diagnostics")
            # a subscriber that comes after the run still gets the latched /scene_markers
            late, latched = Node("late", context=context), []
            late.create_subscription(rclpy_class("visualization_msgs/msg/MarkerArray"), "/scene_markers",
                                     lambda message: latched.append(from_rclpy(message)), LATCHED)
            executor.add_node(late)
            wait_until(lambda: latched, what="the latched /scene_markers")
        received = {topic: collector.messages(topic) for topic in TOPICS}
        received["/scene_markers"] = latched
        published = set(node.publishers_)
    # The simulator alone, from the same initial state over the same times.
    offline = Simulator(load_scene("ball_drop")).run(np.arange(N) * STEP_NS / 1e9)
    return {"received": received, "published": published, "offline": offline,
            "mcap": read_mcap(Path(paths["mcap_path"])), "rrd": Path(paths["rrd_path"])}


def offline_positions(result) -> np.ndarray:
    """(N, 3) ball positions (m, world frame) of the offline run (outputs hold each body's
    pose in its ``pose`` block: x, y, z, qx, qy, qz, qw)."""
    names = list(result.layout.names)
    return result.x[:, [names.index(f"pose[ball.{axis}]") for axis in "xyz"]]


def test_tf_carries_the_sphere_as_the_simulator_moves_it(ball_drop_run) -> None:
    """/tf in the MCAP: one transform world -> ball per sample, equal to the offline run at
    the same times, bit for bit; the ball fell, bounced and rose again."""
    tf = ball_drop_run["mcap"]["/tf"]
    expected = offline_positions(ball_drop_run["offline"])
    assert len(tf) == N
    for k, message in enumerate(tf):
        (transform,) = message.transforms
        assert (transform.header.frame_id, transform.child_frame_id) == ("world", "ball")
        assert stamp_ns(transform) == k * STEP_NS
        assert xyz(transform.transform.translation) == expected[k].tolist()
        assert xyzw(transform.transform.rotation) == [0.0, 0.0, 0.0, 1.0]
    z = expected[:, 2]
    bounce = int(np.argmin(z))
    # falls from 1 m (impact at sqrt(2 m / g) = 0.4515 s) and rises to e^2 = 0.64 of the drop height
    assert z[0] == 1.025 and bounce in (45, 46) and np.all(np.diff(z[:bounce]) < 0)
    assert np.max(z[bounce:]) - 0.025 == pytest.approx(0.64, rel=0.01)
    assert ball_drop_run["mcap"]["/tf_static"][0].transforms == []             # no robot: no links


def test_free_bodies_topic_carries_the_same_poses(ball_drop_run) -> None:
    """/free_bodies over ROS equals its MCAP copy and /tf; no /joint_states or /ee_pose."""
    received, logged, tf = (ball_drop_run["received"]["/free_bodies"], ball_drop_run["mcap"]["/free_bodies"],
                            ball_drop_run["mcap"]["/tf"])
    tf_topics = {"/tf", "/tf_static"} if importlib.util.find_spec("tf2_msgs") else set()   # built by `make`
    assert ball_drop_run["published"] == {"/clock", "/free_bodies", "/free_bodies_markers", "/scene_markers",
                                          "/contacts/floor/ball", "/diagnostics", *tf_topics}  # no robot
    assert not {"/joint_states", "/ee_pose"} & set(ball_drop_run["mcap"])
    assert len(received) == len(logged) == N
    for got, kept, transform in zip(received, logged, tf):
        (pose,), (frame,) = got.poses, transform.transforms
        assert got.header.frame_id == "world" and stamp_ns(got) == stamp_ns(kept) == stamp_ns(frame)
        assert xyz(pose.position) == xyz(kept.poses[0].position) == xyz(frame.transform.translation)
        assert xyzw(pose.orientation) == xyzw(frame.transform.rotation)
    clocks = [m.clock.sec * 10**9 + m.clock.nanosec for m in ball_drop_run["received"]["/clock"]]
    assert clocks == [stamp_ns(m) for m in received]


def test_diagnostics_count_the_contact_events(ball_drop_run) -> None:
    """The last /diagnostics counts the offline run's events (touch, maximum compression,
    separation of the first bounce) and names the body."""
    values = diagnostic_values(ball_drop_run["received"]["/diagnostics"][-1])
    events = ball_drop_run["offline"].contact_events
    assert [e.kind for e in events] == ["touch", "compression", "separation"]
    assert values["free_bodies"] == "ball"
    assert int(values["contact.events"]) == 3
    assert {kind: int(values[f"contact.events.{kind}"]) for kind in ("touch", "compression", "separation")} == \
        {"touch": 1, "compression": 1, "separation": 1}
    assert values["contact.last_event"].startswith(f"separation floor/ball at t = {events[-1].time:.6f} s")
    assert float(values["sim_time"]) == DURATION


def test_rerun_shows_the_sphere_and_no_robot(ball_drop_run) -> None:
    """The .rrd: the sphere as a static ellipsoid of its radius and one transform per sample
    on sim_time, equal to the offline positions (float32); no URDF, no joint series."""
    temporal, static = rerun_rows(ball_drop_run["rrd"])
    assert set(temporal) == {"/free_bodies/ball"}
    assert "/tf_static" not in static and not any(entity.startswith("/none") for entity in static)
    (shape,) = static["/free_bodies/ball"]
    assert np.array_equal(shape["Ellipsoids3D:half_sizes"], np.float32([[0.025] * 3]))
    rows = sorted(temporal["/free_bodies/ball"], key=lambda row: row["sim_time"])
    assert len(rows) == N
    assert [round(row["sim_time"].total_seconds() * 100) for row in rows] == list(range(N))
    expected = offline_positions(ball_drop_run["offline"]).astype(np.float32)
    assert np.array_equal([row["Transform3D:translation"][0] for row in rows], expected)


def test_box_slide_publishes_the_rotated_box(tmp_path: Path) -> None:
    """box_slide (constraint stepper), without ROS: /free_bodies and /tf (MCAP) carry the
    box's pose, equal to the simulator's at the same time (same blocks of 5 samples), and
    the box slides down the incline."""
    scene = load_scene("box_slide")
    with SimulationSession(scene, RATE, samples_per_solve=5, mcap_path=tmp_path / "box.mcap") as session:
        published = [dict(session.step())["/free_bodies"] for _ in range(21)]
    reference = Simulator(scene)
    poses = [reference.snapshot().bodies["box"]] + \
        [s.bodies["box"] for k in range(4) for s in reference.advance_through((5 * k + 1 + np.arange(5)) * 0.01)]
    tf = read_mcap(tmp_path / "box.mcap")["/tf"]
    for message, (transform,), pose in zip(published, (m.transforms for m in tf), poses, strict=True):
        (body,) = message.poses
        assert (transform.header.frame_id, transform.child_frame_id) == ("world", "box")
        assert xyz(body.position) == xyz(transform.transform.translation) == pose[:3, 3].tolist()
        assert xyzw(body.orientation) == xyzw(transform.transform.rotation)
        # Pinocchio's conversion against Shepperd's (model/lie.py): measured 1.1e-16 apart; bound 1e-15
        np.testing.assert_allclose(xyzw(body.orientation), quaternion_from_matrix(pose[:3, :3]), rtol=0, atol=1e-15)
    assert xyzw(published[0].poses[0].orientation) == pytest.approx([0, np.sin(0.2), 0, np.cos(0.2)])
    assert published[-1].poses[0].position.x > published[0].poses[0].position.x + 0.01


def test_robot_free_scene_is_refused_by_inverse_mode_and_names_must_be_distinct(tmp_path: Path) -> None:
    with pytest.raises(UserInputError, match="inverse mode needs a robot"):
        InverseSession(load_scene("ball_drop"))
    source = Path(load_scene("ball_drop").source).read_text()
    clash = tmp_path / "world_drop.yaml"
    clash.write_text(source.replace("name: ball\n", "name: world\n").replace("[floor, ball]", "[floor, world]"))
    with pytest.raises(UserInputError, match=r"free bodies \['world'\] have the names of robot frames"):
        SimulationSession(load_scene(str(clash)), RATE)


def test_markers_draw_the_ball_live_and_the_floor_latched(ball_drop_run) -> None:
    """/free_bodies_markers over ROS equals its MCAP copy: the ball (a sphere of 5 cm
    diameter) at the /free_bodies pose; /scene_markers reaches a late subscriber once
    (latched) and draws the floor halfspace as a 4 m square 1 mm plate, top face at z = 0."""
    received, logged = ball_drop_run["received"], ball_drop_run["mcap"]
    for got, kept, poses in zip(received["/free_bodies_markers"], logged["/free_bodies_markers"],
                                logged["/free_bodies"], strict=True):
        (marker,) = got.markers
        assert (marker.ns, marker.type, marker.header.frame_id) == ("ball", marker.SPHERE, "world")
        assert xyz(marker.scale) == pytest.approx([0.05] * 3)
        assert xyz(marker.pose.position) == xyz(kept.markers[0].pose.position) == xyz(poses.poses[0].position)
        assert stamp_ns(marker) == stamp_ns(poses)
    (scene,) = received["/scene_markers"]
    (floor,) = scene.markers
    assert (floor.ns, floor.type, floor.header.frame_id) == ("floor", floor.CUBE, "world")
    assert xyz(floor.scale) == pytest.approx([4.0, 4.0, 0.001])
    assert floor.pose.position.z + 0.5 * floor.scale.z == pytest.approx(0.0, abs=1e-15)
    (kept,) = logged["/scene_markers"]
    assert [(m.ns, m.type, xyz(m.pose.position), xyzw(m.pose.orientation), xyz(m.scale)) for m in kept.markers] == \
        [(floor.ns, floor.type, xyz(floor.pose.position), xyzw(floor.pose.orientation), xyz(floor.scale))]
    assert [floor.color.r, floor.color.a] == pytest.approx([0.55, 1.0])      # float32 in the message
