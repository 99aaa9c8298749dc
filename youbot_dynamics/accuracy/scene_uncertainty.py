"""A scene's uncertain parameters (``"value ± sigma"``, ``Scene.uncertain``) propagated to
one output over time, two ways, compared at the end time:

- linear: the output's sensitivity to each parameter by central finite differences (runs
  at value +- FD_FRACTION sigma), combined as the ``uncertainties`` package combines
  independent variables, sigma_y^2 = sum_i (dy/dp_i sigma_i)^2, around the nominal run;
- Monte Carlo: N Gaussian samples of the parameters (independent, seeded), each a run of
  the scene; a sample the scene validator refuses (a negative mass or damping) is drawn
  again.

The output is a state component by its name (``q[pivot]``, ``v[arm_joint_1]``,
``pose[ball.z]``: ``SimulationResult.layout.names``) at the scene's output times. Every
run (2 k + 1 linear, N Monte Carlo) is an independent case of
:func:`youbot_dynamics.accuracy.sweeps.map_cases` (serial, a local Dask cluster or the one at
``scheduler``; ``progress``: a bar on stderr). Mean and sigma come as
:class:`~youbot_dynamics.accuracy.propagation.Propagation`; the figures and the plot are
accuracy/propagation.py's (``comparison``, ``plot_uncertainty``), shared with the
uncertain-pendulum study.
"""
from __future__ import annotations

import time
from pathlib import Path
from typing import Sequence

import numpy as np

from youbot_dynamics.accuracy.propagation import Propagation
from youbot_dynamics.accuracy.sweeps import map_cases
from youbot_dynamics.errors import UserInputError
from youbot_dynamics.scene.reader import SceneError
from youbot_dynamics.scene.schema import Scene, find_scene, load_scene
from youbot_dynamics.sim import engine
from youbot_dynamics.sim.build import compile

#: Finite-difference step of the sensitivities, as a fraction of each parameter's sigma:
#: small enough for the truncation error (O(step^2)) and large enough that the integrator's
#: error (the scene's tolerance) divided by the step stays small.
FD_FRACTION = 1e-2
#: Draws of one Monte Carlo sample before its parameters count as impossible.
MAX_DRAWS = 100


def uncertain_scene(path: str | Path, output: str) -> Scene:
    """The scene at ``path`` (a file or a packaged name), refused unless it has uncertain
    parameters and a state component named ``output``."""
    scene = load_scene(path)
    if not scene.uncertain:
        raise UserInputError(f"{scene.source}: no uncertain parameter: write one as \"value ± sigma\" "
                             "(e.g. damping: \"0.5 ± 0.2\")")
    names = compile(scene).layout.names
    if output not in names:
        raise UserInputError(f"{scene.source}: --output {output!r} is no state component; "
                             f"components: {', '.join(names)}")
    return scene


def output_trace(path: str, values: dict[str, float], output: str, duration: float | None) -> np.ndarray:
    """The output (a state component's name) at the output times of the scene at ``path``
    read with ``values`` for its uncertain parameters, over ``duration`` (s; None: the
    scene's)."""
    scene = load_scene(path, values)
    if duration is not None:
        scene = scene.with_duration(duration)
    result = engine.run(compile(scene))
    return result.x[:, result.layout.names.index(output)]


def output_times(path: str, duration: float | None) -> np.ndarray:
    """The scene's output times (s) over ``duration`` (None: the scene's)."""
    scene = load_scene(path)
    return (scene if duration is None else scene.with_duration(duration)).output_times


def linear_propagation(path: str | Path, output: str, duration: float | None = None, *,
                       workers: int | None = 0, scheduler: str | None = None,
                       progress: bool = False) -> tuple[Propagation, np.ndarray]:
    """The nominal run and its linear sigma band; also the sensitivities (k, outputs),
    d output / d parameter, in the order of ``Scene.uncertain``."""
    start = time.perf_counter()
    path = str(find_scene(path))
    parameters = uncertain_scene(path, output).uncertain
    cases = [(path, {}, output, duration)]
    for key, (value, sigma) in parameters.items():
        step = FD_FRACTION * sigma
        cases += [(path, {key: value + step}, output, duration), (path, {key: value - step}, output, duration)]
    traces = map_cases(output_trace, cases, workers=workers, scheduler=scheduler, desc="linear", progress=progress)
    sigmas = np.array([sigma for _, sigma in parameters.values()])
    sensitivities = np.array([(traces[1 + 2 * i] - traces[2 + 2 * i]) / (2.0 * FD_FRACTION * sigmas[i])
                              for i in range(len(sigmas))])
    sigma = np.sqrt(np.sum((sensitivities * sigmas[:, None]) ** 2, axis=0))
    return (Propagation("linear", output_times(path, duration), traces[0], sigma, time.perf_counter() - start),
            sensitivities)


def parameter_samples(path: str | Path, n: int, seed: int = 0) -> tuple[tuple[str, ...], np.ndarray]:
    """(keys, samples (n, k)): independent Gaussian draws of the uncertain parameters; a
    row the scene validator refuses is drawn again (at most MAX_DRAWS times)."""
    if n < 2:
        raise UserInputError(f"the Monte Carlo needs at least 2 samples, got {n}")
    path = str(find_scene(path))
    parameters = load_scene(path).uncertain
    keys = tuple(parameters)
    means = np.array([value for value, _ in parameters.values()])
    sigmas = np.array([sigma for _, sigma in parameters.values()])
    rng = np.random.default_rng(seed)
    samples = rng.normal(means, sigmas, size=(n, len(keys)))
    for row in samples:
        for _ in range(MAX_DRAWS):
            try:
                load_scene(path, dict(zip(keys, row.tolist())))
                break
            except SceneError:
                row[:] = rng.normal(means, sigmas)
        else:
            raise UserInputError(f"{path}: {MAX_DRAWS} draws of the uncertain parameters were all refused "
                                 "by the scene (is a sigma far too large for its value?)")
    return keys, samples


def monte_carlo(path: str | Path, output: str, n: int = 1000, seed: int = 0, duration: float | None = None, *,
                workers: int | None = 0, scheduler: str | None = None, progress: bool = False
                ) -> tuple[Propagation, tuple[str, ...], np.ndarray, np.ndarray]:
    """Sample mean and standard deviation (ddof 1) of the output over n runs; the keys,
    the samples (n, k) and the output of every run ((outputs, n))."""
    start = time.perf_counter()
    path = str(find_scene(path))
    uncertain_scene(path, output)
    keys, samples = parameter_samples(path, n, seed)
    cases = [(path, dict(zip(keys, row.tolist())), output, duration) for row in samples]
    traces = np.array(map_cases(output_trace, cases, workers=workers, scheduler=scheduler,
                                desc="Monte Carlo", progress=progress)).T
    return (Propagation("monte_carlo", output_times(path, duration), traces.mean(axis=1),
                        traces.std(axis=1, ddof=1), time.perf_counter() - start), keys, samples, traces)


def summary_text(scene: str, output: str, keys: Sequence[str], samples: int, seed: int,
                 figures: dict) -> str:
    """The comparison's figures (accuracy.propagation.comparison, in the output's unit and
    s) as the lines ``scene-uncertainty`` prints."""
    return "\n".join([
        f"{scene}: {output} with uncertain {', '.join(keys)}; linear propagation "
        f"(central differences) against {samples} Monte Carlo samples (seed {seed})",
        f"at t = {figures['t_end']:g} s: sigma linear {figures['sigma_linear_end']:.4g}, Monte Carlo "
        f"{figures['sigma_monte_carlo_end']:.4g} (2-sigma bands {figures['band_width_linear_end']:.4g} and "
        f"{figures['band_width_monte_carlo_end']:.4g} wide); means differ by {figures['mean_difference_end']:.3g}",
        f"sigma_linear / sigma_MC ranges over [{figures['min_ratio']:.3g}, {figures['max_ratio']:.3g}]; "
        f"wall time: linear {figures['wall_time_linear']:.3g} s, Monte Carlo "
        f"{figures['wall_time_monte_carlo']:.3g} s"])
