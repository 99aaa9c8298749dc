"""Rigid-body dynamics with joint friction vs bare Pinocchio on the youBot arm (5 joints;
wheels and fingers locked): microseconds per call, side by side, with the ratio. Goal:
RNEA + friction and ABA + friction within 2x of a bare pin.rnea / pin.aba call.

Run: python bench/bench_dynamics.py [--calls 20000] [--repeat 7]. Each figure is the best of
``repeat`` loops of ``calls`` calls at one random state (time.perf_counter), ours and
Pinocchio's loops alternating, so both see the same machine load and both pay the Python
call overhead. Friction: the URDF default (viscous + regularised Coulomb on every joint),
then a mixed one (LuGre on joint 2, Stribeck on joint 3). The inverse pair is checked
(ABA(RNEA(a)) = a) before timing.
"""
from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path
from typing import Callable, Sequence

import numpy as np
import pinocchio as pin

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # run from a source checkout

from youbot_dynamics import default_urdf  # noqa: E402
from youbot_dynamics.dynamics.friction import JointFriction  # noqa: E402
from youbot_dynamics.dynamics.rigid_body import forward_dynamics, inverse_dynamics  # noqa: E402
from youbot_dynamics.model.robot import keep_joints, load_robot  # noqa: E402

ARM = tuple(f"arm_joint_{i}" for i in range(1, 6))
MIXED = {"arm_joint_2": {"law": "lugre", "sigma0": 1e3, "sigma1": 2.0, "sigma2": 0.3, "coulomb": 0.5,
                         "static": 0.8, "stribeck_velocity": 0.1},
         "arm_joint_3": {"law": "stribeck", "coulomb": 0.4, "static": 0.7, "stribeck_velocity": 0.1,
                         "damping": 0.5, "velocity_scale": 0.02}}


def best_microseconds(calls: Sequence[Callable[[], object]], n: int, repeat: int) -> list[float]:
    """Best time per call of each function over ``repeat`` alternating loops, microseconds."""
    best = [float("inf")] * len(calls)
    for _ in range(repeat):
        for i, call in enumerate(calls):
            start = time.perf_counter()
            for _ in range(n):
                call()
            best[i] = min(best[i], time.perf_counter() - start)
    return [b / n * 1e6 for b in best]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--calls", type=int, default=20000)
    parser.add_argument("--repeat", type=int, default=7)
    args = parser.parse_args()
    robot = keep_joints(load_robot(default_urdf()), ARM)
    model, data = robot.model, robot.model.createData()
    rng = np.random.default_rng(0)
    q, v, a = (rng.uniform(-1.5, 1.5, robot.nv) for _ in range(3))

    print(f"youBot arm ({robot.nv} joints: {', '.join(robot.joint_names)}), "
          f"best of {args.repeat} x {args.calls} calls")
    print(f"{'computation':44s} {'ours us':>8s} {'bare pin us':>12s} {'ratio':>6s}")
    for label, friction in (("URDF friction", JointFriction.from_urdf(robot)),
                            ("mixed friction", JointFriction.from_spec(robot, MIXED))):
        z = friction.steady_state_bristles(v)
        tau = inverse_dynamics(robot, data, q, v, a, friction, z)
        assert np.abs(forward_dynamics(robot, data, q, v, tau, friction, z) - a).max() < 1e-9
        pairs = [
            (f"RNEA + {label} vs pin.rnea", lambda: inverse_dynamics(robot, data, q, v, a, friction, z),
             lambda: pin.rnea(model, data, q, v, a)),
            (f"ABA + {label} vs pin.aba", lambda: forward_dynamics(robot, data, q, v, tau, friction, z),
             lambda: pin.aba(model, data, q, v, tau)),
            (f"{label} alone vs pin.rnea", lambda: friction.torque(v, z),
             lambda: pin.rnea(model, data, q, v, a)),
        ]
        for name, ours, theirs in pairs:
            t_ours, t_pin = best_microseconds([ours, theirs], args.calls, args.repeat)
            print(f"{name:44s} {t_ours:8.2f} {t_pin:12.2f} {t_ours / t_pin:6.2f}")


if __name__ == "__main__":
    main()
