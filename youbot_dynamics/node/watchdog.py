"""Callback budgets of the node: how long (wall s) each callback took against a budget, for
/diagnostics (:class:`Watchdog`)."""
from __future__ import annotations

import math


class Watchdog:
    """Callback budgets: ``record(source, seconds)`` counts a callback (a step tick, a
    message, a service; named ``source``) that took longer than ``budget`` wall seconds.
    Measured when the callback returns (the node has one executor thread, so a running
    callback is not interrupted); ``values`` are /diagnostics values (``overruns``,
    ``overruns.<source>``, ``worst_callback_s``, ``worst_callback``) and ``fresh`` tells
    whether an overrun came since the last report."""

    def __init__(self, budget: float) -> None:
        if not (math.isfinite(budget) and budget > 0.0):
            raise ValueError(f"callback budget must be positive and finite, got {budget}")
        self.budget = float(budget)
        self.overruns: dict[str, int] = {}
        self.worst: tuple[float, str] = (0.0, "none")
        self.fresh = False

    def record(self, source: str, seconds: float) -> bool:
        """Note that ``source`` took ``seconds``; True if that overran the budget."""
        if seconds > self.worst[0]:
            self.worst = (seconds, source)
        if seconds <= self.budget:
            return False
        self.overruns[source] = self.overruns.get(source, 0) + 1
        self.fresh = True
        return True

    def values(self) -> dict[str, object]:
        """/diagnostics values; clears ``fresh``."""
        self.fresh = False
        return {"callback_budget_s": self.budget, "overruns": sum(self.overruns.values()),
                **{f"overruns.{source}": count for source, count in self.overruns.items()},
                "worst_callback_s": self.worst[0], "worst_callback": self.worst[1]}
