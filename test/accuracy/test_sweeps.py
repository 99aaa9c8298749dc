"""The Dask layer (accuracy/sweeps.py): a sweep gives the serial run's results, bit for bit,
on an embedded local cluster and on a real one (a ``dask scheduler`` and two ``dask worker``
processes on 127.0.0.1), in the cases' order; a failing case is named.

The sweeps: the measured real-axis stability boundary of BDF1-4 (bisection on the solver's
own growth, studies/bdf.py), checked also against the analytic root locus; work-precision
points on a short youBot scene; the uncertainty study's Monte Carlo samples.
"""
from __future__ import annotations

import dataclasses
import math
import os
import socket
import subprocess
import sys
import time
from pathlib import Path

import pytest

from youbot_dynamics.accuracy import sweeps
from youbot_dynamics.accuracy.sweeps import CaseError, map_cases
from youbot_dynamics.errors import UserInputError
from youbot_dynamics.studies.bdf import locus_radius_on_ray, measured_boundary_radius

ROOT = Path(__file__).resolve().parents[2]
DASK = Path(sys.executable).with_name("dask")
#: Bisection steps of the boundary sweep: the bracket [1e-3, 20] shrinks to 20 / 2^8 = 0.08.
ITERATIONS = 8
BOUNDARY_CASES = [(order, 0.0, 1e-3, 20.0, ITERATIONS) for order in (1, 2, 3, 4)]


def free_port() -> int:
    """A TCP port on 127.0.0.1 that nothing listens on (the OS picks it)."""
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        return probe.getsockname()[1]


@pytest.fixture(scope="module")
def serial_boundaries() -> list[float]:
    return map_cases(measured_boundary_radius, BOUNDARY_CASES, workers=0, progress=False)


def test_serial_boundaries_meet_the_root_locus(serial_boundaries):
    # The bisection ends within half its last bracket (20 / 2^9 = 0.04) of the solver's
    # boundary, which is the root locus's to 1e-5 (test_bdf.py); margin 0.05.
    for (order, *_), radius in zip(BOUNDARY_CASES, serial_boundaries):
        assert radius == pytest.approx(locus_radius_on_ray(order, 0.0), abs=0.05)


@pytest.mark.parametrize("workers", [1, 2])
def test_local_cluster_equals_serial(serial_boundaries, workers):
    assert map_cases(measured_boundary_radius, BOUNDARY_CASES, workers=workers,
                     progress=False) == serial_boundaries


@pytest.fixture(scope="module")
def dask_cluster():
    """A scheduler and two single-threaded workers on 127.0.0.1 (free ports), importing
    this worktree's youbot_dynamics; stopped (by their process ids) afterwards."""
    if not DASK.exists():
        pytest.skip(f"no dask command beside {sys.executable}")
    port = free_port()
    address = f"tcp://127.0.0.1:{port}"
    env = {**os.environ, "MPLBACKEND": "Agg", "PYTHONPATH": os.pathsep.join(  # this tree, this file
        [str(ROOT), str(Path(__file__).resolve().parent), *filter(None, [os.environ.get("PYTHONPATH")])])}
    from distributed import Client
    quiet = dict(stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, cwd=ROOT, env=env)
    processes = [subprocess.Popen([str(DASK), "scheduler", "--host", "127.0.0.1", "--port",
                                   str(port), "--dashboard-address", ":0", "--no-show"], **quiet)]
    try:
        for _ in range(2):
            processes.append(subprocess.Popen(
                [str(DASK), "worker", address, "--host", "127.0.0.1", "--nthreads", "1",
                 "--nworkers", "1", "--no-nanny", "--no-dashboard"], **quiet))
        with Client(address, timeout="60s") as client:
            client.wait_for_workers(2, timeout=120)
            assert len(client.scheduler_info()["workers"]) == 2
        yield address
    finally:
        try:
            with Client(address, timeout="10s") as client:
                client.shutdown()  # the scheduler and its workers close cleanly
        except OSError:
            for process in processes:
                process.terminate()
        for process in reversed(processes):
            try:
                process.wait(timeout=20)
            except subprocess.TimeoutExpired:
                process.kill()
                process.wait()


def test_scheduler_with_two_workers_equals_serial(dask_cluster, serial_boundaries):
    results = map_cases(measured_boundary_radius, BOUNDARY_CASES, scheduler=dask_cluster,
                        progress=False)
    assert results == serial_boundaries


def worker_process(seconds: float) -> int:
    """The id of the process that ran this case, after ``seconds`` of sleep."""
    time.sleep(seconds)
    return os.getpid()


def test_both_workers_take_cases(dask_cluster):
    processes = map_cases(worker_process, [(0.3,)] * 8, scheduler=dask_cluster, progress=False)
    assert os.getpid() not in processes and len(set(processes)) == 2


def nested_sweep(seconds: float, cases: int) -> list[int]:
    """A sweep inside a case: the processes its own cases ran in."""
    return map_cases(worker_process, [(seconds,)] * cases, workers=sweeps.enclosing_workers(),
                     progress=False)


def test_a_sweep_inside_a_case_spreads_over_the_enclosing_cluster(dask_cluster):
    """One outer case on the two-worker cluster: its inner sweep's cases run on both workers
    (the outer case leaves its worker's thread while they run); outside a worker the inner
    sweep is serial."""
    assert sweeps.enclosing_workers() == 0
    [inner] = map_cases(nested_sweep, [(0.3, 8)], scheduler=dask_cluster, progress=False)
    assert os.getpid() not in inner and len(set(inner)) == 2
    assert set(nested_sweep(0.0, 3)) == {os.getpid()}


def test_work_precision_points_on_the_cluster_equal_serial(dask_cluster):
    from youbot_dynamics.accuracy.work_precision import reference_solution, sweep
    from youbot_dynamics.scene.schema import load_scene
    scene = load_scene("arm_swing").with_duration(0.05)
    reference = reference_solution(scene)
    grid = {"rk4": (2e-3, 1e-3), "rk45": (1e-4, 1e-6), "cvode_bdf": (1e-5,)}
    serial = sweep(scene, reference, grid, progress=False, workers=0)
    remote = sweep(scene, reference, grid, progress=False, scheduler=dask_cluster)

    def figures(point):  # the wall time is a figure of the run, not of the case
        return {k: v for k, v in dataclasses.asdict(point).items() if k != "wall_time"}
    assert [figures(p) for p in remote] == [figures(p) for p in serial]
    assert all(p.failure is None and math.isfinite(p.q_error) for p in serial)
    assert [(p.integrator, p.value) for p in remote] == [(m, v) for m, vs in grid.items() for v in vs]


def test_monte_carlo_on_the_cluster_equals_serial(dask_cluster):
    import numpy as np

    from youbot_dynamics.studies.uncertain_pendulum import SAMPLES_PER_CASE, monte_carlo
    n = 3 * SAMPLES_PER_CASE + 17  # four blocks, the last one short
    serial, phi = monte_carlo(n, 2.0)
    remote, phi_remote = monte_carlo(n, 2.0, scheduler=dask_cluster)
    assert phi_remote.shape == phi.shape == (len(serial.t), n)
    assert np.array_equal(phi_remote, phi)
    assert np.array_equal(remote.mean, serial.mean) and np.array_equal(remote.sigma, serial.sigma)


def square_root(x: float) -> float:
    """math.sqrt: raises on a negative case."""
    return math.sqrt(x)


def test_a_failing_case_is_named():
    with pytest.raises(CaseError, match=r"square_root\(-1.0,\) failed: ValueError"):
        map_cases(square_root, [(4.0,), (-1.0,)], workers=0, progress=False)


def test_an_unreachable_scheduler_is_a_user_error(monkeypatch):
    monkeypatch.setattr(sweeps, "CONNECT_TIMEOUT", "1s")
    with pytest.raises(UserInputError, match="--scheduler tcp://127.0.0.1:"):
        map_cases(square_root, [(4.0,)], scheduler=f"tcp://127.0.0.1:{free_port()}",
                  progress=False)
