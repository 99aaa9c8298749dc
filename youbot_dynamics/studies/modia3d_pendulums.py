"""Document 000's two Modia3D examples, Pendulum1 and Pendulum3, as the planar ODEs their
objects define (Modia3D's default scene: gravity g = 9.81 m/s^2 along -y; Revolute about
z; the angle phi from the +x axis, starting at 0, at rest; 3 s as the document runs).

- Pendulum1: a body of mass 1 kg with no inertia (MassProperties(mass = 1.0)) whose frame
  is 0.5 m from the joint (bodyFrame translation (-0.5, 0, 0)): a point mass on a massless
  arm, phi'' = -(g / r) cos(phi). Released horizontal, its period is
  4 sqrt(r / g) K(sin 45 deg) (:func:`released_horizontal_period`). The document's merge
  at simulate! is cut off in its text; its commented line suggests r = 0.3 m, run second.
- Pendulum3: a steel box 1.0 x 0.2 x 0.2 m (Modia3D's Steel, 8000 kg/m^3: 320 kg) whose
  centre is 0.5 m from the joint (obj2 at (-0.5, 0, 0) in obj1), turning about z through
  a RevoluteWithFlange with a rotational Damper d = 100 N m s/rad to the fixed flange:
  I phi'' = -m g r cos(phi) - d phi', I = m (lx^2 + ly^2) / 12 + m r^2.

The document shows only the models and the plot commands (its plots are images its text
does not hold); the period and the energy balance are the checks here.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.special import ellipk

from youbot_dynamics.integrate.integrators import integrate

#: Modia3D's default gravity (m/s^2) and its Steel density (kg/m^3).
GRAVITY, STEEL_DENSITY = 9.81, 8000.0
#: The documents' run length (s).
STOP_TIME = 3.0


@dataclass(frozen=True)
class PlanarPendulum:
    """A body turning about a fixed z axis: mass (kg), centre-of-mass distance r (m) from
    the axis, inertia about the axis (kg m^2), joint damping (N m s/rad)."""

    label: str
    mass: float
    radius: float
    inertia: float
    damping: float = 0.0

    def rhs(self, t: float, x: np.ndarray) -> np.ndarray:
        """(phi', phi'') with phi from +x, gravity along -y."""
        phi, w = x
        torque = -self.mass * GRAVITY * self.radius * np.cos(phi) - self.damping * w
        return np.array([w, torque / self.inertia])

    def energy(self, x: np.ndarray) -> np.ndarray:
        """Kinetic plus potential energy (J) at states (m, 2)."""
        x = np.atleast_2d(x)
        return (0.5 * self.inertia * x[:, 1] ** 2
                + self.mass * GRAVITY * self.radius * np.sin(x[:, 0]))


def pendulum1(radius: float = 0.5) -> PlanarPendulum:
    """Pendulum1: 1 kg point mass at ``radius`` (m) from the joint."""
    return PlanarPendulum(f"Pendulum1, r = {radius:g} m", 1.0, radius, radius ** 2)


def pendulum3() -> PlanarPendulum:
    """Pendulum3: the 1.0 x 0.2 x 0.2 m steel box, centre 0.5 m out, damper 100."""
    lengths, radius = (1.0, 0.2, 0.2), 0.5
    mass = STEEL_DENSITY * float(np.prod(lengths))
    inertia = mass * (lengths[0] ** 2 + lengths[1] ** 2) / 12 + mass * radius ** 2
    return PlanarPendulum("Pendulum3, steel box, d = 100 N m s/rad", mass, radius, inertia,
                          100.0)


def released_horizontal_period(radius: float) -> float:
    """Period (s) of a point-mass pendulum released at rest from the horizontal:
    4 sqrt(r / g) K(k), k = sin(45 deg) (scipy's ellipk takes m = k^2 = 1/2)."""
    return float(4.0 * np.sqrt(radius / GRAVITY) * ellipk(0.5))


def simulate(pendulum: PlanarPendulum, outputs: int = 1501):
    """phi (rad) and phi' (rad/s) from phi = 0 at rest over [0, STOP_TIME] s (DOP853,
    rtol = atol = 1e-10)."""
    return integrate(pendulum.rhs, [0.0, 0.0], np.linspace(0.0, STOP_TIME, outputs), "dop853",
                     rtol=1e-10, atol=1e-10)


def first_return_time(solution) -> float:
    """The first time (s) after the start that phi' changes from negative to positive with
    phi back near 0: one full period of the undamped swing, by linear interpolation of phi'
    at its sign change near the top."""
    t, phi, w = solution.t, solution.x[:, 0], solution.x[:, 1]
    turns = np.nonzero((w[:-1] > 0) & (w[1:] <= 0) & (phi[:-1] > -0.5))[0]
    k = turns[0]
    return float(t[k] + (t[k + 1] - t[k]) * w[k] / (w[k] - w[k + 1]))
