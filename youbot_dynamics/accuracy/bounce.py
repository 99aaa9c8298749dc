"""The apex of a bouncing sphere: the error measure of ``ball_drop``-like scenes.

A sphere in flight moves on a parabola (gravity only: no drag in the scenes), so at any
sample in flight its apex is h + (v . up)^2 / (2 g), exactly, whatever the output rate (to
the integrator's error: a first-order stepper's flight is no exact parabola, and its later
samples read a lower apex):
h is the height of its lowest point above the plane through the world origin normal to
gravity (the floor of ``ball_drop``), up = -gravity / g, v its velocity (m/s). The apex of
the bounce after the first impact is the largest such value over the samples at least
:data:`IN_FLIGHT` above the floor after the first contact event (each later bounce rises
less). With an impulsive law of restitution e it is e^2 times the drop height, exactly;
compliant laws come close to it (``docs/accuracy.md#contact``).
"""
from __future__ import annotations

import math

import numpy as np

from youbot_dynamics.sim.simulator import SimulationResult, Simulator

#: Height (m) above the floor from which a sample counts as in flight (clear of any contact).
IN_FLIGHT = 0.05


def is_single_sphere(simulator: Simulator) -> bool:
    """Whether the scene's only moving thing is one free sphere (no robot joints)."""
    bodies = simulator.scene.free_bodies
    return len(bodies) == 1 and bodies[0].shape.kind == "sphere" and not simulator.scene.robot.nv


def height_and_apex(simulator: Simulator, result: SimulationResult) -> tuple[np.ndarray, np.ndarray]:
    """Per output sample of a single free sphere: the height of its lowest point above the
    floor (m) and the apex of the parabola through the sample, h + (v.up)^2 / 2g (m)."""
    gravity = np.asarray(simulator.scene.gravity, dtype=float)
    g = float(np.linalg.norm(gravity))
    up = -gravity / g
    motion = simulator.model.body_motion(result.x)
    height = motion["position"][:, 0] @ up - simulator.scene.free_bodies[0].shape.radius
    return height, height + (motion["velocity"][:, 0] @ up) ** 2 / (2 * g)


def bounce_apex(simulator: Simulator, result: SimulationResult) -> float:
    """Apex (m above the floor) of the bounce after the first impact of a single free
    sphere: the largest ballistic apex over the samples in flight after its first contact
    event (later bounces rise less); NaN without a contact event or a sample in flight
    after it."""
    if not result.contact_events:
        return math.nan
    height, apex = height_and_apex(simulator, result)
    after = (np.asarray(result.t) > result.contact_events[0].time) & (height > IN_FLIGHT)
    return float(np.max(apex[after])) if np.any(after) else math.nan
