"""Cost against the number of joints: serial chains of 5, 10, 20, 40 and 60 revolute joints
(a generated URDF), ours and Pinocchio's, with the fitted growth exponent p of each
(cost ~ n^p; 1 is linear, below 1 while the fixed cost of a Python call dominates).

Figures, microseconds per call (best of ``repeat`` alternating loops of ``calls`` calls):
- PoE forward kinematics of the tip vs pin.forwardKinematics + updateFramePlacement;
- PoE space Jacobian vs pin.computeFrameJacobian (WORLD);
- RNEA + URDF friction vs pin.rnea; ABA + URDF friction vs pin.aba;
- 1 s of simulation at rest-start, rk4 at 1 ms (4000 right-hand sides): our ``integrate``
  with rigid_body.forward_dynamics (friction included) vs a bare Python rk4 loop on pin.aba
  (milliseconds per run, best of 5).

Run: python bench/bench_scaling.py [--calls 300] [--repeat 15] [--dofs 5,10,20,40,60]
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
sys.path.insert(0, str(Path(__file__).resolve().parent))

from timing import best_per_call, growth_exponent, machine  # noqa: E402
from youbot_dynamics.dynamics.friction import JointFriction  # noqa: E402
from youbot_dynamics.dynamics.rigid_body import forward_dynamics, inverse_dynamics  # noqa: E402
from youbot_dynamics.integrate.integrators import integrate  # noqa: E402
from youbot_dynamics.model.robot import Robot, load_robot  # noqa: E402
from youbot_dynamics.model.screws import fkin_space, jacobian_space, screw_chain  # noqa: E402

DOFS = (5, 10, 20, 40, 60)
FIGURES = ("PoE FK", "PoE space Jacobian", "RNEA + friction", "ABA + friction", "1 s rk4 simulation")


def chain_urdf(n: int) -> str:
    """A serial chain of n revolute joints, axes alternating z and y, 0.1 m apart; links of
    1 kg (centre of mass mid-link, inertia 0.01 kg m^2), URDF damping 0.1 N m s/rad and
    friction 0.2 N m per joint."""
    inertial = ('<inertial><origin xyz="0 0 0.05"/><mass value="1"/>'
                '<inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"/></inertial>')
    links = ['<link name="base"/>'] + [f'<link name="l{i}">{inertial}</link>' for i in range(1, n + 1)]
    joints = [f'<joint name="j{i}" type="revolute"><parent link="{"base" if i == 1 else f"l{i - 1}"}"/>'
              f'<child link="l{i}"/><origin xyz="0 0 {0.0 if i == 1 else 0.1}"/>'
              f'<axis xyz="{"0 0 1" if i % 2 else "0 1 0"}"/><limit lower="-3" upper="3" effort="100" velocity="10"/>'
              f'<dynamics damping="0.1" friction="0.2"/></joint>' for i in range(1, n + 1)]
    return f'<?xml version="1.0"?><robot name="chain{n}">{"".join(links + joints)}</robot>'


def rk4_pinocchio(model: pin.Model, data: pin.Data, x0: np.ndarray, dt: float, steps: int) -> np.ndarray:
    """The bare peer: classic RK4 on (q, v) with a = pin.aba(q, v, 0), no friction."""
    n, x, zero = model.nv, x0.copy(), np.zeros(model.nv)

    def f(x: np.ndarray) -> np.ndarray:
        return np.concatenate((x[n:], pin.aba(model, data, x[:n], x[n:], zero)))

    for _ in range(steps):
        k1 = f(x)
        k2 = f(x + 0.5 * dt * k1)
        k3 = f(x + 0.5 * dt * k2)
        k4 = f(x + dt * k3)
        x = x + dt / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4)
    return x


def per_call_pairs(robot: Robot) -> dict[str, tuple[Callable[[], object], Callable[[], object]]]:
    """figure -> (ours, Pinocchio's) at one random state of ``robot``."""
    model, data, ours_data = robot.model, robot.model.createData(), robot.model.createData()
    chain, friction = screw_chain(robot), JointFriction.from_urdf(robot)
    frame = robot.frame_id(chain.link)
    rng = np.random.default_rng(0)
    q, v, a = (rng.uniform(-1.0, 1.0, robot.nv) for _ in range(3))
    tau = inverse_dynamics(robot, ours_data, q, v, a, friction)

    def pinocchio_pose() -> np.ndarray:
        pin.forwardKinematics(model, data, q)
        return pin.updateFramePlacement(model, data, frame).homogeneous

    world = pin.computeFrameJacobian(model, data, q, frame, pin.WORLD)
    assert np.abs(fkin_space(chain, q) - pinocchio_pose()).max() < 1e-10
    assert np.abs(jacobian_space(chain, q) - np.vstack([world[3:], world[:3]])).max() < 1e-10
    assert np.abs(forward_dynamics(robot, ours_data, q, v, tau, friction) - a).max() < 1e-6
    return {
        "PoE FK": (lambda: fkin_space(chain, q), pinocchio_pose),
        "PoE space Jacobian": (lambda: jacobian_space(chain, q),
                               lambda: pin.computeFrameJacobian(model, data, q, frame, pin.WORLD)),
        "RNEA + friction": (lambda: inverse_dynamics(robot, ours_data, q, v, a, friction),
                            lambda: pin.rnea(model, data, q, v, a)),
        "ABA + friction": (lambda: forward_dynamics(robot, ours_data, q, v, tau, friction),
                           lambda: pin.aba(model, data, q, v, tau)),
    }


def simulation_pair(robot: Robot) -> tuple[Callable[[], object], Callable[[], object]]:
    """(ours, Pinocchio's) 1 s rk4 at 1 ms from q = 0.3 rad per joint, at rest, no torque."""
    model, data = robot.model, robot.model.createData()
    friction, n = JointFriction.from_urdf(robot), robot.nv
    x0, zero = np.concatenate((np.full(n, 0.3), np.zeros(n))), np.zeros(n)

    def rhs(t: float, x: np.ndarray) -> np.ndarray:
        return np.concatenate((x[n:], forward_dynamics(robot, data, x[:n], x[n:], zero, friction)))

    return (lambda: integrate(rhs, x0, [0.0, 1.0], "rk4", dt=1e-3),
            lambda: rk4_pinocchio(model, data, x0, 1e-3, 1000))


def scaling(dofs: tuple[int, ...] = DOFS, calls: int = 300, repeat: int = 15) -> dict[str, dict]:
    """figure -> {"dofs", "ours_us", "pinocchio_us", "exponent_ours", "exponent_pinocchio"}."""
    results = {name: {"dofs": list(dofs), "ours_us": [], "pinocchio_us": []} for name in FIGURES}
    for n in dofs:
        robot = load_robot(chain_urdf(n))
        pairs = {**per_call_pairs(robot), "1 s rk4 simulation": simulation_pair(robot)}
        for name, (ours, theirs) in pairs.items():
            ours(), theirs()  # compile / warm up
            if name == "1 s rk4 simulation":
                t_ours, t_pin = best_per_call([ours, theirs], 1, min(repeat, 5))
            else:  # loops as short as with 5 joints (fewer preemptions on a busy machine), more of them
                short = max(10, calls * DOFS[0] // n)
                t_ours, t_pin = best_per_call([ours, theirs], short, max(1, min(200, repeat * calls // short)))
            results[name]["ours_us"].append(t_ours * 1e6)
            results[name]["pinocchio_us"].append(t_pin * 1e6)
    for figure in results.values():
        figure["exponent_ours"] = growth_exponent(dofs, figure["ours_us"])
        figure["exponent_pinocchio"] = growth_exponent(dofs, figure["pinocchio_us"])
    return results


def print_scaling(results: dict[str, dict]) -> None:
    for name, figure in results.items():
        unit, scale = ("ms", 1e-3) if name == "1 s rk4 simulation" else ("us", 1.0)
        print(f"\n{name} ({unit} per call): growth exponent ours {figure['exponent_ours']:.2f}, "
              f"Pinocchio {figure['exponent_pinocchio']:.2f}")
        print(f"| joints | ours {unit} | Pinocchio {unit} | ratio |\n|---|---|---|---|")
        for n, ours, theirs in zip(figure["dofs"], figure["ours_us"], figure["pinocchio_us"]):
            print(f"| {n} | {ours * scale:.2f} | {theirs * scale:.2f} | {ours / theirs:.2f} |")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--calls", type=int, default=300)
    parser.add_argument("--repeat", type=int, default=15)
    parser.add_argument("--dofs", default=",".join(map(str, DOFS)))
    args = parser.parse_args()
    print(machine())
    start = time.perf_counter()
    print_scaling(scaling(tuple(int(n) for n in args.dofs.split(",")), args.calls, args.repeat))
    print(f"\n({time.perf_counter() - start:.1f} s)")


if __name__ == "__main__":
    main()
