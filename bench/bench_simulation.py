"""Simulation cost, side by side (measured figures, not tests).

1. Per scene: the state dimension, our forward-dynamics right-hand side (ABA + friction +
   controller, as the integrators call it) versus a bare ``pin.aba`` call on the same
   reduced model, in microseconds per call (best of ``--repeat`` alternating loops of ``--calls``).
2. arm_swing against MuJoCo loading the same URDF (wheels and fingers made fixed at 0, as
   the scene locks them; no damping or friction; contacts and joint limits disabled; same
   initial state and gravity), its minimal model (static bodies fused: 5 moving bodies).
   The models are checked first: mass matrix and bias forces at the initial state against
   Pinocchio's. Then, against our reference solution (DOP853 rtol 1e-12, checked at two
   tolerances), for a final joint-space error of ``--target`` rad: the CPU time (the
   measuring thread's, best of ``--repeat``) of our cheapest integrator that reaches it (from the
   work-precision sweep) versus MuJoCo's RK4 at the largest step (halving from 2 ms) that
   reaches it; and MuJoCo's default (semi-implicit Euler) error at its default 2 ms step.
   MuJoCo's steps run inside ``mj_step(..., nstep=N)`` (no Python loop overhead).

Run: python bench/bench_simulation.py [--calls 20000] [--repeat 5] [--target 1e-6]
(BENCH_SMOKE=1: 50 calls, 0.05 s of arm_swing, two sweep settings). Needs ``pip install
mujoco`` (requirements-bench.txt) for part 2.
"""
from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path
from typing import Callable

import numpy as np
import pinocchio as pin
from lxml import etree

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # run from a source checkout
sys.path.insert(0, str(Path(__file__).resolve().parent))

from timing import best_per_call, sized  # noqa: E402
from youbot_dynamics.accuracy.work_precision import recommend, reference_solution, sweep  # noqa: E402
from youbot_dynamics.scene.schema import Scene, load_scene  # noqa: E402
from youbot_dynamics.sim.simulator import Simulator  # noqa: E402

SCENES = ("arm_swing", "arm_friction", "arm_ptp")
SMOKE_GRID = {"rk4": (1e-3,), "dop853": (1e-8,)}


def best_seconds(call, repeat: int) -> float:
    """Best CPU time (s, the measuring thread's) of ``repeat`` calls."""
    return best_per_call([call], 1, repeat)[0]


def rhs_pair(name: str) -> tuple[Callable[[], object], Callable[[], object], dict[str, int | str]]:
    """One call of scene ``name``'s right-hand side at its initial state (t = 0.1 s), one
    bare ``pin.aba`` on the same reduced model at (q, v, 0), and the rhs's cost summary."""
    simulator = Simulator(load_scene(name))
    x = simulator.initial_state()
    model, data = simulator.robot.model, simulator.robot.model.createData()
    q, v, tau = x[:model.nv], x[model.nv:2 * model.nv], np.zeros(model.nv)
    return (lambda: simulator.rhs(0.1, x)), (lambda: pin.aba(model, data, q, v, tau)), simulator.rhs_cost()


def rhs_table(calls: int, repeat: int) -> None:
    print(f"1. right-hand side cost (us per call, best of {repeat} alternating loops of {calls} calls)\n")
    print("| scene | state dim | nv | friction | controller | our rhs | bare pin.aba | ratio |")
    print("|---|---|---|---|---|---|---|---|")
    for name in SCENES:
        ours, bare, cost = rhs_pair(name)
        ours(), bare()  # warm up
        mine, theirs = (t * 1e6 for t in best_per_call([ours, bare], calls, repeat))
        print(f"| {name} | {cost['state_dim']} | {cost['nv']} | {cost['friction_laws']} | {cost['controller']} "
              f"| {mine:.1f} | {theirs:.1f} | {mine / theirs:.1f}x |")


def mujoco_urdf(scene: Scene, fuse: bool = False) -> str:
    """The scene's URDF as MuJoCo should load it: locked joints fixed (all locked at 0 in
    arm_swing), no <dynamics>, no visuals, a <mujoco> compiler block keeping every body (or,
    ``fuse``, merging the bodies fixed to one another: the minimal model, same dynamics)."""
    root = etree.parse(scene.urdf_path).getroot()
    for joint in root.findall("joint"):
        if joint.get("type") != "fixed" and joint.get("name") not in scene.moving:
            assert scene.locked[joint.get("name")] == 0.0, "only zero locks are handled"
            joint.set("type", "fixed")
        for element in joint.findall("dynamics"):
            joint.remove(element)
    for link in root.findall("link"):
        for element in link.findall("visual"):
            link.remove(element)
    extension = etree.SubElement(root, "mujoco")
    etree.SubElement(extension, "compiler", fusestatic=str(fuse).lower(), discardvisual="true", balanceinertia="false")
    return etree.tostring(root, encoding="unicode")


class MujocoArm:
    """arm_swing in MuJoCo: q, v mapped by joint name to our order."""

    def __init__(self, scene: Scene, fuse: bool = False) -> None:
        import mujoco

        self.mj = mujoco
        self.model = mujoco.MjModel.from_xml_string(mujoco_urdf(scene, fuse))
        self.model.opt.disableflags |= mujoco.mjtDisableBit.mjDSBL_CONTACT | mujoco.mjtDisableBit.mjDSBL_LIMIT
        self.model.opt.gravity[:] = scene.gravity
        self.data = mujoco.MjData(self.model)
        self.qadr = np.array([self.model.joint(n).qposadr[0] for n in scene.moving])
        self.vadr = np.array([self.model.joint(n).dofadr[0] for n in scene.moving])
        self.scene = scene

    def reset(self) -> None:
        self.mj.mj_resetData(self.model, self.data)
        self.data.qpos[self.qadr] = self.scene.q0
        self.data.qvel[self.vadr] = self.scene.v0

    def mass_and_bias(self) -> tuple[np.ndarray, np.ndarray]:
        self.reset()
        self.mj.mj_forward(self.model, self.data)
        full = np.zeros((self.model.nv, self.model.nv))
        self.mj.mj_fullM(self.model, self.data, full)
        return full[np.ix_(self.vadr, self.vadr)], self.data.qfrc_bias[self.vadr].copy()

    def run(self, integrator: str, dt: float, duration: float) -> tuple[np.ndarray, float]:
        """Final q and the wall time (s) of the stepping alone."""
        stepping = self.stepping(integrator, dt, duration)
        start = time.perf_counter()
        q = stepping()
        return q, time.perf_counter() - start

    def stepping(self, integrator: str, dt: float, duration: float) -> Callable[[], np.ndarray]:
        """A call that runs ``duration`` s from the scene's initial state with ``integrator``
        at step ``dt`` (set now) and returns the final q."""
        self.model.opt.integrator = getattr(self.mj.mjtIntegrator, integrator)
        self.model.opt.timestep = dt
        steps = int(round(duration / dt))

        def run() -> np.ndarray:
            self.reset()
            self.mj.mj_step(self.model, self.data, nstep=steps)
            return self.data.qpos[self.qadr].copy()

        return run


def model_check(scene: Scene, arm: MujocoArm) -> tuple[float, float]:
    """max |M_mj - M_pin| (kg m^2) and max |b_mj - b_pin| (N m) at the scene's initial state."""
    simulator = Simulator(scene)
    x0 = simulator.initial_state()
    nv = simulator.robot.nv
    q0, v0 = x0[:nv], x0[nv:2 * nv]
    mass, bias = arm.mass_and_bias()
    model, data = simulator.robot.model, simulator.robot.model.createData()
    ours_mass = pin.crba(model, data, q0)
    ours_mass = np.triu(ours_mass) + np.triu(ours_mass, 1).T
    ours_bias = pin.nonLinearEffects(model, data, q0, v0)
    return float(np.abs(mass - ours_mass).max()), float(np.abs(bias - ours_bias).max())


def mujoco_table(target: float, repeat: int) -> None:
    try:
        import mujoco
    except ImportError:
        print("\n2. MuJoCo comparison skipped: pip install -r requirements-bench.txt")
        return
    scene = load_scene("arm_swing")
    scene = scene.with_duration(sized(scene.duration, 0.05))
    arm = MujocoArm(scene, fuse=True)
    mass, bias = model_check(scene, arm)
    print(f"\n2. arm_swing ({scene.duration:g} s) against MuJoCo {mujoco.__version__} (its minimal model: "
          f"{arm.model.nbody} bodies with the world), target final error {target:g} rad\n")
    print(f"model check at x0: max |M_mj - M_pin| = {mass:.2e} kg m^2, max |b_mj - b_pin| = {bias:.2e} N m")

    reference = reference_solution(scene)
    print(f"reference: {reference.spec.describe()}, own error estimate {reference.error_estimate:.1e} rad")
    points = sweep(scene, reference, sized(None, SMOKE_GRID), progress=False)
    best = recommend(points, target)
    if best is not None:
        best_simulator = Simulator(scene, best.spec)
        wall = best_seconds(best_simulator.run, repeat)
    rows = []
    dt, rk4 = 2e-3, None
    while dt > 1e-6:
        q, _ = arm.run("mjINT_RK4", dt, scene.duration)
        error = float(np.abs(q - reference.q).max())
        rows.append((dt, error))
        if error <= target:
            rk4 = (dt, error, best_seconds(lambda: arm.run("mjINT_RK4", dt, scene.duration), repeat))
            break
        dt /= 2
    q_euler = arm.stepping("mjINT_EULER", 2e-3, scene.duration)()
    euler_cpu = best_seconds(arm.stepping("mjINT_EULER", 2e-3, scene.duration), repeat)
    euler_error = float(np.abs(q_euler - reference.q).max())

    print("\nMuJoCo RK4 step halving: " + ", ".join(f"dt={d:.3g}: {e:.2e} rad" for d, e in rows))
    print("\n| run | setting | final error (rad) | CPU time (s) |")
    print("|---|---|---|---|")
    if best is not None:
        print(f"| ours, cheapest meeting target | {best.spec.describe()} | {best.q_error:.2e} | {wall:.4f} |")
    else:
        print("| ours | no swept setting meets the target | - | - |")
    if rk4 is not None:
        print(f"| MuJoCo RK4 | dt={rk4[0]:.3g} | {rk4[1]:.2e} | {rk4[2]:.4f} |")
    print(f"| MuJoCo Euler (default) | dt=0.002 | {euler_error:.2e} | {euler_cpu:.4f} |")
    for method in ("rk4", "dop853", "cvode_adams"):
        candidates = [p for p in points if p.integrator == method and p.meets(target)]
        if candidates:
            p = min(candidates, key=lambda p: p.wall_time)
            print(f"| ours, {method} | {p.spec.describe()} | {p.q_error:.2e} | {p.wall_time:.4f} (wall, single run) |")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--calls", type=int, default=sized(20000, 50))
    parser.add_argument("--repeat", type=int, default=sized(5, 1))
    parser.add_argument("--target", type=float, default=sized(1e-6, 1e-4), help="final joint-space error, rad")
    args = parser.parse_args()
    rhs_table(args.calls, args.repeat)
    mujoco_table(args.target, args.repeat)


if __name__ == "__main__":
    main()
