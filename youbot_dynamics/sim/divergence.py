"""What a run may do before it counts as diverged, and the checks that say so.

Limits (:class:`DivergenceLimits`, defaults stated below, overridable per simulator):

- **Energy ledger** of a passive scene (no controller, no commanded effort): the stored
  energy E = kinetic + gravitational + elastic (compliant contact springs) may only fall;
  what it lost, D(t) = E(0) - E(t), is the energy dissipated by friction, damping and
  contact hysteresis, which is non-negative. D(t) < -tolerance (E grew by more than the
  scene's ``integrator.energy_tolerance``, J) is a :class:`DivergenceError`. Checked at
  output times (where a cheaper form of the same energy shows it far inside, the exact
  value is not computed). LuGre bristle energy sigma0 z^2 / 2 is not counted: it stays below
  F_s^2 / (2 sigma0) (2.5e-4 J in arm_friction, a fortieth of the default tolerance).
- **Free bodies**: every component of a body's velocity within ``body_speed`` (m/s) and of
  its angular velocity within ``body_spin`` (rad/s), checked after every step; the overlap
  of a contact pair within ``penetration_fraction`` of the thinner shape's smallest
  half-extent (a body half-way into the other), checked at output times.
- **Work**: a fixed-step run may take at most ``max_steps`` steps (refused up front), and
  one step-wise call (``Simulator.advance_through``) at most ``max_steps_per_call`` steps of
  any integrator (a :class:`StepBudgetError` once exceeded), so that a node's callback
  always returns.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable

import numpy as np
import pinocchio as pin

from youbot_dynamics.dynamics.collision import Shape
from youbot_dynamics.dynamics.rigid_body import potential_energy
from youbot_dynamics.model.robot import Robot

Monitor = Callable[[float, np.ndarray], "str | None"]

#: Default bound on each component of a free body's velocity, m/s (a fall from 500 m).
BODY_SPEED_LIMIT = 100.0
#: Default bound on each component of a free body's angular velocity, rad/s (~10^4 rpm).
BODY_SPIN_LIMIT = 1000.0
#: Default deepest overlap, as a fraction of the thinner shape's smallest half-extent.
PENETRATION_FRACTION = 0.5
#: Default step budget of a whole fixed-step run (``simulate``/``pendulum --max-steps``).
MAX_STEPS = 10_000_000
#: Default step budget of one step-wise call (a node callback).
MAX_STEPS_PER_CALL = 200_000
#: Fixed-step runs of more steps than this show progress on the command line.
PROGRESS_STEPS = 1_000_000
#: How far, as a share of the kinetic energy, a cheaper form of the stored energy must keep
#: the growth below the ledger's tolerance for the exact value to be skipped. The two forms
#: differ only in the kinetic energy (the potential is the same call), by its rounding
#: amplified by the mass matrix's conditioning: 1e-4 covers eps * cond(M) up to about 4e11
#: (gripping's M: 1.8e5; two coaxial links with inertias 1e-10 and 100 kg m^2 spinning
#: against each other part by 7.6e-6 of T). Beyond that neither form is reliable.
ESTIMATE_MARGIN = 1e-4
#: The share of |T| + |V| + |E(0)| added for the rounding of the sums E = T + V and E - E(0).
SUM_MARGIN = 1e-12


@dataclass(frozen=True)
class DivergenceLimits:
    """The limits above; see the module docstring for units and where each is checked."""

    body_speed: float = BODY_SPEED_LIMIT
    body_spin: float = BODY_SPIN_LIMIT
    penetration_fraction: float = PENETRATION_FRACTION
    max_steps: int = MAX_STEPS
    max_steps_per_call: int = MAX_STEPS_PER_CALL


def smallest_half_extent(shape: Shape) -> float:
    """Half the thinnest dimension of a shape (m); inf for a half-space."""
    if shape.kind == "sphere":
        return shape.radius
    if shape.kind == "box":
        return 0.5 * min(shape.size)
    if shape.kind == "cylinder":
        return min(shape.radius, 0.5 * shape.length)
    if shape.kind == "capsule":
        return shape.radius
    return math.inf


def penetration_limit(shape1: Shape, shape2: Shape, fraction: float) -> float:
    """The deepest overlap (m) a pair of these shapes may reach before it is divergence."""
    return fraction * min(smallest_half_extent(shape1), smallest_half_extent(shape2))


def body_energy(robot: Robot, data: pin.Data, q: np.ndarray, v: np.ndarray) -> tuple[float, float, float]:
    """(E, size) (J) at positions q (nq) and velocities v (nv) of a robot without mimic
    joints or armature: Pinocchio's kinetic energy from the bodies' velocities plus the
    potential energy, the energy of :func:`youbot_dynamics.dynamics.rigid_body.kinetic_energy` +
    :func:`potential_energy` (the
    mass-matrix form, which Pinocchio 4.1's kinetic energy would not match with an armature)
    but for rounding, in about a third of its time; (E, T, V): the energy, its kinetic and
    potential parts."""
    kinetic = pin.computeKineticEnergy(robot.model, data, q, v)
    potential = potential_energy(robot, data, q)
    return kinetic + potential, kinetic, potential


def estimate_margin(kinetic: float, potential: float, energy0: float) -> float:
    """How far (J) below the tolerance the cheaper form's growth must stay for the exact
    value to be skipped: ESTIMATE_MARGIN |T| + SUM_MARGIN (|T| + |V| + |E(0)|)."""
    return ESTIMATE_MARGIN * abs(kinetic) + SUM_MARGIN * (abs(kinetic) + abs(potential) + abs(energy0))


def energy_ledger_monitor(stored_energy: Callable[[np.ndarray], float], energy0: float, tolerance: float,
                          estimate: Callable[[np.ndarray], tuple[float, float, float]] | None = None) -> Monitor:
    """A monitor that complains when the dissipated energy E(0) - E(t) of a passive scene
    falls below -tolerance (J): the stored energy grew, which no passive system does.
    ``estimate(x)``: the same energy in a cheaper form, (E, T, V) (:func:`body_energy`); where
    it keeps the growth below the tolerance by more than :func:`estimate_margin`, beyond the
    two forms' rounding apart, the exact value would too and is not computed (the verdict,
    and any complaint, are the exact value's)."""
    def monitor(t: float, x: np.ndarray) -> str | None:
        if estimate is not None:
            energy, kinetic, potential = estimate(x)
            if energy - energy0 <= tolerance - estimate_margin(kinetic, potential, energy0):
                return None
        growth = stored_energy(x) - energy0
        if not growth <= tolerance:
            return (f"energy grew by {growth:.3g} J in a passive scene (from {energy0:.6g} J; "
                    f"dissipated energy must be >= -{tolerance:g} J, integrator.energy_tolerance)")
        return None
    return monitor


def penetration_monitor(overlaps: Callable[[np.ndarray], dict[str, float]],
                        limits: dict[str, float]) -> Monitor:
    """A monitor that complains when a pair's overlap (m) exceeds its limit."""
    def monitor(t: float, x: np.ndarray) -> str | None:
        deep = [f"{pair} {depth:.3g} m > {limits[pair]:.3g} m"
                for pair, depth in overlaps(x).items() if not depth <= limits[pair]]
        return ("overlap beyond the penetration limit: " + ", ".join(deep)) if deep else None
    return monitor


def all_of(*monitors: Monitor | None) -> Monitor | None:
    """One monitor running the given ones in order (the first complaint wins)."""
    active = [m for m in monitors if m is not None]
    if not active:
        return None
    if len(active) == 1:
        return active[0]

    def monitor(t: float, x: np.ndarray) -> str | None:
        for m in active:
            reason = m(t, x)
            if reason:
                return reason
        return None
    return monitor
