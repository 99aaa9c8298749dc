"""Contact against MuJoCo at matched accuracy (issue 25): the CPU time each engine needs for
the same error on two scenes, each side swept honestly over its settings (measured
figures, not tests).

1. ball_drop: the 5 cm, 45.8 g sphere dropped from 1 m onto a plane with restitution
   e = 0.8. Error: the first hop's apex against e^2 H0 = 0.64 m, in % (apex = max of
   z + vz^2 / 2g over the rising samples). Ours: the constraint stepper (PGS, ADMM) at
   steps from 10 ms down, Hunt-Crossley (k = 1e7) with rk45 at several tolerances. MuJoCo:
   soft contact with the direct solref = (-k, -b) of a linear spring-damper whose
   restitution is e (zeta = -ln e / sqrt(pi^2 + ln^2 e), k = omega^2, b = 2 zeta omega,
   solimp 0.99; MuJoCo's default time-constant form with dampratio = zeta bounces far
   lower, about 0.07 m), the contact lasting T = pi / omega, swept free (BALL_CONTACT_TIMES)
   beside the step, with Euler, implicitfast and RK4.
2. grasp: the same sphere squeezed under gravity (-z) between two 50 g pads (boxes 5 x 30
   x 40 mm) on prismatic joints along x (config/scenes/grasp.yaml; MuJoCo: slide joints),
   each pushed by a PD servo (kp = 1500 N/m, kd = 17 N s/m; ours the scene's pd
   controller, MuJoCo a position actuator with the same kp, kv) towards 1 mm into the
   sphere: 1.5 N per pad, friction 0.3, so the pads hold 2 mu F = 0.9 N against the
   sphere's 0.449 N weight (margin 2): the exact motion is at rest. Error: the sphere's
   slip |z(1 s) - z(0.25 s)| (m), after the squeeze has built up. Ours: the constraint
   stepper with PGS and with ADMM at several steps (and, not in --quick, Hunt-Crossley with
   rk45, whose regularised Coulomb friction creeps by design). MuJoCo: solref = (T, 1)
   with the time constant T swept free (GRASP_TIME_CONSTANTS, and 2 dt, its stiffest
   stable contact) beside the step, default solimp, pyramidal cone, Euler, implicitfast
   and RK4, and Euler with noslip_iterations = 10.

Both engines sample the state at OUTPUT_RATE (ours: the scene's outputs; MuJoCo:
``mj_step(..., nstep)`` between samples), the models built beforehand. Cost: CPU time of
the process (``time.process_time``), the best of two runs per setting (wall time beside
it). Matched accuracy (:func:`matched`): each engine's cheapest setting with |error| <=
the TARGETS error, no interpolation; then those two settings timed again, alternating in
this process, best of MATCH_REPEAT: ratio = ours / MuJoCo's CPU time; goal (issue 25) <= 1.
How stable the choice is (:func:`stability`): the errors at the neighbouring steps (and,
for MuJoCo, contact times) of the chosen setting, and the cheapest setting from which
every finer step of its family holds the error too (:func:`robust_choice`).

Run: python bench/bench_contact_mujoco.py [--quick]     (needs ``pip install mujoco``;
BENCH_SMOKE=1: one coarse setting per family, as test/bench runs it)
"""
from __future__ import annotations

import argparse
import math
import sys
from dataclasses import dataclass, field
from pathlib import Path
from types import ModuleType
from typing import Any, Callable

import numpy as np
import yaml

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # run from a source checkout
sys.path.insert(0, str(Path(__file__).resolve().parent))

from timing import Timing, load_average, sized, smoke, timed  # noqa: E402
from youbot_dynamics.accuracy.contact_extremes import ball_drop_data  # noqa: E402
from youbot_dynamics.integrate.integrators import DivergenceError  # noqa: E402
from youbot_dynamics.scene.schema import Scene, scene_dir  # noqa: E402
from youbot_dynamics.sim.simulator import Simulator  # noqa: E402

E, H0, RADIUS, G = 0.8, 1.0, 0.025, 9.81
MASS = 700 * 4 / 3 * math.pi * RADIUS ** 3  # kg, the scenes' wooden sphere
FRICTION = 0.3
OUTPUT_RATE = 100.0  # Hz, both engines
BALL_DURATION = 1.1  # s: one impact, the first hop's apex
#: the steps swept (s; each divides the 10 ms between samples) and MuJoCo's contact times (s)
STEPS = (1e-2, 5e-3, 2.5e-3, 2e-3, 1e-3, 5e-4, 2e-4, 1e-4)
QUICK_STEPS = STEPS[:-1]
BALL_CONTACT_TIMES = (1e-3, 2e-3, 5e-3, 1e-2, 2e-2)
GRASP_TIME_CONSTANTS = (2e-3, 5e-3, 1e-2, 2e-2)
#: grasp (as in config/scenes/grasp.yaml, for the MJCF): pad PD gains (N/m, N s/m), squeeze depth
#: (m), pad thickness (m), run and slip window (s)
KP, KD, SQUEEZE, PAD = 1500.0, 17.0, 1e-3, 0.005
GRASP_DURATION, SLIP_FROM = 1.0, 0.25
#: the error each engine must reach: apex error (%) and slip (m)
TARGETS = {"ball_drop": 1.0, "grasp": 1e-4}
UNITS = {"ball_drop": "% apex error", "grasp": "m slip"}
SWEEP_REPEAT, MATCH_REPEAT = 2, 7


@dataclass(frozen=True)
class Run:
    """One setting's run: engine (ours | MuJoCo), family (method and contact setting), step
    (s; a tolerance for adaptive methods), error, CPU and wall time (s, best of its runs);
    ``again()`` times one more run."""

    engine: str
    family: str
    step: float
    error: float
    cost: Timing
    again: Callable[[], Timing] | None = field(default=None, compare=False, repr=False)

    @property
    def setting(self) -> str:
        name = "rtol" if "rk45" in self.family else "dt"
        return f"{self.family}, {name}={self.step:g}"


def mujoco_module() -> ModuleType | None:
    """MuJoCo's Python module, or None when it is not installed."""
    try:
        import mujoco
    except ImportError:
        return None
    return mujoco


def best_cost(again: Callable[[], Timing], repeat: int) -> Timing:
    """Best CPU and best wall time of ``repeat`` calls of ``again``."""
    costs = [again() for _ in range(repeat)]
    return Timing(min(c.cpu for c in costs), min(c.wall for c in costs))


def our_run(family: str, step: float, data: dict[str, Any], error: Callable[[Simulator, Any], float],
            repeat: int = SWEEP_REPEAT) -> Run:
    """The scene mapping built, then run ``repeat`` times; ``error(simulator, result)``. A run
    that diverges has an infinite error (and no cost)."""
    simulator = Simulator(Scene.from_dict(data, "bench"))
    try:
        result, cost = timed(simulator.run)
    except DivergenceError:
        return Run("ours", family, step, math.inf, Timing(math.nan, math.nan))

    def again() -> Timing:
        return timed(simulator.run)[1]

    cost = best_cost(again, repeat - 1) if repeat > 1 else cost
    return Run("ours", family, step, error(simulator, result), cost, again)


def mujoco_run(mujoco: ModuleType, family: str, step: float, model, data, duration: float, addresses: list[int],
               error: Callable[[np.ndarray], float], repeat: int = SWEEP_REPEAT) -> Run:
    """qpos/qvel entries (``addresses`` index [qpos | qvel]) sampled at OUTPUT_RATE over
    ``duration`` s from ``data``'s state, ``error(samples)``, the stepping timed ``repeat``
    times. A run that leaves finite numbers has an infinite error."""
    nstep = int(round(1.0 / (OUTPUT_RATE * model.opt.timestep)))
    samples = np.empty((int(round(duration * OUTPUT_RATE)), len(addresses)))
    start_state = mujoco.MjData(model)
    mujoco.mj_copyData(start_state, model, data)

    def stepping() -> None:
        mujoco.mj_copyData(data, model, start_state)
        for i in range(len(samples)):
            mujoco.mj_step(model, data, nstep=nstep)
            samples[i] = np.concatenate([data.qpos, data.qvel])[addresses]

    def again() -> Timing:
        return timed(stepping)[1]

    cost = best_cost(again, repeat)
    value = error(samples) if np.all(np.isfinite(samples)) else math.inf
    return Run("MuJoCo", family, step, value if math.isfinite(value) else math.inf, cost, again)


# ---- 1. ball_drop -------------------------------------------------------------------------
def rising_apex(z: np.ndarray, vz: np.ndarray) -> float:
    """Apex (m) of the hop after the one impact: max of z + vz^2 / 2g where vz > 0."""
    rising = vz > 0
    return float(np.max((z + vz ** 2 / (2 * G))[rising])) if np.any(rising) else 0.0


def apex_error(apex: float) -> float:
    """Apex error against e^2 H0, %."""
    return 100.0 * (apex / (E * E * H0) - 1.0)


def ball_drop_apex_error(simulator: Simulator, result) -> float:
    motion = simulator.model.body_motion(result.x)
    return apex_error(rising_apex(motion["position"][:, 0, 2] - RADIUS, motion["velocity"][:, 0, 2]))


def ball_drop_ours(quick: bool) -> list[Run]:
    constraint = {"law": "constraint", "restitution": E, "friction": FRICTION}
    hunt = {"law": "hunt_crossley", "stiffness": 1e7, "restitution": E, "friction": FRICTION}
    steps = sized(QUICK_STEPS if quick else STEPS, (5e-3,))
    cases = [(constraint, {"method": method, "dt": dt}, dt) for method in ("pgs", "admm") for dt in steps]
    cases += [(hunt, {"method": "rk45", "rtol": rtol, "atol": rtol * 1e-2}, rtol)
              for rtol in sized((1e-5, 1e-6) if quick else (1e-4, 1e-5, 1e-6, 1e-8), ())]
    runs = []
    for law, integrator, step in cases:
        data = ball_drop_data(law, integrator, BALL_DURATION)
        data["outputs"] = {**data["outputs"], "rate": OUTPUT_RATE, "record": ["q", "v"]}  # as MuJoCo: no energy
        runs.append(our_run(f"{law['law']} {integrator['method']}", step, data, ball_drop_apex_error))
    return runs


BALL_MJCF = """<mujoco><option timestep="{dt}" integrator="{integrator}"/>
<worldbody><geom name="floor" type="plane" size="5 5 0.1"/>
<body name="ball" pos="0 0 {z0}"><freejoint/>
<geom type="sphere" size="{r}" mass="{mass}" solref="{k} {b}" solimp="0.99 0.99 0.001" friction="{mu} 0.005 0.0001"/>
</body></worldbody></mujoco>"""


def ball_drop_mujoco(mujoco: ModuleType, quick: bool) -> list[Run]:
    """MuJoCo's ball_drop over every integrator, step and contact time (at least one step
    long)."""
    zeta = -math.log(E) / math.sqrt(math.pi ** 2 + math.log(E) ** 2)
    steps = sized(QUICK_STEPS if quick else STEPS, (5e-3,))
    runs = []
    for integrator in sized(("Euler", "implicitfast", "RK4"), ("Euler",)):
        for contact in sized(BALL_CONTACT_TIMES, (1e-2,)):
            for dt in (dt for dt in steps if dt <= contact):
                omega = math.pi / contact
                model = mujoco.MjModel.from_xml_string(BALL_MJCF.format(
                    dt=dt, integrator=integrator, z0=H0 + RADIUS, r=RADIUS, mass=MASS, k=-omega * omega,
                    b=-2 * zeta * omega, mu=FRICTION))
                runs.append(mujoco_run(
                    mujoco, f"{integrator} contact {1e3 * contact:g} ms", dt, model, mujoco.MjData(model),
                    BALL_DURATION, [2, model.nq + 2],
                    lambda s: apex_error(rising_apex(s[:, 0] - RADIUS, s[:, 1]))))
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
    steps = sized((5e-3, 2e-3, 1e-3, 5e-4) + (() if quick else (2.5e-4, 1e-4)), (5e-3,))
    cases = [(constraint, {"method": method, "dt": dt}, dt) for method in ("pgs", "admm") for dt in steps]
    if not quick and not smoke():  # about 10 s per run: a stiff regularised friction for rk45
        hunt = {"law": "hunt_crossley", "stiffness": 1e7, "restitution": 0.5, "friction": FRICTION,
                "velocity_scale": 1e-3}
        cases += [(hunt, {"method": "rk45", "rtol": rtol, "atol": rtol * 1e-2}, rtol) for rtol in (1e-3, 1e-5)]
    return [our_run(f"{law['law']} {integrator['method']}", step, grasp_data(law, integrator), grasp_slip,
                    repeat=SWEEP_REPEAT if law is constraint else 1)
            for law, integrator, step in cases]


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
    """MuJoCo's grasp over every integrator, step and time constant (2 dt and each of
    GRASP_TIME_CONSTANTS not below it: MuJoCo clamps it to 2 dt)."""
    runs = []
    steps = sized((5e-3, 2e-3, 1e-3, 5e-4, 2e-4) + (() if quick else (1e-4,)), (5e-3,))
    methods = sized((("Euler", 0), ("implicitfast", 0), ("RK4", 0), ("Euler", 10)), (("Euler", 0),))
    for integrator, noslip in methods:
        for dt in steps:
            for timeconst in sorted({2 * dt, *(t for t in sized(GRASP_TIME_CONSTANTS, ()) if t > 2 * dt)}):
                model = mujoco.MjModel.from_xml_string(GRASP_MJCF.format(
                    dt=dt, integrator=integrator, noslip=noslip, mu=FRICTION, timeconst=timeconst, hx=PAD / 2,
                    xl=-RADIUS - PAD / 2, xr=RADIUS + PAD / 2, r=RADIUS, mass=MASS, kp=KP, kd=KD))
                data = mujoco.MjData(model)
                data.ctrl[:] = SQUEEZE
                sphere_z = model.jnt_qposadr[model.body("sphere").jntadr[0]] + 2
                t = np.arange(1, int(round(GRASP_DURATION * OUTPUT_RATE)) + 1) / OUTPUT_RATE
                contact = "2 dt" if timeconst == 2 * dt else f"{1e3 * timeconst:g} ms"
                method = integrator + (f" noslip {noslip}" if noslip else "") + f" solref {contact}"
                runs.append(mujoco_run(mujoco, method, dt, model, data, GRASP_DURATION, [sphere_z],
                                       lambda z: slip(t, z[:, 0])))
    return runs


# ---- matched accuracy ---------------------------------------------------------------------
def holds(run: Run, target: float) -> bool:
    return math.isfinite(run.error) and abs(run.error) <= target


def cheapest(runs: list[Run], target: float) -> Run | None:
    """The run of least CPU time with |error| <= target (None when none holds it)."""
    good = [r for r in runs if holds(r, target)]
    return min(good, key=lambda r: r.cost.cpu) if good else None


def robust_choice(runs: list[Run], target: float) -> Run | None:
    """The cheapest run whose error holds ``target`` and so does every finer step of its
    family (at least one: the finest step swept proves nothing): a choice that the next
    smaller step cannot undo."""
    def finer(r: Run) -> list[Run]:
        return [o for o in runs if o.family == r.family and o.step < r.step]

    good = [r for r in runs if holds(r, target) and finer(r) and all(holds(o, target) for o in finer(r))]
    return min(good, key=lambda r: r.cost.cpu) if good else None


def stability(runs: list[Run], chosen: Run, target: float) -> str:
    """The chosen run's error beside its family's neighbouring steps' (and, where the family
    names a contact setting, the same step's other contact settings), and how many hold."""
    family = sorted((r for r in runs if r.family == chosen.family), key=lambda r: r.step)
    k = family.index(chosen)
    neighbours = family[max(0, k - 1):k] + family[k + 1:k + 2]
    method = chosen.family.split(" contact")[0].split(" solref")[0]
    neighbours += [r for r in runs if r.step == chosen.step and r.family != chosen.family
                   and r.family.startswith(method + " ") and r.engine == chosen.engine]
    cells = ", ".join(f"{r.setting}: {r.error:+.3g}" for r in neighbours)
    held = sum(holds(r, target) for r in neighbours)
    return f"{chosen.setting}: {chosen.error:+.3g}; neighbours {cells or 'none'} ({held} of {len(neighbours)} hold)"


def matched(runs: list[Run], target: float, repeat: int = MATCH_REPEAT, robust: bool = False) -> dict[str, Any]:
    """Each engine's cheapest setting holding ``target`` (``robust``: :func:`robust_choice`),
    then both timed again alternating, best of ``repeat``: CPU and wall seconds and the CPU
    ratio ours / MuJoCo's (None where an engine misses the target)."""
    choose = robust_choice if robust else cheapest
    ours = choose([r for r in runs if r.engine == "ours"], target)
    theirs = choose([r for r in runs if r.engine == "MuJoCo"], target)
    result: dict[str, Any] = {"target": target, "ours": ours, "mujoco": theirs, "ours_cost": None,
                              "mujoco_cost": None, "ratio": None}
    chosen = [r for r in (ours, theirs) if r is not None]
    best = [r.cost for r in chosen]
    for _ in range(repeat):
        for i, run in enumerate(chosen):
            again = run.again()
            best[i] = Timing(min(best[i].cpu, again.cpu), min(best[i].wall, again.wall))
    costs = dict(zip([r.engine for r in chosen], best))
    result["ours_cost"], result["mujoco_cost"] = costs.get("ours"), costs.get("MuJoCo")
    if ours is not None and theirs is not None:
        result["ratio"] = costs["ours"].cpu / costs["MuJoCo"].cpu
    return result


def comparisons(quick: bool) -> tuple[dict[str, list[Run]], str | None]:
    """Every run of both scenes, and MuJoCo's version (None when it is not installed: then
    only our runs)."""
    mujoco = mujoco_module()
    warm_up = ball_drop_data({"law": "constraint", "restitution": E, "friction": FRICTION},
                             {"method": "pgs", "dt": 5e-3}, BALL_DURATION)
    our_run("", 0.0, warm_up, ball_drop_apex_error, repeat=1)  # imports and first builds, not timed below
    runs = {"ball_drop": ball_drop_ours(quick), "grasp": grasp_ours(quick)}
    if mujoco is not None:
        runs["ball_drop"] += ball_drop_mujoco(mujoco, quick)
        runs["grasp"] += grasp_mujoco(mujoco, quick)
    return runs, None if mujoco is None else mujoco.__version__


def table(scene: str, runs: list[Run]) -> str:
    lines = [f"| engine | setting | {UNITS[scene]} | CPU ms | wall ms |", "|---|---|---|---|---|"]
    for r in runs:
        if math.isinf(r.error):
            lines.append(f"| {r.engine} | {r.setting} | diverged | - | - |")
            continue
        error = f"{r.error:+.3f}" if scene == "ball_drop" else f"{r.error:.3g}"
        lines.append(f"| {r.engine} | {r.setting} | {error} | {1e3 * r.cost.cpu:.2f} | {1e3 * r.cost.wall:.2f} |")
    return "\n".join(lines)


def summary_line(runs: list[Run], result: dict[str, Any]) -> str:
    def side(run: Run | None, cost: Timing | None) -> str:
        return "not reached" if run is None else f"{1e3 * cost.cpu:.2f} ms CPU ({run.setting})"

    ratio = "-" if result["ratio"] is None else f"{result['ratio']:.2f}x"
    lines = [f"at {result['target']:g}: ours {side(result['ours'], result['ours_cost'])}, MuJoCo "
             f"{side(result['mujoco'], result['mujoco_cost'])}, ratio {ratio} (goal <= 1x)"]
    lines += [f"  stability, {r.engine}: {stability(runs, r, result['target'])}"
              for r in (result["ours"], result["mujoco"]) if r is not None]
    return "\n".join(lines)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="fewer steps and tolerances (as bench/summary.py)")
    args = parser.parse_args()
    runs, version = comparisons(args.quick)
    print(f"load average {load_average()}")
    if version is None:
        print("MuJoCo not installed: pip install -r requirements-bench.txt (our runs only)\n")
    for scene, title in (("ball_drop", f"ball_drop: first apex against e^2 H0 = {E * E * H0:.2f} m"),
                         ("grasp", f"grasp: the sphere's slip over {SLIP_FROM:g}-{GRASP_DURATION:g} s (exact: 0)")):
        print(f"## {title}" + (f" (MuJoCo {version})" if version else "") + "\n")
        print(table(scene, runs[scene]))
        print("\nMatched accuracy, cheapest setting (the summary's target first, then others):")
        for factor in sized((1.0, 0.5, 2.0), (1.0,)):
            print(f"- {summary_line(runs[scene], matched(runs[scene], factor * TARGETS[scene]))}")
        print("Cheapest setting whose finer steps all hold the target:")
        print(f"- {summary_line(runs[scene], matched(runs[scene], TARGETS[scene], robust=True))}\n")
    print(f"load average {load_average()}")


if __name__ == "__main__":
    main()
