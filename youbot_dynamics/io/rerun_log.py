"""A Rerun recording (.rrd) of a run, written headless.

Layout of the recording (Rerun 0.41):

- the robot (if there is one), by Rerun's built-in URDF loader (``log_file_from_path``, static): geometry
  under ``/<robot name>/...`` and the joint transforms at q = 0 on ``/tf_static``;
- ``/joint_transforms``: one ``Transform3D`` per moving joint per sample, with
  ``parent_frame``/``child_frame`` set to the URDF link names (computed by
  ``rerun.urdf.UrdfJoint``), which is how Rerun >= 0.28 animates a loaded URDF; joints not
  named in a sample keep their last (initially zero) position;
- ``/ee/position``: the end-effector position per sample (``Points3D``, one point, metres,
  in the root frame) and, on close, ``/ee/path``: the whole path as one static
  ``LineStrips3D``;
- ``/joints/q``, ``/joints/v``, ``/joints/tau``: ``Scalars`` with one series per joint
  (rad or m, rad/s or m/s, N m or N), series named by a static ``SeriesLines``;
  ``/energy``: total mechanical energy (J);
- ``/free_bodies/<name>``: each free body as its shape (static ``Ellipsoids3D`` for a
  sphere, ``Boxes3D``, ``Cylinders3D`` or ``Capsules3D``, centred on the body frame as coal
  places it) in the named coordinate frame ``<name>`` (a static ``CoordinateFrame``), with
  one ``Transform3D`` per sample from ``parent_frame`` = the world frame to ``child_frame``
  = ``<name>`` (translation, m, and quaternion x, y, z, w: the body's pose in the world
  frame);
- ``/geometry/<name>``: the scene's static world geometry (in the world frame) and its
  geometry on robot links (in the link's frame, which the URDF loader names after the
  link), static solids placed as the scene places them; a halfspace is drawn as a thin
  square plate on its boundary plane (``io.drawn_shapes.drawn_shape``);
- ``/world_frame``: the static identity transform that joins the root frame to the tree
  (by default: world frame -> root link if they differ, a ``frame_id`` such as ``map``);
- ``/base_frames/<child>``: a moving base's per-sample transforms (``moving_frames``:
  odom -> base_footprint, odom -> world), as the node's /tf has them.

The world frame is the frame free-body poses and world geometry are given in (the robot's
root frame; ``world`` without a robot, or under a moving base); the root frame the one of
the end-effector positions (default: the world frame). Every frame is a named frame whose
chain of parents ends at the root frame, so a 3D view rooted anywhere in the tree finds a
transform path to every entity.

Every sample sits on the ``sim_time`` timeline, a duration logged as integer nanoseconds
(the stamps of the MCAP messages: never float seconds, which Rerun truncates to whole
nanoseconds). The wall-clock ``log_time`` and ``log_tick`` timelines are disabled and no
start time is sent, so the content depends only on the data (Rerun's row ids still differ
between runs).
"""

from __future__ import annotations

import itertools
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import NamedTuple

import numpy as np
import rerun as rr
from rerun.urdf import UrdfJoint, UrdfTree

from youbot_dynamics.dynamics.collision import Geometry, Shape
from youbot_dynamics.errors import UserInputError
from youbot_dynamics.io.closing import ClosesOnExit
from youbot_dynamics.io.log_file import FileSink, LogWriteFailed, open_exclusive, room_left
from youbot_dynamics.io.messages import finite_array, finite_floats, stamps_ns
from youbot_dynamics.model.lie import quaternion_from_matrix
from youbot_dynamics.io.drawn_shapes import drawn_shape

TIMELINE = "sim_time"
JOINT_TRANSFORMS = "/joint_transforms"
EE_POSITION = "/ee/position"
EE_PATH = "/ee/path"
SERIES = {"q": "/joints/q", "v": "/joints/v", "tau": "/joints/tau"}
ENERGY = "/energy"
FREE_BODIES = "/free_bodies"
GEOMETRY = "/geometry"
WORLD_FRAME = "/world_frame"
BASE_FRAMES = "/base_frames"
DEFAULT_BATCH_SIZE = 250
"""Samples ``log_sample`` buffers before sending them in one batch."""
RESERVE_BYTES = 1 << 20
"""Bytes a recording leaves free at least on its file system (and under the file-size
limit), beyond its footer and what is in flight; see ``RerunLogger``."""
DEFAULT_FLUSH_SPAN = 1.0
"""Simulated seconds of samples ``log_sample`` / ``log_body_poses`` buffer at most: a batch
is sent (and Rerun's pipeline flushed towards the file) once it spans this long, so a crash
loses less than this much of the recording."""


class Samples(NamedTuple):
    """Samples of a run: t (N,) integer ns; q, v, tau (N, n); energy (N,) J; ee (N, 3) m."""

    t: np.ndarray
    q: np.ndarray
    v: np.ndarray
    tau: np.ndarray
    energy: np.ndarray
    ee: np.ndarray


def _stamp(stamp_ns: int) -> int:
    """A sample's stamp (integer ns >= 0) as an int; ``stamps_ns`` names what is wrong."""
    if type(stamp_ns) is int and stamp_ns >= 0:
        return stamp_ns
    return int(stamps_ns([stamp_ns], "Rerun stamp_ns")[0])


def body_entity(name: str) -> str:
    """Entity path of the free body ``name``."""
    return f"{FREE_BODIES}/{rr.escape_entity_path_part(name)}"


def geometry_entity(name: str) -> str:
    """Entity path of the static or link geometry ``name``."""
    return f"{GEOMETRY}/{rr.escape_entity_path_part(name)}"


def durations(stamps: np.ndarray) -> np.ndarray:
    """Integer nanoseconds as the numpy durations Rerun's ``sim_time`` timeline takes exactly."""
    return np.asarray(stamps, dtype=np.int64).astype("timedelta64[ns]")


def _float_rows(rows: list[tuple[float, ...]], width: int) -> np.ndarray:
    """Rows of ``width`` Python floats (Rerun's lists of tuples) as a float64 array (rows,
    width), read in one pass (``np.array`` of tuples costs about twice as much)."""
    return np.fromiter(itertools.chain.from_iterable(rows), np.float64, width * len(rows)).reshape(-1, width)


def frame_id_rows(names: Sequence[str], index: np.ndarray) -> object:
    """The frame ids ``names[index[k]]`` (k = 0, 1, ...) as the Arrow string array Rerun takes:
    the names converted once, then gathered (Rerun converts each repeated string)."""
    return rr.components.TransformFrameIdBatch(list(names)).as_arrow_array().take(index)


def joint_transform_columns(joints: Sequence[UrdfJoint], q: np.ndarray) -> rr.ComponentColumnList:
    """One Transform3D column of every joint's transforms at the samples' positions ``q``
    (samples, joints; rad or m), sample after sample, each sample's joints in order (the
    index repeats each sample's time per joint; time-ordered rows spare Rerun a sort of the
    chunk): Rerun's own joint transforms (``UrdfJoint.compute_transform_columns``'
    computation, unclamped) gathered into arrays, one ``columns`` call for all joints
    instead of one per joint (each costs about 0.5 ms whatever its length)."""
    translations, quaternions, parents, children = [], [], [], []
    q = np.asarray(q, dtype=np.float64)
    for joint, values in zip(joints, q.T):
        result = joint._inner.compute_transform_columns(values.tolist(), clamp=False)  # the public call, less lists
        translations += result["translations"]
        quaternions += result["quaternions_xyzw"]
        parents.append(result["parent_frame"])
        children.append(result["child_frame"])
    samples, count = q.shape[0], len(parents)
    time_major = np.arange(samples * count).reshape(count, samples).T.reshape(-1)   # row of joint j, sample k
    joint_of_row = np.tile(np.arange(count), samples)
    return rr.Transform3D.columns(translation=_float_rows(translations, 3)[time_major],
                                  quaternion=_float_rows(quaternions, 4)[time_major],
                                  parent_frame=frame_id_rows(parents, joint_of_row),
                                  child_frame=frame_id_rows(children, joint_of_row))


def shape_archetype(name: str, shape: Shape, placement: np.ndarray | None = None) -> rr.AsComponents:
    """A solid Rerun primitive of ``shape`` (metres) placed by ``placement`` (4x4, default the
    identity) in its owner's frame, labelled ``name``: coal's sphere, box (full edge
    lengths), cylinder and capsule (length along z, centred); a halfspace as
    ``drawn_shape`` draws it."""
    shape, placement = drawn_shape(shape, np.eye(4) if placement is None else placement)
    rotation, centre = placement[:3, :3], placement[:3, 3]
    solid = {"fill_mode": rr.components.FillMode.Solid, "labels": [name],
             "quaternions": [quaternion_from_matrix(rotation)]}
    if shape.kind == "sphere":
        return rr.Ellipsoids3D(half_sizes=[[shape.radius] * 3], centers=[centre], **solid)
    if shape.kind == "box":
        return rr.Boxes3D(half_sizes=[0.5 * np.asarray(shape.size)], centers=[centre], **solid)
    if shape.kind == "cylinder":
        return rr.Cylinders3D(lengths=[shape.length], radii=[shape.radius], centers=[centre], **solid)
    # a capsule: Rerun's runs from its origin along +z
    return rr.Capsules3D(lengths=[shape.length], radii=[shape.radius],
                         translations=[centre - 0.5 * shape.length * rotation[:, 2]], **solid)


class RerunLogger(ClosesOnExit):
    """Writes one .rrd file for a run of the robot in ``urdf_path`` (None: a scene without
    a robot) and of the scene's ``geometries`` (free bodies: owner ``body``; static: owner
    ``world`` or ``link``); a context manager.

    ``log_sample`` appends one sample of the robot (for a running node; buffered and sent
    every ``batch_size`` samples or ``flush_span`` simulated seconds, whichever comes
    first); ``log_trajectory`` appends many at once (for offline runs); ``log_body_poses``
    (or ``log_body_rows``, an array) appends one sample of the free bodies (buffered alike).
    All send with ``send_columns``. ``close`` (idempotent; also on ``__exit__``) sends what
    is buffered, writes the end-effector path and disconnects so the file gets its footer.
    Joint names must be moving URDF joints (``UserInputError`` otherwise); values must be
    finite and times integer nanoseconds (``MessageFieldError``, a ValueError naming the
    field, otherwise). The path is held under an advisory lock while the recording is
    open (a second writer gets ``LogPathInUse``, see ``io.log_file``).

    Room: Rerun 0.41 writes the file from its own thread and reports a failed write only on
    stderr, after which its flush, disconnect and the interpreter's exit block forever. So
    the logger stops before that can happen: before each batch it asks
    :func:`~youbot_dynamics.io.log_file.room_left` (free space, file-size limit), and if
    less is left than ``reserve_bytes`` + four times the most the file grew between two
    batches + an eighth of its size (the footer's manifest: ~7 % measured), it drops the
    batch, finishes the file (footer written) and sets ``failure``
    (:class:`~youbot_dynamics.io.log_file.LogWriteFailed`; ``messages`` counts samples);
    ``closed`` is then True and later log calls do nothing.
    """

    def __init__(
        self,
        path: str | Path,
        urdf_path: str | Path | None,
        *,
        geometries: Sequence[Geometry] = (),
        recording_name: str,
        application_id: str = "youbot_dynamics",
        recording_id: str | None = None,
        world_frame: str | None = None,
        root_frame: str | None = None,
        static_frames: Sequence[tuple[str, str]] | None = None,
        moving_frames: Sequence[tuple[str, str]] = (),
        batch_size: int = DEFAULT_BATCH_SIZE,
        flush_span: float = DEFAULT_FLUSH_SPAN,
        reserve_bytes: int = RESERVE_BYTES,
    ) -> None:
        """Start the recording at ``path``, log the robot from ``urdf_path``, the shapes of
        the free bodies and the static geometry.

        ``world_frame`` is the frame free-body poses and world geometry are given in
        (default: the URDF root link; ``world`` without a robot), ``root_frame`` the one of
        the end-effector positions (default: the world frame); ``static_frames`` the one
        identity transform (parent, child) at most that joins the root to the robot
        (default: world frame -> root link if they differ), ``moving_frames`` the edges
        (parent, child) ``log_frame_rows`` moves each sample. Free bodies need names
        distinct from the URDF's links and the world frame.
        ``reserve_bytes``: room kept free (see the class docstring).
        """
        self.path = Path(path)
        self.urdf_path = None if urdf_path is None else Path(urdf_path)
        self._joints: dict[str, UrdfJoint] = {}
        if self.urdf_path is not None:
            tree = self._urdf_tree(self.urdf_path)
            self._joints = {joint.name: joint for joint in tree.joints() if joint.joint_type != "fixed"}
        bodies = [g for g in geometries if g.owner == "body"]
        self.bodies = tuple(g.name for g in bodies)
        root_link = None if self.urdf_path is None else tree.root_link().name
        self.world_frame = world_frame or root_link or "world"
        self.root_frame = root_frame or self.world_frame
        self.moving_frames = tuple(moving_frames)
        self._frame_rows: list[tuple[int, np.ndarray]] = []
        """Buffered samples of ``log_frame_rows``: stamp (ns) and rows (edges, 7)."""
        links = set() if self.urdf_path is None else {root_link, *(joint.child_link for joint in tree.joints())}
        clash = sorted(set(self.bodies) & (links | {self.world_frame}))
        if clash:
            raise UserInputError(f"Rerun log: free bodies {clash} have the names of robot frames; rename them")
        self._body_rows: list[tuple[int, np.ndarray]] = []
        """Buffered free-body samples: stamp (ns) and rows (bodies, 7) of translation and quaternion."""
        self.batch_size = max(1, int(batch_size))
        self.flush_span_ns = round(float(flush_span) * 1e9)
        self._series_names: tuple[str, ...] | None = None
        self._pending: list[np.ndarray] = []
        """Buffered samples of ``log_sample``: rows of q, v, tau, energy, ee (checked)."""
        self._pending_t: list[int] = []
        self._pending_names: tuple[str, ...] = ()
        self._ee_path: list[np.ndarray] = []
        self._lock: FileSink | None = FileSink(open_exclusive(self.path, "Rerun recording", truncate=False))
        self.failure: LogWriteFailed | None = None
        """Set when logging stopped for want of room (see the class docstring)."""
        self.reserve_bytes = int(reserve_bytes)
        self._growth = 0          # most bytes the file grew by between two batches
        self._size: int | None = None    # the file's size at the last batch (None before the first)
        self._sent = 0            # samples sent (joint, body and moving-frame samples)
        self._rec: rr.RecordingStream | None = rr.RecordingStream(
            application_id, recording_id=recording_id, send_properties=False
        )
        self._rec.save(self.path)
        self._rec.set_log_time_enabled(False)
        self._rec.set_log_tick_enabled(False)
        self._rec.send_recording_name(recording_name)
        for body in bodies:
            self._rec.log(body_entity(body.name), shape_archetype(body.name, body.shape, body.placement),
                          rr.CoordinateFrame(body.name), static=True)
        for geometry in geometries:
            if geometry.owner != "body":
                frame = self.world_frame if geometry.owner == "world" else geometry.owner_name
                self._rec.log(geometry_entity(geometry.name), rr.CoordinateFrame(frame),
                              shape_archetype(geometry.name, geometry.shape, geometry.placement), static=True)
        if root_link is not None:
            self._log_robot(root_link, static_frames)

    def _log_robot(self, root_link: str, static_frames: Sequence[tuple[str, str]] | None) -> None:
        """The URDF (static), the identity transform that joins the root frame to it (the
        first of ``static_frames``; default: world frame -> root link if they differ) and
        the end effector's frame."""
        self._rec.log_file_from_path(self.urdf_path, static=True)
        if static_frames is None:
            static_frames = [(self.world_frame, root_link)] if self.world_frame != root_link else []
        for parent, child in static_frames[:1]:
            self._rec.log(WORLD_FRAME, rr.Transform3D(parent_frame=parent, child_frame=child), static=True)
        self._rec.log(EE_POSITION, rr.CoordinateFrame(self.root_frame), static=True)
        self._rec.log(EE_PATH, rr.CoordinateFrame(self.root_frame), static=True)

    @staticmethod
    def _urdf_tree(urdf_path: Path) -> UrdfTree:
        if not urdf_path.is_file():
            raise UserInputError(f"Rerun log: URDF {urdf_path} does not exist")
        try:
            return UrdfTree.from_file_path(urdf_path)
        except Exception as error:  # the Rust parser raises plain exceptions
            message = f"Rerun log: URDF {urdf_path} cannot be parsed ({error})"
            raise UserInputError(message) from error

    @property
    def closed(self) -> bool:
        """True once the recording is finalised."""
        return self._rec is None

    def log_sample(
        self,
        stamp_ns: int,
        joint_names: Sequence[str],
        q: Sequence[float],
        v: Sequence[float],
        tau: Sequence[float],
        energy: float,
        ee_position: Sequence[float],
    ) -> None:
        """Log one sample at simulated time ``stamp_ns`` (integer ns): joint positions ``q``,
        velocities ``v``, efforts ``tau`` (ordered as ``joint_names``), total energy (J) and
        the end-effector position (m, in ``root_frame``); the joint transforms follow ``q``.

        Samples are checked at once and sent in batches of ``batch_size`` or spanning
        ``flush_span`` s (one Rerun call per entity per batch instead of one per sample);
        ``close`` sends the rest.
        """
        if self.failure is not None:
            return
        self._recording()
        names = tuple(joint_names)
        if names != self._pending_names:
            self._resolve(names)
            self._flush()
            self._pending_names = names
        n = len(names)
        t = _stamp(stamp_ns)
        row = np.concatenate((q, v, tau, (energy,), ee_position), axis=None, dtype=np.float64)
        if row.size != 3 * n + 4 or not np.isfinite(row).all():    # the field checks name what is wrong
            row = np.concatenate([finite_floats(q, "Rerun q", n), finite_floats(v, "Rerun v", n),
                                  finite_floats(tau, "Rerun tau", n), finite_floats([energy], "Rerun energy", 1),
                                  finite_floats(ee_position, "Rerun ee_position", 3)])
        self._pending.append(row)
        self._pending_t.append(t)
        if len(self._pending) >= self.batch_size or t - self._pending_t[0] >= self.flush_span_ns:
            self._flush()

    def log_body_poses(self, stamp_ns: int, poses: Mapping[str, tuple[Sequence[float], Sequence[float]]]) -> None:
        """Log the free bodies at simulated time ``stamp_ns`` (integer ns): ``poses`` maps
        every body named at construction to (translation (m), quaternion (x, y, z, w)) in
        the world frame. Checked at once, sent in batches of ``batch_size`` like
        ``log_sample``."""
        if self.failure is not None:
            return
        self._recording()
        if set(poses) != set(self.bodies):
            raise UserInputError(f"Rerun log: poses for {sorted(poses)}, expected the free bodies "
                                 f"{sorted(self.bodies)}")
        self._buffer_bodies(_stamp(stamp_ns), np.array(
            [finite_floats(poses[name][0], f"Rerun {name} translation", 3)
             + finite_floats(poses[name][1], f"Rerun {name} quaternion", 4) for name in self.bodies]))

    def log_body_rows(self, stamp_ns: int, rows: np.ndarray) -> None:
        """``log_body_poses`` of the free bodies as rows (one per body, in ``bodies``
        order) of translation (m) and quaternion (x, y, z, w): one check of the array."""
        if self.failure is not None:
            return
        self._recording()
        rows = np.asarray(rows, dtype=np.float64)
        if rows.shape != (len(self.bodies), 7) or not np.isfinite(rows).all():    # log_body_poses names it
            self.log_body_poses(stamp_ns, {name: (row[:3], row[3:]) for name, row in zip(self.bodies, rows)})
            return
        self._buffer_bodies(_stamp(stamp_ns), rows)

    def log_frame_rows(self, stamp_ns: int, rows: np.ndarray) -> None:
        """The poses of ``moving_frames`` at simulated time ``stamp_ns`` (integer ns): rows
        (edges, 7) of translation (m) and quaternion (x, y, z, w), child in parent; sent in
        batches like ``log_sample``."""
        self._recording()
        rows = finite_array(rows, "Rerun moving frames", len(self.moving_frames) * 7).reshape(-1, 7)
        t = _stamp(stamp_ns)
        self._frame_rows.append((t, rows))
        if len(self._frame_rows) >= self.batch_size or t - self._frame_rows[0][0] >= self.flush_span_ns:
            self._flush_frames()

    def _buffer_bodies(self, t: int, rows: np.ndarray) -> None:
        """Buffer checked body rows at ``t`` (ns); send the batch when it is full or spans
        ``flush_span``."""
        self._body_rows.append((t, rows))
        if len(self._body_rows) >= self.batch_size or t - self._body_rows[0][0] >= self.flush_span_ns:
            self._flush_bodies()

    def log_trajectory(
        self,
        stamps: Sequence[int],
        joint_names: Sequence[str],
        q: np.ndarray,
        v: np.ndarray,
        tau: np.ndarray,
        energy: Sequence[float],
        ee_position: np.ndarray,
    ) -> None:
        """Log N samples at once: ``stamps`` (N,) in integer ns; ``q``, ``v``, ``tau`` (N, n)
        ordered as ``joint_names``; ``energy`` (N,) in J; ``ee_position`` (N, 3) in m."""
        if self.failure is not None:
            return
        self._recording()
        names = tuple(joint_names)
        self._resolve(names)
        times = stamps_ns(stamps, "Rerun stamps")
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
        if self._out_of_room():
            return
        self._sent += count
        self._send(names, samples)

    def close(self) -> None:
        """Send pending samples, log the end-effector path and finalise the file; later
        calls do nothing."""
        if self._rec is None or self._out_of_room():
            return
        self._flush()
        self._flush_bodies()
        self._flush_frames()
        rec, self._rec = self._rec, None
        if self._ee_path:
            rec.log(EE_PATH, rr.LineStrips3D([np.concatenate(self._ee_path)]), static=True)
        rec.flush()
        rec.disconnect()
        lock, self._lock = self._lock, None
        lock.close()

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

    def _out_of_room(self) -> bool:
        """Stop the recording (footer written, ``failure`` set, buffers dropped) if the file
        has too little room left for the next batch and its footer; True if stopped."""
        if self._rec is None:
            return True
        try:
            size = self.path.stat().st_size
            room, error = room_left(self.path)
        except OSError:            # the file gone or its file system unreadable: Rerun writes on regardless
            return False
        self._growth, self._size = max(self._growth, size - (size if self._size is None else self._size)), size
        needed = self.reserve_bytes + 4 * self._growth + size // 8
        if room >= needed:
            return False
        lost = len(self._pending) + len(self._body_rows)
        self._pending, self._pending_t, self._body_rows = [], [], []
        rec, self._rec = self._rec, None
        rec.flush()
        rec.disconnect()
        lock, self._lock = self._lock, None
        lock.close()
        text = "file-size limit" if error == "EFBIG" else "no space left on its file system"
        self.failure = LogWriteFailed(
            path=self.path, kind="Rerun recording", errno=error,
            reason=f"{error} ({text}: {room} bytes left, {needed} kept for the next batch and the footer)",
            messages=self._sent, bytes=self.path.stat().st_size, lost=lost, finalised=True,  # with its footer
            unit="samples")
        return True

    def _flush(self) -> None:
        """Send the samples buffered by ``log_sample``."""
        if self._pending and self._out_of_room():
            return
        if self._pending:
            self._sent += len(self._pending)
            rows, times, self._pending, self._pending_t = np.vstack(self._pending), self._pending_t, [], []
            n = len(self._pending_names)
            self._send(self._pending_names, Samples(np.array(times, dtype=np.int64), rows[:, :n], rows[:, n:2 * n],
                                                    rows[:, 2 * n:3 * n], rows[:, 3 * n], rows[:, 3 * n + 1:]))
            self._recording().flush(timeout_sec=0.0)     # start writing to the file, do not wait

    def _flush_bodies(self) -> None:
        """Send the free-body poses buffered by ``log_body_poses``: one Transform3D column
        per body."""
        rows, self._body_rows = self._body_rows, []
        self._send_transforms(rows, [(body_entity(name), self.world_frame, name) for name in self.bodies])

    def _flush_frames(self) -> None:
        """Send the moving frames' poses buffered by ``log_frame_rows``."""
        rows, self._frame_rows = self._frame_rows, []
        self._send_transforms(rows, [(f"{BASE_FRAMES}/{child}", parent, child) for parent, child in self.moving_frames])

    def _send_transforms(self, rows: list[tuple[int, np.ndarray]], edges: Sequence[tuple[str, str, str]]) -> None:
        """Send buffered samples (stamp ns, rows (edges, 7)) as one Transform3D column per
        edge (entity, parent frame, child frame)."""
        if not rows or self._out_of_room():
            return
        self._sent += len(rows)
        index = [rr.TimeColumn(TIMELINE, duration=durations([t for t, _ in rows]))]
        poses = np.array([pose for _, pose in rows])    # (samples, edges, 7)
        for k, (entity, parent, child) in enumerate(edges):
            columns = rr.Transform3D.columns(translation=poses[:, k, :3], quaternion=poses[:, k, 3:],
                                             parent_frame=frame_id_rows([parent], np.zeros(len(rows), np.intp)),
                                             child_frame=frame_id_rows([child], np.zeros(len(rows), np.intp)))
            self._recording().send_columns(entity, indexes=index, columns=columns)
        self._recording().flush(timeout_sec=0.0)

    def _send(self, names: tuple[str, ...], samples: Samples) -> None:
        """Send checked samples (arrays as in ``log_trajectory``) with ``send_columns``."""
        rec = self._recording()
        if names != self._series_names:
            for entity in SERIES.values():
                rec.log(entity, rr.SeriesLines(names=list(names)), static=True)
            self._series_names = names
        index = [rr.TimeColumn(TIMELINE, duration=durations(samples.t))]
        joints = self._resolve(names)
        rec.send_columns(JOINT_TRANSFORMS, indexes=[rr.TimeColumn(TIMELINE, duration=durations(
            np.repeat(samples.t, len(joints))))], columns=joint_transform_columns(joints, samples.q))
        for field, entity in SERIES.items():
            scalars = rr.Scalars.columns(scalars=getattr(samples, field))
            rec.send_columns(entity, indexes=index, columns=scalars)
        rec.send_columns(ENERGY, indexes=index, columns=rr.Scalars.columns(scalars=samples.energy))
        points = rr.Points3D.columns(positions=samples.ee).partition([1] * len(samples.t))
        rec.send_columns(EE_POSITION, indexes=index, columns=points)
        self._ee_path.append(samples.ee)

