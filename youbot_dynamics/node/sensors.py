"""The simulated sensors' messages: /wrist_wrench (geometry_msgs/WrenchStamped in the
sensor link's frame), /imu (sensor_msgs/Imu in base_link) and per contact pair
/contacts/<first>/<second> (geometry_msgs/WrenchStamped in the second geometry's frame), from
the readings each snapshot carries (:mod:`youbot_dynamics.sim.sensors` computes them). Each
topic's first message is built by ``io.messages``, the next ones refill its CDR bytes
(:class:`~youbot_dynamics.io.cdr_template.Refilled`)."""
from __future__ import annotations

from collections.abc import Collection, Sequence

import numpy as np

from youbot_dynamics.io import messages
from youbot_dynamics.io.cdr_group import Entry
from youbot_dynamics.io.cdr_template import Refilled, not_covariance
from youbot_dynamics.node.interface import pair_topic
from youbot_dynamics.sim.engine import Snapshot
from youbot_dynamics.sim.model import SimModel

SENSOR_TOPICS = ("/wrist_wrench", "/imu")
"""The sensor topics, in the order of the interface table."""
IMU_COVARIANCES = ((0.0,) * 9,) * 3
"""The IMU's orientation, angular velocity and acceleration covariances: all provided,
exact (a noise-free simulation), so 0 (REP 145 keeps -1 for a quantity not provided)."""


class SensorMessages:
    """The sensor messages of a session simulating ``model``; ``prefix`` goes before the
    frame names (``frame_prefix``), ``root_frame`` is the frame of world geometry;
    ``topics``: the session's per-sample topics."""

    def __init__(self, model: SimModel, prefix: str, root_frame: str, topics: Collection[str]) -> None:
        sensors, contact = model.sensors, model.contact
        #: per contact pair: (its topic, its name, the frame of its second geometry)
        self.pairs = [] if contact is None else [
            (pair_topic(contact.geometries[p.first].name, contact.geometries[p.second].name), p.name,
             root_frame if contact.geometries[p.second].owner == "world"
             else prefix + contact.geometries[p.second].owner_name) for p in contact.pairs]
        self.wanted = any(topic in topics for topic in SENSOR_TOPICS) or any(t in topics for t, _, _ in self.pairs)
        """Whether snapshots must carry their readings."""
        self.wrist_frame = prefix + sensors.wrist.link if sensors.wrist is not None else ""
        self.imu_frame = prefix + "base_link"
        self._templates: dict[str, Refilled] = {}

    def entries(self, snapshots: Sequence[Snapshot], wanted: Collection[str]) -> list[Entry]:
        """The wanted sensor topics of N snapshots as :data:`~youbot_dynamics.io.cdr_group.Entry`
        (values and the builder of the first message)."""
        entries: list[Entry] = []
        if "/wrist_wrench" in wanted:
            entries.append(self._wrenches("/wrist_wrench", self.wrist_frame, [s.sensors.wrist for s in snapshots]))
        if "/imu" in wanted:
            readings = [s.sensors.imu for s in snapshots]    # (angular velocity, acceleration, orientation)
            values = np.hstack([np.array([reading[k] for reading in readings]) for k in (2, 0, 1)])
            entries.append(("/imu", self._refilled("/imu"), values, lambda stamp, row: messages.imu(
                stamp, self.imu_frame, row[:4], row[4:7], row[7:], IMU_COVARIANCES)))
        for topic, name, frame in self.pairs:
            if topic in wanted:
                entries.append(self._wrenches(topic, frame, [s.sensors.pairs[name] for s in snapshots]))
        return entries

    def _refilled(self, topic: str) -> Refilled:
        """The topic's refilled messages (the covariances stay the first message's)."""
        if topic not in self._templates:
            self._templates[topic] = Refilled(not_covariance)
        return self._templates[topic]

    def _wrenches(self, topic: str, frame: str, wrenches: Sequence[tuple[np.ndarray, np.ndarray]]) -> Entry:
        """geometry_msgs/WrenchStamped in ``frame`` of (force, torque) pairs, as an Entry."""
        values = np.array(wrenches).reshape(len(wrenches), 6)
        return topic, self._refilled(topic), values, lambda stamp, row: messages.wrench_stamped(
            stamp, frame, row[:3], row[3:])
