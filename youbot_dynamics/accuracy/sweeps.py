"""Independent cases through Dask: one small layer for every sweep.

``map_cases(function, cases)`` runs ``function(*case)`` for each case and returns the
results in the cases' order, whatever order they finish in. Where they run:

- ``workers=0``: serially, in this process (no Dask at all);
- ``scheduler="tcp://HOST:PORT"``: on a running Dask cluster (``dask scheduler`` and
  ``dask worker`` processes; the workers must import youbot_dynamics);
- otherwise an embedded local cluster of ``workers`` processes (default: one per core, at
  most one per case), one thread each, started for the call and closed after it;
- except inside a case already running on a Dask worker (a report section, say), where
  ``workers=None`` is the cluster that case runs on: the case leaves its worker's thread
  while its own cases run there (``distributed.worker_client``), so a sweep inside one
  study of the report spreads over every worker. :func:`enclosing_workers` gives a case the
  ``workers`` to pass: None there, 0 (serial) when the outer sweep is serial.

Each case runs the same code on the same inputs wherever it runs, so the results equal the
serial run's bit for bit (test/accuracy/test_sweeps.py checks it on a scheduler with two workers).
Wall times measured inside a case are the exception: they are figures of the run, not of
the case. A case that raises is re-raised as :class:`CaseError` naming the case.
"""
from __future__ import annotations

import logging
import os
import reprlib
from contextlib import contextmanager
from typing import Any, Callable, Iterator, Sequence

from tqdm import tqdm

from youbot_dynamics.errors import UserInputError


#: How long a client waits for the scheduler at ``--scheduler`` before giving up.
CONNECT_TIMEOUT = "10s"


class CaseError(RuntimeError):
    """A case of a sweep failed: names the function and the case."""


def inside_worker() -> bool:
    """True inside a case running on a Dask worker."""
    try:
        from distributed import get_worker
        get_worker()
    except (ImportError, ValueError):  # ValueError: no worker here
        return False
    return True


def enclosing_workers() -> int | None:
    """The ``workers`` for a sweep inside a case of another sweep: None (the cluster the
    case runs on) on a Dask worker, 0 (serially, in this process) otherwise."""
    return None if inside_worker() else 0


def default_workers(n_cases: int) -> int:
    """Processes of the embedded cluster: one per core, at most one per case, at least 1."""
    return max(1, min(os.cpu_count() or 1, n_cases))


@contextmanager
def dask_client(workers: int | None = None, scheduler: str | None = None,
                n_cases: int = 1) -> Iterator[Any]:
    """A Dask client on ``scheduler`` or on an embedded local cluster of ``workers``
    processes (see the module docstring); None for ``workers=0`` (serial)."""
    if scheduler is None and workers == 0:
        yield None
        return
    if workers is not None and workers < 0:
        raise UserInputError(f"--workers must be >= 0 (0: serial), got {workers}")
    if scheduler is None and workers is None and inside_worker():
        from distributed import worker_client
        with worker_client() as client:
            yield client
        return
    from distributed import Client, LocalCluster
    if scheduler is not None:
        try:
            client = Client(scheduler, timeout=CONNECT_TIMEOUT)
        except OSError as error:
            raise UserInputError(f"--scheduler {scheduler}: cannot reach a Dask scheduler "
                                 f"there ({error})") from None
        with client:
            yield client
        return
    n = default_workers(n_cases) if workers is None else workers
    with LocalCluster(n_workers=n, threads_per_worker=1, processes=True, dashboard_address=":0",
                      silence_logs=logging.ERROR) as cluster, Client(cluster) as client:
        yield client


def map_cases(function: Callable[..., Any], cases: Sequence[tuple], *,
              workers: int | None = None, scheduler: str | None = None,
              client: Any = None, desc: str | None = None,
              progress: bool = True) -> list[Any]:
    """``[function(*case) for case in cases]``, serially (``workers=0``), on ``client``,
    on the cluster at ``scheduler`` or on an embedded local cluster; a progress bar on
    stderr counts finished cases. ``function`` must be importable (module level) for
    processes to run it."""
    cases = [tuple(case) for case in cases]
    desc = desc or getattr(function, "__name__", "cases")
    if client is None and scheduler is None and workers == 0:
        results = []
        for case in tqdm(cases, desc=desc, unit="case", disable=not progress):
            results.append(_run_case(function, case))
        return results
    if client is None:
        with dask_client(workers, scheduler, len(cases)) as own:
            return map_cases(function, cases, client=own, desc=desc, progress=progress)
    from distributed import as_completed
    futures = [client.submit(_run_case, function, case, pure=False) for case in cases]
    index = {future.key: i for i, future in enumerate(futures)}
    results: list[Any] = [None] * len(cases)
    with tqdm(total=len(cases), desc=desc, unit="case", disable=not progress) as bar:
        for future in as_completed(futures):
            results[index[future.key]] = future.result()
            bar.update(1)
    return results


def _run_case(function: Callable[..., Any], case: tuple) -> Any:
    """``function(*case)``; CaseError naming the function and the case if it raises."""
    try:
        return function(*case)
    except Exception as error:  # re-raised with the case named
        raise CaseError(f"{getattr(function, '__qualname__', function)}"
                        f"{reprlib.repr(case)} failed: {type(error).__name__}: {error}") from error
