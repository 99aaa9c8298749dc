"""Operation counts of inverse dynamics on serial chains (document 002: "RNEA is O(n),
Lagrange O(n^4) without symbolic simplification").

Both formulations are written here in plain numpy with every multiplication counted (a
k x m by m x l product: k m l; a cross product: 6; a dot product of length k: k), on a
chain of n revolute joints (:func:`chain`): joint j turns about its own z axis, placed
``LINK`` m along the parent's x axis and turned by ALPHA[j % 2] about it (a spatial chain,
not a planar one), each link a ``MASS`` kg rod to the next joint. Both equal Pinocchio's
RNEA on the same chain (:func:`pinocchio_chain`), the independent reference.

- :func:`rnea_counted`: Luh, Walker and Paul's recursive Newton-Euler algorithm in link
  frames (3x3 rotations): a fixed count per link, so the count is exactly a n + b.
- :func:`lagrange_euler_counted`: the Lagrange-Euler (Uicker-Kahn) form with 4x4
  homogeneous matrices, as textbooks derive it from L = T - U without symbolic
  simplification: M_ik = sum_j tr(U_jk J_j U_ji^T), h_ikm = sum_j tr(U_jkm J_j U_ji^T)
  (the n^4 term: four indices), c_i = -sum_j m_j g^T U_ji r_j; the partial derivatives
  U_ij = dT_0^j/dq_i and U_ijk are built once from the chain's products.

The counts do not depend on the machine (bench/bench_complexity.py times both in CPU time).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pinocchio as pin

LINK = 0.3          # m, joint to joint along the parent's x axis
MASS = 1.0          # kg per link
ALPHA = (np.pi / 2, 0.0)   # rad, twist of joint j about the parent's x axis: ALPHA[j % 2]
GRAVITY = np.array([0.0, 0.0, -9.81])   # m/s^2, world frame
#: d Rz(q) / dq = Rz(q) Q for the homogeneous rotation about z.
Q = np.zeros((4, 4))
Q[0, 1], Q[1, 0] = -1.0, 1.0


@dataclass
class Counter:
    """Multiplications counted by the products it performs."""

    multiplications: int = 0

    def dot(self, a: np.ndarray, b: np.ndarray) -> np.ndarray:
        """a @ b, counting k m l (matrix by matrix), k m (matrix by vector) or k (vectors)."""
        self.multiplications += a.size * (b.shape[-1] if b.ndim == 2 else 1)
        return a @ b

    def cross(self, a: np.ndarray, b: np.ndarray) -> np.ndarray:
        """a x b: 6 multiplications."""
        self.multiplications += 6
        return np.cross(a, b)


@dataclass(frozen=True)
class Link:
    """One link: its joint's fixed placement in the parent frame (rotation, translation m),
    mass (kg), centre of mass in its own frame (m) and inertia about it (kg m^2)."""

    rotation: np.ndarray
    translation: np.ndarray
    mass: float
    com: np.ndarray
    inertia: np.ndarray


def rotation_x(angle: float) -> np.ndarray:
    """3x3 rotation by ``angle`` (rad) about x."""
    c, s = np.cos(angle), np.sin(angle)
    return np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])


def rotation_z(angle: float) -> np.ndarray:
    """3x3 rotation by ``angle`` (rad) about z."""
    c, s = np.cos(angle), np.sin(angle)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def chain(n: int) -> list[Link]:
    """The n-link chain of the module docstring (a rod of MASS kg and length LINK m per link,
    its inertia about the centre m L^2 / 12 across the rod)."""
    rod = MASS * LINK ** 2 / 12
    return [Link(rotation_x(ALPHA[j % 2]), np.array([LINK, 0.0, 0.0]), MASS, np.array([LINK / 2, 0.0, 0.0]),
                 np.diag([1e-4, rod, rod])) for j in range(n)]


def pinocchio_chain(links: list[Link]) -> pin.Model:
    """The same chain as a Pinocchio model (revolute z joints), gravity GRAVITY."""
    model = pin.Model()
    parent = 0
    for j, link in enumerate(links):
        parent = model.addJoint(parent, pin.JointModelRZ(), pin.SE3(link.rotation, link.translation), f"joint_{j}")
        model.appendBodyToJoint(parent, pin.Inertia(link.mass, link.com, link.inertia), pin.SE3.Identity())
    model.gravity.linear = GRAVITY
    return model


def rnea_counted(links: list[Link], q: np.ndarray, qd: np.ndarray, qdd: np.ndarray,
                 counter: Counter) -> np.ndarray:
    """Joint torques (N m) by the recursive Newton-Euler algorithm in link frames."""
    n, z = len(links), np.array([0.0, 0.0, 1.0])
    omega, omega_d, acc = np.zeros(3), np.zeros(3), -GRAVITY
    rotations, forces, moments = [], [], []
    for j, link in enumerate(links):
        rotation = counter.dot(link.rotation, rotation_z(q[j]))   # parent -> this link
        back = rotation.T
        acc = counter.dot(back, acc + counter.cross(omega_d, link.translation)
                          + counter.cross(omega, counter.cross(omega, link.translation)))
        omega_parent = counter.dot(back, omega)
        omega = omega_parent + qd[j] * z
        omega_d = counter.dot(back, omega_d) + counter.cross(omega_parent, qd[j] * z) + qdd[j] * z
        acc_com = acc + counter.cross(omega_d, link.com) + counter.cross(omega, counter.cross(omega, link.com))
        rotations.append(rotation)
        forces.append(link.mass * acc_com)
        moments.append(counter.dot(link.inertia, omega_d) + counter.cross(omega, counter.dot(link.inertia, omega)))
    tau, f, m = np.zeros(n), np.zeros(3), np.zeros(3)
    for j in range(n - 1, -1, -1):
        link = links[j]
        if j + 1 < n:
            f_child = counter.dot(rotations[j + 1], f)
            m = counter.dot(rotations[j + 1], m) + counter.cross(links[j + 1].translation, f_child)
            f = f_child
        m = m + moments[j] + counter.cross(link.com, forces[j])
        f = f + forces[j]
        tau[j] = m[2]
    return tau


def homogeneous(rotation: np.ndarray, translation: np.ndarray) -> np.ndarray:
    """4x4 transform from a rotation and a translation (m)."""
    t = np.eye(4)
    t[:3, :3], t[:3, 3] = rotation, translation
    return t


def pseudo_inertia(link: Link) -> np.ndarray:
    """The link's 4x4 pseudo-inertia J = int [r; 1][r; 1]^T dm in its own frame."""
    c, m = link.com, link.mass
    about_origin = link.inertia + m * (c @ c * np.eye(3) - np.outer(c, c))
    j = np.zeros((4, 4))
    j[:3, :3] = np.trace(about_origin) / 2 * np.eye(3) - about_origin
    j[:3, 3] = j[3, :3] = m * c
    j[3, 3] = m
    return j


def chain_transforms(links: list[Link], q: np.ndarray, counter: Counter) -> list[list[np.ndarray]]:
    """T[a][b]: the 4x4 transform from frame a to frame b (a < b; frame 0 the world, frame j
    the link of joint j, 1-based), each built from the one before by a product."""
    n = len(links)
    steps = [counter.dot(homogeneous(link.rotation, link.translation), homogeneous(rotation_z(q[j]), np.zeros(3)))
             for j, link in enumerate(links)]
    T = [[np.eye(4) for _ in range(n + 1)] for _ in range(n + 1)]
    for a in range(n + 1):
        for b in range(a + 1, n + 1):
            T[a][b] = counter.dot(T[a][b - 1], steps[b - 1])
    return T


def first_partials(T: list[list[np.ndarray]], n: int, counter: Counter) -> dict[tuple[int, int], np.ndarray]:
    """U[(j, i)] = d T_0^(j+1) / d q_i = T_0^(i+1) Q T_(i+1)^(j+1) for i <= j (0-based)."""
    return {(j, i): counter.dot(counter.dot(T[0][i + 1], Q), T[i + 1][j + 1]) for j in range(n) for i in range(j + 1)}


def second_partials(T: list[list[np.ndarray]], n: int, counter: Counter) -> dict[tuple[int, int, int], np.ndarray]:
    """U[(j, i, k)] = d U[(j, i)] / d q_k for i, k <= j (zero otherwise: not stored)."""
    second = {}
    for j in range(n):
        for i in range(j + 1):
            for k in range(j + 1):
                lo, hi = min(i, k), max(i, k)
                left = counter.dot(counter.dot(counter.dot(T[0][lo + 1], Q), T[lo + 1][hi + 1]), Q)
                second[(j, i, k)] = counter.dot(left, T[hi + 1][j + 1])
    return second


def trace_product(a: np.ndarray, b: np.ndarray, counter: Counter) -> float:
    """tr(a b^T): one multiplication per entry."""
    counter.multiplications += a.size
    return float(np.sum(a * b))


def lagrange_euler_counted(links: list[Link], q: np.ndarray, qd: np.ndarray, qdd: np.ndarray,
                           counter: Counter) -> np.ndarray:
    """Joint torques (N m) by the Lagrange-Euler equations (module docstring), 0-based."""
    n = len(links)
    T = chain_transforms(links, q, counter)
    U = first_partials(T, n, counter)
    J = [pseudo_inertia(link) for link in links]
    UJ = {(j, k): counter.dot(u, J[j]) for (j, k), u in U.items()}
    M = np.array([[sum(trace_product(UJ[(j, k)], U[(j, i)], counter) for j in range(max(i, k), n))
                   for k in range(n)] for i in range(n)])
    second_UJ = {key: counter.dot(u, J[key[0]]) for key, u in second_partials(T, n, counter).items()}
    h = np.zeros(n)
    for i in range(n):
        for k in range(n):
            for m in range(n):
                h_ikm = sum(trace_product(second_UJ[(j, k, m)], U[(j, i)], counter) for j in range(max(i, k, m), n))
                counter.multiplications += 2
                h[i] += h_ikm * qd[k] * qd[m]
    g = np.append(GRAVITY, 0.0)
    c = np.array([-sum(links[j].mass * counter.dot(g, counter.dot(U[(j, i)], np.append(links[j].com, 1.0)))
                       for j in range(i, n)) for i in range(n)])
    return counter.dot(M, qdd) + h + c


def operation_counts(sizes: range | list[int]) -> dict[str, list[int]]:
    """Multiplications of one inverse-dynamics call per chain size, RNEA and Lagrange-Euler
    (at an arbitrary state: the counts do not depend on it)."""
    counts: dict[str, list[int]] = {"rnea": [], "lagrange_euler": []}
    for n in sizes:
        links, x = chain(n), np.linspace(0.1, 0.9, n)
        for name, method in (("rnea", rnea_counted), ("lagrange_euler", lagrange_euler_counted)):
            counter = Counter()
            method(links, x, x, x, counter)
            counts[name].append(counter.multiplications)
    return counts


def growth_exponent(sizes: list[int], costs: list[float]) -> float:
    """p of the least-squares fit cost = c n^p on log-log axes."""
    return float(np.polyfit(np.log(sizes), np.log(costs), 1)[0])
