"""Wheel-floor contact of a mecanum base: the normal load on each wheel, the slip of each
contact point, and the roller friction law. Pure functions, base_footprint frame (x forward,
y left, z up), SI units; the simulation engine calls them.

Normal loads. Four wheels on a flat floor are statically indeterminate: three equilibrium
equations (vertical force, moments about x and y) for four loads. The rule used here: of all
non-negative loads N that balance them,

    sum N_i = W,   sum N_i x_i = W x_c,   sum N_i y_i = W y_c     (W = m g, (x_c, y_c) the
                                                                    centre of mass over the floor)

take the one of least Euclidean norm. While every load is positive this is the distribution
of a rigid base on equally stiff wheels (loads linear in the wheel position, the row space of
the equations); for the youBot's rectangle N_i = W (1/4 + x_c x_i / (4 lx^2) + y_c y_i /
(4 ly^2)). When that would lift a wheel (N_i < 0) the wheel carries nothing and the other
three carry the statically determinate loads; a centre of mass outside the wheels' support
polygon has no solution (:class:`TipOverError`).

With the centre of mass at height h above the floor and accelerating horizontally at a (m/s^2),
the floor's horizontal forces m a act at the floor, h below it: the moment balance shifts the
centre of mass of the rule to (x_c, y_c) - h a / g (the rate of change of the angular
momentum about the centre of mass is neglected).

Roller friction. A contact point slips at u = v_hub - r omega d (the hub's velocity minus the
rolling of the wheel, speed omega about its axis, drive direction d). The roller turns freely
along its axis e: no force there. Across it, along n = z x e, the floor resists with the
regularised Coulomb law of :func:`youbot_dynamics.dynamics.contact.regularised_coulomb`
(mu, velocity scale v_s) applied to the across component (u . n) n. The force acts on the
wheel at its contact point, and the wheel feels -r F . d about its spin axis.
"""
from __future__ import annotations

import math

import numpy as np
import pinocchio as pin

from youbot_dynamics.dynamics.contact import regularised_coulomb
from youbot_dynamics.dynamics.mobile.mecanum import MecanumBase, roller_normals
from youbot_dynamics.dynamics.mobile.support import SupportRule, TipOverError  # noqa: F401 (raised here)
from youbot_dynamics.errors import UserInputError
from youbot_dynamics.model.robot import Robot

STANDARD_GRAVITY = 9.81  # m/s^2, the project's scenes' value
_AT_REST = np.zeros(2)  # horizontal acceleration (m/s^2) of a centre of mass at rest
_AT_REST.setflags(write=False)


def support_loads(positions: np.ndarray, centre: np.ndarray, weight: float) -> np.ndarray:
    """Least-norm non-negative vertical loads (N) at the support points ``positions`` (n, 2)
    (m) carrying ``weight`` (N) applied at ``centre`` (x, y) (m): the rule of the module
    docstring (:class:`~youbot_dynamics.dynamics.mobile.support.SupportRule`, prepared per
    call: a base keeps its own, ``MecanumBase.support``)."""
    return SupportRule(positions).loads(centre, weight)


def wheel_normal_forces(base: MecanumBase, mass: float, centre_of_mass: np.ndarray, *,
                        gravity: float = STANDARD_GRAVITY, com_height: float = 0.0,
                        com_acceleration: np.ndarray = _AT_REST) -> np.ndarray:
    """Normal force on each wheel (N, ``base.names`` order) of a robot of ``mass`` (kg) whose
    centre of mass is at (x_c, y_c) (m, base_footprint; a z component is ignored), ``com_height``
    (m) above the floor, accelerating horizontally at ``com_acceleration`` (m/s^2, base frame).
    Raises :class:`TipOverError` when the shifted centre leaves the wheels' support polygon."""
    if not (math.isfinite(mass) and mass > 0.0 and math.isfinite(gravity) and gravity > 0.0):
        raise UserInputError(f"wheel normal forces: mass (kg) and gravity (m/s^2) must be positive, "
                             f"got {mass}, {gravity}")
    centre = np.asarray(centre_of_mass, dtype=float).ravel()[:2]
    shifted = centre - (com_height / gravity) * np.asarray(com_acceleration, dtype=float).ravel()[:2]
    return base.support.loads(shifted, mass * gravity)


def centre_of_mass_in_base(robot: Robot, data: pin.Data, q: np.ndarray) -> tuple[float, np.ndarray]:
    """Total mass (kg) and centre of mass (m, (3,)) of the whole robot at configuration q, in
    the root link's frame (base_footprint for the youBot), whatever the root joint."""
    com_world = pin.centerOfMass(robot.model, data, np.asarray(q, dtype=float))
    root = data.oMi[1] if robot.root != "fixed" else pin.SE3.Identity()
    return float(data.mass[0]), root.actInv(com_world)


def contact_slip_velocities(base: MecanumBase, twist: np.ndarray, speeds: np.ndarray) -> np.ndarray:
    """(n, 2) velocity (m/s, base frame) of each wheel's contact point over the floor, for the
    base twist (vx, vy, wz) and the wheel speeds (rad/s): u_i = v_hub,i - r omega_i d_i."""
    omega = np.asarray(speeds, dtype=float).ravel()
    return base.hub_velocities(twist) - base.radius * omega[:, None] * base.drive_directions


def roller_friction(slip: np.ndarray, roller_axis: np.ndarray, normal_force: float, mu: float,
                    velocity_scale: float) -> np.ndarray:
    """Planar floor force (N, base frame) on a wheel at its contact point: free along the
    roller axis e, regularised Coulomb (mu, v_s m/s) on the slip across it."""
    across = roller_normals(roller_axis)
    return _across_friction(slip, across / math.hypot(*across), normal_force, mu, velocity_scale)


def roller_forces(base: MecanumBase, slips: np.ndarray, normal_forces: np.ndarray, mu: float,
                  velocity_scale: float) -> np.ndarray:
    """(n, 2) :func:`roller_friction` of every wheel, ``base.names`` order."""
    return np.array([_across_friction(slip, across, load, mu, velocity_scale)
                     for slip, across, load in zip(slips, base.across, normal_forces)])


def _across_friction(slip: np.ndarray, across: np.ndarray, normal_force: float, mu: float,
                     velocity_scale: float) -> np.ndarray:
    """:func:`roller_friction` with the unit direction across the roller given."""
    return regularised_coulomb(float(np.asarray(slip) @ across) * across, normal_force, mu, velocity_scale)


def wheel_spin_torques(base: MecanumBase, forces: np.ndarray) -> np.ndarray:
    """Torque (N m) of each contact force (n, 2) about its wheel's spin axis: -r F . d (the
    contact point lies r below the hub)."""
    return -base.radius * np.einsum("ij,ij->i", np.asarray(forces, dtype=float), base.drive_directions)
