"""Base parameters by QR with column pivoting (Gautier 1990, numerical form).

W (stacked regressor over random samples, (N nv) x p) is factorised W P = Q R with column
pivoting. Its rank r counts the |R_ii| above ``RANK_RTOL`` |R_00|; the first r pivoted
columns are independent, the others are combinations of them: W_2 = W_1 beta with
beta = R_11^{-1} R_12. Hence

    tau = W theta = W_1 (theta_1 + beta theta_2) = W_1 theta_base,

theta_base = K theta with K = [I  beta] P^T (r x p): each base parameter is one kept
standard parameter plus the combination beta of the dropped ones it absorbs. Coefficients
of beta below ``COEFFICIENT_ATOL`` are round-off and are set to zero.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.linalg

from youbot_dynamics.identification.regressor import RegressorLayout, random_samples

#: A pivot |R_ii| below this fraction of |R_00| counts as zero. The youBot arm (5 joints,
#: 200 samples, friction included): the smallest kept pivot is 2.3e-2 of the first, the
#: largest dropped 2.7e-16.
RANK_RTOL = 1e-8
#: Combination coefficients below this are round-off (the youBot's are 1e-3 and more).
COEFFICIENT_ATOL = 1e-9


@dataclass(frozen=True)
class BaseParameters:
    """The base parameters of a regressor layout.

    ``independent`` (r,) are the column indices of the kept standard parameters,
    ``dependent`` the others; ``beta`` (r, p - r) how the dependent ones fold in;
    ``matrix`` K (r, p) maps standard to base parameters; ``pivots`` |R_ii| (all p);
    ``names`` the standard parameters' names (p).
    """

    independent: np.ndarray
    dependent: np.ndarray
    beta: np.ndarray
    matrix: np.ndarray
    pivots: np.ndarray
    names: tuple[str, ...]

    @property
    def count(self) -> int:
        """Number of base parameters r."""
        return len(self.independent)

    @property
    def unidentifiable(self) -> tuple[str, ...]:
        """Standard parameters that have no effect at all on the torques (zero columns of
        K): neither kept nor absorbed by any base parameter."""
        return tuple(self.names[j] for j in np.flatnonzero(~self.matrix.any(axis=0)))

    def of(self, theta: np.ndarray) -> np.ndarray:
        """theta_base = K theta (r,)."""
        return self.matrix @ theta

    def columns(self, stacked: np.ndarray) -> np.ndarray:
        """The base regressor: the independent columns of a stacked Y."""
        return stacked[:, self.independent]

    def describe(self, i: int) -> str:
        """Base parameter i as the linear combination of standard ones, e.g.
        ``arm_joint_2.Iyy + 0.0241 arm_joint_3.m + 0.155 arm_joint_3.mcx``."""
        terms = [self.names[self.independent[i]]]
        for coefficient, j in zip(self.beta[i], self.dependent):
            if coefficient != 0.0:
                sign = "-" if coefficient < 0 else "+"
                terms.append(f"{sign} {abs(coefficient):.6g} {self.names[j]}")
        return " ".join(terms)


def base_parameters_of_regressor(stacked: np.ndarray, names: tuple[str, ...],
                                 rank_rtol: float = RANK_RTOL) -> BaseParameters:
    """Gautier's numerical base parameters of a stacked regressor (see the module docstring)."""
    _, r_factor, permutation = scipy.linalg.qr(stacked, mode="economic", pivoting=True)
    pivots = np.abs(np.diag(r_factor))
    rank = int(np.count_nonzero(pivots > rank_rtol * pivots[0])) if pivots.size and pivots[0] > 0 else 0
    beta = scipy.linalg.solve_triangular(r_factor[:rank, :rank], r_factor[:rank, rank:])
    beta[np.abs(beta) < COEFFICIENT_ATOL] = 0.0
    p = stacked.shape[1]
    matrix = np.zeros((rank, p))
    matrix[:, permutation[:rank]] = np.eye(rank)
    matrix[:, permutation[rank:]] = beta
    full = np.zeros(p)
    full[permutation] = pivots
    return BaseParameters(independent=permutation[:rank], dependent=permutation[rank:], beta=beta,
                          matrix=matrix, pivots=full, names=names)


def base_parameters(layout: RegressorLayout, samples: int = 200, seed: int = 0,
                    rank_rtol: float = RANK_RTOL) -> BaseParameters:
    """Base parameters of a layout from Y stacked over ``samples`` random (q, v, a)."""
    q, v, a = random_samples(layout.robot, samples, np.random.default_rng(seed))
    return base_parameters_of_regressor(layout.stacked(q, v, a), layout.names, rank_rtol)
