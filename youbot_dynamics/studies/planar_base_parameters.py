"""Document 002's 2-DOF planar base-parameter example, three ways.

The arm: two revolute joints about y, the links along x in the vertical x-z plane, gravity
g along -z (or along y, the joint axes: the horizontal arm). Link i has length l_i (only l1
matters), mass m_i, centre of mass (c_i along the link, d_i across it, in the plane) and
inertia I_i about its centre of mass and the joint axis. The document gives no numbers;
ours are :class:`PlanarArm`'s defaults.

1. Symbolic (sympy, :func:`symbolic_torques`): Lagrange's equations of the arm, then the
   torques rewritten in the grouped parameters (Khalil and Dombre 2002, sec. 12.3)

       ZZ1R = I1 + m1 (c1^2 + d1^2) + m2 l1^2,   MX1R = m1 c1 + m2 l1,   MY1 = m1 d1,
       ZZ2  = I2 + m2 (c2^2 + d2^2),             MX2  = m2 c2,           MY2 = m2 d2;

   the torques then hold no m1, m2, c_i, d_i, I_i but through these six (:func:`grouped_torques`
   checks it): they are the base parameters (four without gravity in the plane: MX1R and MY1
   drop out).
2. Numerical: Gautier's QR on Pinocchio's regressor (identification/base_parameters.py);
   its base map K spans the same six functionals.
3. The document's list, ``[I1 + m1 c1^2 + m2 (l1^2 + 2 l1 c2 cos q2 + c2^2), I2 + m2 c2^2,
   m2 c2 cos q2, ...]`` (with d_i = 0), set beside the mass matrix M(q) of 1: its first
   entry is M11 - I2 (M11 has I2 too), its second is M22 = ZZ2, a base parameter, its third
   is (M12 - ZZ2) / l1; the first and third depend on q2, so they are no parameters.
"""
from __future__ import annotations

from dataclasses import asdict, dataclass
from functools import lru_cache

import numpy as np
import sympy as sp

from youbot_dynamics.identification.base_parameters import BaseParameters, base_parameters
from youbot_dynamics.identification.regressor import RegressorLayout
from youbot_dynamics.model.robot import Robot, load_robot

#: The grouped (base) parameters, in the order the study prints them.
GROUPS = ("ZZ1R", "MX1R", "MY1", "ZZ2", "MX2", "MY2")
#: Each group as a functional of the regressor's standard parameters (joint frames' origins,
#: Pinocchio's order; the link's x is along it, z across it in the plane): name -> weights,
#: ``l1`` standing for the length l1 (m).
FUNCTIONALS = {"ZZ1R": {"j1.Iyy": 1.0, "j2.m": "l1^2"}, "MX1R": {"j1.mcx": 1.0, "j2.m": "l1"},
               "MY1": {"j1.mcz": 1.0}, "ZZ2": {"j2.Iyy": 1.0}, "MX2": {"j2.mcx": 1.0},
               "MY2": {"j2.mcz": 1.0}}


@dataclass(frozen=True)
class PlanarArm:
    """The arm's parameters (SI): l1 (m), m_i (kg), c_i and d_i (m, the centre of mass
    along and across link i), I_i (kg m^2, about the centre of mass), g (m/s^2)."""

    l1: float = 0.7
    m1: float = 2.0
    c1: float = 0.3
    d1: float = 0.0
    I1: float = 0.05
    m2: float = 1.5
    c2: float = 0.25
    d2: float = 0.0
    I2: float = 0.03
    g: float = 9.81

    def urdf(self, vertical: bool = True) -> str:
        """The arm as URDF, joints about y: gravity (-z) in the plane of motion when
        ``vertical``, else along the joint axes (the first joint's frame rolled by pi/2)."""
        def link(name: str, m: float, c: float, d: float, inertia: float) -> str:
            return (f'<link name="{name}"><inertial><origin xyz="{c!r} 0 {d!r}"/><mass value="{m!r}"/>'
                    f'<inertia ixx="{inertia!r}" ixy="0" ixz="0" iyy="{inertia!r}" iyz="0" '
                    f'izz="{inertia!r}"/></inertial></link>')

        def joint(name: str, parent: str, child: str, x: float, rpy: str = "0 0 0") -> str:
            return (f'<joint name="{name}" type="revolute"><parent link="{parent}"/>'
                    f'<child link="{child}"/><origin xyz="{x!r} 0 0" rpy="{rpy}"/>'
                    '<axis xyz="0 1 0"/><limit lower="-3.1" upper="3.1" effort="100" '
                    'velocity="5"/></joint>')
        turn = "0 0 0" if vertical else "1.5707963267948966 0 0"  # y (the axes) up: gravity along them
        return ('<robot name="planar_2dof"><link name="base"/>'
                + link("l1", self.m1, self.c1, self.d1, self.I1)
                + link("l2", self.m2, self.c2, self.d2, self.I2)
                + joint("j1", "base", "l1", 0.0, turn) + joint("j2", "l1", "l2", self.l1)
                + "</robot>")

    def groups(self) -> dict[str, float]:
        """The six grouped parameters' values (module docstring)."""
        return {"ZZ1R": self.I1 + self.m1 * (self.c1 ** 2 + self.d1 ** 2) + self.m2 * self.l1 ** 2,
                "MX1R": self.m1 * self.c1 + self.m2 * self.l1, "MY1": self.m1 * self.d1,
                "ZZ2": self.I2 + self.m2 * (self.c2 ** 2 + self.d2 ** 2),
                "MX2": self.m2 * self.c2, "MY2": self.m2 * self.d2}


SYMBOLS = sp.symbols("l1 m1 c1 d1 I1 m2 c2 d2 I2 g", real=True)
Q = sp.symbols("q1 q2", real=True)
V = sp.symbols("v1 v2", real=True)
A = sp.symbols("a1 a2", real=True)


@lru_cache(maxsize=None)
def symbolic_torques() -> tuple[sp.Matrix, sp.Matrix]:
    """(tau, M): the joint torques (N m) of Lagrange's equations d/dt dL/dv - dL/dq and the
    mass matrix, in the symbols of :data:`SYMBOLS`, q, v = q', a = q''. Frame: x along the
    base, z up; joint angles about y (a positive q turns x toward -z)."""
    l1, m1, c1, d1, i1, m2, c2, d2, i2, g = SYMBOLS
    t = sp.Symbol("t")
    q1, q2 = (sp.Function(name)(t) for name in ("q1", "q2"))

    def point(angle, along, across):  # (x, z) of a body point at (along, across) of a link
        return sp.Matrix([along * sp.cos(angle) + across * sp.sin(angle),
                          -along * sp.sin(angle) + across * sp.cos(angle)])
    com1 = point(q1, c1, d1)
    com2 = point(q1, l1, 0) + point(q1 + q2, c2, d2)
    kinetic = (m1 * com1.diff(t).dot(com1.diff(t)) + i1 * q1.diff(t) ** 2
               + m2 * com2.diff(t).dot(com2.diff(t)) + i2 * (q1 + q2).diff(t) ** 2) / 2
    lagrangian = kinetic - g * (m1 * com1[1] + m2 * com2[1])
    torques = [sp.diff(lagrangian.diff(qi.diff(t)), t) - lagrangian.diff(qi) for qi in (q1, q2)]
    plain = {q1.diff(t, 2): A[0], q2.diff(t, 2): A[1], q1.diff(t): V[0], q2.diff(t): V[1]}
    plain_q = {q1: Q[0], q2: Q[1]}
    tau = sp.Matrix([sp.expand(tq.subs(plain).subs(plain_q)) for tq in torques])
    return tau, sp.trigsimp(tau.jacobian(A))


GROUP_SYMBOLS = sp.symbols(" ".join(GROUPS), real=True)


def grouped_torques() -> sp.Matrix:
    """The torques with I_i, c_i, d_i replaced through the grouped parameters (module
    docstring): free of m1, m2, c_i, d_i, I_i when the six are the base parameters."""
    l1, m1, c1, d1, i1, m2, c2, d2, i2, g = SYMBOLS
    zz1r, mx1r, my1, zz2, mx2, my2 = GROUP_SYMBOLS
    c1_, d1_, c2_, d2_ = (mx1r - m2 * l1) / m1, my1 / m1, mx2 / m2, my2 / m2
    replaced = {i1: zz1r - m1 * (c1_ ** 2 + d1_ ** 2) - m2 * l1 ** 2,
                i2: zz2 - m2 * (c2_ ** 2 + d2_ ** 2), c1: c1_, d1: d1_, c2: c2_, d2: d2_}
    tau, _ = symbolic_torques()
    return sp.Matrix([sp.trigsimp(sp.expand(entry.subs(replaced, simultaneous=True))) for entry in tau])


def document_list() -> tuple[sp.Expr, sp.Expr, sp.Expr]:
    """The document's three printed entries (d_i = 0): I1 + m1 c1^2 + m2 (l1^2 + 2 l1 c2
    cos q2 + c2^2), I2 + m2 c2^2, m2 c2 cos q2."""
    l1, m1, c1, _, i1, m2, c2, _, i2, _ = SYMBOLS
    return (i1 + m1 * c1 ** 2 + m2 * (l1 ** 2 + 2 * l1 * c2 * sp.cos(Q[1]) + c2 ** 2),
            i2 + m2 * c2 ** 2, m2 * c2 * sp.cos(Q[1]))


def document_against_mass_matrix() -> tuple[sp.Expr, sp.Expr, sp.Expr]:
    """(first - M11, second - M22, l1 third - (M12 - ZZ2)) at d_i = 0, simplified: -I2, 0, 0."""
    l1, _, _, d1, _, m2, c2, d2, i2, _ = SYMBOLS
    _, mass = symbolic_torques()
    mass = mass.subs({d1: 0, d2: 0})
    first, second, third = document_list()
    return (sp.simplify(first - mass[0, 0]), sp.simplify(second - mass[1, 1]),
            sp.simplify(l1 * third - (mass[0, 1] - (i2 + m2 * c2 ** 2))))


def robot(arm: PlanarArm, vertical: bool = True) -> Robot:
    """The arm as a loaded robot (see :meth:`PlanarArm.urdf`)."""
    return load_robot(arm.urdf(vertical))


def functional_matrix(layout: RegressorLayout, l1: float, groups=GROUPS) -> np.ndarray:
    """The grouped parameters as rows over the layout's standard parameters."""
    names = list(layout.names)
    rows = np.zeros((len(groups), len(names)))
    for i, group in enumerate(groups):
        for name, weight in FUNCTIONALS[group].items():
            rows[i, names.index(name)] = {"l1^2": l1 ** 2, "l1": l1}.get(weight, weight)
    return rows


@dataclass
class PlanarBaseResult:
    """The arm, the numerical base parameters (vertical and horizontal), how far K's row
    space is from the symbolic groups' (largest residual of the least-squares fit of each
    group on K's rows), the groups' values and the symbolic checks."""

    arm: PlanarArm
    vertical: BaseParameters
    horizontal: BaseParameters
    row_space_gap: dict[str, float]
    values: dict[str, float]
    grouped_free: bool
    document_minus_ours: tuple[str, str, str]


def row_space_gap(base: BaseParameters, functionals: np.ndarray) -> float:
    """Largest difference between each functional and its least-squares combination of K's
    rows, and between K's rows and theirs on the functionals (0: the same row space)."""
    there, *_ = np.linalg.lstsq(base.matrix.T, functionals.T, rcond=None)
    back, *_ = np.linalg.lstsq(functionals.T, base.matrix.T, rcond=None)
    return float(max(np.abs(base.matrix.T @ there - functionals.T).max(),
                     np.abs(functionals.T @ back - base.matrix.T).max()))


def run(arm: PlanarArm = PlanarArm()) -> PlanarBaseResult:
    """The three ways of the module docstring on ``arm``."""
    bases, gaps = {}, {}
    for plane, groups in (("vertical", GROUPS), ("horizontal", ("ZZ1R", "ZZ2", "MX2", "MY2"))):
        layout = RegressorLayout(robot(arm, plane == "vertical"), friction_terms=())
        bases[plane] = base_parameters(layout)
        gaps[plane] = row_space_gap(bases[plane], functional_matrix(layout, arm.l1, groups))
    masses = {str(s) for s in SYMBOLS if str(s) in ("m1", "m2", "c1", "c2", "d1", "d2", "I1", "I2")}
    grouped_free = not any(str(s) in masses for s in grouped_torques().free_symbols)
    return PlanarBaseResult(arm, bases["vertical"], bases["horizontal"], gaps, arm.groups(),
                            grouped_free, tuple(str(e) for e in document_against_mass_matrix()))


def as_json(result: PlanarBaseResult) -> dict:
    """The result's figures as a JSON object."""
    return {"parameters": asdict(result.arm), "base_count_vertical": result.vertical.count,
            "base_count_horizontal": result.horizontal.count,
            "base_parameters_vertical": [result.vertical.describe(i) for i in range(result.vertical.count)],
            "row_space_gap": result.row_space_gap, "grouped_values": result.values,
            "symbolic_torques_only_through_groups": result.grouped_free,
            "document_minus_ours": dict(zip(("first - M11", "second - M22", "l1 third - (M12 - ZZ2)"),
                                            result.document_minus_ours))}


def text(result: PlanarBaseResult) -> str:
    """The comparison as the lines ``study base-parameters`` prints."""
    arm = result.arm
    return "\n".join([
        "2-DOF planar arm (document 002's example; our parameters, the document gives none): "
        + ", ".join(f"{k} = {v:g}" for k, v in asdict(arm).items()),
        f"numerical base parameters (QR of Pinocchio's regressor): {result.vertical.count} with gravity in "
        f"the plane, {result.horizontal.count} with gravity along the joint axes",
        *(f"  {result.vertical.describe(i)}" for i in range(result.vertical.count)),
        "symbolic (sympy, Lagrange): the torques depend on the masses, centres of mass and inertias only "
        f"through {', '.join(GROUPS)}: {'yes' if result.grouped_free else 'NO'}",
        "  " + ", ".join(f"{k} = {v:.6g}" for k, v in result.values.items()),
        "numerical against symbolic (largest row-space residual): "
        + ", ".join(f"{plane} {gap:.1e}" for plane, gap in result.row_space_gap.items()),
        "the document's list [I1 + m1 c1^2 + m2 (l1^2 + 2 l1 c2 cos q2 + c2^2), I2 + m2 c2^2, m2 c2 cos q2] "
        "against the mass matrix: first - M11 = {}, second - M22 = {}, l1 third - (M12 - ZZ2) = {}".format(
            *result.document_minus_ours),
        "so the first is M11 without I2 and the third (M12 - ZZ2) / l1: configuration-dependent entries of "
        "M(q), not parameters; the second, ZZ2, is a base parameter"])
