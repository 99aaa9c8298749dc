"""A Rerun recording (.rrd) of a run, written headless.

Layout of the recording (Rerun 0.41):

- the robot, by Rerun's built-in URDF loader (``log_file_from_path``, static): geometry
  under ``/<robot name>/...`` and the joint transforms at q = 0 on ``/tf_static``;
- ``/joint_transforms``: one ``Transform3D`` per moving joint per sample, with
  ``parent_frame``/``child_frame`` set to the URDF link names (computed by
  ``rerun.urdf.UrdfJoint``), which is how Rerun >= 0.28 animates a loaded URDF; joints not
  named in a sample keep their last (initially zero) position;
- ``/ee/position``: the end-effector position per sample (``Points3D``, one point, metres,
  in the URDF root link's frame) and, on close, ``/ee/path``: the whole path as one static
  ``LineStrips3D``;
- ``/joints/q``, ``/joints/v``, ``/joints/tau``: ``Scalars`` with one series per joint
  (rad or m, rad/s or m/s, N m or N), series named by a static ``SeriesLines``;
  ``/energy``: total mechanical energy (J).

Every sample sits on the ``sim_time`` timeline (a duration: simulated seconds). The
wall-clock ``log_time`` and ``log_tick`` timelines are disabled and no start time is sent,
so the content depends only on the data (Rerun's row ids still differ between runs).
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import NamedTuple

import numpy as np
import rerun as rr
from rerun.urdf import UrdfJoint, UrdfTree

from youbot_dynamics.errors import UserInputError
from youbot_dynamics.io.closing import ClosesOnExit
from youbot_dynamics.io.messages import finite_array, finite_floats

TIMELINE = "sim_time"
JOINT_TRANSFORMS = "/joint_transforms"
EE_POSITION = "/ee/position"
EE_PATH = "/ee/path"
SERIES = {"q": "/joints/q", "v": "/joints/v", "tau": "/joints/tau"}
ENERGY = "/energy"
DEFAULT_BATCH_SIZE = 250
"""Samples ``log_sample`` buffers before sending them in one batch."""


class Samples(NamedTuple):
    """Samples of a run: t (N,) s; q, v, tau (N, n); energy (N,) J; ee (N, 3) m.

    ``log_sample`` buffers one sample per instance (floats and lists).
    """

    t: np.ndarray
    q: np.ndarray
    v: np.ndarray
    tau: np.ndarray
    energy: np.ndarray
    ee: np.ndarray


class RerunLogger(ClosesOnExit):
    """Writes one .rrd file for a run of the robot in ``urdf_path``; a context manager.

    ``log_sample`` appends one sample (for a running node; buffered and sent every
    ``batch_size`` samples); ``log_trajectory`` appends many at once (for offline runs).
    Both send with ``send_columns``. ``close`` (idempotent; also on ``__exit__``) sends what
    is buffered, writes the end-effector path and disconnects so the file gets its footer.
    Joint names must be moving URDF joints (``UserInputError`` otherwise); values must be
    finite (``MessageFieldError``, a ValueError naming the field, otherwise).
    """

    def __init__(
        self,
        path: str | Path,
        urdf_path: str | Path,
        *,
        recording_name: str,
        application_id: str = "youbot_dynamics",
        recording_id: str | None = None,
        ee_frame: str | None = None,
        batch_size: int = DEFAULT_BATCH_SIZE,
    ) -> None:
        """Start the recording at ``path`` and log the robot from ``urdf_path``.

        ``ee_frame`` is the frame the end-effector positions are given in (default: the
        URDF root link).
        """
        self.path = Path(path)
        urdf_path = Path(urdf_path)
        if not urdf_path.is_file():
            raise UserInputError(f"Rerun log: URDF {urdf_path} does not exist")
        try:
            self._tree = UrdfTree.from_file_path(urdf_path)
        except Exception as error:  # the Rust parser raises plain exceptions
            message = f"Rerun log: URDF {urdf_path} cannot be parsed ({error})"
            raise UserInputError(message) from error
        self.urdf_path = urdf_path
        self._joints: dict[str, UrdfJoint] = {
            joint.name: joint for joint in self._tree.joints() if joint.joint_type != "fixed"
        }
        self.batch_size = max(1, int(batch_size))
        self._series_names: tuple[str, ...] | None = None
        self._pending: list[Samples] = []
        self._pending_names: tuple[str, ...] = ()
        self._ee_path: list[np.ndarray] = []
        self.path.parent.mkdir(parents=True, exist_ok=True)
        self._rec: rr.RecordingStream | None = rr.RecordingStream(
            application_id, recording_id=recording_id, send_properties=False
        )
        self._rec.save(self.path)
        self._rec.set_log_time_enabled(False)
        self._rec.set_log_tick_enabled(False)
        self._rec.send_recording_name(recording_name)
        self._rec.log_file_from_path(urdf_path, static=True)
        self.ee_frame = ee_frame or self._tree.root_link().name
        self._rec.log(EE_POSITION, rr.CoordinateFrame(self.ee_frame), static=True)
        self._rec.log(EE_PATH, rr.CoordinateFrame(self.ee_frame), static=True)

    @property
    def closed(self) -> bool:
        """True once the recording is finalised."""
        return self._rec is None

    def log_sample(
        self,
        t: float,
        joint_names: Sequence[str],
        q: Sequence[float],
        v: Sequence[float],
        tau: Sequence[float],
        energy: float,
        ee_position: Sequence[float],
    ) -> None:
        """Log one sample at simulated time ``t`` (s): joint positions ``q``, velocities
        ``v``, efforts ``tau`` (ordered as ``joint_names``), total energy (J) and the
        end-effector position (m, in ``ee_frame``); the joint transforms follow ``q``.

        Samples are checked at once and sent in batches of ``batch_size`` (one Rerun call
        per entity per batch instead of one per sample); ``close`` sends the rest.
        """
        self._recording()
        names = tuple(joint_names)
        self._resolve(names)
        n = len(names)
        row = Samples(
            t=finite_floats([t], "Rerun t", 1)[0],
            q=finite_floats(q, "Rerun q", n),
            v=finite_floats(v, "Rerun v", n),
            tau=finite_floats(tau, "Rerun tau", n),
            energy=finite_floats([energy], "Rerun energy", 1)[0],
            ee=finite_floats(ee_position, "Rerun ee_position", 3),
        )
        if names != self._pending_names:
            self._flush()
            self._pending_names = names
        self._pending.append(row)
        if len(self._pending) >= self.batch_size:
            self._flush()

    def log_trajectory(
        self,
        t: Sequence[float],
        joint_names: Sequence[str],
        q: np.ndarray,
        v: np.ndarray,
        tau: np.ndarray,
        energy: Sequence[float],
        ee_position: np.ndarray,
    ) -> None:
        """Log N samples at once: ``t`` (N,) in s; ``q``, ``v``, ``tau`` (N, n) ordered as
        ``joint_names``; ``energy`` (N,) in J; ``ee_position`` (N, 3) in m."""
        self._recording()
        names = tuple(joint_names)
        self._resolve(names)
        times = finite_array(t, "Rerun t")
        count, n = times.size, len(names)
        samples = Samples(
            t=times,
            q=finite_array(q, "Rerun q", count * n).reshape(count, n),
            v=finite_array(v, "Rerun v", count * n).reshape(count, n),
            tau=finite_array(tau, "Rerun tau", count * n).reshape(count, n),
            energy=finite_array(energy, "Rerun energy", count),
            ee=finite_array(ee_position, "Rerun ee_position", count * 3).reshape(count, 3),
        )
        self._flush()
        self._send(names, samples)

    def close(self) -> None:
        """Send pending samples, log the end-effector path and finalise the file; later
        calls do nothing."""
        if self._rec is None:
            return
        self._flush()
        rec, self._rec = self._rec, None
        if self._ee_path:
            rec.log(EE_PATH, rr.LineStrips3D([np.concatenate(self._ee_path)]), static=True)
        rec.flush()
        rec.disconnect()

    def _recording(self) -> rr.RecordingStream:
        if self._rec is None:
            raise RuntimeError(f"{self.path}: Rerun recording already closed")
        return self._rec

    def _resolve(self, names: tuple[str, ...]) -> list[UrdfJoint]:
        """The URDF joints named, in order."""
        unknown = [name for name in names if name not in self._joints]
        if unknown:
            raise UserInputError(
                f"Rerun log: joints {unknown} are not moving joints of {self.urdf_path}"
                f" (known: {sorted(self._joints)})"
            )
        return [self._joints[name] for name in names]

    def _flush(self) -> None:
        """Send the samples buffered by ``log_sample``."""
        if self._pending:
            rows, self._pending = self._pending, []
            self._send(self._pending_names, Samples(*(np.array(column) for column in zip(*rows))))

    def _send(self, names: tuple[str, ...], samples: Samples) -> None:
        """Send checked samples (arrays as in ``log_trajectory``) with ``send_columns``."""
        rec = self._recording()
        if names != self._series_names:
            for entity in SERIES.values():
                rec.log(entity, rr.SeriesLines(names=list(names)), static=True)
            self._series_names = names
        index = [rr.TimeColumn(TIMELINE, duration=samples.t)]
        for joint, values in zip(self._resolve(names), samples.q.T):
            columns = joint.compute_transform_columns(values.tolist(), clamp=False)
            rec.send_columns(JOINT_TRANSFORMS, indexes=index, columns=columns)
        for field, entity in SERIES.items():
            scalars = rr.Scalars.columns(scalars=getattr(samples, field))
            rec.send_columns(entity, indexes=index, columns=scalars)
        rec.send_columns(ENERGY, indexes=index, columns=rr.Scalars.columns(scalars=samples.energy))
        points = rr.Points3D.columns(positions=samples.ee).partition([1] * len(samples.t))
        rec.send_columns(EE_POSITION, indexes=index, columns=points)
        self._ee_path.append(samples.ee)

