"""Document 000's ModiaLang pendulum run as the document runs it, with its statistics log
beside ours.

The document simulates ``Pendulum | Map(L = 0.5u"m")`` with ``Tsit5()``, tolerance 1e-6,
stopTime 10 s, log = true, and prints: 501 results at 0.02 s, 152 accepted and 0 rejected
steps, 913 getDerivatives! calls from the integrator and 1416 in all (:data:`DOCUMENT_LOG`).
Modia hands DifferentialEquations reltol = tolerance and abstol = 0.1 tolerance.

Tsit5 (Tsitouras 5(4)) is a 7-stage explicit Runge-Kutta pair with the first-same-as-last
property: 6 new evaluations per step (152 x 6 + 1 = 913). scipy has no Tsit5; its RK45
(Dormand-Prince 5(4)) is the same kind of pair (7 stages, FSAL, order 5 with an order-4
error estimate), so it is the nearest; DOP853 (order 8, 12 stages) is not. We run RK45 at
rtol 1e-6, atol 1e-7 on the pipeline's generated ODE, 501 outputs on [0, 10] s
(:func:`run_as_document`). The remaining differences are the methods' own: other
coefficients and error estimate, scipy's step control (safety 0.9, factors 0.2-10, its own
first-step guess) against OrdinaryDiffEq's, and Modia calling getDerivatives! once more per
stored result (1416 - 913 = 503) where scipy interpolates its outputs without a call.
"""
from __future__ import annotations

import numpy as np

from youbot_dynamics.integrate.integrators import integrate
from youbot_dynamics.studies.equations import MODIA_MERGE, modia_pendulum
from youbot_dynamics.studies.pipeline import run_pipeline

#: Document 000's statistics log of the L = 0.5 m run (Tsit5, tolerance 1e-6).
DOCUMENT_LOG = {"algorithm": "Tsit5", "tolerance": 1e-6, "interval": 0.02, "nStates": 2,
                "nResults": 501, "nAcceptedSteps": 152, "nRejectedSteps": 0,
                "nf (integrator)": 913, "nGetDerivatives": 1416}
#: Modia's absolute tolerance as a fraction of its (relative) tolerance.
MODIA_ABSTOL_FRACTION = 0.1
#: Our runs beside the document's: (label, integrator, atol) at rtol 1e-6.
DOCUMENT_RUNS = (("RK45, atol 1e-7 (as Modia)", "rk45", 1e-7),
                 ("RK45, atol 1e-9", "rk45", 1e-9),
                 ("DOP853, atol 1e-7", "dop853", 1e-7))


def run_as_document(integrator: str = "rk45", tol: float = 1e-6,
                    atol: float | None = None) -> dict:
    """The L = 0.5 m ModiaLang pendulum through the equation pipeline, integrated with
    ``integrator`` at rtol ``tol`` and atol ``atol`` (default 0.1 tol, as Modia), outputs
    every 0.02 s on [0, 10] s: the statistics in the document's keys and phi (rad) at the
    outputs."""
    result = run_pipeline(modia_pendulum() | MODIA_MERGE)
    ode = result.ode
    times = np.linspace(0.0, 10.0, 501)
    solution = integrate(ode.rhs, ode.x0, times, integrator, rtol=tol,
                         atol=MODIA_ABSTOL_FRACTION * tol if atol is None else atol,
                         state_names=ode.state_names)
    stats = solution.stats
    return {"algorithm": integrator, "tolerance": tol, "interval": float(times[1] - times[0]),
            "nStates": len(ode.state_names), "nResults": len(solution.t),
            "nAcceptedSteps": stats.steps, "nRejectedSteps": stats.rejected_steps,
            "nf (integrator)": stats.rhs_evals, "nGetDerivatives": stats.rhs_evals,
            "t": solution.t, "phi": solution.x[:, ode.state_names.index("phi")]}


def statistics_rows() -> list[dict]:
    """The document's log and each of DOCUMENT_RUNS as rows (label first, no arrays)."""
    rows = [{"run": "document: Tsit5", **DOCUMENT_LOG}]
    for label, integrator, atol in DOCUMENT_RUNS:
        ours = run_as_document(integrator, atol=atol)
        rows.append({"run": f"ours: {label}",
                     **{k: v for k, v in ours.items() if k not in ("t", "phi")}})
    return rows
