"""Screw-axis (PoE) kinematics vs Pinocchio on the youBot arm: microseconds per call, side by
side, with the ratio. Goals: PoE forward kinematics within 4x of Pinocchio's forward
kinematics + frame placement (issue 14), PoE Jacobians within 2x of Pinocchio's frame
Jacobian (issue 25).

Run: python bench/bench_kinematics.py [--calls 300] [--repeat 15]. Each figure is the best
of ``repeat`` alternating loops of ``calls`` calls at one random configuration (CPU time of
the measuring thread, bench/timing.py), so it includes the Python call overhead both sides
pay. The pose and Jacobians of the gripper palm are checked against Pinocchio's before
timing.
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
from youbot_dynamics.model.robot import load_robot  # noqa: E402
from youbot_dynamics.model.screws import (fkin_body, fkin_space, jacobian_body,  # noqa: E402
                                          jacobian_space, screw_chain)

Pair = tuple[Callable[[], object], Callable[[], object]]


def kinematics_pairs() -> dict[str, Pair]:
    """figure -> (ours, Pinocchio's) on the youBot's chain to the gripper palm (5 joints)."""
    robot = load_robot(default_urdf())
    model, data = robot.model, robot.model.createData()
    chain = screw_chain(robot)
    frame = robot.frame_id(chain.link)
    q = np.random.default_rng(0).uniform(-np.pi, np.pi, robot.nv)

    def pinocchio_pose() -> np.ndarray:
        pin.forwardKinematics(model, data, q)
        return pin.updateFramePlacement(model, data, frame).homogeneous

    def pinocchio_jacobian(reference: pin.ReferenceFrame) -> Callable[[], np.ndarray]:
        return lambda: pin.computeFrameJacobian(model, data, q, frame, reference)

    def swapped(jacobian: np.ndarray) -> np.ndarray:  # Pinocchio's rows (v, omega) -> ours (omega, v)
        return np.vstack([jacobian[3:], jacobian[:3]])[:, chain.joints]

    assert np.abs(fkin_space(chain, q) - pinocchio_pose()).max() < 1e-12
    assert np.abs(fkin_body(chain, q) - pinocchio_pose()).max() < 1e-12
    assert np.abs(jacobian_space(chain, q) - swapped(pinocchio_jacobian(pin.WORLD)())).max() < 1e-12
    assert np.abs(jacobian_body(chain, q) - swapped(pinocchio_jacobian(pin.LOCAL)())).max() < 1e-12
    return {
        "PoE FK (space) vs Pinocchio FK": (lambda: fkin_space(chain, q), pinocchio_pose),
        "PoE FK (body) vs Pinocchio FK": (lambda: fkin_body(chain, q), pinocchio_pose),
        "PoE space Jacobian vs WORLD frame Jacobian": (lambda: jacobian_space(chain, q),
                                                       pinocchio_jacobian(pin.WORLD)),
        "PoE body Jacobian vs LOCAL frame Jacobian": (lambda: jacobian_body(chain, q),
                                                      pinocchio_jacobian(pin.LOCAL)),
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--calls", type=int, default=300)
    parser.add_argument("--repeat", type=int, default=15)
    args = parser.parse_args()
    print(f"youBot chain base_footprint -> gripper_palm_link (5 joints), best of {args.repeat} x {args.calls} calls")
    print(f"{'computation':44s} {'ours us':>8s} {'pin us':>8s} {'ratio':>6s}")
    for name, (ours, theirs) in kinematics_pairs().items():
        ours(), theirs()  # compile / warm up
        t_ours, t_pin = (t * 1e6 for t in best_per_call([ours, theirs], args.calls, args.repeat))
        print(f"{name:44s} {t_ours:8.2f} {t_pin:8.2f} {t_ours / t_pin:6.2f}")


if __name__ == "__main__":
    main()
