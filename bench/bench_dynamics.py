"""Rigid-body dynamics with joint friction vs bare Pinocchio on the youBot arm (5 joints;
wheels and fingers locked): microseconds per call, side by side, with the ratio. Goals
(issue 25): RNEA + friction within 1.5x of a bare pin.rnea, ABA + friction within 1.3x of a
bare pin.aba.

Run: python bench/bench_dynamics.py [--calls 300] [--repeat 15]. Each figure is the best of
``repeat`` loops of ``calls`` calls at one random state (CPU time of the measuring thread,
bench/timing.py), ours and Pinocchio's loops alternating, so both see the same machine load
and both pay the Python call overhead. Friction: the URDF default (viscous + regularised Coulomb on every joint),
then a mixed one (LuGre on joint 2, Stribeck on joint 3). The inverse pair is checked
(ABA(RNEA(a)) = a) before timing. The friction alone is compared with the same laws
evaluated by numpy on the whole joint vector (b v + F_c tanh(v / v_s)).
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import Callable

import numpy as np
import pinocchio as pin

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # run from a source checkout
sys.path.insert(0, str(Path(__file__).resolve().parent))

from timing import best_per_call  # noqa: E402
from youbot_dynamics import default_urdf  # noqa: E402
from youbot_dynamics.dynamics import friction as laws  # noqa: E402
from youbot_dynamics.dynamics.friction import JointFriction  # noqa: E402
from youbot_dynamics.dynamics.rigid_body import forward_dynamics, inverse_dynamics  # noqa: E402
from youbot_dynamics.model.robot import Robot, keep_joints, load_robot  # noqa: E402

ARM = tuple(f"arm_joint_{i}" for i in range(1, 6))
MIXED = {"arm_joint_2": {"law": "lugre", "sigma0": 1e3, "sigma1": 2.0, "sigma2": 0.3, "coulomb": 0.5,
                         "static": 0.8, "stribeck_velocity": 0.1},
         "arm_joint_3": {"law": "stribeck", "coulomb": 0.4, "static": 0.7, "stribeck_velocity": 0.1,
                         "damping": 0.5, "velocity_scale": 0.02}}

Pair = tuple[Callable[[], object], Callable[[], object]]


def arm() -> Robot:
    """The youBot arm: wheels and fingers locked."""
    return keep_joints(load_robot(default_urdf()), ARM)


def dynamics_pairs(robot: Robot) -> dict[str, Pair]:
    """figure -> (ours, bare Pinocchio's or numpy's) at one random state."""
    model, data = robot.model, robot.model.createData()
    rng = np.random.default_rng(0)
    q, v, a = (rng.uniform(-1.5, 1.5, robot.nv) for _ in range(3))
    pairs: dict[str, Pair] = {}
    for label, friction in (("URDF friction", JointFriction.from_urdf(robot)),
                            ("mixed friction", JointFriction.from_spec(robot, MIXED))):
        z = friction.steady_state_bristles(v)
        tau = inverse_dynamics(robot, data, q, v, a, friction, z)
        assert np.abs(forward_dynamics(robot, data, q, v, tau, friction, z) - a).max() < 1e-9
        pairs[f"RNEA + {label} vs pin.rnea"] = (lambda f=friction, z=z: inverse_dynamics(robot, data, q, v, a, f, z),
                                                lambda: pin.rnea(model, data, q, v, a))
        pairs[f"ABA + {label} vs pin.aba"] = (lambda f=friction, z=z, t=tau: forward_dynamics(robot, data, q, v, t, f, z),
                                              lambda t=tau: pin.aba(model, data, q, v, t))
    urdf = JointFriction.from_urdf(robot)
    level, scale = urdf.table[2], urdf.table[3]
    np.testing.assert_allclose(urdf.torque(v), laws.viscous(v, urdf.damping) + laws.coulomb(v, level, scale), rtol=1e-15)
    pairs["URDF friction alone vs numpy laws"] = (
        lambda: urdf.torque(v), lambda: laws.viscous(v, urdf.damping) + laws.coulomb(v, level, scale))
    return pairs


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--calls", type=int, default=300)
    parser.add_argument("--repeat", type=int, default=15)
    args = parser.parse_args()
    robot = arm()
    print(f"youBot arm ({robot.nv} joints: {', '.join(robot.joint_names)}), "
          f"best of {args.repeat} x {args.calls} calls")
    print(f"{'computation':44s} {'ours us':>8s} {'peer us':>8s} {'ratio':>6s}")
    for name, (ours, theirs) in dynamics_pairs(robot).items():
        ours(), theirs()  # compile / warm up
        t_ours, t_peer = (t * 1e6 for t in best_per_call([ours, theirs], args.calls, args.repeat))
        print(f"{name:44s} {t_ours:8.2f} {t_peer:8.2f} {t_ours / t_peer:6.2f}")


if __name__ == "__main__":
    main()
