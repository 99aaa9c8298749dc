"""The error estimate against the true error on the issue's four cases (the table of
docs/accuracy.md): every registry integrator that runs the case, at three settings, on
arm_swing, the elastic pendulum (k = 1000), ball_drop and gripping, through
:mod:`youbot_dynamics.accuracy.estimate_check`.

Cases: arm_swing over its 2 s; the elastic pendulum from the seed's state over 2 s (about
10 spring periods), reference DOP853 at rtol 1e-13 (its own error bounded by rtol 1e-12);
ball_drop over 1 s (the first impact and apex); gripping over 12 s (the first grasp and the
drop on the table; the constraint steppers only). :data:`FAST` is the test's subset
(test/accuracy/test_error_estimate.py); ``bench/bench_error_estimate.py`` prints either.
"""
from __future__ import annotations

from functools import partial

import numpy as np

from youbot_dynamics.accuracy.estimate_check import CheckRow, ode_rows, reference_run, scene_rows
from youbot_dynamics.integrate.integrators import integrate
from youbot_dynamics.integrate.registry import integrator_names
from youbot_dynamics.scene.schema import load_scene
from youbot_dynamics.studies.elastic_pendulum import SEED_STATE0, elastic_pendulum_jacobian, elastic_pendulum_rhs

TOLERANCES = (1e-5, 1e-7, 1e-9)
ADAPTIVE = integrator_names("ode", adaptive=True)
#: Per case: (scene, duration) or None for the pendulum, and method -> its three settings.
CASES = {
    "arm_swing": (("arm_swing", 2.0), {"euler": (2e-4, 1e-4, 5e-5), "symplectic_euler": (2e-4, 1e-4, 5e-5),
                                       "rk4": (4e-3, 2e-3, 1e-3), "ida": TOLERANCES,
                                       **{m: TOLERANCES for m in ADAPTIVE}}),
    "elastic_pendulum": (None, {"euler": (4e-5, 2e-5, 1e-5), "symplectic_euler": (1e-4, 5e-5, 2.5e-5),
                                "rk4": (4e-3, 2e-3, 1e-3), **{m: TOLERANCES for m in ADAPTIVE}}),
    "ball_drop": (("ball_drop", 1.0), {"euler": (2e-5, 1e-5, 5e-6),
                                       "rk4": (5e-5, 2.5e-5, 1.25e-5), "ida": TOLERANCES,
                                       **{m: TOLERANCES for m in ADAPTIVE}}),
    "gripping": (("gripping", 12.0), {"pgs": (2e-3, 1e-3, 5e-4), "admm": (2e-3, 1e-3, 5e-4)}),
}
#: The test's subset (test/accuracy/test_estimate_check.py runs the same).
FAST = {
    "arm_swing": (("arm_swing", 0.5), {"rk4": (2e-3,), "dop853": (1e-7,), "cvode_bdf": (1e-7,)}),
    "elastic_pendulum": (None, {"rk4": (2e-3,), "rk45": (1e-7,), "radau": (1e-7,)}),
    "ball_drop": (("ball_drop", 0.6), {"rk45": (1e-7,)}),
    "gripping": (("gripping", 0.3), {"pgs": (1e-3,)}),
}
PENDULUM_K, PENDULUM_T = 1000.0, 2.0


def pendulum_rows(methods: dict[str, tuple[float, ...]]) -> list[CheckRow]:
    """The elastic pendulum's rows: positions (x, y; m) and velocities (m/s)."""
    rhs, jac = partial(elastic_pendulum_rhs, k=PENDULUM_K), partial(elastic_pendulum_jacobian, k=PENDULUM_K)
    times = np.linspace(0.0, PENDULUM_T, 201)
    refs = [integrate(rhs, SEED_STATE0, times, "dop853", rtol=rtol, atol=rtol / 100).x for rtol in (1e-13, 1e-12)]
    own = float(np.max(np.abs(refs[0] - refs[1])))
    groups = {"positions": (slice(0, 2), "m"), "rates": (slice(2, 4), "m/s")}
    return [row for method, values in methods.items()
            for row in ode_rows("elastic_pendulum", rhs, np.array(SEED_STATE0), times, method, values, refs[0], own,
                                groups, jac)]


def table(cases: dict) -> list[CheckRow]:
    """Every row of ``cases`` (see CASES)."""
    rows: list[CheckRow] = []
    for scene_case, methods in cases.values():
        if scene_case is None:
            rows += pendulum_rows(methods)
            continue
        scene = load_scene(scene_case[0]).with_duration(scene_case[1])
        reference = reference_run(scene)
        for method, values in methods.items():
            rows += scene_rows(scene, method, values, reference)
    return rows
