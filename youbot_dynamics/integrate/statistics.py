"""The cost of an integrator run: :class:`IntegratorStats` (steps, evaluations, Jacobians,
rejections, nonlinear iterations and failures, events; wall and simulated time, s), the same
counters for every backend, ``None`` where a backend reports none."""
from __future__ import annotations

import math
from dataclasses import dataclass, fields

#: Counters a backend may not expose: ``None`` means "not reported by this backend".
COUNTERS = ("steps", "rhs_evals", "jac_evals", "rejected_steps", "nonlinear_iterations",
            "nonlinear_convergence_failures", "events")


@dataclass
class IntegratorStats:
    """Cost of one run (or, after ``+=``, of several segments of a hybrid run).

    A counter is ``None`` when the backend does not report it (for example scikit-sundae
    exposes no error-test failures), never a made-up zero. Times in seconds.
    """

    integrator: str
    steps: int | None = 0
    rhs_evals: int | None = 0
    jac_evals: int | None = 0
    rejected_steps: int | None = 0
    nonlinear_iterations: int | None = 0
    nonlinear_convergence_failures: int | None = 0
    events: int | None = 0
    wall_time: float = 0.0
    simulated_time: float = 0.0

    @property
    def real_time_factor(self) -> float:
        """Simulated seconds per wall-clock second (inf for an instantaneous run)."""
        return self.simulated_time / self.wall_time if self.wall_time > 0 else math.inf

    def as_dict(self) -> dict:
        """Every field plus ``real_time_factor``."""
        result = {f.name: getattr(self, f.name) for f in fields(self)}
        result["real_time_factor"] = self.real_time_factor
        return result

    def summary(self) -> str:
        """One readable line: every counter (``n/a`` where the backend reports none), the
        wall time and the real-time factor."""
        labels = ("steps", "rhs evaluations", "Jacobians", "rejected steps",
                  "nonlinear iterations", "convergence failures", "events")
        counts = ", ".join(f"{'n/a' if getattr(self, name) is None else getattr(self, name)} {label}"
                           for name, label in zip(COUNTERS, labels))
        return (f"{self.integrator}: {counts}; wall {self.wall_time:.3f} s, "
                f"real-time factor {self.real_time_factor:.3g}")

    def merge(self, other: IntegratorStats) -> IntegratorStats:
        """Add ``other``'s counters and times to this one (a counter unknown in either
        stays unknown); returns self."""
        for name in COUNTERS:
            mine, theirs = getattr(self, name), getattr(other, name)
            setattr(self, name, None if mine is None or theirs is None else mine + theirs)
        self.wall_time += other.wall_time
        self.simulated_time += other.simulated_time
        return self

    def __iadd__(self, other: IntegratorStats) -> IntegratorStats:
        return self.merge(other)
