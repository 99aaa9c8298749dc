"""Replay with real ROS 2 traffic: (a) a recorded simulate run replayed into an inverse-mode
node gives back the recorded efforts within the bound the acceleration estimate allows;
(b) two simulate runs log identical payloads; (c) a bag written by rosbags' rosbag2 Writer
replays into the node and into a subscriber in another process; the CLI replays a bag."""
from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from ros_support import WAIT, Collector, domain_id, ros_context, spinning, stamp_ns, wait_until

pytestmark = [pytest.mark.ros, pytest.mark.timeout(240)]

from mcap.reader import make_reader  # noqa: E402
from rclpy.parameter import Parameter  # noqa: E402
from rosbags.rosbag2 import StoragePlugin, Writer  # noqa: E402

from youbot_dynamics.dynamics.rigid_body import mass_matrix  # noqa: E402
from youbot_dynamics.errors import UserInputError  # noqa: E402
from youbot_dynamics.io import messages  # noqa: E402
from youbot_dynamics.io.bag_reader import read_bag  # noqa: E402
from youbot_dynamics.io.mcap_log import McapLogger  # noqa: E402
from youbot_dynamics.node.inverse_session import InverseSession  # noqa: E402
from youbot_dynamics.ros.dynamics_node import DynamicsNode  # noqa: E402
from youbot_dynamics.ros.replay_node import ReplayNode  # noqa: E402
from youbot_dynamics.scene.schema import load_scene  # noqa: E402
from youbot_dynamics.sim.simulator import Simulator  # noqa: E402

REPO = Path(__file__).resolve().parents[2]
RATE = 100.0
TORQUES = {"/computed_torques": "sensor_msgs/msg/JointState"}


def simulate(offset: int, mcap: Path, duration: float, time_scale: float = 0.0, scene: str = "arm_ptp") -> None:
    """Run a simulate-mode node for ``duration`` simulated seconds, logging to ``mcap``."""
    with ros_context(offset) as (context, _):
        node = DynamicsNode(context=context, parameter_overrides=[
            Parameter("scene", value=scene), Parameter("publish_rate", value=RATE),
            Parameter("duration", value=duration), Parameter("time_scale", value=time_scale),
            Parameter("mcap_path", value=str(mcap))])
        with spinning(context, node):
            wait_until(lambda: node.finished, what="the simulate run")


def replay_into_inverse_node(offset: int, bag: Path, time_scale: float, expected: int,
                             listener: subprocess.Popen | None = None) -> list:
    """Replay ``bag``'s /joint_states into an inverse-mode node; the /computed_torques. A
    ``listener`` process must also have subscribed and said "ready" first."""
    with ros_context(offset) as (context, _):
        node = DynamicsNode(context=context, parameter_overrides=[
            Parameter("scene", value="arm_ptp"), Parameter("mode", value="inverse")])
        collector = Collector(context, TORQUES)
        replay = ReplayNode(bag, time_scale, ["/joint_states"], context=context)
        with spinning(context, node, collector, replay):
            subscribers = 1 if listener is None else 2
            assert replay.wait_for_subscribers("/joint_states", subscribers, timeout=WAIT)
            if listener is not None:
                assert listener.stdout.readline().strip() == "ready"
            wait_until(lambda: node.publishers_["/computed_torques"].get_subscription_count() > 0,
                       what="the collector")
            assert replay.replay() == expected
            wait_until(lambda: collector.count("/computed_torques") == expected - 2, what="every torque sample")
        return collector.messages("/computed_torques")


@pytest.fixture(scope="module")
def recorded(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """One simulated second of arm_ptp at 100 Hz, logged by the node."""
    path = tmp_path_factory.mktemp("recorded") / "arm_ptp.mcap"
    simulate(10, path, duration=1.0)
    return path


def acceleration_error_bound(times: np.ndarray, q: np.ndarray, h: float) -> np.ndarray:
    """The torque error the central difference allows at each sample (see node/inverse.py):
    sum_j |M_ij(q_k)| max_{|s - t_k| <= h} |a_j(s) - a_j(t_k)|, with a(s) from the
    simulator on a grid 20 times finer than the samples."""
    simulator = Simulator(load_scene("arm_ptp"))
    grid = np.round(np.arange(0.0, times[-1] + h + 1e-12, h / 20), 12)
    run = simulator.run(grid)
    nv = simulator.robot.nv
    a = np.array([simulator.rhs(t, x)[nv:2 * nv] for t, x in zip(run.t, run.x)])
    data = simulator.robot.model.createData()
    bounds = []
    for t, q_k in zip(times, q):
        window = (grid >= t - h - 1e-9) & (grid <= t + h + 1e-9)
        centre = a[int(np.argmin(np.abs(grid - t)))]
        variation = np.max(np.abs(a[window] - centre), axis=0)
        bounds.append(np.abs(mass_matrix(simulator.robot, data, q_k)) @ variation)
    return np.array(bounds)


def test_a_replayed_run_gives_back_its_efforts_within_the_estimate_bound(recorded: Path) -> None:
    states = [m.message for m in read_bag(recorded) if m.topic == "/joint_states"]
    assert len(states) == 101
    torques = replay_into_inverse_node(11, recorded, time_scale=1.0, expected=len(states))
    by_stamp = {stamp_ns(m): m for m in states}
    assert [stamp_ns(t) for t in torques] == [stamp_ns(m) for m in states[1:-1]]
    times = np.array([stamp_ns(t) * 1e-9 for t in torques])
    bound = acceleration_error_bound(times, np.array([t.position for t in torques]), 1.0 / RATE)
    recorded_effort = [dict(zip(by_stamp[stamp_ns(t)].name, by_stamp[stamp_ns(t)].effort)) for t in torques]
    error = np.array([np.abs(t.effort - [effort[name] for name in t.name]) for t, effort in zip(torques, recorded_effort)])
    # 5 % + 1e-3 N m for the difference between the node's run (an integrator restart every
    # 20 ms) and the reference run, and for the finite grid of the bound
    assert np.all(error <= 1.05 * bound + 1e-3), np.max(error - bound)
    assert np.median(error) < 1e-3 < np.max(bound)     # tight where a is smooth; the bound is not vacuous


def test_b_two_simulate_runs_log_identical_payloads(tmp_path: Path) -> None:
    """Same scene twice, once as fast as possible and once at 4x real time: identical
    messages (bytes) and log times on every topic but /diagnostics (wall-clock figures)."""
    runs = []
    for offset, scale in ((12, 0.0), (13, 4.0)):
        path = tmp_path / f"run{offset}.mcap"
        simulate(offset, path, duration=0.5, time_scale=scale)
        with path.open("rb") as stream:
            runs.append([(channel.topic, message.log_time, message.data)
                         for _, channel, message in make_reader(stream).iter_messages(log_time_order=True)
                         if channel.topic != "/diagnostics"])
    assert runs[0] == runs[1]
    topics = [topic for topic, _, _ in runs[0]]
    assert topics.count("/joint_states") == topics.count("/tf") == 51 and topics.count("/tf_static") == 1
    payloads = {data for topic, _, data in runs[0] if topic == "/joint_states"}
    assert len(payloads) == 51                         # the arm moved: every sample differs


LISTENER = """
import json, sys, time
import rclpy
from sensor_msgs.msg import JointState
from youbot_dynamics.ros.qos import RELIABLE_DEEP
rclpy.init()
node = rclpy.create_node("listener")
got = []
subscription = node.create_subscription(JointState, "/joint_states", lambda m: got.append(list(m.position)),
                                        RELIABLE_DEEP)
deadline = time.monotonic() + float(sys.argv[2])
while subscription.get_publisher_count() == 0 and time.monotonic() < deadline:   # matched on this side
    rclpy.spin_once(node, timeout_sec=0.05)
print("ready", flush=True)
while len(got) < int(sys.argv[1]) and time.monotonic() < deadline:
    rclpy.spin_once(node, timeout_sec=0.1)
print(json.dumps({"count": len(got), "last": got[-1] if got else None}))
"""


def test_c_a_rosbags_written_bag_replays_into_the_node_and_another_process(tmp_path: Path) -> None:
    """A rosbag2 folder (MCAP storage, metadata.yaml) from rosbags' Writer, replayed as fast
    as possible: the inverse node's torques equal those computed offline from the same
    samples, and a subscriber process receives every sample."""
    run = Simulator(load_scene("arm_ptp")).run(np.arange(0.0, 0.5, 1.0 / RATE))
    names, nv = load_scene("arm_ptp").moving, len(load_scene("arm_ptp").moving)
    bag = tmp_path / "other_tool"
    samples = []
    with Writer(bag, version=9, storage_plugin=StoragePlugin.MCAP) as writer:
        connection = writer.add_connection("/joint_states", "sensor_msgs/msg/JointState",
                                           typestore=messages.TYPESTORE)
        for t, x in zip(run.t, run.x):
            stamp = round(t * 1e9)
            msg = messages.joint_state(stamp, names, x[:nv], x[nv:2 * nv])
            samples.append(msg)
            writer.write(connection, stamp, messages.TYPESTORE.serialize_cdr(msg, msg.__msgtype__))
    assert (bag / "metadata.yaml").is_file()

    offline = InverseSession(load_scene("arm_ptp"))
    expected = [out for m in samples for topic, out in offline.joint_state(m.name, m.position, m.velocity, stamp_ns(m))
                if topic == "/computed_torques"]
    listener = subprocess.Popen([sys.executable, "-c", LISTENER, str(len(samples)), str(WAIT)], cwd=REPO,
                                env={**os.environ, "ROS_DOMAIN_ID": str(domain_id(14))},
                                stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        torques = replay_into_inverse_node(14, bag, time_scale=0.0, expected=len(samples), listener=listener)
        out, err = listener.communicate(timeout=WAIT + 30)
    finally:
        if listener.poll() is None:
            listener.kill()
    assert len(torques) == len(expected) == len(samples) - 2
    for got, want in zip(torques, expected):
        assert stamp_ns(got) == stamp_ns(want)
        assert np.allclose(got.effort, want.effort, rtol=1e-12, atol=1e-12)
    heard = json.loads(out.strip().splitlines()[-1])
    assert heard["count"] == len(samples), err
    assert heard["last"] == samples[-1].position.tolist()


def test_cli_replay_publishes_with_the_recorded_timing(recorded: Path) -> None:
    """`youbot-dynamics replay BAG --time-scale 2` in a process of its own: the /joint_states here
    equal the bag's, in order, and /clock follows the log times."""
    with ros_context(15) as (context, domain):
        collector = Collector(context, {"/joint_states": "sensor_msgs/msg/JointState",
                                        "/clock": "rosgraph_msgs/msg/Clock"})
        with spinning(context, collector):
            process = subprocess.run(
                [sys.executable, "-m", "youbot_dynamics", "replay", str(recorded), "--time-scale", "2",
                 "--topic", "/joint_states", "--wait-for", "/joint_states"],
                cwd=REPO, env={**os.environ, "ROS_DOMAIN_ID": str(domain)}, capture_output=True, text=True,
                timeout=120)
            wait_until(lambda: collector.count("/joint_states") == 101, what="the replayed samples")
    assert process.returncode == 0, process.stderr
    assert "replay: 101 messages" in process.stdout
    recorded_states = [m.message for m in read_bag(recorded) if m.topic == "/joint_states"]
    got = collector.messages("/joint_states")
    assert [stamp_ns(m) for m in got] == [stamp_ns(m) for m in recorded_states]
    assert all(np.array_equal(a.position, b.position) for a, b in zip(got, recorded_states))
    clocks = [c.clock.sec * 10**9 + c.clock.nanosec for c in collector.messages("/clock")]
    assert clocks == [stamp_ns(m) for m in recorded_states]           # /clock driven by the log times


def test_cli_fast_replay_loses_nothing_into_a_slower_inverse_node(tmp_path: Path) -> None:
    """`youbot-dynamics replay BAG --time-scale 0` in a process of its own, 3000 samples into an
    inverse-mode node that handles them more slowly than the replay sends them: keep-all on both
    sides, the replay retrying while its writer's history is full and waiting for the
    acknowledgements before it leaves, so there is a torque for every interior sample."""
    scene = load_scene("arm_ptp")
    count, bag = 3000, tmp_path / "many.mcap"
    with McapLogger(bag) as log:
        log.add_topic("/joint_states", "sensor_msgs/msg/JointState")
        centre = (scene.robot.lower + scene.robot.upper) / 2      # within the joint limits
        for k in range(count):
            q = centre + 0.1 * np.sin(np.full(len(scene.moving), k * 1e-3))
            log.write("/joint_states", messages.joint_state(k * 10**6, scene.moving, q, np.zeros(len(scene.moving))),
                      k * 10**6)
    with ros_context(18) as (context, domain):
        node = DynamicsNode(context=context, parameter_overrides=[
            Parameter("scene", value="arm_ptp"), Parameter("mode", value="inverse")])
        collector = Collector(context, TORQUES)
        with spinning(context, node, collector, single_threaded=True):
            wait_until(lambda: node.publishers_["/computed_torques"].get_subscription_count() > 0,
                       what="the collector")
            process = subprocess.run(
                [sys.executable, "-m", "youbot_dynamics", "replay", str(bag), "--time-scale", "0",
                 "--wait-for", "/joint_states"],
                cwd=REPO, env={**os.environ, "ROS_DOMAIN_ID": str(domain)}, capture_output=True, text=True,
                timeout=120)
            assert process.returncode == 0, process.stderr
            assert f"replay: {count} messages" in process.stdout
            wait_until(lambda: collector.count("/computed_torques") >= count - 2, what="every torque sample")
            got = [stamp_ns(m) for m in collector.messages("/computed_torques")]
    assert got == [k * 10**6 for k in range(1, count - 1)]


def test_replay_refuses_topics_the_bag_does_not_replay(recorded: Path) -> None:
    """A --topic the bag lacks, or a --wait-for topic that is not replayed, is a user error
    naming the topic and what the bag has; so is a time scale out of range (one line, exit 2)."""
    with ros_context(16) as (context, _):
        with pytest.raises(UserInputError, match=r"has no topic /nope \(it has /clock, /diagnostics"):
            ReplayNode(recorded, 1.0, ["/nope", "/clock"], context=context)
        with pytest.raises(UserInputError, match=r"wait_for /tf is not a replayed topic .*replayed: /clock\)"):
            ReplayNode(recorded, 1.0, ["/clock"], wait_for="/tf", context=context)
    process = subprocess.run([sys.executable, "-m", "youbot_dynamics", "replay", str(recorded), "--time-scale", "5000"],
                             cwd=REPO, env={**os.environ, "ROS_DOMAIN_ID": str(domain_id(17))},
                             capture_output=True, text=True, timeout=120)
    lines = process.stderr.strip().splitlines()
    assert process.returncode == 2 and len(lines) == 1, process.stderr
    assert lines[0].startswith("youbot-dynamics replay: error: ") and "time_scale" in lines[0] and "5000" in lines[0]
