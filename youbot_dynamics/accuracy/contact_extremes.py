"""Contact at its extremes, measured: stiffness sweep per integrator and the constraint
stepper at several steps, a 1 g body on a heavy one, a thin fast object against a 1 cm
plate (tunnelling) and a grasp at the friction-cone limit.

Every case is a scene built here as a mapping and validated by :meth:`Scene.from_dict` like
any file, run by the :class:`~youbot_dynamics.sim.simulator.Simulator`; the tables are lists
of dicts (one row per run) with the figures named in their keys.
"""
from __future__ import annotations

import math
import time
from typing import Any

import numpy as np
import yaml

from youbot_dynamics.accuracy.bounce import bounce_apex, height_and_apex
from youbot_dynamics.errors import UserInputError
from youbot_dynamics.integrate.errors import IntegrationError
from youbot_dynamics.integrate.registry import STEPPERS
from youbot_dynamics.scene.schema import Scene, scene_dir
from youbot_dynamics.sim.simulator import SimulationResult, Simulator

STIFFNESSES = (1e3, 1e4, 1e5, 1e6, 1e7, 1e8)
ODE_METHODS = (("rk45", None), ("radau", None), ("cvode_bdf", None), ("rk4", 1e-4))
STEPPER_STEPS = (1e-2, 1e-3, 1e-4)


def integrator_of(method: str, dt: float | None) -> dict[str, Any]:
    """A scene's ``integrator`` section: fixed step dt (s), else rtol 1e-6, atol 1e-9."""
    return {"method": method, "dt": dt} if dt is not None else {"method": method, "rtol": 1e-6, "atol": 1e-9}


def run_case(data: dict[str, Any]) -> tuple[Simulator | None, SimulationResult | None, str, float]:
    """(simulator, result or None, status, wall time s): status ``ok`` or the failure."""
    start = time.perf_counter()
    try:
        simulator = Simulator(Scene.from_dict(data, f"contact extremes: {data.get('name', 'case')}"))
        result = simulator.run()
    except (IntegrationError, UserInputError, FloatingPointError, np.linalg.LinAlgError) as error:
        return None, None, f"failed: {str(error)[:60]}", time.perf_counter() - start
    finite = np.all(np.isfinite(result.x))
    return simulator, result, "ok" if finite else "non-finite", time.perf_counter() - start


def ball_drop_data(law: dict[str, Any], integrator: dict[str, Any], duration: float) -> dict[str, Any]:
    """The packaged ball_drop scene with another contact law, integrator and duration (s)."""
    data = yaml.safe_load((scene_dir() / "ball_drop.yaml").read_text())
    data["contacts"][0] = {"pair": ["floor", "ball"], **law}
    data["integrator"], data["duration"] = integrator, duration
    return data


def first_bounce(simulator: Simulator, result: SimulationResult, restitution: float) -> dict[str, float]:
    """Apex after the first impact (m above the floor, :func:`bounce_apex`) and the energy
    gained at the impact beyond the law's e^2 (J): E_after - e^2 E_before, gravity
    potential from the floor (the ball's radius and g are the scene's)."""
    after = bounce_apex(simulator, result)
    drop = height_and_apex(simulator, result)[1][0]
    g = float(np.linalg.norm(simulator.scene.gravity))
    mass = simulator.scene.free_bodies[0].body.mass
    return {"apex_m": after, "energy_gain_J": mass * g * (after - restitution ** 2 * drop)}


def stiffness_sweep() -> list[dict[str, Any]]:
    """ball_drop (e = 0.8, 1 m) over 1.1 s (one impact, the apex of the first hop at
    0.64 m): every stiffness per ODE integrator, and the constraint stepper (rigid: no
    stiffness) at several steps. A run gaining more than 1 % of the drop energy at the
    impact (beyond the law's e^2) is marked unstable."""
    rows = []
    for k in STIFFNESSES:
        for method, dt in ODE_METHODS:
            law = {"law": "hunt_crossley", "stiffness": k, "restitution": 0.8, "friction": 0.3}
            simulator, result, status, wall = run_case(ball_drop_data(law, integrator_of(method, dt), 1.1))
            row = {"case": f"k={k:.0e}", "integrator": method + (f" dt={dt:g}" if dt else ""), "status": status,
                   "max_penetration_m": math.nan, "apex_m": math.nan, "energy_gain_J": math.nan, "wall_s": wall}
            if result is not None:
                row.update(first_bounce(simulator, result, 0.8), max_penetration_m=result.max_penetration,
                           rhs_evals=result.stats.rhs_evals)
                if row["energy_gain_J"] > 0.01 * simulator.scene.free_bodies[0].body.mass * 9.81:
                    row["status"] = "unstable: energy gained"
            rows.append(row)
    for solver in STEPPERS:
        for dt in STEPPER_STEPS:
            law = {"law": "constraint", "restitution": 0.8, "friction": 0.3}
            simulator, result, status, wall = run_case(ball_drop_data(law, {"method": solver, "dt": dt}, 1.1))
            row = {"case": "rigid", "integrator": f"{solver} dt={dt:g}", "status": status, "wall_s": wall}
            if result is not None:
                row.update(first_bounce(simulator, result, 0.8), max_penetration_m=result.max_penetration)
            rows.append(row)
    return rows


def light_on_heavy() -> list[dict[str, Any]]:
    """A 1 g sphere resting on a 10 kg box resting on the floor, 1 s: does the pile stay put?"""
    rows = []
    for label, law, integrator in (
            ("hunt_crossley k=1e6", {"law": "hunt_crossley", "stiffness": 1e6, "restitution": 0.5, "friction": 0.5},
             {"method": "cvode_bdf", "rtol": 1e-6, "atol": 1e-9}),
            ("constraint pgs dt=1e-3", {"law": "constraint", "restitution": 0.0, "friction": 0.5},
             {"method": "pgs", "dt": 1e-3}),
            ("constraint admm dt=1e-3", {"law": "constraint", "restitution": 0.0, "friction": 0.5},
             {"method": "admm", "dt": 1e-3})):
        data = {"name": "light_on_heavy", "robot": "none",
                "free_bodies": [{"name": "heavy", "shape": {"type": "box", "size": [0.2, 0.2, 0.2]}, "mass": 10.0,
                                 "inertia": [0.0667, 0.0667, 0.0667], "position": [0, 0, 0.1]},
                                {"name": "light", "shape": {"type": "sphere", "radius": 0.0062}, "mass": 0.001,
                                 "inertia": [1.5e-8, 1.5e-8, 1.5e-8], "position": [0, 0, 0.2062]}],
                "world": [{"name": "floor", "shape": {"type": "halfspace", "normal": [0, 0, 1], "offset": 0}}],
                "contacts": [{"pair": ["floor", "heavy"], **law}, {"pair": ["heavy", "light"], **law}],
                "integrator": integrator, "duration": 1.0, "outputs": {"rate": 100, "record": ["q"]}}
        simulator, result, status, wall = run_case(data)
        row = {"case": "1 g on 10 kg", "integrator": label, "status": status, "wall_s": wall}
        if result is not None:
            z = simulator.model.body_motion(result.x)["position"][:, :, 2]
            row.update(light_drift_m=float(np.max(np.abs(z[:, 1] - z[0, 1]))),
                       heavy_drift_m=float(np.max(np.abs(z[:, 0] - z[0, 0]))),
                       max_penetration_m=result.max_penetration)
        rows.append(row)
    return rows


def tunnelling() -> list[dict[str, Any]]:
    """A 2 mm sphere at 50 m/s against a 1 cm plate 5 cm ahead, 4 ms: does it get through?"""
    rows = []
    for label, law, integrator in (
            ("hunt_crossley k=1e9 rk45", {"law": "hunt_crossley", "stiffness": 1e9, "restitution": 0.5,
                                          "friction": 0.0}, {"method": "rk45", "rtol": 1e-6, "atol": 1e-9}),
            ("hunt_crossley k=1e9 rk4 dt=1e-3", {"law": "hunt_crossley", "stiffness": 1e9, "restitution": 0.5,
                                                 "friction": 0.0}, {"method": "rk4", "dt": 1e-3}),
            ("hunt_crossley k=1e9 rk4 dt=1e-5", {"law": "hunt_crossley", "stiffness": 1e9, "restitution": 0.5,
                                                 "friction": 0.0}, {"method": "rk4", "dt": 1e-5}),
            ("newton rk45", {"law": "newton", "restitution": 0.5, "friction": 0.0},
             {"method": "rk45", "rtol": 1e-6, "atol": 1e-9}),
            ("constraint pgs dt=1e-3", {"law": "constraint", "restitution": 0.5, "friction": 0.0},
             {"method": "pgs", "dt": 1e-3}),
            ("constraint pgs dt=1e-4", {"law": "constraint", "restitution": 0.5, "friction": 0.0},
             {"method": "pgs", "dt": 1e-4})):
        data = {"name": "tunnelling", "robot": "none", "gravity": [0, 0, 0],
                "free_bodies": [{"name": "pellet", "shape": {"type": "sphere", "radius": 0.002}, "density": 7800,
                                 "position": [0, 0, 0], "velocity": [50.0, 0, 0]}],
                "world": [{"name": "plate", "shape": {"type": "box", "size": [0.01, 0.2, 0.2]},
                           "pose": {"xyz": [0.055, 0, 0]}}],
                "contacts": [{"pair": ["plate", "pellet"], **law}],
                "integrator": integrator, "duration": 0.004, "outputs": {"rate": 1000, "record": ["q"]}}
        simulator, result, status, wall = run_case(data)
        row = {"case": "2 mm at 50 m/s vs 1 cm plate", "integrator": label, "status": status, "wall_s": wall}
        if result is not None:
            x_end = float(simulator.model.body_motion(result.x[-1])["position"][0, 0, 0])
            row.update(final_x_m=x_end, tunnelled=bool(x_end > 0.06), max_penetration_m=result.max_penetration)
        rows.append(row)
    return rows


def grasp_at_cone_limit(margins=(0.9, 0.99, 1.01, 1.1)) -> list[dict[str, Any]]:
    """The wooden sphere (45.8 g) squeezed between two vertical plates with a set overlap:
    normal force N per side, weight m g; it holds if m g <= 2 mu N. ``margins`` are
    m g / (2 mu N). Reported: the sphere's sinking speed after 0.25 s against the
    regularised law's creep prediction v_s s / sqrt(1 - s^2) below the limit, or its
    acceleration (fitted over 0.05-0.25 s, while it is still between the plates) against
    g (1 - 1/s) above it."""
    rows = []
    mu, k, v_s, radius = 0.3, 1e6, 1e-3, 0.025
    mass = 700 * 4 / 3 * math.pi * radius ** 3
    for s in margins:
        normal = mass * 9.81 / (2 * mu * s)
        overlap = (normal / k) ** (1 / 1.5)
        law = {"law": "hunt_crossley", "stiffness": k, "restitution": 0.5, "friction": mu, "velocity_scale": v_s}
        half_gap = radius - overlap
        data = {"name": "grasp", "robot": "none",
                "free_bodies": [{"name": "sphere", "shape": {"type": "sphere", "radius": radius}, "density": 700,
                                 "position": [0, 0, 0.5]}],
                "world": [{"name": "left", "shape": {"type": "box", "size": [0.01, 0.1, 0.1]},
                           "pose": {"xyz": [-half_gap - 0.005, 0, 0.5]}},
                          {"name": "right", "shape": {"type": "box", "size": [0.01, 0.1, 0.1]},
                           "pose": {"xyz": [half_gap + 0.005, 0, 0.5]}}],
                "contacts": [{"pair": ["left", "sphere"], **law}, {"pair": ["right", "sphere"], **law}],
                "integrator": {"method": "cvode_bdf", "rtol": 1e-8, "atol": 1e-11}, "duration": 0.25,
                "outputs": {"rate": 100, "record": ["q"]}}
        simulator, result, status, wall = run_case(data)
        row = {"case": f"m g / (2 mu N) = {s:g}", "integrator": "hunt_crossley cvode_bdf", "status": status,
               "wall_s": wall}
        if result is not None:
            vz = simulator.model.body_motion(result.x)["velocity"][:, 0, 2]
            late = result.t >= 0.05
            measured_accel = float(np.polyfit(result.t[late], vz[late], 1)[0])
            row.update(sink_speed_m_s=float(-vz[-1]), held=bool(-vz[-1] < 10 * v_s),
                       predicted=(f"creep {v_s * s / math.sqrt(1 - s * s):.3g} m/s" if s < 1 else
                                  f"accel {9.81 * (1 - 1 / s):.3g} m/s^2"),
                       measured_accel_m_s2=-measured_accel)
        rows.append(row)
    return rows


TABLES = {"stiffness": stiffness_sweep, "light_on_heavy": light_on_heavy, "tunnelling": tunnelling,
          "grasp": grasp_at_cone_limit}
