"""The simulate-mode session: a scene stepped at a fixed rate, each sample's messages built
(:mod:`youbot_dynamics.node.session` says what is built and logged, and when).

Simulate mode advances simulated time by fixed increments: sample k is at exactly
``k * round(1e9 / publish_rate)`` ns, whatever the wall clock does. ``reset`` restarts the
scene but not the clock: the samples after a reset continue from the last stamp (the
scene's t = 0 is then at ``epoch_ns``), so /clock, every header stamp and the log times of
the MCAP and the Rerun recording stay monotonic in one run and no stamp repeats. The reset
is recorded as an event: /diagnostics (also logged) carries ``resets`` and
``last_reset_at`` (node time, s). Time semantics of the inputs: :mod:`youbot_dynamics.node.commands`.

Free bodies are published on /free_bodies (their names, in that order, are the
``free_bodies`` value of /diagnostics) and drawn in the Rerun recording as their shapes. A
moving base (:mod:`youbot_dynamics.node.mobile_base`) adds /cmd_vel, /odom and
/base_pose_ground_truth; the sensors (:mod:`youbot_dynamics.node.sensors`) /wrist_wrench and
/imu.
"""
from __future__ import annotations

import dataclasses
import math
import time
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from youbot_dynamics.integrate.integrators import DivergenceError, checked_output_spacing
from youbot_dynamics.io import messages
from youbot_dynamics.io.cdr_group import Entry, TopicBatches
from youbot_dynamics.io.cdr_template import Refilled
from youbot_dynamics.io.stamps import NS_PER_S
from youbot_dynamics.node.commands import (DEFAULT_EFFORT_LIMIT, EffortCommands, InputCounters, InputRejected,
                                           follow, joint_trajectory, node_time_of_stamp)
from youbot_dynamics.node.frames import FramesBatch, ee_rows
from youbot_dynamics.node.interface import Outputs
from youbot_dynamics.node.mobile_base import BaseSample, MobileBase
from youbot_dynamics.node.sensors import SensorMessages
from youbot_dynamics.node.session import Session
from youbot_dynamics.scene.schema import Scene
from youbot_dynamics.sim.companion import CompanionStream
from youbot_dynamics.sim.error_estimate import ErrorEstimate
from youbot_dynamics.sim.simulator import Simulator, Snapshot

NOT_REPORTED = "n/a"
"""The value (diagnostics) of a figure that is not known."""


def reported(value: float | int | str | None) -> float | int | str:
    """``value``, or ``NOT_REPORTED`` when it is None (a counter the integrator does not
    report) or a non-finite float (a rate over no wall time yet)."""
    if value is None or (isinstance(value, float) and not math.isfinite(value)):
        return NOT_REPORTED
    return value


class SimulationSession(Session):
    """A scene simulated step by step at ``publish_rate`` (Hz) samples per simulated second
    (the same scene, rate and ``samples_per_solve`` give the same samples, bit for bit).

    Inputs: ``effort_command`` (sensor_msgs/JointState fields), ``trajectory``
    (trajectory_msgs/JointTrajectory fields), ``reset``, ``paused``. Each ``step`` advances
    simulated time by one increment and returns the messages to publish. A divergence pauses
    the session (``failure`` says why); it never yields non-finite output.
    """

    mode = "simulate"
    moving_base: MobileBase | None = None
    """The moving base's command and odometry (None for a fixed base)."""

    @property
    def sample_topic(self) -> str:
        """The topic that carries every sample of the motion: /joint_states, or /free_bodies in
        a scene without a robot (/clock if it has neither)."""
        return next(topic for topic in ("/joint_states", "/free_bodies", "/clock") if topic in self.topics)

    def __init__(self, scene: Scene, publish_rate: float, *, command_timeout: float = 0.5,
                 on_timeout: str = "hold", samples_per_solve: int = 5, frame_id: str = "", ee_link: str = "",
                 mcap_path: str | Path | None = None, rrd_path: str | Path | None = None,
                 default_effort_limit: float = DEFAULT_EFFORT_LIMIT, callback_budget: float = 0.05,
                 frame_prefix: str = "", node_name: str = "dynamics_node", error_estimate: bool = False) -> None:
        self.simulator = Simulator(scene, scene.pinned_integrator())
        self.companion = CompanionStream(self.simulator.model) if error_estimate else None
        if self.simulator.model.base is not None:
            self.moving_base = MobileBase(self.simulator.model.base, InputCounters(), command_timeout, frame_prefix,
                                          self.simulator.robot.root_link)
        moving = self.moving_base is not None
        sensors = frozenset(feature for feature, present in (
            ("wrist_sensor", self.simulator.model.sensors.wrist is not None),
            ("contact_pairs", bool(scene.contacts))) if present)
        super().__init__(scene, self.simulator.robot, frame_id, ee_link, mcap_path, rrd_path, callback_budget,
                         frame_prefix, node_name, moving_base=moving, moving_root=moving, sensors=sensors,
                         pairs=[(pair.geometry1, pair.geometry2) for pair in scene.contacts])
        self._sensors = SensorMessages(self.simulator.model, self.frames.prefix, self.frames.root_frame, self.topics)
        if self.moving_base is not None:
            self.moving_base.counters = self.counters
        self.step_ns = max(1, round(NS_PER_S / publish_rate))
        checked_output_spacing(self.simulator.integrator.dt, np.array([0.0, self.step_ns / NS_PER_S]),
                               f"{scene.source}: integrator.dt (publish_rate {publish_rate:g} Hz)")
        self.samples_per_solve = max(1, int(samples_per_solve))
        self.commands = EffortCommands(self.robot, command_timeout, on_timeout, self.counters, default_effort_limit)
        self.locked_names = tuple(j.name for j in self.robot.tree if j.name in self.robot.locked)
        self._joint_states = Refilled()
        self._clock = Refilled(stamped=lambda path: path == "clock")
        self._batches = TopicBatches()
        self._locked_q = np.array([self.robot.locked[name] for name in self.locked_names])
        self.paused = False
        self.failure: str | None = None
        self.k, self.epoch_ns, self.resets, self.last_reset_ns, self._started = 0, 0, 0, None, False
        self.reset()

    @property
    def t(self) -> float:
        """Node time (s): simulated time since the start, resets included."""
        return self.stamp_ns / NS_PER_S

    @property
    def stamp_ns(self) -> int:
        """Stamp (ns) of the current sample (node time)."""
        return self.epoch_ns + self.k * self.step_ns

    @property
    def scene_time(self) -> float:
        """Simulated time (s) of the current sample since the scene's last (re)start."""
        return self.k * self.step_ns / NS_PER_S

    def reset(self) -> None:
        """Back to the scene's initial state (the next ``step`` gives that sample, one
        increment after the last one published: node time goes on, see the module
        docstring); forgets commands and trajectories."""
        if self._started:
            self.epoch_ns = self.last_reset_ns = self.stamp_ns + self.step_ns
            self.resets += 1
        self.simulator.reset()
        if self.companion is not None:
            self.companion.reset()
        self.commands.clear()
        if self.moving_base is not None:
            self.moving_base.reset()
        self.k, self.failure, self.wall_time, self._pending, self._prebuilt, self._based = 0, None, 0.0, [], [], []
        self.snapshot = self.simulator.snapshot(self._sensors.wanted)
        self.energy0, self.energy_error = self.snapshot.energy, 0.0
        self._started = False

    def effort_command(self, names: Sequence[str], efforts: Sequence[float], stamp_ns: int,
                       wall_ns: int | None = None) -> None:
        """Accept an effort command (raises and counts :class:`InputRejected`); ``wall_ns``:
        the wall clock (default: the machine's), for wall-clock stamps."""
        self.commands.accept(names, efforts, stamp_ns, self.t, wall_ns)

    def base_command(self, linear: Sequence[float], angular: Sequence[float]) -> None:
        """Accept a /cmd_vel twist (raises and counts :class:`InputRejected`; a scene without
        a moving base rejects it as ``no_controller``)."""
        if self.moving_base is None:
            error = InputRejected("no_controller", f"/cmd_vel: scene {self.scene.name!r} has a fixed base")
            self.counters.reject(error)
            raise error
        self.moving_base.accept(linear, angular, self.t)

    def trajectory(self, names: Sequence[str], points: Sequence[tuple[int, Sequence[float], Sequence[float]]],
                   stamp_ns: int, wall_ns: int | None = None) -> None:
        """Follow a joint trajectory from its stamp (node time, see
        :func:`~youbot_dynamics.node.commands.node_time_of_stamp`: unstamped or a past stamp
        within the command timeout: now; a wall-clock stamp: by its age; far future or older:
        rejected); ``points`` are (time_from_start (int ns), positions, velocities)."""
        try:
            start_ns = max(node_time_of_stamp(stamp_ns, self.stamp_ns, round(self.commands.timeout * NS_PER_S),
                                              "trajectory", wall_ns), self.stamp_ns)
            follow(self.simulator, joint_trajectory(self.robot, names, points, start_ns - self.epoch_ns,
                                                               self.simulator.q))
        except InputRejected as error:
            self.counters.reject(error)
            raise
        self.counters.accepted += 1
        self.commands.clear()

    def step(self) -> Outputs:
        """The sample at t = 0 first, then advance one increment per call; returns the
        messages to publish (none when paused or failed).

        The simulator runs ``samples_per_solve`` increments per integrator call and the
        samples are handed out one per step, so a command or trajectory takes effect at the
        next such block (a latency of at most ``samples_per_solve`` increments)."""
        if self.paused or self.failure is not None:
            return []
        if not self._started:
            self._started = True
            based = self._base_outputs([self.snapshot], self.k)
            return self._outputs(self.snapshot, None, based[0] if based else None)
        if not self._pending:
            times = (self.k + 1 + np.arange(self.samples_per_solve)) * self.step_ns / NS_PER_S
            if self.moving_base is not None:
                state = self.simulator.state
                state.reference = dataclasses.replace(state.reference, base_twist=self.moving_base.twist(self.t))
            start, command = time.perf_counter(), self.commands.torque(self.t)
            try:
                self._pending = self.simulator.advance_through(times, command, self._sensors.wanted)[::-1]
            except DivergenceError as error:
                self.failure = f"diverged after t = {self.t:.6f} s: {error}"
                return []
            finally:
                self.wall_time += time.perf_counter() - start
            pending = self._pending[::-1]
            if self.companion is not None:
                self.companion.submit(times, command, self.simulator.state.reference, pending)
            self._based = self._base_outputs(pending, self.k + 1)[::-1]
            self._prebuilt = self._block(pending, self._based[::-1])
        self.k += 1
        prebuilt = self._prebuilt.pop() if self._prebuilt else None
        based = self._based.pop() if self._based else None
        return self._outputs(self._pending.pop(), prebuilt if prebuilt is not None and prebuilt[0] == self.wanted
                             else None, based)

    def _base_outputs(self, snapshots: list[Snapshot], first: int) -> list[BaseSample]:
        """A moving base's outputs (:class:`~youbot_dynamics.node.mobile_base.BaseSample`) of
        samples ``first``, ``first + 1``, ... (``snapshots``, in time order), advancing its
        odometry once per sample in order ([] for a fixed base)."""
        if self.moving_base is None:
            return []
        return [self.moving_base.sample(k * self.step_ns / NS_PER_S, snapshot)
                for k, snapshot in enumerate(snapshots, start=first)]

    def _block(self, snapshots: list[Snapshot], based: list[BaseSample]) -> list[tuple]:
        """The messages of the next samples (``snapshots``, in time order; ``based``: a moving
        base's outputs of each) built at once, in pop order, each with the ``wanted`` they
        were built for; none when a message would be invalid (then each is built at its own
        step, so that the failure falls on its sample)."""
        stamps = [self.epoch_ns + (self.k + 1 + j) * self.step_ns for j in range(len(snapshots))]
        try:
            built = self._sample_messages(snapshots, stamps, based)
        except messages.MessageFieldError:
            return []
        return [(self.wanted, *sample) for sample in reversed(built)]

    def _sample_messages(self, snapshots: Sequence[Snapshot], stamps: Sequence[int],
                         based: Sequence[BaseSample]
                         ) -> list[tuple[Outputs, np.ndarray | None, np.ndarray | None, np.ndarray | None]]:
        """The messages of the topics in ``wanted`` of N samples at ``stamps`` (ns), built
        together, with each sample's end-effector row for the Rerun sample (the samples'
        kinematics in one pass feed /tf, /ee_pose and it; none when nothing takes them) and
        its free bodies' rows. A moving base's outputs (``based``, per sample: see
        :meth:`_base_outputs`) add /odom and /base_pose_ground_truth (before /tf); their rows
        (odom -> base_footprint, odom -> world) place /ee_pose(s) and go on /tf. Raises
        MessageFieldError."""
        bodies = self.frames.body_poses([snapshot.bodies for snapshot in snapshots]) if self.frames.body_shapes \
            else None
        samples = self.frames.links.at_many(np.array([snapshot.q for snapshot in snapshots])) \
            if self.frames.has_robot and self.kinematics_wanted else None
        base = np.array([sample.rows for sample in based]) if based else None
        entries = self._motion_entries(stamps, snapshots, samples, bodies, base)
        if based:
            entries += self.moving_base.entries(based, self.wanted)
        if "/tf" in self.wanted:
            entries.append(self.frames.tf_entry(len(stamps), samples, bodies, base))
        per_sample = self._batches.fill(stamps, entries)
        ee = None if samples is None else ee_rows(samples, base)[:, samples[0].ee_index]
        return [(outputs, None if ee is None else ee[k], None if bodies is None else bodies[k],
                 None if base is None else base[k]) for k, outputs in enumerate(per_sample)]

    def _motion_entries(self, stamps: Sequence[int], snapshots: Sequence[Snapshot], samples: FramesBatch | None,
                        bodies: np.ndarray | None, base: np.ndarray | None) -> list[Entry]:
        """The wanted topics before the base's and /tf, as :data:`~youbot_dynamics.io.cdr_group.Entry`
        of N samples at ``stamps`` (ns): /clock, /joint_states, /ee_pose(s) (from the
        kinematics ``samples`` and a moving base's rows ``base``), /free_bodies and
        /free_bodies_markers (from the body rows ``bodies``), then the sensors'."""
        wanted = self.wanted
        entries: list[Entry] = []
        if "/clock" in wanted:
            entries.append(("/clock", self._clock, np.zeros((len(stamps), 0)),
                            lambda stamp_ns, _: messages.clock(stamp_ns)))
        if "/joint_states" in wanted:
            entries.append(self._joint_states_entry(snapshots))
        if samples is not None:
            entries += self.frames.ee_entries(samples, wanted, base)
        if bodies is not None and "/free_bodies" in wanted:
            entries.append(self.frames.free_bodies_entry(bodies))
        if bodies is not None and "/free_bodies_markers" in wanted:
            entries.append(self.frames.free_body_markers_entry([s.bodies for s in snapshots]))
        return entries + self._sensors.entries(snapshots, wanted)

    def _outputs(self, snapshot: Snapshot, prebuilt: tuple | None, based: BaseSample | None) -> Outputs:
        """The sample's messages (``prebuilt``: (wanted, messages, end-effector row, body rows,
        base rows) of :meth:`_block`, or built now; ``based``: a moving base's outputs of the
        sample), logged (the Rerun recording's end effector in the root frame, or in odom
        with a moving base: :func:`~youbot_dynamics.node.frames.ee_rows`)."""
        stamp = self.stamp_ns
        self.snapshot = snapshot
        if self.simulator.conservative:
            self.energy_error = max(self.energy_error, abs(snapshot.energy - self.energy0))
        if self.moving_base is not None:
            self.moving_base.track_slip(based)
        try:
            outputs, ee, bodies, base = prebuilt[1:] if prebuilt is not None else \
                self._sample_messages([snapshot], [stamp], [based] if based is not None else [])[0]
            self.recorder.write(outputs, stamp)
        except messages.MessageFieldError as error:
            self.failure = f"non-finite output at t = {self.t:.6f} s: {error}"
            return []
        if base is not None:
            self.recorder.base(stamp, base)
        if ee is not None:
            self.recorder.sample(stamp, snapshot.joint_names, snapshot.q, snapshot.v, snapshot.tau, snapshot.energy,
                                 ee[:3])
        if bodies is not None:
            self.recorder.bodies(stamp, bodies)
        return outputs

    def _joint_states_entry(self, snapshots: Sequence[Snapshot]) -> Entry:
        """/joint_states of N samples as an :data:`~youbot_dynamics.io.cdr_group.Entry`: the
        moving joints (joint order), then every locked joint (URDF tree order) at its locked
        value with velocity and effort 0, so that every movable joint of the URDF has a
        position (robot_state_publisher needs wheels and fingers)."""
        count = len(snapshots)
        locked, zeros = np.tile(self._locked_q, (count, 1)), np.zeros((count, len(self.locked_names)))
        values = np.hstack([np.array([s.q for s in snapshots]), locked, np.array([s.v for s in snapshots]), zeros,
                            np.array([s.tau for s in snapshots]), zeros])
        return "/joint_states", self._joint_states, values, lambda stamp_ns, row: messages.joint_state(
            stamp_ns, (*snapshots[0].joint_names, *self.locked_names), *np.split(row, 3))

    def diagnostics(self, real_time_factor: float, progress: float | None = None) -> Outputs:
        """/diagnostics now: real-time factor (simulated s per wall s), integrator statistics,
        energy (J), input counters, the free bodies (names in /free_bodies order) and the
        contact events so far, a moving base's slip, the error estimate (with
        ``error_estimate``; at 100 % progress, every chunk's) and ``progress`` (percent of a
        run of set duration) if given; level ERROR after a divergence, WARN when paused or when the base's
        wheels slip. Figures not known (counters the integrator does not report) are
        ``NOT_REPORTED``."""
        stats = {f"integrator.{key}": reported(value) for key, value in self.simulator.stats.as_dict().items()}
        base_level, base_values = self.moving_base.report() if self.moving_base is not None else ("OK", {})
        values = {"sim_time": self.t, "real_time_factor": reported(real_time_factor),
                  "energy": self.snapshot.energy, "energy_error": self.energy_error,
                  "paused": self.paused, "command": self._command_source(), "resets": self.resets,
                  "last_reset_at": "none" if self.last_reset_ns is None else self.last_reset_ns / NS_PER_S,
                  **stats, **self.counters.as_values(),
                  **self.contact_values(), **base_values, **({} if progress is None else {"progress": progress}),
                  **self.error_estimate_values(wait=progress is not None and progress >= 100.0)}
        level, text = ("ERROR", self.failure) if self.failure else (("WARN", "paused") if self.paused else ("OK", "running"))
        if (level, base_level) == ("OK", "WARN"):
            level, text = "WARN", f"base wheels slip: {base_values['base.slip']:.3g} m/s at a hub"
        return self._diagnostic_outputs(level, text, values)

    def error_estimate(self, wait: bool = False) -> ErrorEstimate | None:
        """The run's error estimate so far (None without ``error_estimate`` or before the
        companion's first answer; ``wait``: after every chunk handed to it)."""
        if self.companion is None:
            return None
        return self.companion.estimate(self.simulator.events if self.simulator.model.contact else None, wait)

    def error_estimate_values(self, wait: bool = False) -> dict[str, object]:
        """/diagnostics ``accuracy`` (a scene with an ``accuracy`` target: the front point
        chosen, and why), ``error_estimate.*`` (:meth:`ErrorEstimate.values`, the largest
        difference per group since the last reset) and ``error_estimate.lag (chunks)``
        (nothing without ``error_estimate``). ``wait`` (a run's last report): after every chunk."""
        choice = {} if self.scene.accuracy_choice is None else {"accuracy": self.scene.accuracy_choice}
        if self.companion is None:
            return choice
        estimate = self.error_estimate(wait)
        values = {**choice, "error_estimate.lag (chunks)": self.companion.lag}
        return {**values, **({"error_estimate": "pending"} if estimate is None else estimate.values())}

    def close(self) -> None:
        """Stop the companion's worker, finalise the logs (idempotent)."""
        if self.companion is not None:
            self.companion.close()
        super().close()

    def contact_values(self) -> dict[str, object]:
        """``free_bodies`` (names, comma-separated, in /free_bodies order) and the contact
        events since the last reset up to the current sample (the simulator may have run
        ahead within its solve horizon): ``contact.events``, ``contact.events.<kind>`` per
        kind seen (touch, compression, separation, impact, contact: see
        :class:`~youbot_dynamics.sim.state.ContactEvent`) and ``contact.last_event``.
        Nothing for a scene without contact."""
        if self.simulator.model.contact is None:
            return {}
        events = [e for e in self.simulator.events if e.time <= self.scene_time + 0.5 / NS_PER_S]
        kinds = sorted({e.kind for e in events})
        last = events[-1] if events else None
        return {"free_bodies": ",".join(spec.body.name for spec in self.scene.free_bodies),
                "contact.events": len(events),
                **{f"contact.events.{kind}": sum(e.kind == kind for e in events) for kind in kinds},
                "contact.last_event": "none" if last is None else
                f"{last.kind} {last.pair} at t = {last.time:.6f} s (value {last.value:.6g})"}

    def _command_source(self) -> str:
        if self.commands.active(self.t):
            return "effort_command"
        if self.commands.received_at is not None and self.commands.on_timeout == "zero_torque":
            return "zero_torque (command timed out)"
        return f"scene controller ({self.simulator.controller.kind})"


