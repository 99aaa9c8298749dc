"""Free bodies and contact pairs of a scene for the ODE integrators: state blocks, contact
forces (compliant law), impacts (impulsive law) and the guards of the hybrid run.

The state extends the simulator's x = [q, v, z] with, per free body (see
:mod:`youbot_dynamics.dynamics.free_body`), the blocks ``p``, ``r``, ``phi``, ``u``, ``w``
and, per compliant pair, ``s``: the normal approach speed (m/s) at the pair's last touch,
held constant (zero derivative) and set by the touch guard; the Hunt-Crossley hysteresis
factor of the pair is derived from it. Pairs in contact at t = 0 start with
``MIN_APPROACH_SPEED``, the floor applied at every touch.

Generalised velocities for impacts: nu = [v (robot, nv), (u_k, w_k) per body], with the
block-diagonal inverse mass diag(M(q)^-1, (I/m_k, I_w,k^-1)).

Where a pair's overlap is a patch of N points (a face on a face), each point carries 1/N of
the law's force at the patch depth.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from youbot_dynamics.dynamics import free_body as fb
from youbot_dynamics.dynamics.collision import BroadPhase, ContactPoint, Geometry, PlacedPair
from youbot_dynamics.dynamics.contact import (HuntCrossley, NewtonImpact, hunt_crossley_force,
                                              hunt_crossley_potential, hysteresis_factor, newton_impulse,
                                              regularised_coulomb)
from youbot_dynamics.model.lie import skew
from youbot_dynamics.model.robot import Robot
from youbot_dynamics.sim.events import Transition
from youbot_dynamics.sim.integrators import IntegrationError
from youbot_dynamics.sim.scene import Scene

#: Floor (m/s) of the approach speed the hysteresis factor is derived from.
MIN_APPROACH_SPEED = 1e-2
#: Pairs farther apart than this (m) skip the narrow phase.
BROAD_PHASE_MARGIN = 1e-3


#: Guard values below this magnitude (m, m/s) read 0: a pair resting exactly at contact
#: would otherwise flicker across 0 at round-off level between a step's end and the
#: interpolated state there, and the root finder would see no sign change.
GUARD_RESOLUTION = 1e-12


def snapped(value: float) -> float:
    """``value``, or 0 when its magnitude is below GUARD_RESOLUTION."""
    return 0.0 if abs(value) < GUARD_RESOLUTION else value


@dataclass
class ContactEvent:
    """A contact event: time (s), pair, kind and value: ``impact`` (impulsive law): the
    normal impulse, N s; ``touch`` (compliant law): the approach speed, m/s;
    ``compression`` (compliant, maximum compression): the normal force there, N;
    ``separation`` (compliant): the separation speed, m/s; ``contact`` (constraint
    stepper, first step of a contact): the normal impulse, N s."""

    time: float
    pair: str
    kind: str
    value: float

    def as_dict(self) -> dict:
        """The event as plain data (time in s, value in the unit of its kind)."""
        return {"time": self.time, "pair": self.pair, "kind": self.kind, "value": self.value}


def homogeneous(rotation: np.ndarray, position: np.ndarray) -> np.ndarray:
    """The 4x4 homogeneous pose of a rotation (3x3) and a position (3,) in m."""
    pose = np.eye(4)
    pose[:3, :3], pose[:3, 3] = rotation, position
    return pose


def body_blocks(names: list[str]) -> dict[str, list[str]]:
    """State blocks of the free bodies: symbol -> component labels (``ball.x`` ...)."""
    axes = {3: ("x", "y", "z"), 4: ("qx", "qy", "qz", "qw")}
    return {symbol: [f"{name}.{axis}" for name in names for axis in axes[size]] for symbol, size in fb.BODY_BLOCKS}


class ContactSystem:
    """Contact part of a compiled scene (ODE path); ``layout`` slices come from the simulator."""

    def __init__(self, scene: Scene, robot: Robot, data: pin.Data) -> None:
        self.robot, self.data, self.gravity = robot, data, np.asarray(scene.gravity)
        self.bodies = [spec.body for spec in scene.free_bodies]
        self.initial = scene.free_bodies
        self.geometries: tuple[Geometry, ...] = scene.geometries
        index = {g.name: i for i, g in enumerate(self.geometries)}
        self.body_index = {body.name: k for k, body in enumerate(self.bodies)}
        self.pairs = scene.contacts
        self.sides = [(index[p.geometry1], index[p.geometry2]) for p in self.pairs]
        self.narrow = [PlacedPair(self.geometries[a].shape, self.geometries[b].shape) for a, b in self.sides]
        self.broad = BroadPhase([g.shape for g in self.geometries], self.sides, BROAD_PHASE_MARGIN)
        self.compliant = [k for k, p in enumerate(self.pairs) if isinstance(p.law, HuntCrossley)]
        self.impulsive = [k for k, p in enumerate(self.pairs) if isinstance(p.law, NewtonImpact)]
        self.frames = {g.owner_name: robot.frame_id(g.owner_name) for g in self.geometries if g.owner == "link"}
        self.awaiting = np.zeros(len(self.pairs), dtype=bool)
        self.deepest = 0.0
        self.events: list[ContactEvent] = []
        self.nb = len(self.bodies)

    def bind(self, slices: dict[str, slice]) -> None:
        """Where the blocks p, r, phi, u, w, s sit in x."""
        self.slices = slices

    def extra_blocks(self) -> dict[str, list[str]]:
        """The state blocks this system adds (symbol -> component labels): the free bodies'
        p, r, phi, u, w and the compliant pairs' approach speeds s."""
        blocks = body_blocks([b.name for b in self.bodies])
        blocks["s"] = [self.pairs[k].name for k in self.compliant]
        return blocks

    def initial_blocks(self) -> dict[str, np.ndarray]:
        """Initial body states and approach speeds."""
        values = {"p": [s.position for s in self.initial], "r": [s.orientation for s in self.initial],
                  "phi": [np.zeros(3)] * self.nb, "u": [s.velocity for s in self.initial],
                  "w": [s.angular_velocity for s in self.initial]}
        blocks = {k: np.concatenate(v) for k, v in values.items() if self.nb}
        if self.compliant:
            blocks["s"] = np.full(len(self.compliant), MIN_APPROACH_SPEED)
        return blocks

    # ---- kinematics ----------------------------------------------------------------------
    def _bodies(self, x: np.ndarray):
        get = {name: x[sl].reshape(self.nb, -1) for name, sl in self.slices.items() if name != "s"}
        rotations = [fb.orientation(get["r"][k], get["phi"][k]) for k in range(self.nb)]
        return get["p"], rotations, get["u"], get["w"], get["phi"]

    def _poses(self, q: np.ndarray, positions, rotations) -> list[np.ndarray]:
        if self.frames:
            pin.framesForwardKinematics(self.robot.model, self.data, q)
        poses = []
        for g in self.geometries:
            if g.owner == "world":
                poses.append(g.placement)
            elif g.owner == "body":
                k = self.body_index[g.owner_name]
                poses.append(homogeneous(rotations[k], positions[k]) @ g.placement)
            else:
                poses.append(self.data.oMf[self.frames[g.owner_name]].homogeneous @ g.placement)
        return poses

    def _point_jacobian(self, geometry: Geometry, point: np.ndarray, q: np.ndarray, positions) -> np.ndarray:
        """3 x (nv + 6 nb): velocity of the material point at ``point`` of the geometry's owner."""
        nv = self.robot.nv
        jacobian = np.zeros((3, nv + 6 * self.nb))
        if geometry.owner == "body":
            k = self.body_index[geometry.owner_name]
            jacobian[:, nv + 6 * k:nv + 6 * k + 3] = np.eye(3)
            jacobian[:, nv + 6 * k + 3:nv + 6 * k + 6] = -skew(point - positions[k])
        elif geometry.owner == "link":
            frame = self.frames[geometry.owner_name]
            full = pin.computeFrameJacobian(self.robot.model, self.data, q, frame, pin.LOCAL_WORLD_ALIGNED)
            origin = self.data.oMf[frame].translation
            jacobian[:, :nv] = full[:3] - skew(point - origin) @ full[3:]
        return jacobian

    def _relative_jacobian(self, k: int, point: np.ndarray, q: np.ndarray, positions) -> np.ndarray:
        """3 x (nv + 6 nb): velocity at ``point`` (world frame, m) of pair k's second
        geometry's owner relative to its first's (nu -> relative velocity, m/s)."""
        a, b = self.sides[k]
        return self._point_jacobian(self.geometries[b], point, q, positions) - \
            self._point_jacobian(self.geometries[a], point, q, positions)

    def _nu(self, x: np.ndarray, v: np.ndarray) -> np.ndarray:
        _, _, u, w, _ = self._bodies(x)
        return np.concatenate([v, *[np.concatenate([u[k], w[k]]) for k in range(self.nb)]])

    def _contacts(self, k: int, poses, margin: float) -> list[ContactPoint]:
        a, b = self.sides[k]
        return self.narrow[k].contact_points(poses[a], poses[b], margin)

    # ---- forces (compliant law) ------------------------------------------------------------
    def forces(self, x: np.ndarray, q: np.ndarray, v: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Joint torques (nv,) and body wrenches (nb, 6: force, torque about the centre of
        mass; world frame) of the compliant pairs at state x."""
        positions, rotations, _, _, _ = self._bodies(x)
        poses = self._poses(q, positions, rotations)
        nu = self._nu(x, v)
        generalised = np.zeros(self.robot.nv + 6 * self.nb)
        speeds = x[self.slices["s"]] if self.compliant else ()
        close = set(self.broad.close_pairs(poses))
        for j, k in enumerate(self.compliant):
            if k not in close:
                continue
            law: HuntCrossley = self.pairs[k].law
            points = [c for c in self._contacts(k, poses, 0.0) if c.depth > 0.0]
            chi = hysteresis_factor(law.restitution, speeds[j], law.damping_model)
            for c in points:
                relative = self._relative_jacobian(k, 0.5 * (c.point1 + c.point2), q, positions)
                u = relative @ nu
                un = float(u @ c.normal)
                fn = hunt_crossley_force(c.depth, -un, law.stiffness, law.exponent, chi) / len(points)
                force = fn * c.normal + regularised_coulomb(u - un * c.normal, fn, law.friction, law.velocity_scale)
                generalised += relative.T @ force
        wrenches = generalised[self.robot.nv:].reshape(self.nb, 6)
        return generalised[:self.robot.nv], wrenches

    def body_derivative(self, x: np.ndarray, wrenches: np.ndarray) -> dict[str, np.ndarray]:
        """d/dt of the body blocks (r and s: zero)."""
        _, rotations, u, w, phi = self._bodies(x)
        out = {"p": u.ravel(), "r": np.zeros(4 * self.nb), "phi": np.empty(3 * self.nb),
               "u": np.empty(3 * self.nb), "w": np.empty(3 * self.nb)}
        for k, body in enumerate(self.bodies):
            a, alpha = fb.newton_euler(body, rotations[k], w[k], wrenches[k, :3], wrenches[k, 3:], self.gravity)
            out["phi"][3 * k:3 * k + 3] = fb.phi_rate(phi[k], rotations[k], w[k])
            out["u"][3 * k:3 * k + 3], out["w"][3 * k:3 * k + 3] = a, alpha
        return out

    def energy(self, x: np.ndarray) -> float:
        """Kinetic plus gravitational potential energy of the free bodies (J)."""
        positions, rotations, u, w, _ = self._bodies(x)
        return sum(fb.kinetic_energy(b, rotations[k], u[k], w[k]) - b.mass * float(self.gravity @ positions[k])
                   for k, b in enumerate(self.bodies))

    def elastic_energy(self, x: np.ndarray, q: np.ndarray) -> float:
        """Energy (J) stored in the springs of the compliant pairs at state x: per contact
        point 1/N of the law's potential at the patch depth, as the force is shared."""
        positions, rotations, _, _, _ = self._bodies(x)
        poses = self._poses(q, positions, rotations)
        stored = 0.0
        for k in self.compliant:
            law: HuntCrossley = self.pairs[k].law
            points = [c for c in self._contacts(k, poses, 0.0) if c.depth > 0.0]
            stored += sum(hunt_crossley_potential(c.depth, law.stiffness, law.exponent) for c in points) / max(len(points), 1)
        return stored

    def overlaps(self, x: np.ndarray, q: np.ndarray) -> dict[str, float]:
        """The deepest overlap (m, >= 0) of every pair at state x, by pair name."""
        positions, rotations, _, _, _ = self._bodies(x)
        poses = self._poses(q, positions, rotations)
        return {pair.name: max([0.0] + [c.depth for c in self._contacts(k, poses, 0.0)])
                for k, pair in enumerate(self.pairs)}

    def poses_of(self, x: np.ndarray) -> dict[str, np.ndarray]:
        """World pose (4x4) of every free body at state x."""
        positions, rotations, _, _, _ = self._bodies(x)
        return {body.name: homogeneous(rotations[k], positions[k]) for k, body in enumerate(self.bodies)}

    # ---- guards and resets -----------------------------------------------------------------
    def transitions(self, q_slice: slice, v_slice: slice, mass_matrix) -> tuple[Transition, ...]:
        """Touch, maximum-compression and separation guards of compliant pairs, impact
        guards of impulsive pairs and the re-centring guards of the bodies. The compression
        guard (normal relative velocity rising through 0) is armed by a touch and disarmed
        when it fires (it reads -1 then), so a resting contact raises no events."""
        out = []

        def gap(k: int):
            a, b = self.sides[k]

            def function(t: float, x: np.ndarray) -> float:
                positions, rotations, _, _, _ = self._bodies(x)
                poses = self._poses(x[q_slice], positions, rotations)
                return snapped(self.narrow[k].signed_distance(poses[a], poses[b]))
            return function

        for j, k in enumerate(self.compliant):
            out.append(Transition(f"touch:{self.pairs[k].name}", gap(k), self._touch(j, k, q_slice, v_slice), -1))
            out.append(Transition(f"compression:{self.pairs[k].name}", self._armed_normal_speed(k, q_slice, v_slice),
                                  self._compression(j, k, q_slice), +1))
            out.append(Transition(f"separation:{self.pairs[k].name}", gap(k), self._separation(k, q_slice, v_slice), +1))
        for k in self.impulsive:
            out.append(Transition(f"impact:{self.pairs[k].name}", gap(k), self._impact(k, q_slice, v_slice, mass_matrix), -1))
        for k in range(self.nb):
            out.append(Transition(f"recentre:{self.bodies[k].name}", self._phi_norm(k), self._recentre(k), +1))
        return tuple(out)

    def _approach(self, k: int, x: np.ndarray, q: np.ndarray, v: np.ndarray):
        positions, rotations, _, _, _ = self._bodies(x)
        poses = self._poses(q, positions, rotations)
        c = self._contacts(k, poses, np.inf)[0]
        relative = self._relative_jacobian(k, 0.5 * (c.point1 + c.point2), q, positions)
        return c, relative, relative @ self._nu(x, v)

    def _touch(self, j: int, k: int, q_slice: slice, v_slice: slice):
        def reset(t: float, x: np.ndarray):
            c, _, u = self._approach(k, x, x[q_slice], x[v_slice])
            speed = max(-float(u @ c.normal), MIN_APPROACH_SPEED)
            x = x.copy()
            x[self.slices["s"].start + j] = speed
            self.events.append(ContactEvent(t, self.pairs[k].name, "touch", speed))
            self.awaiting[k] = True
            return "contact", x
        return reset

    def _armed_normal_speed(self, k: int, q_slice: slice, v_slice: slice):
        def function(t: float, x: np.ndarray) -> float:
            if not self.awaiting[k]:
                return -1.0
            c, _, u = self._approach(k, x, x[q_slice], x[v_slice])
            return snapped(float(u @ c.normal))
        return function

    def _compression(self, j: int, k: int, q_slice: slice):
        law: HuntCrossley = self.pairs[k].law

        def reset(t: float, x: np.ndarray):
            positions, rotations, _, _, _ = self._bodies(x)
            depth = max(c.depth for c in self._contacts(k, self._poses(x[q_slice], positions, rotations), np.inf))
            self.deepest = max(self.deepest, depth)
            force = hunt_crossley_force(depth, 0.0, law.stiffness, law.exponent, 0.0)
            self.events.append(ContactEvent(t, self.pairs[k].name, "compression", force))
            self.awaiting[k] = False
            return "contact", x
        return reset

    def _separation(self, k: int, q_slice: slice, v_slice: slice):
        def reset(t: float, x: np.ndarray):
            c, _, u = self._approach(k, x, x[q_slice], x[v_slice])
            self.events.append(ContactEvent(t, self.pairs[k].name, "separation", float(u @ c.normal)))
            self.awaiting[k] = False
            return "contact", x
        return reset

    def _impact(self, k: int, q_slice: slice, v_slice: slice, mass_matrix):
        law: NewtonImpact = self.pairs[k].law

        def reset(t: float, x: np.ndarray):
            q, v = x[q_slice], x[v_slice]
            c, relative, u = self._approach(k, x, q, v)
            if -float(u @ c.normal) < law.rest_speed:
                raise IntegrationError(
                    f"pair {self.pairs[k].name}: impact at {-float(u @ c.normal):.3g} m/s below rest_speed "
                    f"{law.rest_speed:g} m/s at t={t:.6g} s: the impulsive law carries impacts, not resting "
                    "contact (shorten the duration or use hunt_crossley or the constraint stepper)")
            inverse = self._inverse_mass(x, q, mass_matrix)
            impulse, _ = newton_impulse(relative @ inverse @ relative.T, u, c.normal, law.restitution, law.friction)
            change = inverse @ relative.T @ impulse
            x = x.copy()
            x[v_slice] += change[:self.robot.nv]
            for b in range(self.nb):
                x[self.slices["u"].start + 3 * b:self.slices["u"].start + 3 * b + 3] += \
                    change[self.robot.nv + 6 * b:self.robot.nv + 6 * b + 3]
                x[self.slices["w"].start + 3 * b:self.slices["w"].start + 3 * b + 3] += \
                    change[self.robot.nv + 6 * b + 3:self.robot.nv + 6 * b + 6]
            self.events.append(ContactEvent(t, self.pairs[k].name, "impact", float(impulse @ c.normal)))
            return "contact", x
        return reset

    def shortest_flight(self, gravity: float) -> float:
        """Duration (s) of the shortest ballistic hop an impulsive pair accepts,
        2 e v_rest / g (e at least 0.05): the step-size cap of adaptive integrators, so that a
        step never spans a whole hop (its impact would go unseen)."""
        hops = [2.0 * max(self.pairs[k].law.restitution, 0.05) * self.pairs[k].law.rest_speed / max(gravity, 1e-9)
                for k in self.impulsive]
        return min(hops)

    def _inverse_mass(self, x: np.ndarray, q: np.ndarray, mass_matrix) -> np.ndarray:
        nv = self.robot.nv
        inverse = np.zeros((nv + 6 * self.nb, nv + 6 * self.nb))
        if nv:
            inverse[:nv, :nv] = np.linalg.inv(mass_matrix(q))
        _, rotations, _, _, _ = self._bodies(x)
        for k, body in enumerate(self.bodies):
            start = nv + 6 * k
            inverse[start:start + 3, start:start + 3] = np.eye(3) / body.mass
            inverse[start + 3:start + 6, start + 3:start + 6] = rotations[k] @ np.linalg.inv(body.inertia) @ rotations[k].T
        return inverse

    def _phi_norm(self, k: int):
        def function(t: float, x: np.ndarray) -> float:
            return float(np.linalg.norm(x[self.slices["phi"]][3 * k:3 * k + 3])) - fb.RECENTRE_ANGLE
        return function

    def _recentre(self, k: int):
        def reset(t: float, x: np.ndarray):
            x = x.copy()
            r, phi = self.slices["r"].start + 4 * k, self.slices["phi"].start + 3 * k
            x[r:r + 4] = fb.recentred(x[r:r + 4], x[phi:phi + 3])
            x[phi:phi + 3] = 0.0
            return "contact", x
        return reset
