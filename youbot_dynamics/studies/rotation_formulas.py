"""Document 000's section-1 formulas as it prints them, checked against independent
references (scipy.spatial.transform.Rotation, sympy's Quaternion):

- the composite Cardan matrix Rot(alpha, beta, gamma) = Rot(z, alpha) Rot(y, beta)
  Rot(x, gamma), printed entry by entry (:func:`document_composite_matrix`);
- the quaternion multiplication table (:data:`DOCUMENT_PRODUCT_TABLE`);
- the rotation matrix of a unit quaternion q = q0 + q1 i + q2 j + q3 k
  (:func:`document_quaternion_matrix`): its R31 is printed 2(q1 q3 + q0 q2), where the
  rotation's is 2(q1 q3 - q0 q2); with the printed entry the matrix is not a rotation
  (|R^T R - I| = 0.970 at :data:`SHOWN_QUATERNION`, up to 1.76 over 2000 random unit
  quaternions; where it is orthogonal, e.g. 90 deg about y, its determinant is -1);
- the Rodrigues form of q v q* (:func:`rodrigues`);
- the gimbal-lock claim: at beta = 90 deg the x and z axes line up, so the matrix depends
  on alpha - gamma only.

Angles in rad; matrices map body coordinates to world coordinates (v' = R v).
"""
from __future__ import annotations

import numpy as np
import sympy as sp
from scipy.spatial.transform import Rotation

#: The document's multiplication table: row x column, as it prints it ("1", "i", "-j", ...).
DOCUMENT_PRODUCT_TABLE = {
    "1": {"1": "1", "i": "i", "j": "j", "k": "k"},
    "i": {"1": "i", "i": "-1", "j": "k", "k": "-j"},
    "j": {"1": "j", "i": "-k", "j": "-1", "k": "i"},
    "k": {"1": "k", "i": "j", "j": "-i", "k": "-1"},
}
#: The unit quaternion (q0, q1, q2, q3) at which the printed matrix's error is shown:
#: 60 deg about the unit axis (1, 2, 3) / sqrt(14).
SHOWN_QUATERNION = np.r_[np.cos(np.pi / 6), np.sin(np.pi / 6) * np.array([1.0, 2.0, 3.0])
                         / np.sqrt(14.0)]


def document_composite_matrix(alpha: float, beta: float, gamma: float) -> np.ndarray:
    """Rot(alpha, beta, gamma) entry by entry as document 000 prints it (sympy symbols
    give a symbolic matrix)."""
    symbolic = any(isinstance(angle, sp.Basic) for angle in (alpha, beta, gamma))
    cos, sin = (sp.cos, sp.sin) if symbolic else (np.cos, np.sin)
    ca, sa, cb, sb, cg, sg = (cos(alpha), sin(alpha), cos(beta), sin(beta), cos(gamma),
                              sin(gamma))
    return np.array([[ca * cb, ca * sb * sg - sa * cg, ca * sb * cg + sa * sg],
                     [sa * cb, sa * sb * sg + ca * cg, sa * sb * cg - ca * sg],
                     [-sb, cb * sg, cb * cg]])


def document_quaternion_matrix(q: np.ndarray, corrected: bool = False) -> np.ndarray:
    """The rotation matrix of the unit quaternion q = (q0, q1, q2, q3) as document 000
    prints it (R31 = 2(q1 q3 + q0 q2)), or with R31 = 2(q1 q3 - q0 q2) if ``corrected``."""
    q0, q1, q2, q3 = q
    r31 = 2 * (q1 * q3 - q0 * q2) if corrected else 2 * (q1 * q3 + q0 * q2)
    return np.array([[q0**2 + q1**2 - q2**2 - q3**2, 2 * (q1 * q2 - q0 * q3), 2 * (q0 * q2 + q1 * q3)],
                     [2 * (q0 * q3 + q1 * q2), q0**2 - q1**2 + q2**2 - q3**2, 2 * (q2 * q3 - q0 * q1)],
                     [r31, 2 * (q0 * q1 + q2 * q3), q0**2 - q1**2 - q2**2 + q3**2]])


def orthogonality_error(matrix: np.ndarray) -> float:
    """|R^T R - I| (spectral norm): 0 for a rotation."""
    return float(np.linalg.norm(matrix.T @ matrix - np.eye(3), 2))


def scipy_quaternion_matrix(q: np.ndarray) -> np.ndarray:
    """scipy's matrix of q = (q0, q1, q2, q3) (scipy takes the scalar last)."""
    return Rotation.from_quat([q[1], q[2], q[3], q[0]]).as_matrix()


def rodrigues(axis: np.ndarray, angle: float, v: np.ndarray) -> np.ndarray:
    """v turned by ``angle`` about the unit ``axis``, in the document's form
    cos(theta) v + (1 - cos(theta)) (u . v) u + sin(theta) (u x v)."""
    u = np.asarray(axis, dtype=float)
    return (np.cos(angle) * v + (1 - np.cos(angle)) * np.dot(u, v) * u
            + np.sin(angle) * np.cross(u, v))


def sympy_product_table() -> dict[str, dict[str, str]]:
    """The unit quaternions' products computed by sympy's Quaternion, in the table's form."""
    units = {"1": sp.Quaternion(1, 0, 0, 0), "i": sp.Quaternion(0, 1, 0, 0),
             "j": sp.Quaternion(0, 0, 1, 0), "k": sp.Quaternion(0, 0, 0, 1)}

    def name(q: sp.Quaternion) -> str:
        for label, unit in units.items():
            if q == unit:
                return label
            if q == -unit:
                return f"-{label}"
        raise ValueError(f"{q} is not a signed unit quaternion")
    return {a: {b: name(units[a] * units[b]) for b in units} for a in units}


def quaternion_matrix_check(q: np.ndarray = SHOWN_QUATERNION) -> dict:
    """The printed and corrected quaternion matrices against scipy at q: the entries that
    differ (1-based 'Rrc'), |R^T R - I| of each, the largest error over many random unit
    quaternions of the printed one."""
    printed, corrected = document_quaternion_matrix(q), document_quaternion_matrix(q, True)
    reference = scipy_quaternion_matrix(q)
    wrong = [f"R{r + 1}{c + 1}" for r in range(3) for c in range(3)
             if not np.isclose(printed[r, c], reference[r, c], atol=1e-12)]
    samples = Rotation.random(2000, random_state=0).as_quat()
    worst = max(orthogonality_error(document_quaternion_matrix(np.r_[s[3], s[:3]]))
                for s in samples)
    return {"quaternion": q.tolist(), "entries_differing_from_scipy": wrong,
            "printed_orthogonality_error": orthogonality_error(printed),
            "corrected_orthogonality_error": orthogonality_error(corrected),
            "corrected_minus_scipy": float(np.abs(corrected - reference).max()),
            "printed_determinant": float(np.linalg.det(printed)),
            "printed_worst_orthogonality_error": worst}
