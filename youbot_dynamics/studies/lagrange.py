"""Lagrange's equations by computer algebra (document 003, the KTH report; benchmarks.md
section 4): sympy.physics.mechanics derives M(q) q'' = f(q, q') from the Lagrangian T - V,
joint friction enters as the generalised force Q_i = -c q_i', and lambdify turns M, f, the
energy T + V and the particle's position into numpy functions (cached per model).

Models (angles in rad, lengths in m, masses in kg; z up, gravity -g z):

- ``2d``: a uniform rod (m1, l) pivoted at O swings in the vertical x-z plane (q1 from
  the downward vertical); at its end A a light rod is hinged (q2, relative to the first);
  a bead m2 slides on it at distance l0 + q3 from A, held by a spring (k, rest length l0).
- ``3d``: the document's double cylindrical-spherical pendulum, with its kinematics
  (appendix B): a uniform rod OA (m1, l) turns about the horizontal axis x through O (q1
  from the downward vertical); the frame A' is turned by q1 + q2 about x; the massless
  rod AB (length l2) lies in A' at angle q3 from A's downward axis, B = A + l2 (-sin q3
  x' - cos q3 z'), and carries a particle m2 at B.
- ``arm``: a planar 2-link arm (uniform links m1, l1 and m2, l2, revolute joints about z,
  q from the x axis, gravity -g y), for the cross-check against Pinocchio's RNEA.

Parameter values (DEFAULTS, the document's appendix B; any can be overridden, ``study
lagrange --param NAME=VALUE``):

- ``2d``: m1 = 1 kg, m2 = 0.5 kg, k = 50 N/m, l0 = 0.25 m, l = 0.5 m, g = 9.82 m/s^2.
- ``3d``: m = 0.5 kg for rod and particle, l = 0.5 m for both rods, g = 9.82 m/s^2.
  OUR_3D is the second, labelled parameter set (m1 = 1 kg, m2 = 0.1 kg, l2 = 1 m,
  g = 9.81 m/s^2: a light particle on a long arm) that earlier versions used by default.

Document 003's 3D potential (its eq. 2.22) omits q3: by its own position vector rB the
particle's height is z_B = -l cos q1 - l2 cos q3 cos(q1 + q2), so V = -m1 g l cos q1 / 2 +
m2 g z_B and dV/dq3 = m2 g l2 sin q3 cos(q1 + q2): -0.860 N m at the document's state
(3.2), q = (1, 1, 1) rad. A potential without q3 drops that gravity torque: right only
while q3 = 0 or q1 + q2 = pi/2, and the energy it defines is not conserved by the true
motion. Ours keeps q3. (The document's friction run takes gravity as generalised forces
from the true rB, so its equations there do keep the q3 term.)
"""
from __future__ import annotations

from dataclasses import dataclass
from functools import cache, cached_property
from typing import Callable

import numpy as np
import sympy as sp
from sympy.physics import mechanics as me

from youbot_dynamics.errors import UserInputError
from youbot_dynamics.integrate.integrators import integrate
from youbot_dynamics.studies.stats_table import stats_table

#: Parameter values used unless given (SI). c is the joint friction coefficient.
DEFAULTS = {
    "2d": {"m1": 1.0, "l": 0.5, "m2": 0.5, "l0": 0.25, "k": 50.0, "g": 9.82, "c": 0.0},
    "3d": {"m1": 0.5, "l": 0.5, "m2": 0.5, "l2": 0.5, "g": 9.82, "c": 0.0},
    "3d-document": {"m1": 0.5, "l": 0.5, "m2": 0.5, "l2": 0.5, "g": 9.82, "c": 0.0},
    "arm": {"m1": 1.3, "l1": 0.7, "m2": 0.9, "l2": 0.5, "g": 9.81, "c": 0.0},
}
#: Our second, labelled parameter set of the 3D pendulum (overrides of DEFAULTS["3d"]).
OUR_3D = {"m1": 1.0, "m2": 0.1, "l2": 1.0, "g": 9.81}
#: The document's initial states (q, q'): 2D appendix B; 3D eq. (3.2), every angle 1 rad
#: at rest (Figs 10-12, 15, 17-21).
DOCUMENT_INITIAL = {"2d": ((0.8, 0.0, 0.0), (0.0, 0.0, 0.0)),
                    "3d": ((1.0, 1.0, 1.0), (0.0, 0.0, 0.0))}


@dataclass(frozen=True)
class LagrangeModel:
    """Equations of motion M(q) q'' = f(q, q') of one model, as sympy expressions in the
    plain symbols ``q``, ``u`` (= q') and ``parameters``, with their numeric versions."""

    name: str
    q: tuple[sp.Symbol, ...]
    u: tuple[sp.Symbol, ...]
    parameters: tuple[sp.Symbol, ...]
    mass_matrix: sp.Matrix
    forcing: sp.Matrix
    energy: sp.Expr
    particle: sp.ImmutableMatrix = sp.ImmutableMatrix.zeros(3, 1)

    @cached_property
    def numeric(self) -> tuple[Callable, Callable, Callable]:
        """(M(q, p), f(q, u, p), E(q, u, p)) as numpy functions."""
        args = (self.q, self.u, self.parameters)
        return (sp.lambdify(args, self.mass_matrix, "numpy", cse=True),
                sp.lambdify(args, self.forcing, "numpy", cse=True),
                sp.lambdify(args, self.energy, "numpy", cse=True))

    def particle_path(self, x: np.ndarray, p: tuple[float, ...]) -> np.ndarray:
        """The particle's position (m; N frame x, y, z, z up) at states x ((m, 2n)): the
        bead of ``2d``, B of ``3d``; shape (m, 3)."""
        n = len(self.q)
        position = sp.lambdify((self.q, self.parameters), self.particle, "numpy")
        return np.array([np.ravel(position(row[:n], p)) for row in np.atleast_2d(x)])

    def parameter_values(self, overrides: dict[str, float] | None = None) -> tuple[float, ...]:
        """The DEFAULTS for this model with ``overrides`` (name -> value) applied."""
        values = dict(DEFAULTS[self.name])
        unknown = set(overrides or {}) - set(values)
        if unknown:
            raise UserInputError(f"model {self.name!r} has no parameter(s) "
                                 f"{sorted(unknown)}; it has {sorted(values)}")
        values.update(overrides or {})
        return tuple(float(values[str(s)]) for s in self.parameters)

    def rhs(self, p: tuple[float, ...]) -> Callable[[float, np.ndarray], np.ndarray]:
        """x' = (q', M^-1 f) for x = (q, q') with parameter values p."""
        mass, forcing, _ = self.numeric
        n = len(self.q)

        def rhs(t: float, x: np.ndarray) -> np.ndarray:
            q, u = x[:n], x[n:]
            acceleration = np.linalg.solve(mass(q, u, p), forcing(q, u, p).ravel())
            return np.concatenate((u, acceleration))
        return rhs

    def energy_of(self, x: np.ndarray, p: tuple[float, ...]) -> np.ndarray:
        """Total energy T + V (J) at states x ((2n,) or (m, 2n))."""
        x = np.atleast_2d(x)
        n = len(self.q)
        _, _, energy = self.numeric
        return np.array([energy(row[:n], row[n:], p) for row in x])

    def inverse_dynamics(self, q, u, acceleration, p: tuple[float, ...]) -> np.ndarray:
        """Generalised forces tau = M(q) q'' - f(q, q') that produce the given motion."""
        mass, forcing, _ = self.numeric
        return mass(q, u, p) @ np.asarray(acceleration) - forcing(q, u, p).ravel()

    def equations(self) -> list[str]:
        """Short text of each equation: sum_j M_ij q_j'' = f_i, each term expanded and
        common factors pulled out (sympy's simplify gives text 7 % shorter on the 3D model
        but took 13 s against 0.03 s, measured)."""
        qdd = sp.symbols(" ".join(f"{s}''" for s in self.q))
        lines = []
        for i in range(len(self.q)):
            left = sum(readable(self.mass_matrix[i, j]) * qdd[j] for j in range(len(self.q)))
            lines.append(f"{sp.sstr(left)} = {sp.sstr(readable(self.forcing[i]))}")
        return lines


def readable(expression: sp.Expr) -> sp.Expr:
    """An expression expanded, with its common factors pulled out: cheap and readable."""
    return sp.factor_terms(sp.expand(expression))


def lagranges_method(frame: me.ReferenceFrame, q: list, bodies: list,
                     extra_potential: sp.Expr, parameters: tuple[sp.Symbol, ...],
                     friction: sp.Symbol, name: str,
                     particle: me.Vector | None = None) -> LagrangeModel:
    """Lagrange's equations for ``bodies`` (each with ``potential_energy`` set) in
    ``frame`` plus ``extra_potential``, with Q_i = -friction q_i'; returns the model in
    plain symbols (q'(t) -> u, q(t) -> q), with ``particle`` (position from the origin)
    as its x, y, z in ``frame``."""
    lagrangian = me.Lagrangian(frame, *bodies) - extra_potential
    method = me.LagrangesMethod(lagrangian, q, frame=frame)
    method.form_lagranges_equations()
    qd = [qi.diff(me.dynamicsymbols._t) for qi in q]
    kinetic = sum(body.kinetic_energy(frame) for body in bodies)
    potential = sum(body.potential_energy for body in bodies) + extra_potential
    q_plain = sp.symbols(" ".join(str(qi.func) for qi in q))
    u_plain = sp.symbols(" ".join(f"u{str(qi.func)[1:]}" for qi in q))
    plain = dict(zip(qd, u_plain)) | dict(zip(q, q_plain))

    def to_plain(expression):
        return me.msubs(expression, plain)

    forcing = method.forcing - friction * sp.Matrix(qd)
    where = sp.zeros(3, 1) if particle is None else particle.to_matrix(frame)
    where = sp.ImmutableMatrix(where)
    return LagrangeModel(name, tuple(q_plain), tuple(u_plain), parameters,
                         to_plain(method.mass_matrix), to_plain(forcing),
                         to_plain(kinetic + potential), to_plain(where))


def rod(name: str, frame: me.ReferenceFrame, center: me.Point, mass: sp.Symbol,
        length: sp.Expr, axis: me.Vector) -> me.RigidBody:
    """A uniform thin rod along ``axis`` of ``frame``: inertia m l^2 / 12 about the two
    axes normal to it, through its center."""
    normal = mass * length ** 2 / 12
    inertia = normal * (me.outer(frame.x, frame.x) + me.outer(frame.y, frame.y)
                        + me.outer(frame.z, frame.z) - me.outer(axis, axis))
    return me.RigidBody(name, center, frame, mass, (inertia, center))


@cache
def model(name: str) -> LagrangeModel:
    """The derived model ``2d``, ``3d`` or ``arm`` (cached)."""
    if name not in DEFAULTS:
        raise UserInputError(f"unknown Lagrange model {name!r}; choose from {sorted(DEFAULTS)}")
    symbols = sp.symbols(" ".join(DEFAULTS[name]), positive=True)
    p = dict(zip(DEFAULTS[name], symbols))
    g, c = p["g"], p["c"]
    N = me.ReferenceFrame("N")
    O = me.Point("O")
    O.set_vel(N, 0)
    if name == "2d":
        q1, q2, q3 = q = list(me.dynamicsymbols("q1 q2 q3"))
        A_frame = N.orientnew("A", "Axis", (q1, N.y))
        B_frame = A_frame.orientnew("B", "Axis", (q2, N.y))
        center = O.locatenew("Ac", -p["l"] / 2 * A_frame.z)
        A = O.locatenew("A", -p["l"] * A_frame.z)
        bead = A.locatenew("P", -(p["l0"] + q3) * B_frame.z)
        for point in (center, A, bead):
            point.set_vel(N, point.pos_from(O).dt(N))
        body = rod("rod", A_frame, center, p["m1"], p["l"], A_frame.z)
        particle = me.Particle("bead", bead, p["m2"])
        spring = p["k"] * q3 ** 2 / 2
    elif name in ("3d", "3d-document"):
        q1, q2, q3 = q = list(me.dynamicsymbols("q1 q2 q3"))
        A_frame = N.orientnew("A", "Axis", (q1, N.x))
        B_frame = N.orientnew("B", "Axis", (q1 + q2, N.x))
        center = O.locatenew("Ac", -p["l"] / 2 * A_frame.z)
        A = O.locatenew("A", -p["l"] * A_frame.z)
        tip = A.locatenew("B", p["l2"] * (-sp.sin(q3) * B_frame.x - sp.cos(q3) * B_frame.z))
        for point in (center, A, tip):
            point.set_vel(N, point.pos_from(O).dt(N))
        body = rod("rod", A_frame, center, p["m1"], p["l"], A_frame.z)
        particle = me.Particle("tip", tip, p["m2"])
        spring = sp.S.Zero
    else:
        q1, q2 = q = list(me.dynamicsymbols("q1 q2"))
        L1 = N.orientnew("L1", "Axis", (q1, N.z))
        L2 = L1.orientnew("L2", "Axis", (q2, N.z))
        c1 = O.locatenew("c1", p["l1"] / 2 * L1.x)
        elbow = O.locatenew("E", p["l1"] * L1.x)
        c2 = elbow.locatenew("c2", p["l2"] / 2 * L2.x)
        for point in (c1, c2):
            point.set_vel(N, point.pos_from(O).dt(N))
        link1 = rod("link1", L1, c1, p["m1"], p["l1"], L1.x)
        link2 = rod("link2", L2, c2, p["m2"], p["l2"], L2.x)
        link1.potential_energy = p["m1"] * g * c1.pos_from(O).dot(N.y)
        link2.potential_energy = p["m2"] * g * c2.pos_from(O).dot(N.y)
        return lagranges_method(N, q, [link1, link2], sp.S.Zero, tuple(symbols), c, name)
    body.potential_energy = p["m1"] * g * center.pos_from(O).dot(N.z)
    particle.potential_energy = p["m2"] * g * particle.point.pos_from(O).dot(N.z)
    if name == "3d-document":
        # the document's eq. (2.22): the particle's height without its cos q3 factor
        particle.potential_energy = -p["m2"] * g * (p["l"] * sp.cos(q1)
                                                    + p["l2"] * sp.cos(q1 + q2))
    return lagranges_method(N, q, [body, particle], spring, tuple(symbols), c, name,
                            particle.point.pos_from(O))


def equilibrium(name: str, p: tuple[float, ...]) -> np.ndarray:
    """The hanging equilibrium q* (potential minimum) of ``2d`` or ``3d``: everything
    hanging straight down; in ``2d`` the spring stretched by the bead's weight,
    q3 = m2 g / k."""
    if name == "2d":
        values = dict(zip(DEFAULTS["2d"], p))
        return np.array([0.0, 0.0, values["m2"] * values["g"] / values["k"]])
    return np.zeros(3)


#: Relative tolerance of the study's runs; atol = rtol unless given.
LAGRANGE_RTOL = 1e-12
#: Output times of a run, equally spaced over [0, duration].
OUTPUTS = 201


@dataclass(frozen=True)
class LagrangeConfig:
    """One run from the document's initial state: the problem ('2d' or '3d'), joint friction
    c (generalised force -c q_i'), parameter overrides (SI), the simulated ``duration``
    (s), the integrator and its tolerances (atol None: rtol; a number or one per state
    component)."""

    problem: str = "2d"
    friction: float = 0.0
    overrides: tuple[tuple[str, float], ...] = ()
    duration: float = 10.0
    integrator: str = "dop853"
    rtol: float = LAGRANGE_RTOL
    atol: object = None


@dataclass
class LagrangeRun:
    """The run's figures as plain data (equations, parameters, final state, energy in J,
    statistics)."""

    config: LagrangeConfig
    summary: dict


def initial_state(problem: str) -> np.ndarray:
    """The document's initial (q, u) of the problem."""
    q0, u0 = DOCUMENT_INITIAL[problem]
    return np.r_[q0, u0]


def run(config: LagrangeConfig) -> LagrangeRun:
    """Derive the equations with sympy, simulate them, and measure the energy."""
    lagrange = model(config.problem)
    p = lagrange.parameter_values({**dict(config.overrides), "c": config.friction})
    solution = integrate(lagrange.rhs(p), initial_state(config.problem),
                         np.linspace(0.0, config.duration, OUTPUTS), config.integrator,
                         rtol=config.rtol, atol=config.rtol if config.atol is None else config.atol,
                         state_names=[*map(str, lagrange.q), *map(str, lagrange.u)])
    energy = lagrange.energy_of(solution.x, p)
    return LagrangeRun(config, {
        "problem": config.problem, "friction": config.friction,
        "parameters": dict(zip(map(str, lagrange.parameters), p)),
        "equations": lagrange.equations(),
        "final_state": dict(zip(solution.state_names, solution.x[-1].tolist())),
        "energy_initial": float(energy[0]), "energy_final": float(energy[-1]),
        "energy_relative_drift": float(np.abs(energy - energy[0]).max() / abs(energy[0])),
        "energy_nonincreasing": bool(np.all(np.diff(energy) <= 1e-12)),
        "stats": solution.stats.as_dict(),
    })


def as_json(result: LagrangeRun) -> dict:
    """The run's summary."""
    return result.summary


def text(result: LagrangeRun) -> str:
    """Parameters, the equations (long ones cut at 160 characters), the final state, the
    energy drift and the statistics."""
    config, summary = result.config, result.summary
    lines = [f"Lagrange {config.problem}, friction c = {config.friction:g}, parameters "
             + ", ".join(f"{k}={v:g}" for k, v in summary["parameters"].items())]
    lines += [f"  {line if len(line) <= 160 else line[:157] + '...'}"
              for line in summary["equations"]]
    lines += [f"final state at t = {config.duration:g} s: "
              + ", ".join(f"{k}={v:.6g}" for k, v in summary["final_state"].items()),
              f"energy {summary['energy_initial']:.10g} J -> {summary['energy_final']:.10g} J, "
              f"max relative drift {summary['energy_relative_drift']:.3g}, "
              f"non-increasing: {summary['energy_nonincreasing']}",
              stats_table({config.integrator: summary["stats"]})]
    return "\n".join(lines)
