"""The integrators' typed errors: a solver's own failure (:class:`IntegrationError`), a
solution that diverged (:class:`DivergenceError`: when, with what, why and which
components) and a spent step budget (:class:`StepBudgetError`)."""
from __future__ import annotations


class IntegrationError(RuntimeError):
    """The solver failed for a reason other than divergence; the message is the solver's."""


class DivergenceError(IntegrationError):
    """The solution diverged: non-finite state, a bound exceeded, a monitor's complaint or a
    collapsed step size. Says when (``time``, s), with what (``integrator``, ``step_size``,
    s), why (``reason``) and which state components (``components``: name -> value)."""

    def __init__(self, time: float, integrator: str, step_size: float, reason: str,
                 components: dict[str, float] | None = None) -> None:
        self.time = time
        self.integrator = integrator
        self.step_size = step_size
        self.reason = reason
        self.components = dict(components or {})
        listed = ", ".join(f"{name}={value:.6g}" for name, value in self.components.items())
        super().__init__(f"{integrator} diverged at t={time:.6g} s (step {step_size:.3g} s): "
                         f"{reason}" + (f": {listed}" if listed else ""))


class StepBudgetError(DivergenceError):
    """A run needed more steps than its budget (``budget``): refused up front for fixed
    steps, stopped when spent for adaptive ones (a step size collapsing without end)."""

    def __init__(self, time: float, integrator: str, step_size: float, budget: int,
                 message: str) -> None:
        IntegrationError.__init__(self, message)
        self.time, self.integrator, self.step_size = time, integrator, step_size
        self.reason, self.components, self.budget = f"step budget of {budget} steps spent", {}, budget
