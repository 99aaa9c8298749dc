"""Contact cost and accuracy, side by side (measured figures, not tests).

1. The cost of a scene with its contact pairs against the same scene with them removed
   (ball_drop: rk45; box_slide: the constraint stepper, which without pairs integrates a
   free fall): wall time and right-hand-side evaluations or steps. The scene pays for
   contact only where it declares it.
2. ball_drop against MuJoCo (the same 5 cm, 45.8 g sphere dropped from 1 m onto a plane,
   restitution target e = 0.8, so the first hop's apex should be e^2 = 0.64 m): the apex
   error versus wall time, ours with Hunt-Crossley (rk45 at several tolerances, the
   impulsive law) and the constraint stepper at several steps, MuJoCo's soft contact at
   several time steps with the direct solref = (-k, -b) of a linear spring-damper whose
   restitution is e: zeta = -ln e / sqrt(pi^2 + ln^2 e), contact lasting 10 steps
   (omega = pi / (10 dt), k = omega^2, b = 2 zeta omega), solimp 0.99 (MuJoCo's default
   time-constant form with dampratio = zeta bounces far lower: about 0.07 m); Euler
   (MuJoCo's default) and RK4. The apex is max(z + vz^2 / 2g) over the rising samples.
3. gripping: not shipped (see the closing report of issue 5), so no real-time factor.

Run: python bench/bench_contact.py      (needs ``pip install mujoco`` for part 2)
"""
from __future__ import annotations

import math
import sys
import time
from pathlib import Path

import numpy as np
import yaml

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # run from a source checkout

from youbot_dynamics.analysis.contact_extremes import ball_drop_data, scene_from  # noqa: E402
from youbot_dynamics.sim.scene import scene_dir  # noqa: E402
from youbot_dynamics.sim.simulator import Simulator  # noqa: E402

E, H0, RADIUS, G = 0.8, 1.0, 0.025, 9.81


def timed(data: dict) -> tuple[Simulator, object, float]:
    simulator = Simulator(scene_from(data))
    start = time.perf_counter()
    result = simulator.run()
    return simulator, result, time.perf_counter() - start


def contact_cost() -> None:
    print("## 1. cost of the declared contact pairs\n")
    print("| scene | pairs | integrator | wall s | rhs evals / steps | events |")
    print("|---|---|---|---|---|---|")
    for name in ("ball_drop", "box_slide"):
        data = yaml.safe_load((scene_dir() / f"{name}.yaml").read_text())
        for label, variant in (("declared", data), ("removed", {**data, "contacts": []})):
            if not variant["contacts"] and variant["integrator"]["method"] in ("pgs", "admm"):
                variant = {**variant, "integrator": {"method": "rk4", "dt": variant["integrator"]["dt"]}}
            _, result, wall = timed(variant)
            stats = result.stats
            work = stats.rhs_evals if stats.rhs_evals else stats.steps
            print(f"| {name} | {label} | {result.integrator.describe()} | {wall:.3f} | {work} | {stats.events} |")
    print()


def rising_apex(z: np.ndarray, vz: np.ndarray) -> float:
    """Apex (m) of the hop after the one impact: max of z + vz^2 / 2g where vz > 0."""
    return float(np.max((z + vz ** 2 / (2 * G))[vz > 0]))


def first_apex(simulator: Simulator, result) -> float:
    return rising_apex(result.x[:, simulator.layout.slice("p")][:, 2] - RADIUS,
                       result.x[:, simulator.layout.slice("u")][:, 2])


def ours() -> list[tuple[str, float, float]]:
    rows = []
    hunt = {"law": "hunt_crossley", "stiffness": 1e7, "restitution": E, "friction": 0.3}
    for rtol in (1e-4, 1e-6, 1e-8):
        simulator, result, wall = timed(ball_drop_data(hunt, {"method": "rk45", "rtol": rtol, "atol": rtol * 1e-2}, 1.1))
        rows.append((f"ours hunt_crossley k=1e7 rk45 rtol={rtol:g}", first_apex(simulator, result), wall))
    newton = {"law": "newton", "restitution": E, "friction": 0.3}
    simulator, result, wall = timed(ball_drop_data(newton, {"method": "rk45", "rtol": 1e-8, "atol": 1e-10}, 1.1))
    rows.append(("ours newton (impulsive) rk45 rtol=1e-8", first_apex(simulator, result), wall))
    for dt in (1e-2, 1e-3, 1e-4):
        constraint = {"law": "constraint", "restitution": E, "friction": 0.3}
        simulator, result, wall = timed(ball_drop_data(constraint, {"method": "pgs", "dt": dt}, 1.1))
        rows.append((f"ours constraint pgs dt={dt:g}", first_apex(simulator, result), wall))
    return rows


MJCF = """<mujoco><option timestep="{dt}" integrator="{integrator}"/>
<worldbody><geom name="floor" type="plane" size="5 5 0.1"/>
<body name="ball" pos="0 0 {z0}"><freejoint/>
<geom type="sphere" size="{r}" mass="{mass}" solref="{k} {b}" solimp="0.99 0.99 0.001" friction="0.3 0.005 0.0001"/>
</body></worldbody></mujoco>"""


def mujoco_rows() -> list[tuple[str, float, float]]:
    try:
        import mujoco
    except ImportError:
        print("MuJoCo not installed: pip install mujoco (requirements-bench.txt)\n")
        return []
    zeta = -math.log(E) / math.sqrt(math.pi ** 2 + math.log(E) ** 2)
    mass = 700 * 4 / 3 * math.pi * RADIUS ** 3
    rows = []
    for integrator in ("Euler", "RK4"):
        for dt in (2e-3, 5e-4, 1e-4):
            omega = math.pi / (10 * dt)
            model = mujoco.MjModel.from_xml_string(MJCF.format(dt=dt, integrator=integrator, z0=H0 + RADIUS, r=RADIUS,
                                                               mass=mass, k=-omega * omega, b=-2 * zeta * omega))
            data = mujoco.MjData(model)
            steps = int(round(1.1 / dt))
            z, vz = np.empty(steps), np.empty(steps)
            start = time.perf_counter()
            for i in range(steps):
                mujoco.mj_step(model, data)
                z[i], vz[i] = data.qpos[2] - RADIUS, data.qvel[2]
            wall = time.perf_counter() - start
            rows.append((f"MuJoCo {mujoco.__version__} {integrator} dt={dt:g}", rising_apex(z, vz), wall))
    return rows


def accuracy() -> None:
    print(f"## 2. ball_drop: apex of the first hop (target e^2 H0 = {E * E * H0:.4f} m) vs wall time\n")
    print("| model | apex m | error % | wall s |")
    print("|---|---|---|---|")
    for label, apex, wall in ours() + mujoco_rows():
        print(f"| {label} | {apex:.5f} | {100 * (apex / (E * E * H0) - 1):+.3f} | {wall:.4f} |")
    print()


if __name__ == "__main__":
    contact_cost()
    accuracy()
    print("## 3. gripping\n\nnot shipped (issue 5 closing report): no real-time factor measured.")
