"""Sanity bounds on physical magnitudes and sizes, in one place.

The URDF loader (:mod:`youbot_dynamics.model.robot`) and the scene validator
(:mod:`youbot_dynamics.scene.schema`, :mod:`youbot_dynamics.scene.contacts`) refuse values
beyond these bounds with a one-line error naming the file and the key (scene) or file:line and
the element (URDF). Every bound is far beyond any real robot or useful simulation, and far
inside what double precision survives: the largest product the dynamics forms is about
mass x length^2 x rate^2 (an energy, J), here at most 1e6 x (1e4)^2 x (1e4)^2 = 1e22 J,
nowhere near overflow (1.8e308), where a mass of 1e308 kg or an origin of 1e200 m overflowed
to an infinite energy.

Measured on example-robot-data 6.0.0 (68 robots): at most 130 links and 129 joints, masses
up to 116 kg, inertia entries up to 9.2 kg m^2, origins up to 1.57 m, shape dimensions up to
1.05 m, damping up to 2e4, friction up to 12, files up to 211 kB.
"""
from __future__ import annotations

import math
import sys
from dataclasses import dataclass


@dataclass(frozen=True)
class Bound:
    """A bound on one physical quantity: |value| <= ``maximum`` (``unit``), and value >= 0
    when ``non_negative``; ``why`` says why the bound is safe."""

    quantity: str
    maximum: float
    unit: str
    why: str
    non_negative: bool = False

    def problem(self, value: float) -> str:
        """'' when ``value`` is within the bound, else the reason (one line)."""
        if not math.isfinite(value):
            return f"{self.quantity} {value} is not finite"
        if self.non_negative and value < 0.0:
            return f"{self.quantity} must not be negative, got {value:g}"
        if abs(value) > self.maximum:
            return (f"|{value:g}| {self.unit} is beyond the {self.quantity} bound {self.maximum:g} "
                    f"{self.unit} ({self.why})")
        return ""


MASS = Bound("mass", 1e6, "kg", "a 1000 t body; the heaviest example-robot link has 116 kg")
INERTIA = Bound("moment of inertia", 1e14, "kg m^2", "MASS x LENGTH^2")
LENGTH = Bound("length or position", 1e4, "m", "10 km; the largest example-robot origin is 1.57 m")
GRAVITY = Bound("gravity component", 1e3, "m/s^2", "100 g")
SPEED = Bound("speed", 1e4, "m/s", "30 times the speed of sound")
JOINT_SPEED = Bound("joint speed", 1e4, "rad/s or m/s", "95 000 rpm; the largest example-robot velocity limit is 1e4")
ANGULAR_SPEED = Bound("angular speed", 1e4, "rad/s", "95 000 rpm")
DAMPING = Bound("damping", 1e8, "N m s/rad or N s/m", "example robots reach 2e4", non_negative=True)
FRICTION = Bound("friction", 1e8, "N m or N", "example robots reach 12", non_negative=True)
RATE = Bound("output rate", 1e6, "Hz", "1 MHz, 1 us between samples")
DURATION = Bound("duration", 1e4, "s", "2.8 h of simulated time", non_negative=True)

#: Tolerances: rtol (and the accuracy knob ``tol``) at least 100 machine epsilons (2.2e-14),
#: the floor below which scipy's solvers raise rtol themselves with a warning: there a step's
#: error estimate is round-off and no step can meet it. At most MAX_RTOL: 100 % is no
#: accuracy at all.
MIN_RTOL = 100 * sys.float_info.epsilon
MAX_RTOL = 1.0

#: Sizes, counted in the URDF's XML before Pinocchio sees it. Pinocchio 4.1's Data takes about
#: 64 nv^3 bytes whatever the tree's shape (measured: 66 MB at 100 moving joints, 505 MB at
#: 200, 4 GB at 400; 2000 links hit a MemoryError in createData and 20 000 crash Pinocchio's
#: parser), so moving joints (mimic joints included) are bounded at MAX_MOVING_JOINTS; links
#: and joints (fixed ones are folded into frames) at MAX_LINKS. The largest example robot has
#: 130 links and 101 moving joints (tiago_dual). A file beyond MAX_URDF_BYTES is not read (the
#: largest example file has 211 kB).
MAX_LINKS = 1000
MAX_MOVING_JOINTS = 200
#: A scene's velocity dimension (robot joints plus 6 per free body, each a free-flyer of the
#: one Pinocchio model): the moving joints' bound plus one floating root (Data 0.55 GB).
MAX_DOFS = MAX_MOVING_JOINTS + 6
MAX_URDF_BYTES = 50_000_000
#: Output samples of one run (duration x rate): a million samples of a 100-entry state take
#: 800 MB at most; ``outputs.rate: 1e9`` asked for 15 GiB.
MAX_OUTPUT_SAMPLES = 1_000_000
#: Scene files: at most this many bytes, YAML aliases and nodes counted with every alias
#: expanded (a 445-byte alias bomb expands to 4.9e8 nodes; the packaged scenes have at most
#: 12 aliases (gripping) and 658 expanded nodes).
MAX_SCENE_BYTES = 10_000_000
MAX_YAML_ALIASES = 100
MAX_YAML_NODES = 1_000_000


def tolerance_problem(value: float) -> str:
    """'' when ``value`` is a usable relative tolerance, else the reason (one line)."""
    if not (math.isfinite(value) and MIN_RTOL <= value <= MAX_RTOL):
        return (f"a relative tolerance must be within [{MIN_RTOL:.3g}, {MAX_RTOL:g}] (below 100 machine "
                f"epsilons no step can meet it), got {value:g}")
    return ""


def samples_problem(duration: float, rate: float) -> str:
    """'' when a run of ``duration`` s sampled at ``rate`` Hz stays within MAX_OUTPUT_SAMPLES."""
    samples = duration * rate
    if not samples <= MAX_OUTPUT_SAMPLES:
        return (f"{duration:g} s at {rate:g} Hz is {samples:.3g} output samples, beyond the bound "
                f"{MAX_OUTPUT_SAMPLES:g} (lower the rate or the duration)")
    return ""
