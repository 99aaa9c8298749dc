"""Batch dynamics over N samples on the youBot arm (5 joints, URDF friction): milliseconds per
batch. Goals (issue 25): inverse_dynamics_batch within 1.1x of a bare
pin.rneaInParallel (1 thread) plus the friction laws in numpy on the whole batch (the
per-sample inverse_dynamics loop beside it); forward_dynamics_batch likewise against
pin.abaInParallel.

Run: python bench/bench_batch.py [--samples 2000] [--repeat 7]. Best of ``repeat``
alternating runs (CPU time of the measuring thread, bench/timing.py); both batch functions
get a prebuilt pin.ModelPool, as the bare calls do. The batches are checked against the
per-sample functions first.
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

from bench_dynamics import arm  # noqa: E402
from timing import best_per_call  # noqa: E402
from youbot_dynamics.dynamics import friction as laws  # noqa: E402
from youbot_dynamics.dynamics.friction import JointFriction  # noqa: E402
from youbot_dynamics.dynamics.rigid_body import (forward_dynamics, forward_dynamics_batch,  # noqa: E402
                                                 inverse_dynamics, inverse_dynamics_batch)

Calls = tuple[Callable[[], object], ...]


def batch_calls(samples: int = 2000) -> dict[str, Calls]:
    """figure -> (ours, bare batch peer[, per-sample loop]) on ``samples`` random states."""
    robot = arm()
    model, data = robot.model, robot.model.createData()
    friction = JointFriction.from_urdf(robot)
    pool = pin.ModelPool(model, 1)
    rng = np.random.default_rng(0)
    q, v, a = (rng.uniform(-1.5, 1.5, (samples, robot.nv)) for _ in range(3))
    level, scale = friction.table[2], friction.table[3]

    def numpy_friction() -> np.ndarray:
        return laws.viscous(v, friction.damping) + laws.coulomb(v, level, scale)

    tau = inverse_dynamics_batch(robot, q, v, a, friction, pool=pool)
    for k in (0, samples - 1):
        assert np.abs(tau[k] - inverse_dynamics(robot, data, q[k], v[k], a[k], friction)).max() < 1e-12
        assert np.abs(forward_dynamics_batch(robot, q, v, tau, friction, pool=pool)[k]
                      - forward_dynamics(robot, data, q[k], v[k], tau[k], friction)).max() < 1e-12
    return {
        "inverse": (lambda: inverse_dynamics_batch(robot, q, v, a, friction, pool=pool),
                    lambda: pin.rneaInParallel(1, pool, q.T, v.T, a.T).T + numpy_friction(),
                    lambda: [inverse_dynamics(robot, data, q[k], v[k], a[k], friction) for k in range(samples)]),
        "forward": (lambda: forward_dynamics_batch(robot, q, v, tau, friction, pool=pool),
                    lambda: pin.abaInParallel(1, pool, q.T, v.T, (tau - numpy_friction()).T).T),
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--samples", type=int, default=2000)
    parser.add_argument("--repeat", type=int, default=7)
    args = parser.parse_args()
    print(f"youBot arm, {args.samples} samples, best of {args.repeat} (ms per batch)")
    for name, calls in batch_calls(args.samples).items():
        for call in calls:
            call()  # compile / warm up
        times = [t * 1e3 for t in best_per_call(calls, 1, args.repeat)]
        line = f"{name:8s} ours {times[0]:7.2f}  bare {times[1]:7.2f}  ratio {times[0] / times[1]:5.2f}"
        if len(times) > 2:
            line += f"  per-sample loop {times[2]:7.2f} ({times[2] / times[0]:.1f}x ours)"
        print(line)


if __name__ == "__main__":
    main()
