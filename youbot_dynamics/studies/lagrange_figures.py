"""Figures of the KTH Lagrange report (benchmarks.md section 4), from the equations sympy
derives (studies/lagrange.py): the planar elastic double pendulum's q1..q3 and energy, the
3D pendulum conservative and with joint friction (decaying to the potential minimum), the
chaos test, and what the seed's potential (which omits q3) would call the energy.

Runs: DOP853 at rtol = atol = 1e-9 (1e-12 with ``full``) from the seed's initial states,
outputs every 0.02 s.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from youbot_dynamics.integrate.integrators import integrate
from youbot_dynamics.studies.figures import FigureSet, panels, save, specs
from youbot_dynamics.studies.lagrange import SEED_INITIAL, equilibrium, model

#: Joint friction coefficient of the friction runs (N m s/rad, Q_i = -c q_i').
FRICTION = 0.05
#: Spans (s): the conservative runs, the friction runs (short form, full form), the chaos
#: test.
T_CONSERVATIVE, T_FRICTION, T_CHAOS = 10.0, {False: 25.0, True: 40.0}, 3.0
#: The chaos test's second start: q1 = 0.6 instead of 0.5.
CHAOS_Q1 = 0.6
#: |q2 difference| (rad) at which the two chaos runs count as parted.
PARTED = (0.01, 0.1)


def simulate(name: str, q0, friction: float, t_end: float, full: bool):
    """(model, parameter values, solution) of one run from q0 at rest."""
    lagrange = model(name)
    p = lagrange.parameter_values({"c": friction})
    tol = 1e-12 if full else 1e-9
    x0 = np.r_[q0, np.zeros(len(q0))]
    solution = integrate(lagrange.rhs(p), x0, np.linspace(0.0, t_end, int(t_end * 50) + 1),
                         "dop853", rtol=tol, atol=tol)
    return lagrange, p, solution


def coordinates_plot(path: Path, solution, title: str, units: tuple[str, ...]) -> None:
    """q1..q3 over time."""
    figure, axis = panels(size=(7.5, 3.6))
    for i, unit in enumerate(units):
        axis.plot(solution.t, solution.x[:, i], linewidth=0.8, label=f"q{i + 1} ({unit})")
    axis.set_xlabel("t (s)")
    axis.legend(fontsize=7)
    save(figure, path, title)


def energy_plot(path: Path, t, energies: dict[str, np.ndarray], title: str,
                level: tuple[str, float] | None = None) -> None:
    """Energies (J) over time; an optional horizontal level (label, J)."""
    figure, axis = panels(size=(7.5, 3.4))
    for label, energy in energies.items():
        axis.plot(t, energy, linewidth=0.8, label=label)
    if level is not None:
        axis.axhline(level[1], color="red", linewidth=0.7, linestyle="--", label=level[0])
    axis.set_xlabel("t (s)")
    axis.set_ylabel("J")
    axis.legend(fontsize=7)
    save(figure, path, title)


def parameters_text(lagrange, p) -> str:
    """'m1 = 1, l = 0.5, ...'"""
    return ", ".join(f"{symbol} = {value:g}" for symbol, value in zip(lagrange.parameters, p))


def conservative_figures(out: Path, name: str, q0, label: str, units: tuple[str, ...], full: bool):
    """The conservative run of model ``name`` from q0 at rest, its q plot and its energy-error
    plot (``lagrange_<name>_q.png``, ``lagrange_<name>_energy.png``); (model, parameter values,
    solution, energy (J), max relative energy drift)."""
    lagrange, p, solution = simulate(name, q0, 0.0, T_CONSERVATIVE, full)
    start = ", ".join(f"{value:g}" for value in q0)
    coordinates_plot(out / f"lagrange_{name}_q.png", solution,
                     f"{label} from ({start}), conservative: q1, q2, q3", units)
    energy = lagrange.energy_of(solution.x, p)
    drift = float(np.max(np.abs(energy - energy[0])) / abs(energy[0]))
    energy_plot(out / f"lagrange_{name}_energy.png", solution.t, {"E - E(0)": energy - energy[0]},
                f"{label}: energy error (conservative)")
    return lagrange, p, solution, energy, drift


def draw_lagrange_2d(result: object, out: Path, full: bool) -> dict[str, tuple[str, str]]:
    """The figures of LAGRANGE_2D_SET."""
    q0 = SEED_INITIAL["2d"][0]
    lagrange, p, solution, energy, drift = conservative_figures(out, "2d", q0, "Planar elastic double pendulum",
                                                                ("rad", "rad", "m"), full)
    _, pf, damped = simulate("2d", q0, FRICTION, T_FRICTION[full], full)
    damped_energy = lagrange.energy_of(damped.x, pf)
    rest = np.r_[equilibrium("2d", pf), np.zeros(3)]
    minimum = float(lagrange.energy_of(rest, pf)[0])
    energy_plot(out / "lagrange_2d_friction_energy.png", damped.t, {"E(t)": damped_energy},
                f"Planar elastic double pendulum with joint friction c = {FRICTION:g}",
                ("potential minimum", minimum))
    parameters = parameters_text(lagrange, p)
    return {
        "lagrange_2d_q.png": (
            f"parameters {parameters}; at t = {T_CONSERVATIVE:g} s q = "
            + ", ".join(f"{value:.4g}" for value in solution.x[-1, :3]),
            "Same start (q1 = 0.8, rest) and the seed appendix's parameters; the seed's "
            "curves are not in benchmarks.md: compare by eye."),
        "lagrange_2d_energy.png": (
            f"E(0) = {energy[0]:.6g} J, max relative drift {drift:.2g}",
            "The seed states the energy is conserved; ours holds it to the integrator's "
            "tolerance."),
        "lagrange_2d_friction_energy.png": (
            f"E from {damped_energy[0]:.4g} J to {damped_energy[-1]:.4g} J at "
            f"t = {T_FRICTION[full]:g} s; the potential minimum (hanging, spring stretched by "
            f"m2 g / k) is {minimum:.4g} J",
            "The seed shows friction for the 3D pendulum only; the 2D one decays the same "
            f"way, E rising in {int(np.sum(np.diff(damped_energy) > 1e-9))} of "
            f"{len(damped_energy) - 1} output intervals."),
    }


def draw_lagrange_3d(result: object, out: Path, full: bool) -> dict[str, tuple[str, str]]:
    """The figures of LAGRANGE_3D_SET."""
    q0 = SEED_INITIAL["3d"][0]
    lagrange, p, solution, energy, drift = conservative_figures(out, "3d", q0, "3D pendulum", ("rad", "rad", "rad"),
                                                                full)
    drawn = {
        "lagrange_3d_q.png": (
            f"parameters {parameters_text(lagrange, p)}; at t = {T_CONSERVATIVE:g} s q = "
            + ", ".join(f"{value:.4g}" for value in solution.x[-1, :3]),
            "Our parameters are chosen (the seed's are not in benchmarks.md): a light "
            "particle on a long arm, so that the chaos test shows."),
        "lagrange_3d_energy.png": (
            f"E(0) = {energy[0]:.6g} J, max relative drift {drift:.2g}",
            "Conserved, as the seed says."),
    }
    potential = lagrange.energy_of(np.c_[solution.x[:, :3], np.zeros((len(solution.t), 3))], p)
    no_q3 = np.c_[solution.x[:, :2], np.zeros((len(solution.t), 4))]
    seed_form = energy - potential + lagrange.energy_of(no_q3, p)
    energy_plot(out / "lagrange_3d_seed_potential.png", solution.t,
                {"ours: T + V(q1, q2, q3)": energy - energy[0],
                 "seed's form: T + V(q1, q2, 0)": seed_form - seed_form[0]},
                "3D pendulum: the energy with and without q3 in the potential")
    drawn["lagrange_3d_seed_potential.png"] = (
        f"along our motion, T + V(q1, q2, 0) swings by "
        f"{np.ptp(seed_form):.3g} J against {np.ptp(energy):.2g} J for ours",
        "The seed's potential omits q3; it is right only while q1 = q3 = 0, and the energy "
        "it defines is not conserved by the true motion (ours keeps q3).")

    _, pf, damped = simulate("3d", q0, FRICTION, T_FRICTION[full], full)
    coordinates_plot(out / "lagrange_3d_friction_q.png", damped,
                     f"3D pendulum with joint friction c = {FRICTION:g}: q1, q2, q3",
                     ("rad", "rad", "rad"))
    damped_energy = lagrange.energy_of(damped.x, pf)
    minimum = float(lagrange.energy_of(np.zeros(6), pf)[0])
    energy_plot(out / "lagrange_3d_friction_energy.png", damped.t, {"E(t)": damped_energy},
                f"3D pendulum with joint friction c = {FRICTION:g}",
                ("potential minimum (hanging)", minimum))
    increasing = int(np.sum(np.diff(damped_energy) > 1e-9))
    drawn["lagrange_3d_friction_q.png"] = (
        f"|q| at t = {T_FRICTION[full]:g} s: {np.max(np.abs(damped.x[-1, :3])):.3g} rad",
        "As the seed: the motion decays to the hanging equilibrium q = 0.")
    drawn["lagrange_3d_friction_energy.png"] = (
        f"E from {damped_energy[0]:.4g} J to {damped_energy[-1]:.4g} J; potential minimum "
        f"{minimum:.4g} J; {increasing} output intervals where E rose",
        "As the seed: the energy tends to the potential minimum.")

    _, _, other = simulate("3d", (CHAOS_Q1, *q0[1:]), 0.0, T_CHAOS, full)
    _, _, base = simulate("3d", q0, 0.0, T_CHAOS, full)
    figure, axis = panels(size=(7.5, 3.6))
    axis.plot(base.t, base.x[:, 1], linewidth=0.8, label=f"q2 from q1 = {q0[0]:g}")
    axis.plot(other.t, other.x[:, 1], linewidth=0.8, label=f"q2 from q1 = {CHAOS_Q1:g}")
    gap = np.abs(base.x[:, 1] - other.x[:, 1])
    parted = [float(base.t[np.argmax(gap > level)]) if np.any(gap > level) else None
              for level in PARTED]
    for time in parted:
        if time is not None:
            axis.axvline(time, color="grey", linewidth=0.6, linestyle=":")
    axis.set_xlabel("t (s)")
    axis.set_ylabel("q2 (rad)")
    axis.legend(fontsize=7)
    save(figure, out / "lagrange_3d_chaos.png",
         "3D pendulum: q2 from (0.5, 0.1, 0.5) and from (0.6, 0.1, 0.5)")
    drawn["lagrange_3d_chaos.png"] = (
        "the q2 curves differ by " + ", ".join(
            f"{level:g} rad from t = {time:.2f} s" if time is not None else
            f"less than {level:g} rad throughout" for level, time in zip(PARTED, parted)),
        "Seed: they agree to about t = 0.5 s, then part. Ours part later with our chosen "
        "parameters (the seed's are not given), but part they do.")
    return drawn


LAGRANGE_2D_SET = FigureSet("lagrange-2d", specs(
    ("lagrange_2d_q.png", "Planar elastic double pendulum: q1, q2 (rad), q3 (m) from q1 = 0.8",
     "The KTH report's q1..q3 plot."),
    ("lagrange_2d_energy.png", "Planar elastic double pendulum: energy error E(t) - E(0)",
     "The report's energy plot: constant."),
    ("lagrange_2d_friction_energy.png", "Planar elastic double pendulum with joint "
     "friction: E(t) and the potential minimum", "Not in the report for 2D (see 3D)."),
), draw_lagrange_2d)

LAGRANGE_3D_SET = FigureSet("lagrange-3d", specs(
    ("lagrange_3d_q.png", "3D pendulum, conservative: q1, q2, q3 from (0.5, 0.1, 0.5)",
     "The report's conservative 3D plot."),
    ("lagrange_3d_energy.png", "3D pendulum, conservative: energy error E(t) - E(0)",
     "The report: total energy constant."),
    ("lagrange_3d_seed_potential.png", "3D pendulum: energy with our potential and with "
     "the seed's (q3 omitted), along the same motion", "The seed's potential omits q3."),
    ("lagrange_3d_friction_q.png", "3D pendulum with joint friction: q1, q2, q3 decaying",
     "The report: with joint friction the motion decays to the hanging equilibrium."),
    ("lagrange_3d_friction_energy.png", "3D pendulum with joint friction: E(t) tending to "
     "the potential minimum", "The report: the energy tends to its potential minimum."),
    ("lagrange_3d_chaos.png", "3D pendulum, chaos: q2 from (0.5, 0.1, 0.5) against "
     "q1 = 0.6", "The report: the q2 curves agree to about t = 0.5 s and then part."),
), draw_lagrange_3d)
