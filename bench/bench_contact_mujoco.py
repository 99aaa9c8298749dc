"""Contact against MuJoCo at equal accuracy (issue 14, item 2): wall time of each engine at
the step it needs for the same error, on two scenes (measured figures, not tests).

1. ball_drop: the 5 cm, 45.8 g sphere dropped from 1 m onto a plane with restitution
   e = 0.8. Error: the first hop's apex against e^2 H0 = 0.64 m, in % (apex = max of
   z + vz^2 / 2g over the rising samples). Ours: the constraint stepper (PGS, ADMM) at
   several steps, Hunt-Crossley (k = 1e7) with rk45 at several tolerances. MuJoCo: soft
   contact with the direct solref = (-k, -b) of a linear spring-damper whose restitution is
   e (zeta = -ln e / sqrt(pi^2 + ln^2 e), k = omega^2, b = 2 zeta omega, solimp 0.99;
   MuJoCo's default time-constant form with dampratio = zeta bounces far lower, about
   0.07 m), the contact lasting CONTACT_STEPS steps (omega = pi / (10 dt): its error does
   not shrink with dt) or CONTACT_TIME (omega = pi / 2 ms: it levels off at +1 to +2 % as
   dt shrinks), Euler, implicitfast and RK4 at several dt.
2. grasp: the same sphere squeezed under gravity (-z) between two 50 g pads (boxes 5 x 30
   x 40 mm) on prismatic joints along x (config/scenes/grasp.yaml; MuJoCo: slide joints),
   each pushed by a PD servo (kp = 1500 N/m, kd = 17 N s/m; ours the scene's pd
   controller, MuJoCo a position actuator with the same kp, kv) towards 1 mm into the
   sphere: 1.5 N per pad, friction 0.3, so the pads hold 2 mu F = 0.9 N against the
   sphere's 0.449 N weight (margin 2): the exact motion is at rest. Error: the sphere's
   slip |z(1 s) - z(0.25 s)| (m), after the squeeze has built up. Ours: the constraint
   stepper with PGS and with ADMM at several steps (and, not in --quick, Hunt-Crossley with
   rk45, whose regularised Coulomb friction creeps by design). MuJoCo: solref = (2 dt, 1) (its
   stiffest stable contact, so its creep shrinks with dt like our error), default solimp,
   pyramidal cone, Euler, implicitfast and RK4, and Euler with noslip_iterations = 10.

Both engines sample the state at OUTPUT_RATE (ours: the scene's outputs; MuJoCo:
``mj_step(..., nstep)`` between samples). Wall time: the best of two runs (ours on the
grasp with Hunt-Crossley and rk45, about 10 s a run: one run), the model built beforehand.
Equal accuracy: for each engine, the least wall time at which some of its methods reaches
the TARGETS error (:func:`wall_at_error`: log-log interpolation between the cheapest run
that meets the target and the next cheaper run of the same method, if their errors have the
same sign); ratio = ours / MuJoCo's; goal (issue 14) <= 3.

Run: python bench/bench_contact_mujoco.py [--quick]     (needs ``pip install mujoco``)
"""
from __future__ import annotations

import argparse
import math
import sys
import time
from dataclasses import dataclass
from pathlib import Path
from types import ModuleType
from typing import Any, Callable

import numpy as np
import yaml

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # run from a source checkout

from youbot_dynamics.accuracy.contact_extremes import ball_drop_data  # noqa: E402
from youbot_dynamics.integrate.integrators import DivergenceError  # noqa: E402
from youbot_dynamics.scene.schema import Scene, scene_dir  # noqa: E402
from youbot_dynamics.sim.simulator import Simulator  # noqa: E402

E, H0, RADIUS, G = 0.8, 1.0, 0.025, 9.81
MASS = 700 * 4 / 3 * math.pi * RADIUS ** 3  # kg, the scenes' wooden sphere
FRICTION = 0.3
#: MuJoCo's ball_drop contact: lasting this many steps, or this long (s)
CONTACT_STEPS, CONTACT_TIME = 10, 2e-3
OUTPUT_RATE = 100.0  # Hz, both engines
#: grasp (as in config/scenes/grasp.yaml, for the MJCF): pad PD gains (N/m, N s/m), squeeze depth
#: (m), pad thickness (m), run and slip window (s)
KP, KD, SQUEEZE, PAD = 1500.0, 17.0, 1e-3, 0.005
GRASP_DURATION, SLIP_FROM = 1.0, 0.25
#: the error each engine must reach: apex error (%) and slip (m)
TARGETS = {"ball_drop": 1.0, "grasp": 1e-4}
UNITS = {"ball_drop": "% apex error", "grasp": "m slip"}


@dataclass(frozen=True)
class Run:
    """One run: engine (ours | MuJoCo), method, step or tolerance, error, wall time (s)."""

    engine: str
    method: str
    setting: str
    error: float
    wall: float


def mujoco_module() -> ModuleType | None:
    """MuJoCo's Python module, or None when it is not installed."""
    try:
        import mujoco
    except ImportError:
        return None
    return mujoco


def our_run(method: str, setting: str, data: dict[str, Any], error: Callable[[Simulator, Any], float],
            repeat: int = 1) -> Run:
    """The scene mapping built, then run ``repeat`` times (the best wall time, s, is kept);
    ``error(simulator, result)``. A run that diverges has an infinite error (no wall time)."""
    simulator = Simulator(Scene.from_dict(data, "bench"))
    wall = math.inf
    for _ in range(repeat):
        start = time.perf_counter()
        try:
            result = simulator.run()
        except DivergenceError:
            return Run("ours", method, setting, math.inf, math.nan)
        wall = min(wall, time.perf_counter() - start)
    return Run("ours", method, setting, error(simulator, result), wall)


# ---- 1. ball_drop -------------------------------------------------------------------------
def rising_apex(z: np.ndarray, vz: np.ndarray) -> float:
    """Apex (m) of the hop after the one impact: max of z + vz^2 / 2g where vz > 0."""
    return float(np.max((z + vz ** 2 / (2 * G))[vz > 0]))


def apex_error(apex: float) -> float:
    """Apex error against e^2 H0, %."""
    return 100.0 * (apex / (E * E * H0) - 1.0)


def ball_drop_apex_error(simulator: Simulator, result) -> float:
    motion = simulator.model.body_motion(result.x)
    return apex_error(rising_apex(motion["position"][:, 0, 2] - RADIUS, motion["velocity"][:, 0, 2]))


def ball_drop_ours(quick: bool) -> list[Run]:
    runs = []
    laws = {"constraint": {"law": "constraint", "restitution": E, "friction": FRICTION},
            "hunt_crossley": {"law": "hunt_crossley", "stiffness": 1e7, "restitution": E, "friction": FRICTION}}
    cases = [("constraint", {"method": "pgs", "dt": dt}, f"dt={dt:g}")
             for dt in ((2e-3, 1e-3, 5e-4) if quick else (2e-3, 1e-3, 5e-4, 2e-4, 1e-4))]
    cases += [("constraint", {"method": "admm", "dt": dt}, f"dt={dt:g}") for dt in (2e-3,) + (() if quick else (1e-3,))]
    cases += [("hunt_crossley", {"method": "rk45", "rtol": rtol, "atol": rtol * 1e-2}, f"rtol={rtol:g}")
              for rtol in ((1e-5, 1e-6) if quick else (1e-5, 1e-6, 1e-8))]
    for law, integrator, setting in cases:
        data = ball_drop_data(laws[law], integrator, 1.1)
        data["outputs"] = {**data["outputs"], "rate": OUTPUT_RATE}
        runs.append(our_run(f"{law} {integrator['method']}", setting, data, ball_drop_apex_error, repeat=2))
    return runs


BALL_MJCF = """<mujoco><option timestep="{dt}" integrator="{integrator}"/>
<worldbody><geom name="floor" type="plane" size="5 5 0.1"/>
<body name="ball" pos="0 0 {z0}"><freejoint/>
<geom type="sphere" size="{r}" mass="{mass}" solref="{k} {b}" solimp="0.99 0.99 0.001" friction="{mu} 0.005 0.0001"/>
</body></worldbody></mujoco>"""


def mujoco_samples(mujoco: ModuleType, model, data, duration: float, addresses: list[int],
                   repeat: int = 2) -> tuple[np.ndarray, float]:
    """qpos/qvel entries (``addresses`` index [qpos | qvel]) at OUTPUT_RATE over ``duration`` s
    from ``data``'s state, and the best wall time (s) of the stepping over ``repeat`` runs."""
    nstep = int(round(1.0 / (OUTPUT_RATE * model.opt.timestep)))
    samples = np.empty((int(round(duration * OUTPUT_RATE)), len(addresses)))
    start_state = mujoco.MjData(model)
    mujoco.mj_copyData(start_state, model, data)
    wall = math.inf
    for _ in range(repeat):
        mujoco.mj_copyData(data, model, start_state)
        start = time.perf_counter()
        for i in range(len(samples)):
            mujoco.mj_step(model, data, nstep=nstep)
            samples[i] = np.concatenate([data.qpos, data.qvel])[addresses]
        wall = min(wall, time.perf_counter() - start)
    return samples, wall


def ball_drop_mujoco(mujoco: ModuleType, quick: bool) -> list[Run]:
    """MuJoCo's ball_drop with the contact lasting CONTACT_STEPS steps (its stiffness tied to
    dt) or CONTACT_TIME s (fixed, so that the error converges as dt shrinks)."""
    zeta = -math.log(E) / math.sqrt(math.pi ** 2 + math.log(E) ** 2)
    sweeps = {f"contact {CONTACT_STEPS} steps": (2e-3, 1e-3, 5e-4, 2e-4) + (() if quick else (1e-4,)),
              f"contact {1e3 * CONTACT_TIME:g} ms": (2e-4, 1e-4) + (() if quick else (5e-5,))}
    runs = []
    for integrator in ("Euler", "implicitfast", "RK4"):
        for contact, steps in sweeps.items():
            for dt in steps:
                omega = math.pi / (CONTACT_STEPS * dt if "steps" in contact else CONTACT_TIME)
                model = mujoco.MjModel.from_xml_string(BALL_MJCF.format(
                    dt=dt, integrator=integrator, z0=H0 + RADIUS, r=RADIUS, mass=MASS, k=-omega * omega,
                    b=-2 * zeta * omega, mu=FRICTION))
                samples, wall = mujoco_samples(mujoco, model, mujoco.MjData(model), 1.1, [2, model.nq + 2])
                apex = rising_apex(samples[:, 0] - RADIUS, samples[:, 1])
                runs.append(Run("MuJoCo", f"{integrator} {contact}", f"dt={dt:g}", apex_error(apex), wall))
    return runs


# ---- 2. grasp -----------------------------------------------------------------------------
def grasp_data(law: dict[str, Any], integrator: dict[str, Any]) -> dict[str, Any]:
    """The packaged grasp scene (config/scenes/grasp.yaml) with this contact law on both
    pairs and this integrator."""
    data = yaml.safe_load((scene_dir() / "grasp.yaml").read_text())
    data["robot"] = str(scene_dir() / data["robot"])
    data["contacts"] = [{"pair": c["pair"], **law} for c in data["contacts"]]
    data["integrator"] = integrator
    return data


def slip(t: np.ndarray, z: np.ndarray) -> float:
    """|z(end) - z(SLIP_FROM)| (m): the sphere's slip once the squeeze has built up."""
    return float(abs(z[-1] - z[int(np.searchsorted(t, SLIP_FROM - 1e-9))]))


def grasp_slip(simulator: Simulator, result) -> float:
    return slip(result.t, simulator.model.body_motion(result.x)["position"][:, 0, 2])


def grasp_ours(quick: bool) -> list[Run]:
    constraint = {"law": "constraint", "restitution": 0.0, "friction": FRICTION}
    steps = {"pgs": (2e-3, 1e-3, 5e-4) + (() if quick else (2.5e-4, 1e-4)),
             "admm": (5e-3, 2e-3) + (() if quick else (1e-3,))}
    cases = [(constraint, {"method": method, "dt": dt}, f"dt={dt:g}") for method in steps for dt in steps[method]]
    if not quick:  # about 10 s per run: a stiff regularised friction for rk45
        hunt = {"law": "hunt_crossley", "stiffness": 1e7, "restitution": 0.5, "friction": FRICTION,
                "velocity_scale": 1e-3}
        cases += [(hunt, {"method": "rk45", "rtol": rtol, "atol": rtol * 1e-2}, f"rtol={rtol:g}")
                  for rtol in (1e-3, 1e-5)]
    return [our_run(f"{law['law']} {integrator['method']}", setting, grasp_data(law, integrator), grasp_slip,
                    repeat=2 if law is constraint else 1)
            for law, integrator, setting in cases]


GRASP_MJCF = """<mujoco><option timestep="{dt}" integrator="{integrator}" noslip_iterations="{noslip}"/>
<default><geom friction="{mu} 0.005 0.0001" solref="{timeconst} 1"/></default>
<worldbody>
<body name="pad_l"><joint name="pad_l" type="slide" axis="1 0 0"/>
<geom type="box" size="{hx} 0.015 0.02" pos="{xl} 0 0" mass="0.05"/></body>
<body name="pad_r"><joint name="pad_r" type="slide" axis="-1 0 0"/>
<geom type="box" size="{hx} 0.015 0.02" pos="{xr} 0 0" mass="0.05"/></body>
<body name="sphere"><freejoint/><geom type="sphere" size="{r}" mass="{mass}"/></body>
</worldbody>
<contact><exclude body1="pad_l" body2="pad_r"/></contact>
<actuator><position joint="pad_l" kp="{kp}" kv="{kd}"/><position joint="pad_r" kp="{kp}" kv="{kd}"/></actuator>
</mujoco>"""


def grasp_mujoco(mujoco: ModuleType, quick: bool) -> list[Run]:
    runs = []
    steps = (2e-3, 1e-3, 5e-4, 2e-4) if quick else (2e-3, 1e-3, 5e-4, 2e-4, 1e-4)
    for integrator, noslip in (("Euler", 0), ("implicitfast", 0), ("RK4", 0), ("Euler", 10)):
        for dt in steps:
            model = mujoco.MjModel.from_xml_string(GRASP_MJCF.format(
                dt=dt, integrator=integrator, noslip=noslip, mu=FRICTION, timeconst=2 * dt, hx=PAD / 2,
                xl=-RADIUS - PAD / 2, xr=RADIUS + PAD / 2, r=RADIUS, mass=MASS, kp=KP, kd=KD))
            data = mujoco.MjData(model)
            data.ctrl[:] = SQUEEZE
            sphere_z = model.jnt_qposadr[model.body("sphere").jntadr[0]] + 2
            z, wall = mujoco_samples(mujoco, model, data, GRASP_DURATION, [sphere_z])
            t = np.arange(1, len(z) + 1) / OUTPUT_RATE
            method = integrator + (f" noslip {noslip}" if noslip else "")
            runs.append(Run("MuJoCo", method, f"dt={dt:g}", slip(t, z[:, 0]), wall))
    return runs


# ---- equal accuracy -----------------------------------------------------------------------
def wall_at_error(runs: list[Run], target: float) -> float | None:
    """Least wall time (s) at which one of the runs' methods reaches |error| <= target: per
    method, the cheapest run meeting it, moved by log-log interpolation towards the next
    cheaper run of that method when that one misses with an error of the same sign; None
    when no run reaches the target. Diverged runs (infinite error) are left out."""
    best = None
    for method in dict.fromkeys(r.method for r in runs):
        ordered = sorted((r for r in runs if r.method == method and math.isfinite(r.error)), key=lambda r: r.wall)
        for k, run in enumerate(ordered):
            if abs(run.error) > target:
                continue
            wall = run.wall
            if k > 0 and run.error != 0.0 and ordered[k - 1].error * run.error > 0:
                low = ordered[k - 1]
                x = math.log(target / abs(low.error)) / math.log(run.error / low.error)
                wall = low.wall * (run.wall / low.wall) ** x
            best = wall if best is None else min(best, wall)
            break
    return best


def equal_accuracy(scene: str, runs: list[Run], target: float | None = None) -> dict[str, Any]:
    """ours / MuJoCo wall time at ``target`` (default the scene's TARGETS error; None where
    an engine misses it)."""
    target = TARGETS[scene] if target is None else target
    ours = wall_at_error([r for r in runs if r.engine == "ours"], target)
    theirs = wall_at_error([r for r in runs if r.engine == "MuJoCo"], target)
    ratio = None if ours is None or theirs is None else ours / theirs
    return {"scene": scene, "target": target, "unit": UNITS[scene], "ours_s": ours, "mujoco_s": theirs,
            "ratio": ratio}


def comparisons(quick: bool) -> tuple[dict[str, list[Run]], str | None]:
    """Every run of both scenes, and MuJoCo's version (None when it is not installed: then
    only our runs)."""
    mujoco = mujoco_module()
    warm_up = ball_drop_data({"law": "constraint", "restitution": E, "friction": FRICTION},
                             {"method": "pgs", "dt": 2e-3}, 1.1)
    our_run("", "", warm_up, ball_drop_apex_error)  # imports and first builds, not timed below
    runs = {"ball_drop": ball_drop_ours(quick), "grasp": grasp_ours(quick)}
    if mujoco is not None:
        runs["ball_drop"] += ball_drop_mujoco(mujoco, quick)
        runs["grasp"] += grasp_mujoco(mujoco, quick)
    return runs, None if mujoco is None else mujoco.__version__


def table(scene: str, runs: list[Run]) -> str:
    lines = [f"| engine | method | step / tolerance | {UNITS[scene]} | wall s |", "|---|---|---|---|---|"]
    for r in runs:
        error = "diverged" if math.isinf(r.error) else f"{r.error:+.3f}" if scene == "ball_drop" else f"{r.error:.3g}"
        lines.append(f"| {r.engine} | {r.method} | {r.setting} | {error} | {r.wall:.4f} |")
    return "\n".join(lines)


def summary_line(result: dict[str, Any]) -> str:
    def seconds(x: float | None) -> str:
        return "not reached" if x is None else f"{x:.4f} s"

    ratio = "-" if result["ratio"] is None else f"{result['ratio']:.1f}x"
    return (f"at {result['target']:g} {result['unit']}: ours {seconds(result['ours_s'])}, MuJoCo "
            f"{seconds(result['mujoco_s'])}, ratio {ratio} (goal <= 3x)")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="fewer steps and tolerances (as bench/summary.py)")
    args = parser.parse_args()
    runs, version = comparisons(args.quick)
    if version is None:
        print("MuJoCo not installed: pip install -r requirements-bench.txt (our runs only)\n")
    for scene, title in (("ball_drop", f"ball_drop: first apex against e^2 H0 = {E * E * H0:.2f} m"),
                         ("grasp", f"grasp: the sphere's slip over {SLIP_FROM:g}-{GRASP_DURATION:g} s (exact: 0)")):
        print(f"## {title}" + (f" (MuJoCo {version})" if version else "") + "\n")
        print(table(scene, runs[scene]))
        print("\nEqual accuracy (the target of bench/summary.py first, then others for the sensitivity):")
        for factor in (1.0, 0.5, 2.0, 5.0):
            print(f"- {summary_line(equal_accuracy(scene, runs[scene], factor * TARGETS[scene]))}")
        print()


if __name__ == "__main__":
    main()
