"""Hairer's DOPRI5 (the Fortran code of Hairer, Norsett & Wanner, through
scipy.integrate.ode's ``dopri5``): the Dormand-Prince 5(4) pair with Hairer's step-size
control, the code Assimulo's Dopri5 wraps. Document 001's Dopri45 counts (Tables 6 and 11)
come from it; scipy's solve_ivp RK45 is the same pair with another controller.

Hairer's controller: the error norm is the RMS of err_i / (atol + rtol max(|y_i|,
|y_new_i|)); the new step is h / fac with fac = err^(1/5 - 0.75 beta) / err_old^beta / 0.9
clipped to [1/10, 5] (beta = 0.04: a PI controller), and no increase right after a
rejection; the initial step comes from Hairer's ``hinit`` (one extra f evaluation). Every
step attempt costs 6 evaluations (the seventh stage is the next step's first, FSAL), so
nfcn = 6 (accepted + rejected) + 2. scipy's RK45 uses the same norm and FSAL but a pure
error-per-step controller (fac = 0.9 err^(-1/5), within [0.2, 10]) and its own initial
step, so its step sequence differs.
"""
from __future__ import annotations

from typing import Callable

import numpy as np

from youbot_dynamics.integrate.errors import IntegrationError


def hairer_dopri5(rhs: Callable[[float, np.ndarray], np.ndarray], y0, t_end: float,
                  rtol: float, atol: float, max_steps: int = 100_000) -> dict:
    """Integrate y' = rhs(t, y) from t = 0 to t_end (s) with Hairer's DOPRI5; its counts:
    ``rhs_evals`` (nfcn), ``steps`` (accepted + rejected attempts), ``accepted``,
    ``rejected``, and the final state ``y``. IntegrationError if the code fails."""
    from scipy.integrate import ode
    solver = ode(rhs).set_integrator("dopri5", rtol=rtol, atol=atol, nsteps=max_steps)
    solver.set_initial_value(np.asarray(y0, dtype=float), 0.0)
    y = solver.integrate(t_end)
    if not solver.successful():
        raise IntegrationError(f"DOPRI5 failed before t = {t_end:g} s "
                               f"(istate {solver.get_return_code()})")
    counts = solver._integrator.iwork  # DOPRI5's IWORK(17..20): nfcn, nstep, naccpt, nrejct
    return {"rhs_evals": int(counts[16]), "steps": int(counts[17]),
            "accepted": int(counts[18]), "rejected": int(counts[19]), "y": np.array(y)}
