"""Screw-axis (PoE) kinematics vs Pinocchio on the youBot arm: microseconds per call, side by
side, with the ratio. Goal: PoE forward kinematics within 10x of Pinocchio's forward
kinematics + frame placement.

Run: python bench/bench_kinematics.py [--calls 20000] [--repeat 5]. Each figure is the best
of ``repeat`` loops of ``calls`` calls at one random configuration (time.perf_counter), so
it includes the Python call overhead both sides pay. The pose / Jacobian of the gripper palm
is checked against Pinocchio's before timing.
"""
from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path
from typing import Callable

import numpy as np
import pinocchio as pin

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # run from a source checkout

from youbot_dynamics import default_urdf  # noqa: E402
from youbot_dynamics.model.robot import load_robot  # noqa: E402
from youbot_dynamics.model.screws import (fkin_body, fkin_space, jacobian_body,  # noqa: E402
                                          jacobian_space, screw_chain)


def microseconds(call: Callable[[], object], calls: int, repeat: int) -> float:
    """Best time per call over ``repeat`` loops, in microseconds."""
    best = float("inf")
    for _ in range(repeat):
        start = time.perf_counter()
        for _ in range(calls):
            call()
        best = min(best, time.perf_counter() - start)
    return best / calls * 1e6


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--calls", type=int, default=20000)
    parser.add_argument("--repeat", type=int, default=5)
    args = parser.parse_args()
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

    assert np.abs(fkin_space(chain, q) - pinocchio_pose()).max() < 1e-12
    world = pinocchio_jacobian(pin.WORLD)()
    assert np.abs(jacobian_space(chain, q) - np.vstack([world[3:], world[:3]])[:, chain.joints]).max() < 1e-12

    pairs = [
        ("forward kinematics (space PoE)", lambda: fkin_space(chain, q), pinocchio_pose),
        ("forward kinematics (body PoE)", lambda: fkin_body(chain, q), pinocchio_pose),
        ("space Jacobian vs WORLD frame Jacobian", lambda: jacobian_space(chain, q),
         pinocchio_jacobian(pin.WORLD)),
        ("body Jacobian vs LOCAL frame Jacobian", lambda: jacobian_body(chain, q),
         pinocchio_jacobian(pin.LOCAL)),
    ]
    print(f"youBot arm, chain {robot.root_link} -> {chain.link} ({chain.n} joints), "
          f"best of {args.repeat} x {args.calls} calls")
    print(f"{'computation':40s} {'ours us':>9s} {'pinocchio us':>13s} {'ratio':>7s}")
    for name, ours, theirs in pairs:
        t_ours = microseconds(ours, args.calls, args.repeat)
        t_pin = microseconds(theirs, args.calls, args.repeat)
        print(f"{name:40s} {t_ours:9.2f} {t_pin:13.2f} {t_ours / t_pin:7.1f}")
    batch = np.random.default_rng(1).uniform(-np.pi, np.pi, (1000, robot.nv))
    t_batch = microseconds(lambda: fkin_space(chain, batch), max(1, args.calls // 1000), args.repeat)
    print(f"{'forward kinematics, batch of 1000':40s} {t_batch / 1000:9.2f} {'':13s} (per configuration)")


if __name__ == "__main__":
    main()
