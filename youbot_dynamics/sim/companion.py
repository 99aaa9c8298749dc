"""The companion run of the error estimate (:mod:`youbot_dynamics.sim.error_estimate`):
where it runs and how it is fed, and :func:`run`, the engine's run with an optional estimate.

:func:`run_estimated` runs the companion in a worker process (a one-process
``concurrent.futures`` pool; the scene, settings and any Python controller travel by
cloudpickle) while the main run goes on in this one; the companion's statistics and CPU
time are its reported cost. A controller that cannot be sent runs the companion here,
after the main run, and ``where`` says so. :class:`CompanionStream` is the same for a run
made in chunks (the ROS node): the worker keeps the companion's state, takes each chunk's
times, torque command and reference, and the differences are drawn as its answers arrive.
"""
from __future__ import annotations

import multiprocessing
import pickle
import sys
import time
from concurrent.futures import ProcessPoolExecutor
from dataclasses import replace
from typing import Callable, Sequence

import cloudpickle
import numpy as np

from youbot_dynamics.integrate.errors import IntegrationError
from youbot_dynamics.integrate.statistics import IntegratorStats
from youbot_dynamics.sim import engine
from youbot_dynamics.sim.build import compile
from youbot_dynamics.sim.error_estimate import (ErrorEstimate, companion_spec, estimate_from, make_estimate,
                                                view_differences, views_of_snapshots)
from youbot_dynamics.sim.model import SimModel
from youbot_dynamics.sim.simulator import Simulator
from youbot_dynamics.sim.state import ContactEvent, SimState


def run(model: SimModel, state0: SimState | None = None, t_eval: np.ndarray | None = None,
        progress: Callable[[float], None] | None = None, error_estimate: bool = False) -> engine.SimulationResult:
    """:func:`youbot_dynamics.sim.engine.run`; ``error_estimate``: with the run's error
    estimate (``result.error_estimate``, :func:`run_estimated`)."""
    if error_estimate:
        return run_estimated(model, state0, t_eval, progress)
    return engine.run(model, state0, t_eval, progress)


def _start_method() -> str:
    """How a worker starts: spawned in a ROS process (rclpy loaded: forking beside its
    executor's threads is unsafe; a node's entry point guards its ``__main__``), else
    forked (cheap, and a script without a ``__main__`` guard works)."""
    return "spawn" if "rclpy" in sys.modules else "fork"


def _worker_pool() -> ProcessPoolExecutor:
    """A one-process pool (:func:`_start_method`)."""
    return ProcessPoolExecutor(max_workers=1, mp_context=multiprocessing.get_context(_start_method()))


def companion_arguments(model: SimModel) -> tuple:
    """What the worker needs to build the companion's model: (scene, settings, limits,
    controller callback, control rate)."""
    control = model.control
    rate = None if control.period is None else 1.0 / control.period
    return model.scene, companion_spec(model.integrator), model.limits, control.callback, rate


def run_companion(arguments: tuple, x0: np.ndarray | None, t0: float, t_eval: np.ndarray
                  ) -> tuple[np.ndarray, list[ContactEvent], IntegratorStats, float]:
    """Build the companion from ``arguments`` (:func:`companion_arguments`) and run it from
    state ``x0`` at ``t0`` (None: the scene's initial state) over ``t_eval``; (states on
    t_eval, contact events, statistics, CPU time in s)."""
    start = time.process_time()
    model = compile(*arguments)
    state = engine.initial_state(model)
    if x0 is not None:
        state.t, state.x = t0, np.array(x0, dtype=float)
    result = engine.run(model, state, t_eval)
    return result.x, list(result.contact_events), result.stats, time.process_time() - start


def companion_from_payload(payload: bytes) -> tuple[np.ndarray, list[ContactEvent], IntegratorStats, float]:
    """Worker side of :func:`run_companion`: its arguments cloudpickled."""
    return run_companion(*pickle.loads(payload))


def run_estimated(model: SimModel, state0=None, t_eval: np.ndarray | None = None,
                  progress: Callable[[float], None] | None = None):
    """:func:`~youbot_dynamics.sim.engine.run` with its error estimate
    (``result.error_estimate``): the companion in a worker process while the main run goes
    on here (module docstring)."""
    start = engine.initial_state(model) if state0 is None else state0
    times = model.scene.output_times + start.t if t_eval is None else np.asarray(t_eval, dtype=float)
    case = (companion_arguments(model), start.x, start.t, times)
    try:
        payload, where = cloudpickle.dumps(case), "worker process"
    except Exception as error:  # noqa: BLE001 - whatever the callback holds that cannot travel
        payload, where = None, f"this process, after the run (the controller cannot be sent to a worker: {error})"
    pool = None if payload is None else _worker_pool()
    try:
        future = None if pool is None else pool.submit(companion_from_payload, payload)
        result = engine.run(model, state0, times, progress)
        try:
            x_c, events_c, stats_c, cpu = run_companion(*case) if future is None else future.result()
        except IntegrationError as error:
            raise IntegrationError(f"the error estimate's companion ({case[0][1].describe()}) failed where the "
                                   f"run did not: {error}") from error
    finally:
        if pool is not None:
            pool.shutdown()
    contact = model.contact is not None
    estimate = estimate_from(model, result.x, x_c, result.contact_events if contact else None,
                             events_c if contact else None, stats_c, cpu, where)
    return replace(result, error_estimate=estimate)


# ---- the companion of a run made in chunks (the node) ---------------------------------------
def stream_worker(connection, arguments: bytes) -> None:
    """Worker side of :class:`CompanionStream`: build the companion's Simulator from
    cloudpickled :func:`companion_arguments`, then answer each message until ``None``:
    ``(generation, "reset")`` restarts it; ``(generation, "advance", times, tau_command,
    reference)`` (reference cloudpickled when it changed, else None) moves it through
    ``times`` and answers (generation, its views there, its contact events when their
    number changed (else None), statistics, CPU time so far, time reached); a failure
    answers (generation, "failed: why") and ends."""
    start = time.process_time()
    scene, spec, limits, callback, rate = pickle.loads(arguments)
    simulator, events = Simulator(scene, spec, limits, callback, rate), 0
    while (message := connection.recv()) is not None:
        generation, kind, *rest = message
        try:
            if kind == "reset":
                simulator.reset()
                events = 0
                continue
            times, tau_command, reference = rest
            if reference is not None:
                simulator.state.reference = pickle.loads(reference)
            views = views_of_snapshots(simulator.advance_through(times, tau_command))
            new = list(simulator.events) if len(simulator.events) != events else None
            events = len(simulator.events)
            connection.send((generation, views, new, simulator.stats, time.process_time() - start, simulator.t))
        except Exception as error:  # noqa: BLE001 - any failure is reported, not raised in the worker
            connection.send((generation, f"failed: {type(error).__name__}: {error}"))
            return


class CompanionStream:
    """The companion of a run made in chunks (a node's ``advance_through`` calls): a worker
    process keeps its own Simulator at the companion's settings (:func:`companion_spec`);
    :meth:`submit` sends it each chunk's times, torque command and controller reference
    (over a pipe: a few tens of microseconds here) and keeps the main run's snapshots
    there; :meth:`estimate` draws the answers that have arrived (``wait``: all of them) into
    the running estimate. A reset of the main run is passed on with :meth:`reset`. Answers
    are drawn at every submit too, so neither side's pipe fills."""

    def __init__(self, model: SimModel) -> None:
        self.model = model
        context = multiprocessing.get_context(_start_method())
        self._connection, child = context.Pipe()
        self._process = context.Process(target=stream_worker, daemon=True, name="error-estimate companion",
                                        args=(child, cloudpickle.dumps(companion_arguments(model))))
        self._process.start()
        child.close()
        self._sent_reference: object = None
        self._generation, self.failure = 0, None
        self._pending: list[dict[str, np.ndarray]] = []
        self._clear()

    def _clear(self) -> None:
        self._largest: dict[str, float] = {}
        self._last: dict[str, float] = {}
        self._events: list[ContactEvent] = []
        self._stats: IntegratorStats | None = None
        self._cpu, self.reached = 0.0, 0.0

    def submit(self, times: np.ndarray, tau_command: np.ndarray | None, reference: object,
               snapshots: Sequence) -> None:
        """The chunk the main run just made: its output ``times`` (s), the ``tau_command``
        it held (None: its controller), its controller ``reference`` and its snapshots."""
        if self.failure is not None:
            return
        self._draw(wait=False)
        sent = None if reference is self._sent_reference else cloudpickle.dumps(reference)
        self._sent_reference = reference
        self._send((self._generation, "advance", np.asarray(times, dtype=float), tau_command, sent))
        self._pending.append(views_of_snapshots(snapshots))

    def reset(self) -> None:
        """The main run restarted from the scene's initial state: so does the companion;
        the estimate starts again (answers still on their way are dropped)."""
        self._generation += 1
        self._pending, self._sent_reference = [], None
        self._send((self._generation, "reset"))
        self._clear()

    def _send(self, message: tuple | None) -> None:
        try:
            self._connection.send(message)
        except (OSError, ValueError) as error:   # the worker is gone
            self.failure = self.failure or f"failed: the companion's worker stopped ({error})"

    @property
    def lag(self) -> int:
        """Chunks handed to the worker and not yet drawn."""
        return len(self._pending)

    def _draw(self, wait: bool) -> None:
        """Take the worker's answers in order: those that have arrived (``wait``: all)."""
        while self._pending and self.failure is None and (wait or self._connection.poll()):
            try:
                answer = self._connection.recv()
            except (EOFError, OSError) as error:
                self.failure = f"failed: the companion's worker stopped ({error!r})"
                return
            if answer[0] != self._generation:
                continue   # from before a reset
            if len(answer) == 2:
                self.failure = answer[1]
                return
            _, views_c, events, self._stats, self._cpu, self.reached = answer
            self._events = self._events if events is None else events
            for name, diff in view_differences(self._pending.pop(0), views_c).items():
                self._largest[name] = max(self._largest.get(name, 0.0), float(np.max(diff)))
                self._last[name] = float(diff[-1])

    def estimate(self, events: Sequence[ContactEvent] | None, wait: bool = False) -> ErrorEstimate | None:
        """The estimate over the chunks answered so far (``wait``: every chunk submitted),
        against the main run's contact ``events`` up to the companion's time (None without
        contact); None before the first answer."""
        self._draw(wait)
        if self._stats is None:
            return None
        mine = None if events is None else [e for e in events if e.time <= self.reached + 1e-12]
        return make_estimate(self.model.integrator, self._largest, self._last, mine,
                             None if events is None else self._events, self._stats, self._cpu,
                             self.failure or f"worker process, {self.lag} chunks behind")

    def close(self) -> None:
        """Take every answer still owed (the estimate stays readable), stop the worker
        (idempotent)."""
        if self._process is None:
            return
        self._draw(wait=True)
        self._send(None)
        self._process.join(timeout=5.0)
        if self._process.is_alive():
            self._process.terminate()
        self._connection.close()
        self._process = None
