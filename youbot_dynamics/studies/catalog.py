"""The report's catalogue: one :class:`Section` per study of the page, in page order, with
the function that runs the study and returns the text its command prints, and the figure
set (studies/figures.py) that draws the source document's figures beside ours.

A section runs the study through its own module (``run(config)`` and ``text(result)``,
as ``youbot-dynamics study NAME`` does), never through the command line. The product's
accuracy tools that the page also shows (a scene's uncertain parameters, contact at its
extremes, work-precision) run through accuracy/. Short forms (``full`` False) keep the
whole report to minutes on two cores; ``full`` runs the source documents' sizes. Studies that sweep
on Dask themselves pass ``workers=enclosing_workers()``: their cases go to the cluster the
report runs them on (every worker takes some while the section waits), or run serially
when the report is serial (``--workers 0``).
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Callable

from youbot_dynamics.accuracy import scene_uncertainty
from youbot_dynamics.accuracy.contact_extremes import TABLES
from youbot_dynamics.accuracy.propagation import comparison, plot_uncertainty
from youbot_dynamics.accuracy.sweeps import enclosing_workers
from youbot_dynamics.accuracy.work_precision import work_precision
from youbot_dynamics.io.text_tables import records_table
from youbot_dynamics.scene.schema import load_scene
from youbot_dynamics.studies import (bdf_study, elastic_pendulum, equation_figures, lagrange,
                                     lagrange_figures, pendulum_figures, pipeline_report,
                                     planar_base_parameters, rotations, rotations_figures,
                                     squeezer, squeezer_figures, structure, uncertain_pendulum,
                                     uncertain_pendulum_figures, unicycle, woodpecker,
                                     woodpecker_figures)
from youbot_dynamics.studies.figures import FigureSet, FigureSpec


@dataclass(frozen=True)
class Section:
    """One section of the page: its ``name`` (anchor, ``--only``), title, the command line
    that reproduces it (short form; ``full_command`` for the document's sizes, None: the same),
    the source document's figure or verdict (``seed``), how ours differs in method or
    criterion, the PNGs its run
    writes into the report folder, and ``run(out_dir, full) -> (text, result)``: the text
    the command prints and the study's result, which its figure set draws from."""

    name: str
    title: str
    command: tuple[str, ...]
    seed: str
    run: Callable[[Path, bool], tuple[str, object]]
    method: str = ""
    full_command: tuple[str, ...] | None = None
    files: tuple[str, ...] = ()

    def command_line(self, full: bool) -> str:
        """``youbot-dynamics ...`` as a user types it (files relative to the report folder)."""
        argv = self.full_command if full and self.full_command is not None else self.command
        return "youbot-dynamics " + " ".join(argv)


def pendulum_tables_section(out: Path, full: bool) -> tuple[str, object]:
    """``study pendulum-tables``."""
    rows = elastic_pendulum.elastic_pendulum_study()
    return elastic_pendulum.tables_text(rows), rows


def bdf_section(out: Path, full: bool) -> tuple[str, object]:
    """``study bdf [--short]``."""
    result = bdf_study.run(bdf_study.BdfConfig(short=not full, workers=enclosing_workers(),
                                                progress=False))
    return bdf_study.text(result), result


def squeezer_section(out: Path, full: bool) -> tuple[str, object]:
    """``study squeezer``."""
    result = squeezer.run(squeezer.SqueezerConfig())
    return squeezer.text(result), result


def suppression_section(out: Path, full: bool) -> tuple[str, object]:
    """``study squeezer --table``."""
    result = squeezer.run_suppression(squeezer.SuppressionConfig())
    return squeezer.suppression_text(result), result


def woodpecker_section(out: Path, full: bool) -> tuple[str, object]:
    """``study woodpecker``."""
    result = woodpecker.run(woodpecker.WoodpeckerConfig())
    return woodpecker.text(result), result


def lagrange_section(problem: str) -> Callable[[Path, bool], tuple[str, object]]:
    """``study lagrange PROBLEM``."""
    def run(out: Path, full: bool) -> tuple[str, object]:
        result = lagrange.run(lagrange.LagrangeConfig(problem=problem))
        return lagrange.text(result), result
    return run


def structure_section(example: str) -> Callable[[Path, bool], tuple[str, object]]:
    """``study structure EXAMPLE``."""
    def run(out: Path, full: bool) -> tuple[str, object]:
        report = structure.structure_report(example)
        return structure.structure_text(report), report
    return run


def pipeline_section(example: str) -> Callable[[Path, bool], tuple[str, object]]:
    """``study pipeline EXAMPLE``."""
    def run(out: Path, full: bool) -> tuple[str, object]:
        report = pipeline_report.run(pipeline_report.PipelineConfig(example=example))
        return pipeline_report.text(report), report
    return run


def rotations_section(out: Path, full: bool) -> tuple[str, object]:
    """``study rotations`` (short: the tumble and top runs)."""
    runs = tuple(rotations.RUNS) if full else ("tumble", "top")
    result = rotations.run(rotations.RotationsConfig(runs=runs))
    return rotations.text(result), result


def uncertainty_section(out: Path, full: bool) -> tuple[str, object]:
    """``study uncertainty`` (200 samples short, 1000 full)."""
    result = uncertain_pendulum.run(uncertain_pendulum.UncertaintyConfig(
        samples=1000 if full else 200, workers=enclosing_workers()))
    return uncertain_pendulum.text(result), result


def unicycle_section(out: Path, full: bool) -> tuple[str, object]:
    """``study unicycle`` (document 002's parameters)."""
    result = unicycle.run(unicycle.UnicycleConfig())
    return unicycle.text(result), result


def base_parameters_section(out: Path, full: bool) -> tuple[str, object]:
    """``study base-parameters``."""
    result = planar_base_parameters.run()
    return planar_base_parameters.text(result), result


#: The scene, output and file of the scene-uncertainty section.
SCENE, SCENE_OUTPUT, SCENE_PLOT = "uncertain_pendulum", "q[pivot]", "scene_uncertainty.png"


def scene_uncertainty_section(out: Path, full: bool) -> tuple[str, object]:
    """``scene-uncertainty uncertain_pendulum --output q[pivot]`` with its band plot (40
    samples over 3 s short; 1000 over the scene's 10 s full)."""
    samples, duration = (1000, None) if full else (40, 3.0)
    linear, _ = scene_uncertainty.linear_propagation(SCENE, SCENE_OUTPUT, duration,
                                                   workers=enclosing_workers())
    sampled, keys, _, traces = scene_uncertainty.monte_carlo(SCENE, SCENE_OUTPUT, samples, 0,
                                                             duration, workers=enclosing_workers())
    figures = comparison(linear, sampled)
    plot_uncertainty(linear, sampled, traces, str(out / SCENE_PLOT), f"{SCENE}: {SCENE_OUTPUT}",
                     SCENE_OUTPUT)
    return (scene_uncertainty.summary_text(SCENE, SCENE_OUTPUT, keys, samples, 0, figures)
            + f"\nplot written to {out / SCENE_PLOT}"), figures


def contact_extremes_section(out: Path, full: bool) -> tuple[str, object]:
    """``contact-extremes`` (short: without the stiffness sweep)."""
    tables = {name: TABLES[name]() for name in
              (list(TABLES) if full else ["light_on_heavy", "tunnelling", "grasp"])}
    return "\n".join(f"## {name}\n\n{records_table(rows)}\n"
                     for name, rows in tables.items()), tables


#: The work-precision section's scene and folder.
WORK_SCENE, WORK_FOLDER = "arm_swing", "work_precision"


def work_precision_section(out: Path, full: bool) -> tuple[str, object]:
    """``work-precision --scene arm_swing`` (0.2 s of the scene short)."""
    scene = load_scene(WORK_SCENE)
    if not full:
        scene = scene.with_duration(0.2)
    study = work_precision(scene, out / WORK_FOLDER, progress=False,
                           workers=enclosing_workers())
    return (study.files[1].read_text(encoding="utf-8") + "\n"
            + "written: " + ", ".join(str(f) for f in study.files)), study


SECTIONS: tuple[Section, ...] = (
    Section("pendulum-tables", "Elastic pendulum: explicit Euler, CVODE statistics, energy "
            "error (document 001 Tables 1, 5-7)", ("study", "pendulum-tables"),
            run=pendulum_tables_section,
            seed="The document's column of each table: verdicts (stable / accurate) of explicit "
                 "Euler over k and N, and the document's CVODE steps and f-evals at rtol = atol = "
                 "1e-6.",
            method="Our verdict is an energy criterion (stated above the table); study bdf "
                   "judges position against a DOP853 reference instead."),
    Section("bdf", "Fixed-step BDF1-4, stability regions, CVODE order caps (document 001 "
            "sections 1.6-1.9, Tables 1-4)", ("study", "bdf", "--short"),
            full_command=("study", "bdf"), run=bdf_section,
            seed="Tables 1-4: verdicts of explicit Euler, BDF2, BDF3, BDF4 over k and N (the "
                 "document's column); CVODE at order 1: 38 501 steps (k = 10) and 76 856 (k = 50) "
                 "against 536 and 1100 at order 5 (the document's steps); the rtol = atol = 0.1 "
                 "'choppy' traces.",
            method="Accuracy is judged on position against DOP853 at 1e-12 (stated above the "
                   "tables); the short form runs only the cells with a verdict of the document and no "
                   "order-1 run at k = 50."),
    Section("squeezer", "Andrew's squeezer: index 1, 2 and 3, positions, velocities, "
            "multipliers, drift (document 001 section 2)", ("study", "squeezer"), run=squeezer_section,
            seed="The reference end state at t = 0.03 s (Hairer-Wanner), and the document's plots "
                 "of the index-1, -2 and -3 runs and of the index-1 drift.",
            method="`rel. error q` is our end state (index 1 with projection, RK45) against "
                   "that reference; the figures below run each index."),
    Section("squeezer-index3", "Andrew's squeezer: index-3 tolerance-by-suppression grids "
            "(document 001 Tables 8-10)", ("study", "squeezer", "--table"), run=suppression_section,
            seed="Tables 8 and 9: Assimulo IDA on index 3 (v' and lambda out of the error "
                 "test: 843 steps, 1811 f-evals) and index 2 (1603 steps); the document's "
                 "tolerance grid itself is not in benchmarks.md.",
            method="Per tolerance, ours runs IDA with and without suppress-alg and Radau5 with "
                   "and without the index-dependent error scaling, and gives q's error against "
                   "the reference or why the run failed."),
    Section("woodpecker", "Woodpecker toy: state events and impacts (document 001, Lund FMNN05 "
            "project 3; Tables 15 and 16)", ("study", "woodpecker"), run=woodpecker_section,
            seed="22 beak hits over 2 s; Assimulo IDA 7228 steps and 224 state events, Dymola "
                 "3239 steps and 177 events (the document's rows of the statistics table).",
            method="Ours is DOP853 at rtol 1e-6 with a hybrid event loop, not a DAE solver: "
                   "step counts are not comparable one to one; beak hits and the mode "
                   "sequence are."),
    Section("lagrange-2d", "Lagrange by sympy: planar elastic double pendulum (the KTH "
            "Lagrange report)", ("study", "lagrange", "2d"), run=lagrange_section("2d"),
            seed="The equations of motion with the appendix's parameters (m1 1, m2 0.5, k 50, "
                 "l0 0.25, l 0.5, g 9.82), and the q1..q3 and energy plots from q1 = 0.8.",
            method="Ours prints its parameters above the equations; energy drift (conserved "
                   "without friction) is our figure of merit."),
    Section("lagrange-3d", "Lagrange by sympy: 3D pendulum (the KTH Lagrange report)",
            ("study", "lagrange", "3d"), run=lagrange_section("3d"),
            seed="The equations of motion from the document's Lagrangian (whose potential omits "
                 "q3); the conservative run, the run with joint friction decaying to the "
                 "potential minimum, and the chaos plot of q2.",
            method="Energy drift is our figure of merit; the document's parameters and start "
                   "by default, our earlier set drawn second and labelled."),
    Section("structure-lowpass", "Structural analysis: the low-pass filter (document 000 item 4)",
            ("study", "structure", "lowpass"), run=structure_section("lowpass"),
            seed="The document's matching `assign` list and BLT blocks (benchmarks.md section 6)."),
    Section("structure-pendulum", "Structural analysis: Cartesian pendulum, Pantelides (document "
            "000 item 4)", ("study", "structure", "pendulum"), run=structure_section("pendulum"),
            seed="Structural index 3; the constraint differentiated twice (vmap/eqmap lists)."),
    Section("structure-squeezer", "Structural analysis: Andrew's squeezer (document 000 item 4)",
            ("study", "structure", "squeezer"), run=structure_section("squeezer"),
            seed="Index 3: the six constraints differentiated twice."),
    *(Section(f"pipeline-{example}", f"Equation pipeline: {example} (document 000 items 4-5, "
              f"ModiaBase / ModelingToolkit)", ("study", "pipeline", example),
              run=pipeline_section(example),
              seed="Each stage as the document's tools print it (alias elimination, matching, BLT, "
                   "Pantelides, dummy derivatives, tearing) and, for modia-pendulum, its "
                   "statistics log.")
      for example in ("lag", "pendulum", "lowpass", "modia-pendulum")),
    Section("rotations", "Rotations: Cardan vs adaptive Cardan vs quaternion (document 000 item 1)",
            ("study", "rotations", "--runs", "tumble", "top"), full_command=("study", "rotations"),
            run=rotations_section,
            seed="Qualitative: Cardan angles take larger steps on a body spinning about one "
                 "axis; the fixed sequence fails at gimbal lock; Modia3D's adaptive switch "
                 "and quaternions do not.",
            method="Every run is an axisymmetric top, judged against its closed form. The "
                   "short form's table leaves out the spin run and its wobble sweep: the "
                   "figures below run them (the pure spin beside the spin run; five "
                   "wobbles with --full)."),
    Section("unicycle", "The differential drive (document 002's UnicycleDynamics)",
            ("study", "unicycle"), run=unicycle_section,
            seed="m 10 kg, I 0.5 kg m^2, r 0.05 m, wheel base 0.3 m, linear friction 1 N s/m, "
                 "angular 0.5 N m s/rad, and its equations (no run, no figure).",
            method="Ours runs the document's parameters from rest and compares with the closed "
                   "forms; the ledger's rows 002-unicycle-* set its equations beside ours."),
    Section("base-parameters", "Base parameters of the 2-DOF planar arm (document 002)",
            ("study", "base-parameters"), run=base_parameters_section,
            seed="Theta_base = [I1 + m1 c1^2 + m2 (l1^2 + 2 l1 c2 cos q2 + c2^2), I2 + m2 c2^2, "
                 "m2 c2 cos q2, ...] and '6+6+5n' base parameters for a planar arm.",
            method="Ours by QR of Pinocchio's regressor and by a sympy derivation (our "
                   "parameters: the document gives none)."),
    Section("uncertainty", "Uncertain damped pendulum: linear propagation vs Monte Carlo "
            "(document 000 item 5)", ("study", "uncertainty", "--samples", "200", "--workers", "0"),
            full_command=("study", "uncertainty", "--samples", "1000", "--workers", "0"),
            run=uncertainty_section,
            seed="Measurements.jl's band of phi(t) (linear propagation only, a figure).",
            method="We add Monte Carlo (200 samples in the short form, 1000 with --full) and "
                   "say where linearisation fails."),
    Section("scene-uncertainty", "Uncertain scene parameters: the same pendulum as a scene "
            "with 'value ± sigma' mass and damping (document 000 item 5)",
            ("scene-uncertainty", SCENE, "--output", SCENE_OUTPUT, "--samples", "40",
             "--duration", "3", "--workers", "0", "--plot", SCENE_PLOT),
            full_command=("scene-uncertainty", SCENE, "--output", SCENE_OUTPUT, "--samples",
                          "1000", "--workers", "0", "--plot", SCENE_PLOT),
            run=scene_uncertainty_section, files=(SCENE_PLOT,),
            seed="Measurements.jl's band of phi(t) from parameters written as value ± sigma.",
            method="A scene (config/scenes/uncertain_pendulum.yaml) instead of equations: the "
                   "length is fixed (a URDF joint origin is no scene value); linear band by "
                   "central differences against Monte Carlo through the engine (40 samples "
                   "over 3 s in the short form, 1000 over 10 s with --full)."),
    Section("contact-extremes", "Contact at its extremes (stiffness, mass ratio, tunnelling, "
            "friction cone)", ("contact-extremes", "--table", "light_on_heavy", "--table",
                               "tunnelling", "--table", "grasp"),
            full_command=("contact-extremes",), run=contact_extremes_section,
            seed="No source-document table: our own measurements (benchmarks.md, contact).",
            method="The short form leaves out the stiffness sweep (2.5 minutes on two busy "
                   "cores); --full runs it."),
    Section("work-precision", "Work-precision on the youBot arm swing (document 001 Table 6 "
            "style)", ("work-precision", "--scene", WORK_SCENE, "--duration", "0.2",
                       "--workers", "0", "--out", WORK_FOLDER),
            full_command=("work-precision", "--scene", WORK_SCENE, "--workers", "0", "--out",
                          WORK_FOLDER),
            run=work_precision_section, files=(f"{WORK_FOLDER}/work_precision_{WORK_SCENE}.png",),
            seed="No source-document figure for the youBot; document 001's Table 6 compares integrators on "
                 "the elastic pendulum the same way (steps, f-evals, CPU time).",
            method="The short form simulates 0.2 s of the scene."),
)
SECTION_NAMES = tuple(section.name for section in SECTIONS)

#: Section name -> the figure set drawn after its run.
FIGURE_SETS: dict[str, FigureSet] = {figure_set.name: figure_set for figure_set in (
    pendulum_figures.PENDULUM_SET, pendulum_figures.BDF_SET, squeezer_figures.SQUEEZER_SET,
    woodpecker_figures.WOODPECKER_SET, lagrange_figures.LAGRANGE_2D_SET,
    lagrange_figures.LAGRANGE_3D_SET, *equation_figures.STRUCTURE_SETS,
    *equation_figures.PIPELINE_SETS, rotations_figures.ROTATIONS_SET,
    uncertain_pendulum_figures.UNCERTAINTY_SET)}


def all_specs() -> list[FigureSpec]:
    """Every declared figure of every set, in page order."""
    return [spec for section in SECTIONS if section.name in FIGURE_SETS
            for spec in FIGURE_SETS[section.name].specs]
