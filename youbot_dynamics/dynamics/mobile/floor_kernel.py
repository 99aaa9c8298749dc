"""The roller friction of a mecanum base's wheels on the floor as one compiled loop (numba):
the generalised force of :meth:`youbot_dynamics.sim.mobile_base.MobileBase.floor_force`
without its dozen small numpy calls per step.

Every product and sum is taken in the order the numpy form takes it (the 2-term dots, numpy's
sum of four values added in turn; the hub velocities stay numpy's ``hub_maps @ twist``, whose
rounding a loop does not reproduce), and numba does not contract a product and a sum into one FMA, so the result is bit for bit
the numpy form's (test/dynamics/test_floor_kernel.py checks it on random states).
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit, types


_READ2 = types.Array(types.float64, 2, "C", readonly=True)
_VECTOR = types.Array(types.float64, 1, "A", readonly=True)
_INDEX = types.Array(types.int64, 1, "C", readonly=True)
_OUT = types.Array(types.float64, 1, "C")
_SIGNATURE = types.void(_VECTOR, _VECTOR, _READ2, _READ2, _READ2, _READ2, types.float64, types.float64,
                        types.float64, _INDEX, _OUT)


@njit(cache=True)
def _numpy_sum(values: np.ndarray) -> float:
    """numpy's sum of fewer than nine values: added in turn from the first."""
    total = values[0]
    for k in range(1, values.shape[0]):
        total += values[k]
    return total


@njit(_SIGNATURE, cache=True)
def roller_floor_force(v: np.ndarray, loads: np.ndarray, hubs: np.ndarray, positions: np.ndarray,
                       drive_directions: np.ndarray, across: np.ndarray, radius: float, mu: float,
                       velocity_scale: float, wheels: np.ndarray, out: np.ndarray) -> None:
    """out[:3] = (F_x, F_y, M_z) (N, N m, base frame) of the wheels' floor forces and
    out[3 + wheels] = their torques about the spin axes (N m), for the plant velocity v
    (planar root twist (vx, vy, wz) first, then the joints), the hubs' velocities ``hubs``
    (n, 2) (m/s, base frame; ``MecanumBase.hub_velocities``) and the wheels' normal loads
    (N): slip u_i = v_hub,i - (r omega_i) d_i, F_i = -mu N_i (u_i . n_i) n_i /
    sqrt(|(u_i . n_i) n_i|^2 + v_s^2) with n_i the unit direction across the roller,
    spin torque -r F_i . d_i. ``out`` is zero elsewhere on entry and left so."""
    n = wheels.shape[0]
    fx = np.empty(n)
    fy = np.empty(n)
    moment = np.empty(n)
    for i in range(n):
        spin = radius * v[3 + wheels[i]]
        slip_x = hubs[i, 0] - spin * drive_directions[i, 0]
        slip_y = hubs[i, 1] - spin * drive_directions[i, 1]
        along = slip_x * across[i, 0] + slip_y * across[i, 1]
        ux, uy = along * across[i, 0], along * across[i, 1]
        scale = -mu * loads[i] / math.sqrt((ux * ux + uy * uy) + velocity_scale * velocity_scale)
        fx[i], fy[i] = scale * ux, scale * uy
        moment[i] = positions[i, 0] * fy[i] - positions[i, 1] * fx[i]
        out[3 + wheels[i]] = -radius * (fx[i] * drive_directions[i, 0] + fy[i] * drive_directions[i, 1])
    out[0] = _numpy_sum(fx)
    out[1] = _numpy_sum(fy)
    out[2] = _numpy_sum(moment)
