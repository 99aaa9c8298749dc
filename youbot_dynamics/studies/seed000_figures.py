"""Figures of seed 000's rotation and uncertainty items, drawn with those studies' own
plot functions where they have one (studies/rotations.py, studies/uncertain_pendulum.py)
and from the same runs otherwise: one PNG per rotation run (attitude error against the
closed-form top, middle Cardan angle, |q| drift), Cardan's steps against the quaternion's
as the spin loses its wobble, and the uncertain pendulum's band, the sample histogram at
the end and the ratio of the two standard deviations.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from youbot_dynamics.studies.figures import FigureSet, panels, save, specs

#: Monte Carlo samples of the short and the full form.
SAMPLES_SHORT, SAMPLES_FULL = 200, 1000
ROTATION_RUNS = ("spin", "tumble", "top")


def draw_rotations(out: Path, full: bool) -> dict[str, tuple[str, str]]:
    """The figures of ROTATIONS_SET."""
    from youbot_dynamics.studies.rotations import (RUNS, plot_rotations, rotations_study,
                                                   spin_wobble_sweep)
    results = rotations_study()
    drawn = {}
    for name in ROTATION_RUNS:
        mine = [result for result in results if result.run == name]
        plot_rotations(mine, str(out / f"rotations_{name}.png"))
        drawn[f"rotations_{name}.png"] = (
            "; ".join(f"{r.formulation}: " + (f"failed ({r.failure})" if r.failure else
                                             f"{r.stats.steps} steps, attitude error "
                                             f"{r.errors['attitude']:.2g} rad")
                      for r in mine),
            ROTATION_DIFFERENCE[name](mine))
    if full:
        sweep = spin_wobble_sweep()
    else:  # the pure spin, and the spin run itself (its wobble) from the study above
        by = {r.formulation: r for r in results if r.run == "spin"}
        sweep = spin_wobble_sweep(wobbles=(0.0,)) + [
            {"wobble": RUNS["spin"].w0[1],
             **{f"{name}_steps": by[name].stats.steps for name in ("cardan", "quaternion")}}]
    figure, axis = panels(size=(6.5, 3.8))
    shown = [max(row["wobble"], 1e-4) for row in sweep]
    for formulation in ("cardan", "quaternion"):
        axis.semilogx(shown, [row[f"{formulation}_steps"] for row in sweep], "o-",
                      label=formulation)
    axis.set_xlabel("wobble about body y (rad/s; 0 drawn at 1e-4)")
    axis.set_ylabel("steps (RK45, tol 1e-8)")
    axis.legend(fontsize=7)
    save(figure, out / "rotations_spin_steps.png",
         f"Spin about x at {RUNS['spin'].w0[0]:g} rad/s: steps against wobble")
    pure = sweep[0]
    drawn["rotations_spin_steps.png"] = (
        "steps cardan / quaternion: " + ", ".join(
            f"wobble {row['wobble']:g}: {row['cardan_steps']} / {row['quaternion_steps']}"
            for row in sweep),
        "Seed: Cardan angles take larger steps when the body turns mostly about one axis. "
        + ("Ours confirms it for the pure spin" if pure["cardan_steps"] < pure["quaternion_steps"]
           else "Ours does not show it even for the pure spin")
        + f" ({pure['cardan_steps']} against {pure['quaternion_steps']} steps); the ratio "
        "of Cardan's steps to the quaternion's grows with the wobble: " + ", ".join(
            f"{row['cardan_steps'] / row['quaternion_steps']:.2f} at {row['wobble']:g} rad/s"
            for row in sweep) + ".")
    return drawn


def _spin_difference(results) -> str:
    by = {r.formulation: r for r in results}
    return ("Seed: Cardan is nearly linear here, so it should step larger. Ours: "
            f"{by['cardan'].stats.steps} Cardan steps against {by['quaternion'].stats.steps} "
            "quaternion steps at this wobble (see the sweep figure).")


def _tumble_difference(results) -> str:
    by = {r.formulation: r for r in results}
    fixed = by["cardan"]
    verdict = (f"failed ({fixed.failure})" if fixed.failure else
               f"crawled: {fixed.stats.steps} steps against {by['quaternion'].stats.steps} "
               f"for the quaternion, attitude error {fixed.errors['attitude']:.2g} rad")
    return (f"Seed: the fixed sequence fails at gimbal lock, the adaptive switch and the "
            f"quaternion do not. Ours: fixed x-y-z {verdict}; adaptive "
            f"{by['cardan_adaptive'].switches} switches, {by['cardan_adaptive'].stats.steps} "
            "steps.")


def _top_difference(results) -> str:
    worst = max(r.errors["attitude"] for r in results)
    return (f"No seed figure: all three formulations against the closed form, worst "
            f"attitude error {worst:.2g} rad.")


ROTATION_DIFFERENCE = {"spin": _spin_difference, "tumble": _tumble_difference,
                       "top": _top_difference}


def draw_uncertainty(out: Path, full: bool) -> dict[str, tuple[str, str]]:
    """The figures of UNCERTAINTY_SET."""
    from youbot_dynamics.studies.uncertain_pendulum import (FAILURE_FLOOR, FAILURE_RATIO,
                                                            comparison, linear_propagation,
                                                            monte_carlo, plot_uncertainty)
    samples = SAMPLES_FULL if full else SAMPLES_SHORT
    linear = linear_propagation()
    sampled, phi = monte_carlo(samples)
    figures = comparison(linear, sampled)
    plot_uncertainty(linear, sampled, phi, str(out / "uncertainty.png"))
    fails = figures["linearisation_fails_at"]
    drawn = {"uncertainty.png": (
        f"at t = {figures['t_end']:g} s the 2-sigma band is {figures['band_width_linear_end']:.3g}"
        f" rad wide by linear propagation, {figures['band_width_monte_carlo_end']:.3g} rad by "
        f"{samples} Monte Carlo samples",
        "The seed draws the linear band only (Measurements.jl); the Monte Carlo shows where it "
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
        "No seed figure: the samples' spread at the end is not the linear normal.")
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


ROTATIONS_SET = FigureSet("rotations", specs(
    ("rotations_spin.png", "Spin about one axis: attitude error and middle angle of Cardan, "
     "adaptive Cardan, quaternion", "Seed: Cardan takes larger steps here."),
    ("rotations_tumble.png", "Tumbling through gimbal lock: attitude error and middle angle",
     "Seed: the fixed sequence fails at gimbal lock; adaptive and quaternion do not."),
    ("rotations_top.png", "Nutating top against its closed form: attitude error, middle "
     "angle, |q| drift", "Not a seed figure: the closed-form check."),
    ("rotations_spin_steps.png", "Spin with less and less wobble: Cardan steps against "
     "quaternion steps", "The seed's claim about step sizes, as a curve."),
), draw_rotations)

UNCERTAINTY_SET = FigureSet("uncertainty", specs(
    ("uncertainty.png", "Uncertain damped pendulum: phi with the linear and Monte Carlo "
     "+-sigma bands (two panels, as the seed's band plus the sigmas)",
     "Measurements.jl's band of phi(t)."),
    ("uncertainty_histogram.png", "Uncertain damped pendulum: phi at t = 10 s, samples "
     "against the linear normal", "No seed figure."),
    ("uncertainty_sigma_ratio.png", "Uncertain damped pendulum: sigma linear / sigma Monte "
     "Carlo over time", "No seed figure."),
), draw_uncertainty)
