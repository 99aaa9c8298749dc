"""The compiled roller friction (dynamics/mobile/floor_kernel.py) against the numpy form it
replaces in the step (wheel_floor.roller_forces and friends): bit for bit, on random states
from rest to 10 m/s, so the main job's outputs stay byte-identical."""
import numpy as np

from youbot_dynamics.dynamics.mobile.floor_kernel import roller_floor_force
from youbot_dynamics.dynamics.mobile.mecanum import youbot_base
from youbot_dynamics.dynamics.mobile.wheel_floor import contact_slip_velocities, roller_forces, wheel_spin_torques


def numpy_floor_force(base, v, loads, wheels, mu, velocity_scale):
    forces = roller_forces(base, contact_slip_velocities(base, v[:3], v[3 + wheels]), loads, mu, velocity_scale)
    generalised = np.zeros(len(v))
    positions = base.positions
    generalised[:3] = [forces[:, 0].sum(), forces[:, 1].sum(),
                       float(np.sum(positions[:, 0] * forces[:, 1] - positions[:, 1] * forces[:, 0]))]
    generalised[3 + wheels] = wheel_spin_torques(base, forces)
    return generalised


def test_roller_floor_force_is_the_numpy_form_bit_for_bit():
    base, rng, wheels = youbot_base(), np.random.default_rng(7), np.array([2, 3, 4, 5])
    for _ in range(2000):
        v = rng.normal(size=11) * 10.0 ** rng.uniform(-6, 1)
        loads, mu, velocity_scale = rng.uniform(0.0, 100.0, 4), rng.uniform(0.1, 1.0), 10.0 ** rng.uniform(-4, -1)
        out = np.zeros(11)
        roller_floor_force(v, loads, base.hub_velocities(v[:3]), base.positions, base.drive_directions, base.across,
                           base.radius, mu, velocity_scale, wheels, out)
        assert np.array_equal(out, numpy_floor_force(base, v, loads, wheels, mu, velocity_scale))
        assert out[2:4].any()  # the moment and a wheel torque are exercised, not zero by construction
