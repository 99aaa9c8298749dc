"""The logs of one node run: an MCAP in rosbag2 form (:class:`~youbot_dynamics.io.mcap_log.McapLogger`)
of the session's topics, and a Rerun recording (:class:`~youbot_dynamics.io.rerun_log.RerunLogger`)
of the robot, the scene's static geometry and (simulate mode) its free bodies, in the
frames of the node's tf tree (:func:`~youbot_dynamics.node.frames.frame_tree`, without the
frame prefix: Rerun names the URDF's frames by its link names). Log times are int ns:
simulated time, the messages' stamps (simulate mode), or the receive time of the sample they
come from on the node's monotonic receive clock (inverse mode; the messages keep the sender's
stamps). The Rerun recording takes the stamps.
"""
from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np

from youbot_dynamics.io.log_file import LogPathError, LogWriteFailed, describe_os_error
from youbot_dynamics.io.mcap_log import McapLogger
from youbot_dynamics.io.rerun_log import RerunLogger
from youbot_dynamics.model.robot import Robot
from youbot_dynamics.node.frames import FrameTree
from youbot_dynamics.node.interface import Outputs, topic_qos, topic_type
from youbot_dynamics.scene.schema import Scene


def urdf_file(scene: Scene, robot: Robot, rrd_path: Path) -> Path | None:
    """The URDF file of the scene's robot for Rerun: None without a robot; the scene's file;
    or, for a composed robot (no file of its own), its URDF text written next to the
    recording as ``<rrd name>.urdf``."""
    if not robot.tree:
        return None
    if scene.urdf_path is not None:
        return scene.urdf_path
    path = rrd_path.with_suffix(".urdf")
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(scene.urdf, encoding="utf-8")
    return path


def writable(path: Path, parameter: str) -> None:
    """Make sure the log file ``path`` (given as ``parameter``) can be written, before either
    log is opened: its folder created if missing, the file opened for appending. Raises
    LogPathError naming the parameter, the path and the reason (a read-only folder, a
    directory at ``path``)."""
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        with path.open("ab"):
            pass
    except OSError as error:
        raise LogPathError(f"{parameter} {path}: cannot write it ({describe_os_error(error)})") from error


class Recorder:
    """The logs of one node run: an MCAP (``mcap_path``) of ``topics`` (each recorded as
    offered with its profile in the interface table, :data:`TOPIC_QOS`, as the node's
    publishers offer it), and a Rerun recording (``rrd_path``) of the robot, the scene's
    static geometry and (simulate mode) its free bodies; either may be None; a path that
    cannot be written raises LogPathError (a UserInputError). ``close`` finalises both and
    may be called more than once."""

    def __init__(self, mode: str, scene: Scene, robot: Robot, topics: Sequence[str],
                 mcap_path: str | Path | None, rrd_path: str | Path | None, tree: FrameTree) -> None:
        for parameter, path in (("mcap_path", mcap_path), ("rrd_path", rrd_path)):
            if path:
                writable(Path(path), parameter)
        self.mcap = McapLogger(mcap_path) if mcap_path else None
        if self.mcap is not None:
            for topic in topics:
                self.mcap.add_topic(topic, topic_type(topic), qos=topic_qos(topic))
        self.rerun = RerunLogger(
            rrd_path, urdf_file(scene, robot, Path(rrd_path)), recording_name=f"{scene.name} ({mode})",
            geometries=[g for g in scene.geometries if mode == "simulate" or g.owner != "body"],
            world_frame=tree.world, root_frame=tree.root, static_frames=tree.static,
            moving_frames=tree.moving) if rrd_path else None

    @property
    def paths(self) -> list[Path]:
        """The log files being written."""
        return [log.path for log in (self.mcap, self.rerun) if log is not None]

    @property
    def failures(self) -> dict[str, LogWriteFailed]:
        """The logs whose writes failed (``mcap``, ``rerun``: the failure); each stopped
        logging there, the other goes on."""
        return {name: log.failure for name, log in (("mcap", self.mcap), ("rerun", self.rerun))
                if log is not None and log.failure is not None}

    def write(self, outputs: Outputs, stamp_ns: int) -> None:
        """Log messages at ``stamp_ns`` (log and publish time)."""
        if self.mcap is not None and not self.mcap.closed:
            self.mcap.write_all(outputs, stamp_ns)

    def sample(self, stamp_ns: int, names: Sequence[str], q: np.ndarray, v: np.ndarray, tau: np.ndarray,
               energy: float, ee_position: np.ndarray) -> None:
        """One Rerun sample at simulated time ``stamp_ns`` (ns)."""
        if self.rerun is not None and not self.rerun.closed:
            self.rerun.log_sample(stamp_ns, names, q, v, tau, energy, ee_position)

    def bodies(self, stamp_ns: int, rows: np.ndarray) -> None:
        """The free bodies' poses (rows of translation (m) and quaternion (x, y, z, w), world
        frame, in the scene's order, as the recording's ``bodies``) in the Rerun recording
        at ``stamp_ns`` (ns)."""
        if self.rerun is not None and not self.rerun.closed:
            self.rerun.log_body_rows(stamp_ns, rows)

    def base(self, stamp_ns: int, rows: np.ndarray) -> None:
        """A moving base's rows (2, 7) of the tree's moving edges (odom -> base_footprint,
        odom -> world) in the Rerun recording at ``stamp_ns`` (ns)."""
        if self.rerun is not None and not self.rerun.closed:
            self.rerun.log_frame_rows(stamp_ns, rows)

    def records(self, topic: str) -> bool:
        """True if the MCAP log records ``topic`` (so its messages must be built)."""
        return self.mcap is not None and not self.mcap.closed and topic in self.mcap.topics

    @property
    def samples(self) -> bool:
        """True if the Rerun recording takes samples (joint values, energy, end effector)."""
        return self.rerun is not None and not self.rerun.closed

    def close(self) -> None:
        """Finalise both logs (idempotent)."""
        for log in (self.mcap, self.rerun):
            if log is not None:
                log.close()
