"""Independent reference: Lagrange's equations derived with sympy (no Pinocchio), compared
with inverse_dynamics (RNEA, no friction) on two robots given to load_robot as URDF strings:
a 2-link planar arm (also checked against its textbook closed form) and a 3-joint spatial
chain with offsets, a tilted (rpy) joint origin, off-centre masses and full inertia tensors.

Derivation: for each link, the pose T_i(q) = T_{i-1} Trans(xyz_i) Rot(rpy_i) Rot(axis_i, q_i),
the centre of mass c_i = T_i com_i, the angular velocity from [w_i]x = dR_i/dt R_i^T, then
L = sum_i (m_i |dc_i/dt|^2 + w_i . R_i I_i R_i^T w_i) / 2 - sum_i m_i g z_ci and
tau = d/dt dL/dqdot - dL/dq, expanded symbolically (Christoffel form).
"""
from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np
import pytest
import sympy as sp

from youbot_dynamics.dynamics.rigid_body import inverse_dynamics
from youbot_dynamics.model.robot import load_robot

GRAVITY = 9.81


@dataclass(frozen=True)
class Link:
    """A revolute joint and the link it moves (URDF conventions, SI units)."""

    xyz: tuple[float, float, float]
    rpy: tuple[float, float, float]
    axis: tuple[float, float, float]
    mass: float
    com: tuple[float, float, float]
    inertia: tuple[float, float, float, float, float, float]  # ixx ixy ixz iyy iyz izz at the COM


def urdf_of(links: list[Link]) -> str:
    """The chain as a URDF string: base -> link1 -> ... with revolute joints j1, j2, ..."""
    def v(t):
        return " ".join(repr(float(x)) for x in t)

    parts = ['<robot name="chain">', '<link name="base"/>']
    for i, link in enumerate(links, start=1):
        ixx, ixy, ixz, iyy, iyz, izz = link.inertia
        parent = "base" if i == 1 else f"link{i - 1}"
        parts.append(
            f'<link name="link{i}"><inertial><origin xyz="{v(link.com)}" rpy="0 0 0"/>'
            f'<mass value="{link.mass!r}"/><inertia ixx="{ixx!r}" ixy="{ixy!r}" ixz="{ixz!r}" '
            f'iyy="{iyy!r}" iyz="{iyz!r}" izz="{izz!r}"/></inertial></link>'
            f'<joint name="j{i}" type="revolute"><parent link="{parent}"/><child link="link{i}"/>'
            f'<origin xyz="{v(link.xyz)}" rpy="{v(link.rpy)}"/><axis xyz="{v(link.axis)}"/>'
            f'<limit lower="-10" upper="10" effort="100" velocity="10"/></joint>')
    parts.append("</robot>")
    return "\n".join(parts)


def _skew(k) -> np.ndarray:
    return np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]], dtype=float)


def _rotation(axis, cos, sin) -> np.ndarray:
    """Rodrigues' formula about an axis, the angle given by its cosine and sine (numbers or
    polynomials)."""
    k = _skew(np.asarray(axis, dtype=float) / np.linalg.norm(axis))
    return np.eye(3) + k * sin + (k @ k) * (1 - cos)


def _rpy(roll, pitch, yaw) -> np.ndarray:
    """URDF fixed-axis roll-pitch-yaw: Rz(yaw) Ry(pitch) Rx(roll)."""
    def r(axis, angle):
        return _rotation(axis, np.cos(angle), np.sin(angle))
    return r((0, 0, 1), yaw) @ r((0, 1, 0), pitch) @ r((1, 0, 0), roll)


def lagrange_inverse_dynamics(links: list[Link]):
    """tau(q, qd, qdd) from Lagrange's equations, as a numpy function.

    With T = qd . M(q) qd / 2, Lagrange's equations read
    tau_i = sum_j M_ij qdd_j + sum_jk (dM_ij/dq_k - dM_jk/dq_i / 2) qd_j qd_k + dV/dq_i;
    M is assembled from the centre-of-mass velocities dc_i/dt = (dc_i/dq) qd and the angular
    velocities from [w_i]x = dR_i/dt R_i^T. Every quantity is an exact polynomial (sympy's
    polynomial ring over the reals) in c_i = cos q_i and s_i = sin q_i, with
    d/dq_i = c_i d/ds_i - s_i d/dc_i.
    """
    n = len(links)
    ring, *generators = sp.ring([f"c{i}" for i in range(n)] + [f"s{i}" for i in range(n)], sp.RR)
    c, s = generators[:n], generators[n:]
    d = np.vectorize(lambda p, i: ring(p).diff(s[i]) * c[i] - ring(p).diff(c[i]) * s[i], otypes=[object])

    rotation, position = np.eye(3), np.zeros(3)
    mass_matrix, potential = np.zeros((n, n)), 0.0
    for i, link in enumerate(links):
        position = position + rotation @ np.array(link.xyz)
        rotation = rotation @ _rpy(*link.rpy) @ _rotation(link.axis, c[i], s[i])
        com = position + rotation @ np.array(link.com)
        linear = np.stack([d(com, j) for j in range(n)], axis=1)  # dc/dt = linear qd
        spins = [d(rotation, j) @ rotation.T for j in range(n)]
        angular = np.stack([[w[2, 1], w[0, 2], w[1, 0]] for w in spins], axis=1)  # w = angular qd
        ixx, ixy, ixz, iyy, iyz, izz = link.inertia
        inertia = rotation @ np.array([[ixx, ixy, ixz], [ixy, iyy, iyz], [ixz, iyz, izz]]) @ rotation.T
        mass_matrix = mass_matrix + link.mass * linear.T @ linear + angular.T @ inertia @ angular
        potential = potential + link.mass * GRAVITY * com[2]
    gravity = [d(potential, i)[()] for i in range(n)]
    dmass = [d(mass_matrix, k) for k in range(n)]
    christoffel = [[[dmass[k][i, j] - dmass[i][j, k] / 2 for k in range(n)] for j in range(n)]
                   for i in range(n)]
    symbols = ring.symbols
    as_expr = np.vectorize(lambda p: ring(p).as_expr(), otypes=[object])
    terms = sp.lambdify([symbols[:n], symbols[n:]],
                        [as_expr(mass_matrix).tolist(), as_expr(np.array(christoffel)).tolist(),
                         as_expr(np.array(gravity)).tolist()], modules="numpy", cse=True)

    def tau(qv, vv, av):
        m, christoffel_values, g = (np.array(x, dtype=float) for x in terms(np.cos(qv), np.sin(qv)))
        return m @ av + np.einsum("ijk,j,k->i", christoffel_values, vv, vv) + g

    return tau


# 2-link planar arm in the x-z plane: axis -y, so that q > 0 lifts the arm from +x to +z.
L1, LC1, LC2, M1, M2, I1, I2 = 0.5, 0.22, 0.17, 1.3, 0.8, 0.031, 0.012
PLANAR = [
    Link((0, 0, 0), (0, 0, 0), (0, -1, 0), M1, (LC1, 0, 0), (0.002, 0, 0, I1, 0, 0.0305)),
    Link((L1, 0, 0), (0, 0, 0), (0, -1, 0), M2, (LC2, 0, 0), (0.001, 0, 0, I2, 0, 0.0115)),
]

SPATIAL = [
    Link((0.0, 0.0, 0.1), (0, 0, 0), (0, 0, 1), 2.1, (0.02, -0.01, 0.06),
         (0.021, 0.001, -0.002, 0.032, 0.0015, 0.026)),
    Link((0.05, 0.01, 0.3), (0.2, -0.1, 0.3), (0, 1, 0), 1.4, (0.15, 0.012, -0.02),
         (0.006, -0.0005, 0.0008, 0.018, 0.0004, 0.015)),
    Link((0.3, -0.02, 0.04), (0, 0, 0), (0, 1, 0), 0.7, (0.1, 0.0, 0.01),
         (0.002, 0.0001, -0.0002, 0.007, 0.0, 0.0065)),
]


CHAINS = {"planar_2link": PLANAR, "spatial_3joint": SPATIAL}


@functools.cache
def reference(name: str):
    """The Lagrange reference of one of CHAINS, derived once per test session."""
    return lagrange_inverse_dynamics(CHAINS[name])


def planar_closed_form(q, v, a) -> np.ndarray:
    """Textbook 2-link planar arm (Spong, Hutchinson and Vidyasagar, section 7.3)."""
    c2, s2 = np.cos(q[1]), np.sin(q[1])
    m11 = M1 * LC1**2 + M2 * (L1**2 + LC2**2 + 2 * L1 * LC2 * c2) + I1 + I2
    m12 = M2 * (LC2**2 + L1 * LC2 * c2) + I2
    m22 = M2 * LC2**2 + I2
    h = M2 * L1 * LC2 * s2
    g1 = (M1 * LC1 + M2 * L1) * GRAVITY * np.cos(q[0]) + M2 * LC2 * GRAVITY * np.cos(q[0] + q[1])
    g2 = M2 * LC2 * GRAVITY * np.cos(q[0] + q[1])
    return np.array([m11 * a[0] + m12 * a[1] - h * (2 * v[0] * v[1] + v[1] ** 2) + g1,
                     m12 * a[0] + m22 * a[1] + h * v[0] ** 2 + g2])


def random_states(n: int, count: int, seed: int):
    rng = np.random.default_rng(seed)
    for _ in range(count):
        yield rng.uniform(-np.pi, np.pi, n), rng.uniform(-3, 3, n), rng.uniform(-5, 5, n)


@pytest.mark.parametrize("name", CHAINS)
def test_rnea_agrees_with_lagrange(name):
    links = CHAINS[name]
    robot = load_robot(urdf_of(links))
    data = robot.model.createData()
    for q, v, a in random_states(len(links), 10, seed=len(links)):
        tau = inverse_dynamics(robot, data, q, v, a)
        expected = reference(name)(q, v, a)
        np.testing.assert_allclose(tau, expected, rtol=0, atol=1e-10 * max(1.0, np.abs(expected).max()))


def test_lagrange_derivation_matches_planar_closed_form():
    """The sympy reference itself reproduces the textbook equations."""
    for q, v, a in random_states(2, 10, seed=7):
        np.testing.assert_allclose(reference("planar_2link")(q, v, a), planar_closed_form(q, v, a), rtol=0, atol=1e-11)


def test_references_see_gravity_and_coupling():
    """Guard against a vacuous comparison: the spatial chain's torques depend on every term."""
    q = np.array([0.3, -0.7, 1.1])
    static = reference("spatial_3joint")(q, np.zeros(3), np.zeros(3))
    moving = reference("spatial_3joint")(q, np.array([1.0, -2.0, 0.5]), np.zeros(3))
    assert np.all(np.abs(static[1:]) > 0.1) and np.all(np.abs(moving - static) > 1e-3)
