"""The simulated sensors' messages: /wrist_wrench (geometry_msgs/WrenchStamped in the
sensor link's frame) and /imu (sensor_msgs/Imu in base_link), from the readings each
snapshot carries (:mod:`youbot_dynamics.sim.sensors` computes them)."""
from __future__ import annotations

from collections.abc import Collection, Sequence

from youbot_dynamics.io import messages
from youbot_dynamics.sim.engine import Snapshot
from youbot_dynamics.sim.sensors import SensorModel

SENSOR_TOPICS = ("/wrist_wrench", "/imu")
"""The sensor topics, in the order of the interface table."""
IMU_COVARIANCES = ((0.0,) * 9,) * 3
"""The IMU's orientation, angular velocity and acceleration covariances: all provided,
exact (a noise-free simulation), so 0 (REP 145 keeps -1 for a quantity not provided)."""


class SensorMessages:
    """The sensor messages of a session whose scene has ``sensors``; ``prefix`` goes before
    the frame names (``frame_prefix``); ``topics``: the session's per-sample topics."""

    def __init__(self, sensors: SensorModel, prefix: str, topics: Collection[str]) -> None:
        self.topics = tuple(topic for topic in SENSOR_TOPICS if topic in topics)
        self.wanted = bool(self.topics)
        """Whether snapshots must carry their readings."""
        self.wrist_frame = prefix + sensors.wrist.link if sensors.wrist is not None else ""
        self.imu_frame = prefix + "base_link"

    def columns(self, stamps: Sequence[int], snapshots: Sequence[Snapshot], wanted: Collection[str]
                ) -> list[tuple[str, list[object]]]:
        """(topic, its messages at ``stamps`` (ns)) of the wanted sensor topics."""
        columns: list[tuple[str, list[object]]] = []
        if "/wrist_wrench" in wanted:
            columns.append(("/wrist_wrench", [messages.wrench_stamped(stamp, self.wrist_frame, *s.sensors.wrist)
                                              for stamp, s in zip(stamps, snapshots)]))
        if "/imu" in wanted:
            columns.append(("/imu", [messages.imu(stamp, self.imu_frame, s.sensors.imu[2], s.sensors.imu[0],
                                                  s.sensors.imu[1], IMU_COVARIANCES)
                                     for stamp, s in zip(stamps, snapshots)]))
        return columns
