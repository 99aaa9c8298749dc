"""Wall-clock pacing of the simulate-mode node, without rclpy.

A steady-clock timer paces the samples at ``publish_rate x time_scale`` per wall second; a
late tick publishes the samples that are due (up to :data:`MAX_BURST`, the rest at the next
ticks), so the average rate holds while the simulation keeps up; only after falling
:data:`MAX_LAG` wall seconds behind does the pacing restart from now (the real-time factor
then drops below the requested time scale). Simulated time itself advances by fixed
increments, independent of the wall clock. Wall time is ``time.monotonic`` (s).
"""
from __future__ import annotations

import time

MAX_BURST = 20
"""Most samples one timer tick publishes (and, at time_scale 0, the samples per tick)."""
MAX_LAG = 0.25
"""Wall seconds the samples may fall behind their pacing before it restarts from now (the
real-time factor then drops below the requested time scale)."""


class Pacing:
    """The schedule of samples in wall time: sample ``k0 + n`` is due ``n / rate`` wall
    seconds after ``start``."""

    def __init__(self, k: int = 0) -> None:
        self.restart(k)

    def restart(self, k: int) -> None:
        """Sample ``k`` is due now."""
        self.start, self.k0 = time.monotonic(), k

    def due(self, k: int, rate: float) -> int:
        """How many samples to publish now, the next being sample ``k``, at ``rate`` samples
        per wall second (0: as fast as possible, :data:`MAX_BURST` a tick); restarts the
        schedule when it lags more than :data:`MAX_LAG` behind."""
        due = MAX_BURST if rate == 0.0 else int((time.monotonic() - self.start) * rate) - (k - self.k0)
        if due > MAX_LAG * rate:
            self.restart(k)
        return min(max(0, due), MAX_BURST)


class RealTimeFactor:
    """Simulated seconds per wall second between two readings (:meth:`since_last`)."""

    def __init__(self, t: float) -> None:
        self.mark(t)

    def mark(self, t: float) -> None:
        """Start measuring now, at simulated time ``t`` (s)."""
        self.wall, self.t = time.monotonic(), t

    def since_last(self, t: float) -> float:
        """Simulated seconds per wall second from the last mark to now (simulated time ``t``);
        marks now. 0 when no wall time has passed."""
        now, start, t0 = time.monotonic(), self.wall, self.t
        self.wall, self.t = now, t
        return (t - t0) / (now - start) if now > start else 0.0
