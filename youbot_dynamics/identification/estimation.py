"""Least-squares estimation of base parameters: ordinary, then iterated weighted.

With the base regressor W ((N n) x r, sample by sample, n joints) and the measured efforts
y (N n):

- OLS: theta = argmin |W theta - y|^2, covariance sigma^2 (W^T W)^-1 with
  sigma^2 = |r|^2 / (N n - r).
- WLS (Gautier's weighting): each joint's rows are divided by that joint's residual
  standard deviation sigma_j = |r_j| / sqrt(N - r / n); solved again, sigma_j recomputed
  from the new residuals, until they change by less than ``WLS_RTOL`` (or ``iterations``).
  Covariance (W^T S^-1 W)^-1, S = diag(sigma_j^2).

Relative standard deviation: 100 std / |theta| (%); a parameter above ``FLAG_PERCENT`` is
flagged as not identified by this data. The condition number is cond(W) (2-norm).
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from youbot_dynamics.errors import UserInputError

#: Relative standard deviation (%) above which a parameter counts as not identified.
FLAG_PERCENT = 10.0
#: WLS stops when every joint's sigma_j changes by less than this fraction.
WLS_RTOL = 1e-6


@dataclass(frozen=True)
class Estimate:
    """Estimated parameters (r,) with standard deviations, relative deviations (%),
    ``covariance`` (r, r), cond(W), per-joint residual RMS (n; N m) and sigma_j (n; N m),
    the method (``ols`` or ``wls``) and its iterations."""

    method: str
    values: np.ndarray
    std: np.ndarray
    covariance: np.ndarray
    condition: float
    residual_rms: np.ndarray
    sigma: np.ndarray
    iterations: int

    @property
    def relative_std(self) -> np.ndarray:
        """100 std / |value| (%); infinite for a value of exactly 0."""
        with np.errstate(divide="ignore"):
            return 100.0 * self.std / np.abs(self.values)

    @property
    def flagged(self) -> np.ndarray:
        """Indices of parameters with relative deviation above FLAG_PERCENT."""
        return np.flatnonzero(self.relative_std > FLAG_PERCENT)

    def to_dict(self, names: list[str]) -> dict[str, Any]:
        """JSON-ready figures; parameters listed by ``names``."""
        return {"method": self.method, "condition": self.condition, "iterations": self.iterations,
                "residual_rms": self.residual_rms.tolist(), "sigma": self.sigma.tolist(),
                "parameters": [{"name": name, "value": float(v), "std": float(s), "relative_std": float(p),
                                "identified": bool(p <= FLAG_PERCENT)}
                               for name, v, s, p in zip(names, self.values, self.std, self.relative_std)]}


def _per_joint_rms(residual: np.ndarray, joints: int) -> np.ndarray:
    return np.sqrt(np.mean(residual.reshape(-1, joints) ** 2, axis=0))


def ordinary_least_squares(regressor: np.ndarray, effort: np.ndarray, joints: int) -> Estimate:
    """OLS estimate of theta in effort = regressor theta (see the module docstring)."""
    rows, count = regressor.shape
    if rows <= count:
        raise UserInputError(f"least squares: {rows} equations for {count} parameters; record a longer motion")
    values, *_ = np.linalg.lstsq(regressor, effort, rcond=None)
    residual = effort - regressor @ values
    variance = residual @ residual / (rows - count)
    covariance = variance * np.linalg.inv(regressor.T @ regressor)
    rms = _per_joint_rms(residual, joints)
    return Estimate("ols", values, np.sqrt(np.diag(covariance)), covariance, float(np.linalg.cond(regressor)),
                    rms, np.full(joints, np.sqrt(variance)), 1)


def weighted_least_squares(regressor: np.ndarray, effort: np.ndarray, joints: int,
                           iterations: int = 20) -> Estimate:
    """Iterated WLS with per-joint weights, started from OLS (see the module docstring)."""
    estimate = ordinary_least_squares(regressor, effort, joints)
    rows, count = regressor.shape
    dof = rows / joints - count / joints
    values = estimate.values
    sigma = np.sqrt(np.sum((effort - regressor @ values).reshape(-1, joints) ** 2, axis=0) / dof)
    done = 0
    for done in range(1, iterations + 1):
        weights = np.tile(1.0 / np.maximum(sigma, np.finfo(float).tiny), rows // joints)
        values, *_ = np.linalg.lstsq(regressor * weights[:, None], effort * weights, rcond=None)
        residual = effort - regressor @ values
        updated = np.sqrt(np.sum(residual.reshape(-1, joints) ** 2, axis=0) / dof)
        converged = np.all(np.abs(updated - sigma) <= WLS_RTOL * sigma)
        sigma = updated
        if converged:
            break
    weights = np.tile(1.0 / sigma, rows // joints)
    weighted = regressor * weights[:, None]
    covariance = np.linalg.inv(weighted.T @ weighted)
    return Estimate("wls", values, np.sqrt(np.diag(covariance)), covariance, float(np.linalg.cond(regressor)),
                    _per_joint_rms(effort - regressor @ values, joints), sigma, done)
