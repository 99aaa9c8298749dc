"""Figures of the rotations study (document 000 section 1; studies/rotations.py): one PNG per
rotation run (attitude error against the closed-form top in rad, middle Cardan angle in
rad, |q| drift), and Cardan's steps against the quaternion's as the spin loses its wobble.
"""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from youbot_dynamics.model.rotations import SWITCH_ANGLE
from youbot_dynamics.studies.figures import FigureSet, panels, save, specs
from youbot_dynamics.studies.rotations import (RUNS, RotationResult, RotationsConfig,
                                               RotationsStudy, attitude_error, axisymmetric_top,
                                               rotations_study, spin_wobble_sweep)

ROTATION_RUNS = ("spin", "tumble", "top")


def plot_rotations(results: list[RotationResult], path: str) -> None:
    """PNG (matplotlib, Agg): per run, the attitude error against the closed form (log
    scale) of each formulation, and the middle angle of the Cardan formulations; legends
    beside the axes, clear of the curves."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    runs = list(dict.fromkeys(result.run for result in results))
    figure, axes = plt.subplots(2, len(runs), figsize=(7.5 * len(runs), 7), squeeze=False)
    for column, name in enumerate(runs):
        top, bottom = axes[0, column], axes[1, column]
        extra = []
        for result in (r for r in results if r.run == name):
            run = RUNS[name]
            inertia = np.array(run.inertia, dtype=float)
            references, _ = axisymmetric_top(inertia, run.rotation0, np.array(run.w0),
                                             result.t)
            error = np.maximum(attitude_error(result.rotations, references), 1e-17)
            label = (f"{result.formulation} ({result.stats.steps} steps)"
                     if result.failure is None else f"{result.formulation} (failed)")
            top.semilogy(result.t, error, label=label, linewidth=0.9)
            if result.middle_angle is not None:
                bottom.plot(result.t, result.middle_angle, label=result.formulation,
                            linewidth=0.9)
            if result.quaternion_norm is not None:
                drift = bottom.twinx()
                extra += drift.plot(result.t, result.quaternion_norm - 1.0, color="tab:green",
                                    label="quaternion |q| - 1 (right axis)", linewidth=0.9)
                drift.set_ylabel("|q| - 1 (dimensionless)")
        for level in (SWITCH_ANGLE, -SWITCH_ANGLE, math.pi / 2, -math.pi / 2):
            bottom.axhline(level, color="grey", linewidth=0.5,
                           linestyle=":" if abs(level) == SWITCH_ANGLE else "--")
        top.set_title(f"{name}: {RUNS[name].purpose}", fontsize=9)
        top.set_ylabel("attitude error vs closed form (rad)")
        bottom.set_ylabel("middle Cardan angle a2 (rad)")
        bottom.set_xlabel("t (s)")
        for axis, more in ((top, []), (bottom, extra)):
            axis.grid(True, alpha=0.3)
            handles, labels = axis.get_legend_handles_labels()
            handles += more
            axis.legend(handles, labels + [h.get_label() for h in more], fontsize=7,
                        loc="upper left", bbox_to_anchor=(1.12, 1.0), borderaxespad=0.0)
    figure.tight_layout()
    figure.savefig(path, dpi=110, bbox_inches="tight")
    plt.close(figure)


def draw_rotations(result: RotationsStudy | None, out: Path,
                   full: bool) -> dict[str, tuple[str, str]]:
    """The figures of ROTATIONS_SET, from ``result`` when it is the whole study at its
    defaults (every run, rk45 at 1e-8: ``study rotations``, the report's full form), else
    from a run of it."""
    study = result if result is not None and result.config == RotationsConfig() else None
    results = rotations_study() if study is None else study.results
    drawn = {}
    for name in ROTATION_RUNS:
        mine = [each for each in results if each.run == name]
        plot_rotations(mine, str(out / f"rotations_{name}.png"))
        drawn[f"rotations_{name}.png"] = (
            "; ".join(f"{r.formulation}: " + (f"failed ({r.failure})" if r.failure else
                                             f"{r.stats.steps} steps, attitude error "
                                             f"{r.errors['attitude']:.2g} rad")
                      for r in mine),
            ROTATION_DIFFERENCE[name](mine))
    if full:
        sweep = spin_wobble_sweep() if study is None else study.sweep
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
        "Document 000: Cardan angles take larger steps when the body turns mostly about one axis. "
        + ("Ours confirms it for the pure spin" if pure["cardan_steps"] < pure["quaternion_steps"]
           else "Ours does not show it even for the pure spin")
        + f" ({pure['cardan_steps']} against {pure['quaternion_steps']} steps); the ratio "
        "of Cardan's steps to the quaternion's grows with the wobble: " + ", ".join(
            f"{row['cardan_steps'] / row['quaternion_steps']:.2f} at {row['wobble']:g} rad/s"
            for row in sweep) + ".")
    return drawn


def _spin_difference(results) -> str:
    by = {r.formulation: r for r in results}
    return ("Document 000: Cardan is nearly linear here, so it should step larger. Ours: "
            f"{by['cardan'].stats.steps} Cardan steps against {by['quaternion'].stats.steps} "
            "quaternion steps at this wobble (see the sweep figure).")


def _tumble_difference(results) -> str:
    by = {r.formulation: r for r in results}
    fixed = by["cardan"]
    verdict = (f"failed ({fixed.failure})" if fixed.failure else
               f"crawled: {fixed.stats.steps} steps against {by['quaternion'].stats.steps} "
               f"for the quaternion, attitude error {fixed.errors['attitude']:.2g} rad")
    return (f"Document 000: the fixed sequence fails at gimbal lock, the adaptive switch and the "
            f"quaternion do not. Ours: fixed x-y-z {verdict}; adaptive "
            f"{by['cardan_adaptive'].switches} switches, {by['cardan_adaptive'].stats.steps} "
            "steps.")


def _top_difference(results) -> str:
    worst = max(r.errors["attitude"] for r in results)
    return (f"No document figure: all three formulations against the closed form, worst "
            f"attitude error {worst:.2g} rad.")


ROTATION_DIFFERENCE = {"spin": _spin_difference, "tumble": _tumble_difference,
                       "top": _top_difference}


ROTATIONS_SET = FigureSet("rotations", specs(
    ("rotations_spin.png", "Spin about one axis: attitude error and middle angle of Cardan, "
     "adaptive Cardan, quaternion", "Document 000: Cardan takes larger steps here."),
    ("rotations_tumble.png", "Tumbling through gimbal lock: attitude error and middle angle",
     "Document 000: the fixed sequence fails at gimbal lock; adaptive and quaternion do not."),
    ("rotations_top.png", "Nutating top against its closed form: attitude error, middle "
     "angle, |q| drift", "Not a document figure: the closed-form check."),
    ("rotations_spin_steps.png", "Spin with less and less wobble: Cardan steps against "
     "quaternion steps", "Document 000's claim about step sizes, as a curve."),
), draw_rotations)

