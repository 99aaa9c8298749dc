"""Figures of document 003 (the KTH Lagrange report; benchmarks.md section 4), from the
equations sympy derives (studies/lagrange.py), with the document's parameters and initial
states (appendix B, eqs. 3.1-3.2) first and, for the 3D pendulum, our second parameter set
(lagrange.OUR_3D) labelled beside them: the planar elastic double pendulum's coordinates,
phase portraits, particle path and energy; the 3D pendulum's coordinates, energy (with the
document's potential, eq. 2.22, and with ours), the sensitivity test, the particle's paths
and the friction runs (k = 0.1 N m s/rad).

The document's curves are images that its text does not hold; what it prints in numbers
(its eq. 3.4 and 3.5 energy levels follow from its formulas, the parting near t = 0.5 s of
Figs 13-14) is drawn beside ours. Runs: DOP853 at rtol = atol = 1e-9 (1e-12 with
``full``), outputs every 0.02 s.
"""
from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np

from youbot_dynamics.integrate.integrators import integrate
from youbot_dynamics.studies.figures import FigureSet, panels, save, specs
from youbot_dynamics.studies.lagrange import DOCUMENT_INITIAL, OUR_3D, equilibrium, model

#: The document's joint friction constant k (N m s/rad, Q_i = -k q_i'), appendix B.
FRICTION = 0.1
#: Spans (s) as the document plots them: coordinates 0-10, the 2D path 0-20 (Fig. 9), the
#: 3D path 0-30 (Fig. 16), friction energy and path 0-50 (Figs 20-21); the chaos test 0-3.
T_CONSERVATIVE, T_PATH_2D, T_PATH_3D, T_FRICTION, T_CHAOS = 10.0, 20.0, 30.0, 50.0, 3.0
#: The phase portrait of q3 spans 0-5 s (Fig. 8); the others 0-10 s.
T_PHASE = (10.0, 10.0, 5.0)
#: The sensitivity test's starts (Figs 13-14) and the document's parting time (s).
CHAOS_STARTS, DOCUMENT_PARTING = ((0.5, 0.1, 0.5), (0.6, 0.1, 0.5)), 0.5
#: |q2 difference| (rad) at which the two chaos runs count as parted.
PARTED = (0.01, 0.1)
#: The 3D path's start (appendix B): q1 = 0.5 rad, q3' = 1 rad/s, the rest zero.
PATH_3D_START = (0.5, 0.0, 0.0, 0.0, 0.0, 1.0)
#: Our second, labelled parameter set's label.
OURS_LABEL = "our parameters (m1 = 1, m2 = 0.1, l2 = 1, g = 9.81)"
DOCUMENT_LABEL = "document's parameters (m = 0.5, l = 0.5, g = 9.82)"


def simulate(name: str, x0, t_end: float, full: bool, overrides: dict | None = None):
    """(model, parameter values, solution) of one run of ``name`` from the state x0 (q, or
    (q, q') ) with parameter ``overrides`` (c: joint friction)."""
    lagrange = model(name)
    p = lagrange.parameter_values(overrides)
    tol = 1e-12 if full else 1e-9
    x0 = np.asarray(x0, dtype=float)
    x0 = np.r_[x0, np.zeros(len(x0))] if len(x0) == len(lagrange.q) else x0
    solution = integrate(lagrange.rhs(p), x0, np.linspace(0.0, t_end, int(t_end * 50) + 1),
                         "dop853", rtol=tol, atol=tol)
    return lagrange, p, solution


def coordinates_axis(axis, solution, units: tuple[str, ...], which=(0, 1, 2), label: str = ""):
    """q_i over time on one axis, y label from the units."""
    for i in which:
        axis.plot(solution.t, solution.x[:, i], linewidth=0.8,
                  label=f"q{i + 1} ({units[i]}){label}")
    axis.set_ylabel(", ".join(f"q{i + 1}" for i in which) + f" ({units[which[0]]})")
    axis.legend(fontsize=7, loc="upper right")


def energy_plot(path: Path, t, energies: dict[str, np.ndarray], title: str,
                levels: tuple[tuple[str, float], ...] = ()) -> None:
    """Energies (J) over time; horizontal levels (label, J) dashed."""
    figure, axis = panels(size=(7.5, 3.4))
    for label, energy in energies.items():
        axis.plot(t, energy, linewidth=0.8, label=label)
    for (label, value), color in zip(levels, ("red", "black", "grey")):
        axis.axhline(value, color=color, linewidth=0.7, linestyle="--", label=label)
    axis.set_xlabel("t (s)")
    axis.set_ylabel("E (J)")
    axis.legend(fontsize=7)
    save(figure, path, title)


def path_plot(path: Path, points: np.ndarray, title: str, planes=((0, 2),)) -> None:
    """The particle's path (m) in the given coordinate planes of N (0 x, 1 y, 2 z up)."""
    figure, axes = panels(1, len(planes), size=(4.2 * len(planes), 4.0), sharex=False)
    for axis, (a, b) in zip(np.atleast_1d(axes), planes):
        axis.plot(points[:, a], points[:, b], linewidth=0.5)
        axis.plot(points[0, a], points[0, b], "go", markersize=4, label="start")
        axis.set_xlabel(f"{'xyz'[a]} (m)")
        axis.set_ylabel(f"{'xyz'[b]} (m, up)" if b == 2 else f"{'xyz'[b]} (m)")
        axis.set_aspect("equal", adjustable="datalim")
        axis.legend(fontsize=7)
    save(figure, path, title)


def parameters_text(lagrange, p) -> str:
    """'m1 = 1, l = 0.5, ...'"""
    return ", ".join(f"{symbol} = {value:g}" for symbol, value in zip(lagrange.parameters, p))


def draw_lagrange_2d(result: object, out: Path, full: bool) -> dict[str, tuple[str, str]]:
    """The figures of LAGRANGE_2D_SET."""
    q0 = DOCUMENT_INITIAL["2d"][0]
    lagrange, p, solution = simulate("2d", q0, T_PATH_2D, full)
    span = solution.t <= T_CONSERVATIVE
    figure, axes = panels(2, 1, size=(7.5, 4.6))
    head = replace(solution, t=solution.t[span], x=solution.x[span])
    coordinates_axis(axes[0], head, ("rad", "rad", "m"), (0, 1))
    coordinates_axis(axes[1], head, ("rad", "rad", "m"), (2,))
    axes[1].set_xlabel("t (s)")
    save(figure, out / "lagrange_2d_q.png",
         "Planar elastic double pendulum from q1 = 0.8 rad at rest (document's Figs 3-5)")
    figure, axes = panels(1, 3, size=(11.0, 3.6), sharex=False)
    for i, (axis, t_end) in enumerate(zip(axes, T_PHASE)):
        shown = solution.t <= t_end
        axis.plot(solution.x[shown, i], solution.x[shown, 3 + i], linewidth=0.5)
        unit = "m" if i == 2 else "rad"
        axis.set_xlabel(f"q{i + 1} ({unit})")
        axis.set_ylabel(f"u{i + 1} = q{i + 1}' ({unit}/s)")
        axis.set_title(f"0-{t_end:g} s (Fig. {6 + i})", fontsize=8)
    save(figure, out / "lagrange_2d_phase.png",
         "Planar elastic double pendulum: phase portraits (document's Figs 6-8)")
    bead = lagrange.particle_path(solution.x, p)
    path_plot(out / "lagrange_2d_path.png", bead,
              f"Planar elastic double pendulum: the bead's path, 0-{T_PATH_2D:g} s (Fig. 9)")
    energy = lagrange.energy_of(solution.x[span], p)
    drift = float(np.max(np.abs(energy - energy[0])) / abs(energy[0]))
    energy_plot(out / "lagrange_2d_energy.png", head.t, {"E(t) - E(0)": energy - energy[0]},
                "Planar elastic double pendulum: energy error (conservative)")
    _, pf, damped = simulate("2d", q0, 25.0, full, {"c": FRICTION})
    damped_energy = lagrange.energy_of(damped.x, pf)
    minimum = float(lagrange.energy_of(np.r_[equilibrium("2d", pf), np.zeros(3)], pf)[0])
    energy_plot(out / "lagrange_2d_friction_energy.png", damped.t, {"E(t)": damped_energy},
                f"Planar elastic double pendulum with joint friction k = {FRICTION:g} N m s/rad",
                (("potential minimum (hanging, spring stretched by m2 g / k)", minimum),))
    rises = [np.sign(np.diff(solution.x[span, i])) for i in range(3)]
    return {
        "lagrange_2d_q.png": (
            f"parameters {parameters_text(lagrange, p)}; at t = {T_CONSERVATIVE:g} s q = "
            + ", ".join(f"{value:.4g}" for value in head.x[-1, :3]),
            "Document: the same start and parameters; its curves are images its text does "
            "not hold, and it says none is periodic."),
        "lagrange_2d_phase.png": (
            "turning points over 0-10 s: " + ", ".join(
                f"q{i + 1} {int(np.sum(r[1:] != r[:-1]))}" for i, r in enumerate(rises)),
            "Document: phase portraits u_i against q_i, no closed orbit (not periodic); ours "
            "are not closed either."),
        "lagrange_2d_path.png": (
            f"the bead stays within {np.max(np.linalg.norm(bead, axis=1)):.3g} m of O; "
            f"lowest z {bead[:, 2].min():.3g} m",
            "Document's Fig. 9: the bead's path over 20 s (an image)."),
        "lagrange_2d_energy.png": (
            f"E(0) = {energy[0]:.6g} J, max relative drift {drift:.2g}",
            "The document states the energy is conserved; ours holds it to the integrator's "
            "tolerance."),
        "lagrange_2d_friction_energy.png": (
            f"E from {damped_energy[0]:.4g} J to {damped_energy[-1]:.4g} J at t = 25 s; the "
            f"potential minimum is {minimum:.4g} J",
            "The document shows friction for the 3D pendulum only; the 2D one decays the "
            f"same way, E rising in {int(np.sum(np.diff(damped_energy) > 1e-9))} of "
            f"{len(damped_energy) - 1} output intervals."),
    }


def document_energy_levels(p) -> tuple[float, float]:
    """The document's eq. 3.4 and 3.5 (J): its potential (2.22, without q3) at its start
    (3.2), every angle 1 rad, and at q1 = q2 = 0."""
    values = dict(zip(("m1", "l", "m2", "l2", "g", "c"), p))
    m, g, length = values["m1"], values["g"], values["l"]
    start = -(m * g * length * np.cos(1.0) / 2) - m * g * (length * np.cos(1.0)
                                                           + length * np.cos(2.0))
    return float(start), float(-m * g * length * (0.5 + 2.0))


def parting_times(first, second) -> list[float | None]:
    """The first time (s) the q2 curves differ by each PARTED level (None: never)."""
    gap = np.abs(first.x[:, 1] - second.x[:, 1])
    return [float(first.t[np.argmax(gap > level)]) if np.any(gap > level) else None
            for level in PARTED]


def chaos_figure(out: Path, full: bool) -> tuple[str, str]:
    """Figs 13-14: q2 from the two starts, the document's parameters and ours."""
    figure, axes = panels(2, 1, size=(7.5, 5.0))
    texts = []
    for axis, (label, overrides) in zip(axes, ((DOCUMENT_LABEL, {}), (OURS_LABEL, OUR_3D))):
        runs = [simulate("3d", start, T_CHAOS, full, overrides)[2] for start in CHAOS_STARTS]
        for start, run in zip(CHAOS_STARTS, runs):
            axis.plot(run.t, run.x[:, 1], linewidth=0.8, label=f"q2 from q1(0) = {start[0]:g}")
        axis.axvline(DOCUMENT_PARTING, color="red", linewidth=0.8, linestyle="--",
                     label="document: part near 0.5 s")
        parted = parting_times(*runs)
        texts.append(f"{label}: " + ", ".join(
            f"{level:g} rad from {time:.2f} s" if time is not None else
            f"< {level:g} rad throughout" for level, time in zip(PARTED, parted)))
        axis.set_ylabel("q2 (rad)")
        axis.set_title(label, fontsize=8)
        axis.legend(fontsize=7, loc="lower left")
    axes[1].set_xlabel("t (s)")
    save(figure, out / "lagrange_3d_chaos.png",
         "3D pendulum: q2 from (0.5, 0.1, 0.5) and (0.6, 0.1, 0.5) rad (Figs 13-14)")
    return ("the q2 curves differ by " + "; ".join(texts),
            "Document: about the same to t = 0.5 s, then different (read by eye). The 0.1 "
            "rad change of q1 changes the swing at once; with its parameters the gap stays "
            "small (the motion from these starts is nearly periodic), with ours it grows.")


def draw_lagrange_3d(result: object, out: Path, full: bool) -> dict[str, tuple[str, str]]:
    """The figures of LAGRANGE_3D_SET."""
    q0 = DOCUMENT_INITIAL["3d"][0]
    lagrange, p, solution = simulate("3d", q0, T_CONSERVATIVE, full)
    _, p_ours, ours = simulate("3d", q0, T_CONSERVATIVE, full, OUR_3D)
    figure, axes = panels(2, 1, size=(7.5, 5.0))
    for axis, (label, run) in zip(axes, ((DOCUMENT_LABEL, solution), (OURS_LABEL, ours))):
        coordinates_axis(axis, run, ("rad",) * 3)
        axis.set_title(label, fontsize=8)
    axes[1].set_xlabel("t (s)")
    save(figure, out / "lagrange_3d_q.png",
         "3D pendulum from q = (1, 1, 1) rad at rest (document's Figs 10-12)")
    energy = lagrange.energy_of(solution.x, p)
    document_model, p_doc, document_run = simulate("3d-document", q0, T_CONSERVATIVE, full)
    document_energy = document_model.energy_of(document_run.x, p_doc)
    kinetic = energy - lagrange.energy_of(np.c_[solution.x[:, :3], np.zeros((len(solution.t), 3))], p)
    document_form = kinetic + document_model.energy_of(
        np.c_[solution.x[:, :3], np.zeros((len(solution.t), 3))], p_doc)
    start_level, rest_level = document_energy_levels(p)
    energy_plot(out / "lagrange_3d_energy.png", solution.t,
                {"ours: T + V (V with q3), our equations": energy,
                 "document's V (2.22), its own equations": document_energy,
                 "T + document's V along our motion": document_form},
                "3D pendulum: total energy (document's Fig. 15)",
                (("document's eq. 3.4 from its formula", start_level),))
    drift = float(np.max(np.abs(energy - energy[0])) / abs(energy[0]))
    drawn = {
        "lagrange_3d_q.png": (
            f"{DOCUMENT_LABEL}: at t = {T_CONSERVATIVE:g} s q = "
            + ", ".join(f"{value:.4g}" for value in solution.x[-1, :3])
            + f"; {OURS_LABEL}: q = " + ", ".join(f"{value:.4g}" for value in ours.x[-1, :3]),
            "Document: chaotic q1..q3 (images); ours from the same start and parameters, "
            "with V keeping q3 (the document's V omits it)."),
        "lagrange_3d_energy.png": (
            f"ours E = {energy[0]:.4g} J (max relative drift {drift:.2g}); the document's "
            f"equations conserve theirs at {document_energy[0]:.4g} J; along our motion T + "
            f"its V swings by {np.ptp(document_form):.3g} J",
            f"Document: E constant at its eq. 3.4 ({start_level:.4g} J from its formula); "
            "ours is constant too, at a lower level, because our V keeps the particle's "
            "cos q3 height."),
        "lagrange_3d_chaos.png": chaos_figure(out, full),
    }
    _, _, path_run = simulate("3d", PATH_3D_START, T_PATH_3D, full)
    tip = lagrange.particle_path(path_run.x, p)
    path_plot(out / "lagrange_3d_path.png", tip,
              f"3D pendulum: the particle's path, 0-{T_PATH_3D:g} s (document's Fig. 16)",
              ((1, 2), (0, 2)))
    drawn["lagrange_3d_path.png"] = (
        f"from q1 = 0.5 rad, q3' = 1 rad/s: x spans {np.ptp(tip[:, 0]):.3g} m, y "
        f"{np.ptp(tip[:, 1]):.3g} m, z {np.ptp(tip[:, 2]):.3g} m",
        "Document's Fig. 16: the path over 30 s from a smaller start (the appendix's: q1 = "
        "0.5, q3' = 1), an image.")
    _, pf, damped = simulate("3d", q0, T_FRICTION, full, {"c": FRICTION})
    shown = damped.t <= T_CONSERVATIVE
    figure, axis = panels(size=(7.5, 3.6))
    head = replace(damped, t=damped.t[shown], x=damped.x[shown])
    coordinates_axis(axis, head, ("rad",) * 3)
    axis.set_xlabel("t (s)")
    save(figure, out / "lagrange_3d_friction_q.png",
         f"3D pendulum with joint friction k = {FRICTION:g} N m s/rad (Figs 17-19)")
    damped_energy = lagrange.energy_of(damped.x, pf)
    energy_plot(out / "lagrange_3d_friction_energy.png", damped.t, {"ours: E(t)": damped_energy},
                f"3D pendulum with joint friction k = {FRICTION:g} N m s/rad (Fig. 21)",
                (("document's eq. 3.5: hanging, q1 = q2 = 0", rest_level),
                 ("document's eq. 3.4: its start", start_level)))
    friction_tip = lagrange.particle_path(damped.x, pf)
    path_plot(out / "lagrange_3d_friction_path.png", friction_tip,
              f"3D pendulum with friction: the particle's path, 0-{T_FRICTION:g} s (Fig. 20)",
              ((1, 2), (0, 2)))
    increasing = int(np.sum(np.diff(damped_energy) > 1e-9))
    drawn["lagrange_3d_friction_q.png"] = (
        f"|q| at t = {T_CONSERVATIVE:g} s: {np.max(np.abs(head.x[-1, :3])):.3g} rad, at "
        f"{T_FRICTION:g} s: {np.max(np.abs(damped.x[-1, :3])):.3g} rad",
        "As the document: the amplitudes decay towards q = 0.")
    drawn["lagrange_3d_friction_energy.png"] = (
        f"E from {damped_energy[0]:.4g} J to {damped_energy[-1]:.4g} J at {T_FRICTION:g} s; "
        f"{increasing} output intervals where E rose",
        f"Document: E decays from its eq. 3.4 ({start_level:.4g} J) to its eq. 3.5 "
        f"({rest_level:.4g} J); ours starts lower ({damped_energy[0]:.4g} J, V keeps q3) "
        "and tends to the same minimum.")
    drawn["lagrange_3d_friction_path.png"] = (
        f"end point {np.round(friction_tip[-1], 3).tolist()} m; hanging point (0, 0, "
        f"{-pf[1] - pf[3]:g}) m",
        "As the document's Fig. 20: the particle tends to the point under O.")
    return drawn


LAGRANGE_2D_SET = FigureSet("lagrange-2d", specs(
    ("lagrange_2d_q.png", "Planar elastic double pendulum: q1, q2 (rad) and q3 (m) from "
     "q1 = 0.8 rad", "Document 003 Figs 3-5."),
    ("lagrange_2d_phase.png", "Planar elastic double pendulum: phase portraits u_i against "
     "q_i", "Document 003 Figs 6-8."),
    ("lagrange_2d_path.png", "Planar elastic double pendulum: the bead's path over 20 s",
     "Document 003 Fig. 9."),
    ("lagrange_2d_energy.png", "Planar elastic double pendulum: energy error E(t) - E(0)",
     "The document: energy conserved."),
    ("lagrange_2d_friction_energy.png", "Planar elastic double pendulum with joint "
     "friction: E(t) and the potential minimum", "Not in the document for 2D (see 3D)."),
), draw_lagrange_2d)

LAGRANGE_3D_SET = FigureSet("lagrange-3d", specs(
    ("lagrange_3d_q.png", "3D pendulum, conservative: q1, q2, q3 from (1, 1, 1) rad, the "
     "document's parameters and ours", "Document 003 Figs 10-12."),
    ("lagrange_3d_energy.png", "3D pendulum, conservative: total energy, ours and with the "
     "document's potential", "Document 003 Fig. 15 and eq. 3.4."),
    ("lagrange_3d_chaos.png", "3D pendulum, sensitivity: q2 from q1(0) = 0.5 and 0.6 rad",
     "Document 003 Figs 13-14: the q2 curves agree to about t = 0.5 s and then part."),
    ("lagrange_3d_path.png", "3D pendulum: the particle's path over 30 s",
     "Document 003 Fig. 16."),
    ("lagrange_3d_friction_q.png", "3D pendulum with joint friction: q1, q2, q3 decaying",
     "Document 003 Figs 17-19."),
    ("lagrange_3d_friction_energy.png", "3D pendulum with joint friction: E(t) tending to "
     "the potential minimum", "Document 003 Fig. 21 and eq. 3.5."),
    ("lagrange_3d_friction_path.png", "3D pendulum with joint friction: the particle's "
     "path over 50 s", "Document 003 Fig. 20."),
), draw_lagrange_3d)
