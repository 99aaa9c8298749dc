"""Figures of the uncertainty study (document 000 section 3; studies/uncertain_pendulum.py): the
uncertain pendulum's phi (rad) with both +-sigma bands, the sample histogram at the end
and the ratio of the two standard deviations over time (s).
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from youbot_dynamics.accuracy.propagation import (FAILURE_FLOOR, FAILURE_RATIO, comparison,
                                                  plot_uncertainty)
from youbot_dynamics.studies.figures import FigureSet, panels, save, specs
from youbot_dynamics.studies.uncertain_pendulum import UncertaintyConfig, UncertaintyResult, run

#: Monte Carlo samples of the short and the full form.
SAMPLES_SHORT, SAMPLES_FULL = 200, 1000
#: Title and quantity of the band plot.
PENDULUM_TITLE = "Damped pendulum, L = 0.8 +- 0.2, m = 1 +- 0.2, d = 0.5 +- 0.2"
QUANTITY = "phi (rad)"


def plot_band(result: UncertaintyResult, path: str) -> None:
    """The band plot of a run of the study (``study uncertainty --plot``)."""
    plot_uncertainty(result.linear, result.sampled, result.phi, path, PENDULUM_TITLE, QUANTITY)


def draw_uncertainty(result: UncertaintyResult | None, out: Path,
                     full: bool) -> dict[str, tuple[str, str]]:
    """The figures of UNCERTAINTY_SET, from ``result`` when it is the study at the
    report's size (SAMPLES_SHORT, or SAMPLES_FULL when ``full``, random seed 0 over T_END), else
    from a run of that size."""
    config = UncertaintyConfig(samples=SAMPLES_FULL if full else SAMPLES_SHORT, workers=0)
    if result is None or (result.config.samples, result.config.seed, result.config.duration) \
            != (config.samples, config.seed, config.duration):
        result = run(config)
    samples, linear, sampled, phi = config.samples, result.linear, result.sampled, result.phi
    figures = comparison(linear, sampled)
    plot_uncertainty(linear, sampled, phi, str(out / "uncertainty.png"), PENDULUM_TITLE,
                     QUANTITY)
    fails = figures["linearisation_fails_at"]
    drawn = {"uncertainty.png": (
        f"at t = {figures['t_end']:g} s the 2-sigma band is {figures['band_width_linear_end']:.3g}"
        f" rad wide by linear propagation, {figures['band_width_monte_carlo_end']:.3g} rad by "
        f"{samples} Monte Carlo samples",
        "Document 000 draws the linear band only (Measurements.jl); the Monte Carlo shows where it "
        + ("holds throughout." if fails is None else f"fails: first at t = {fails:g} s."))}
    figure, axis = panels(size=(6.5, 3.8))
    end = phi[-1]
    axis.hist(end, bins=30, density=True, alpha=0.6, label=f"{samples} samples")
    grid = np.linspace(end.min(), end.max(), 200)
    sigma, mean = linear.sigma[-1], linear.mean[-1]
    axis.plot(grid, np.exp(-0.5 * ((grid - mean) / sigma) ** 2) / (sigma * np.sqrt(2 * np.pi)),
              label="linear propagation (normal)")
    axis.set_xlabel(f"phi at t = {linear.t[-1]:g} s (rad)")
    axis.set_ylabel("density")
    axis.legend(fontsize=7)
    save(figure, out / "uncertainty_histogram.png",
         "Uncertain pendulum: the Monte Carlo's phi at the end against the linear normal")
    drawn["uncertainty_histogram.png"] = (
        f"samples: mean {end.mean():.3g} rad, sigma {end.std(ddof=1):.3g} rad; linear: mean "
        f"{mean:.3g} rad, sigma {sigma:.3g} rad",
        "No document figure: the samples' spread at the end is not the linear normal.")
    figure, axis = panels(size=(7.0, 3.4))
    ratio = np.divide(linear.sigma, sampled.sigma, out=np.ones_like(linear.sigma),
                      where=sampled.sigma > 0)
    axis.plot(linear.t, ratio, linewidth=0.8)
    axis.axhspan(1 - FAILURE_RATIO, 1 + FAILURE_RATIO, color="green", alpha=0.15,
                 label=f"within {FAILURE_RATIO:.0%}")
    axis.set_xlabel("t (s)")
    axis.set_ylabel("sigma linear / sigma Monte Carlo")
    axis.legend(fontsize=7)
    save(figure, out / "uncertainty_sigma_ratio.png",
         "Uncertain pendulum: linear against Monte Carlo standard deviation")
    drawn["uncertainty_sigma_ratio.png"] = (
        f"ratio from {figures['min_ratio']:.2g} to {figures['max_ratio']:.2g}",
        f"Linearisation counts as failed where the sigmas differ by more than "
        f"{FAILURE_RATIO:.0%} and {FAILURE_FLOOR:g} rad: "
        + ("never." if fails is None else f"first at t = {fails:g} s."))
    return drawn


UNCERTAINTY_SET = FigureSet("uncertainty", specs(
    ("uncertainty.png", "Uncertain damped pendulum: phi with the linear and Monte Carlo "
     "+-sigma bands (two panels, as the document's band plus the sigmas)",
     "Measurements.jl's band of phi(t)."),
    ("uncertainty_histogram.png", "Uncertain damped pendulum: phi at t = 10 s, samples "
     "against the linear normal", "No document figure."),
    ("uncertainty_sigma_ratio.png", "Uncertain damped pendulum: sigma linear / sigma Monte "
     "Carlo over time", "No document figure."),
), draw_uncertainty)
