"""Vertical loads on point supports (wheels on a flat floor): the least-norm non-negative
loads that balance a weight, with what depends only on where the supports are (the
pseudo-inverse of the equilibrium equations and their free direction) prepared once.

Equilibrium of n supports at (x_i, y_i) (m) carrying a weight W (N) applied at (x_c, y_c):

    sum N_i = W,   sum N_i x_i = W x_c,   sum N_i y_i = W y_c,

three equations for n loads. Of the solutions, take the least-norm one (A^+ b); while every
load is positive that is the distribution of a rigid body on equally stiff supports. Four
supports leave one free direction f (the null space of A): when the least-norm loads hold a
negative one, move along f by the least step that makes every load non-negative (a wheel
lifts, the others carry the statically determinate loads). No step does it when (x_c, y_c)
lies outside the supports' polygon: :class:`TipOverError`. The step along f and the checks run
compiled (:func:`shift_to_non_negative`, numba, the same operations in the same order as the
Python form it replaced); A^+ b stays numpy's product, whose rounding a loop does not reproduce.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from numba import njit, types

from youbot_dynamics.errors import UserInputError

_VECTOR = types.Array(types.float64, 1, "C", readonly=True)


class TipOverError(ValueError):
    """The centre of mass (shifted by the acceleration) lies outside the wheels' support
    polygon: no non-negative wheel loads balance the robot."""


@njit(types.boolean(_VECTOR, _VECTOR, types.float64, types.Array(types.float64, 1, "C")), cache=True)
def shift_to_non_negative(loads: np.ndarray, free: np.ndarray, weight: float, out: np.ndarray) -> bool:
    """out = max(loads + s free, 0) (N) with s the least step >= 0 along the free direction
    ``free`` ((n,), empty: none) that makes every load non-negative; False when none does
    (the loads of ``weight`` N, rounding aside, cannot all be >= 0: the base tips over)."""
    low, high, scale = -math.inf, math.inf, 0.0
    if free.shape[0]:
        for i in range(loads.shape[0]):  # keep load + s step >= 0
            if free[i] > 0.0:
                low = max(low, -loads[i] / free[i])
            elif free[i] < 0.0:
                high = min(high, -loads[i] / free[i])
        scale = min(max(0.0, low), high)
    tolerance = 1e-12 * max(abs(weight), 1.0)
    fits = not low > high + 1e-15
    for i in range(loads.shape[0]):
        load = loads[i] + scale * free[i] if free.shape[0] else loads[i]
        fits = fits and not load < -tolerance
        out[i] = max(load, 0.0)
    return fits


@dataclass(frozen=True, eq=False)
class SupportRule:
    """The least-norm load rule of supports at ``positions`` (n, 2) (m, x-y plane): their
    equilibrium equations' pseudo-inverse ``pseudo_inverse`` (n, 3) and the free direction
    ``free`` ((n,) unit vector; None with three supports), from one SVD.

    Raises UserInputError when the supports lie on one line, or (more than four) leave more
    than one free direction, which this rule does not handle.
    """

    positions: np.ndarray
    pseudo_inverse: np.ndarray = field(init=False, repr=False)
    free: np.ndarray | None = field(init=False, repr=False)
    _free: np.ndarray = field(init=False, repr=False)  # free, or empty with three supports

    def __post_init__(self) -> None:
        points = np.array(self.positions, dtype=float)
        equations = np.vstack([np.ones(len(points)), points.T])
        _, singular, rows = np.linalg.svd(equations)
        if singular[-1] < 1e-9 * singular[0]:
            raise UserInputError(f"support loads: the {len(points)} supports lie on one line")
        free = rows[3:]
        if len(free) > 1:
            raise UserInputError(f"support loads: {len(points)} supports leave {len(free)} free directions; "
                                 "the least-norm rule here handles at most four supports")
        pseudo_inverse = np.linalg.pinv(equations)
        for array in (points, pseudo_inverse, free):
            array.setflags(write=False)
        object.__setattr__(self, "positions", points)
        object.__setattr__(self, "pseudo_inverse", pseudo_inverse)
        object.__setattr__(self, "free", free[0] if len(free) else None)
        object.__setattr__(self, "_free", free[0] if len(free) else np.empty(0))

    def loads(self, centre: np.ndarray, weight: float) -> np.ndarray:
        """Vertical loads (N, ``positions`` order) carrying ``weight`` (N) applied at
        ``centre`` (x, y) (m). Raises :class:`TipOverError` outside the support polygon."""
        x, y = np.asarray(centre, dtype=float).ravel().tolist()
        return self.loads_at(x, y, weight)

    def loads_at(self, x: float, y: float, weight: float) -> np.ndarray:
        """:meth:`loads` with the centre's coordinates x, y (m) as floats."""
        loads = np.empty(len(self.positions))
        if not shift_to_non_negative(self.pseudo_inverse @ np.array([weight, weight * x, weight * y]), self._free,
                                     weight, loads):
            raise TipOverError(f"centre of mass at ({x:.4g}, {y:.4g}) m lies outside the support "
                               f"polygon of the wheels at {np.round(self.positions, 4).tolist()} m: the base tips over")
        return loads
