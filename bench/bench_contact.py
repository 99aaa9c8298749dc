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
3. gripping (28 s, two youBots, 7 pairs, constraint stepper PGS at 1 ms): one run of the
   simulator (outputs at the scene's 50 Hz), then the dynamics node's session without ROS
   (ros/session.py: the simulator advanced sample by sample, solve horizon 0.02 s, the
   messages built) at 50 and 500 Hz (the node's default rate), logs off and on (MCAP in
   rosbag2 form and a Rerun recording, as the node writes them). Real-time factor =
   simulated / wall time; also the sphere's final place, the deepest overlap and the
   stepper's statistics. Each row is the best of REPEATS runs.

Run: python bench/bench_contact.py      (needs ``pip install mujoco`` for part 2)
"""
from __future__ import annotations

import math
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import yaml

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # run from a source checkout

from youbot_dynamics.analysis.contact_extremes import ball_drop_data  # noqa: E402
from youbot_dynamics.ros.session import SimulationSession  # noqa: E402
from youbot_dynamics.sim.scene import Scene, load_scene, scene_dir  # noqa: E402
from youbot_dynamics.sim.simulator import Simulator  # noqa: E402

E, H0, RADIUS, G = 0.8, 1.0, 0.025, 9.81
#: gripping runs per row; the best wall time is kept (a shared machine slows single runs).
REPEATS = 2


def timed(data: dict) -> tuple[Simulator, object, float]:
    simulator = Simulator(Scene.from_dict(data, "bench"))
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
    motion = simulator.model.body_motion(result.x)
    return rising_apex(motion["position"][:, 0, 2] - RADIUS, motion["velocity"][:, 0, 2])


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


def session_wall(rate: float, logs: Path | None) -> float:
    """Wall time (s) of the node's session over the gripping scene at ``rate`` Hz."""
    paths = {} if logs is None else {"mcap_path": logs / "gripping.mcap", "rrd_path": logs / "gripping.rrd"}
    scene = load_scene("gripping")
    session = SimulationSession(scene, rate, samples_per_solve=max(1, round(0.02 * rate)), **paths)
    start = time.perf_counter()
    while session.t < scene.duration:
        session.step()
    session.close()
    return time.perf_counter() - start


def gripping() -> None:
    print("## 3. gripping: the sphere's hand-over and its real-time factor\n")
    simulator = Simulator(load_scene("gripping"))
    walls = []
    for _ in range(REPEATS):
        start = time.perf_counter()
        result = simulator.run()
        walls.append(time.perf_counter() - start)
    wall = min(walls)
    stats = result.stats
    final = simulator.model.body_motion(result.x[-1])["position"][0, 0]
    on_plate = simulator.body_in_link(result, "sphere", "yb2_plate_link")[-1]
    print(f"sphere at the end: ({final[0]:.4f}, {final[1]:.4f}, {final[2]:.4f}) m; in yb2_plate_link "
          f"({on_plate[0]:+.4f}, {on_plate[1]:+.4f}, {on_plate[2]:+.4f}) m (plate 0.2 x 0.3, top at +0.005)")
    print(f"deepest overlap {1e3 * result.max_penetration:.3f} mm; {stats.steps} steps, "
          f"{stats.nonlinear_iterations} PGS iterations, {stats.events} contact events\n")
    print("| run | rate Hz | logs | wall s | real-time factor |")
    print("|---|---|---|---|---|")
    print(f"| Simulator.run | 50 | off | {wall:.2f} | {result.t[-1] / wall:.2f} |")
    with tempfile.TemporaryDirectory() as folder:
        for rate in (50.0, 500.0):
            for logs in (None, Path(folder)):
                best = min(session_wall(rate, logs) for _ in range(REPEATS))
                print(f"| session | {rate:g} | {'MCAP + Rerun' if logs else 'off'} | {best:.2f} | "
                      f"{result.t[-1] / best:.2f} |")
    print()


if __name__ == "__main__":
    contact_cost()
    accuracy()
    gripping()
