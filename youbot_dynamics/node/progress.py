"""How far a run of a set duration has come, in simulated time: the ``progress`` figure of
/diagnostics (percent) and, for long runs, a log line at every tenth."""
from __future__ import annotations

LONG_RUN = 10.0
"""Simulated seconds above which a run logs its progress."""
STEP = 10
"""Percent between two progress log lines."""


class Progress:
    """Progress of a run that ends after ``duration`` simulated seconds (0: open-ended, no
    progress to report)."""

    def __init__(self, duration: float) -> None:
        self.duration = float(duration)
        self._reported = 0    # the last mark (percent) reported by :meth:`passed`

    def percent(self, t: float) -> float | None:
        """Percent of the run done at node time ``t`` (s), at most 100; None when open-ended."""
        return None if self.duration <= 0.0 else min(100.0, 100.0 * t / self.duration)

    def passed(self, t: float) -> int | None:
        """The highest :data:`STEP` mark (10, 20, ... 90 percent) that node time ``t`` (s)
        has reached since the last call that returned one, for runs longer than
        :data:`LONG_RUN`; None otherwise (the end of the run is reported as such)."""
        if self.duration <= LONG_RUN:
            return None
        mark = int(100.0 * t / self.duration + 1e-9) // STEP * STEP
        if mark <= self._reported or mark >= 100:
            return None
        self._reported = mark
        return mark
