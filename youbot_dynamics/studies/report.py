"""Every study in one report: the seed's figures or verdicts, ours, and the difference.

Each :class:`Study` is one section of the page: a sub-command of ``youbot-dynamics`` (the
existing study, run as the user would run it, its PNGs written into the report folder),
what the seed gives for it, and how the two are compared. The studies are independent
cases of :func:`youbot_dynamics.accuracy.sweeps.map_cases` (a local Dask cluster by
default, ``scheduler`` for a real one, serial with ``workers=0``); each runs in one
process with its stdout captured, and the page (``report.md``) is assembled from the
captured outputs in the order of :data:`STUDIES`, whatever order they finished in.

After its command, a study draws its figure set (studies/figures.py: the seed's figures
from our runs, each declared with its caption and the seed's figure or verdict) into the
same folder; the page gives each figure a subsection under its study (seed, ours with the
PNG, difference) and lists them all at the top.

Short forms (the default) keep the whole report to minutes on two cores; ``full`` runs the
seed's sizes. Studies that sweep on Dask themselves (bdf-study, uncertainty, work-precision) run with
``--workers 0`` here: each is already one case on a worker, and the report's cluster is
the one that spreads the work. A study whose command or option is not in this build (the equation pipeline
and the index-3 tables come from other branches) is listed as missing, not run.
"""
from __future__ import annotations

import contextlib
import io
import time
import traceback
from dataclasses import dataclass
from pathlib import Path
from typing import Sequence

from youbot_dynamics.accuracy.sweeps import map_cases
from youbot_dynamics.errors import UserInputError
from youbot_dynamics.studies.figures import Figure, FigureSpec, draw_set, figure_sets

#: Placeholder in a study's arguments for the report folder.
OUT = "{out}"
#: Name of the Markdown page in the report folder.
PAGE = "report.md"


@dataclass(frozen=True)
class Study:
    """One section: ``argv`` of the sub-command (``{out}`` stands for the report folder),
    ``full_argv`` for the seed's sizes (None: the same), the PNGs it writes (file names in
    the folder), the seed's figure or verdict, and how ours differs in method or
    criterion."""

    name: str
    title: str
    argv: tuple[str, ...]
    seed: str
    method: str = ""
    full_argv: tuple[str, ...] | None = None
    figures: tuple[str, ...] = ()

    def arguments(self, out_dir: Path, full: bool) -> list[str]:
        """The command line of this study with the folder filled in."""
        argv = self.full_argv if full and self.full_argv is not None else self.argv
        return [str(out_dir / a[len(OUT) + 1:]) if a.startswith(OUT) else a for a in argv]


@dataclass(frozen=True)
class StudyResult:
    """What one study printed (stdout, stderr), its exit status (None: not in this build)
    and its wall time (s); the figures its set drew (``figure_error``: why the set failed,
    its traceback) and the time that took (s)."""

    name: str
    argv: tuple[str, ...]
    status: int | None
    output: str
    errors: str
    wall_time: float
    figures: tuple[Figure, ...] = ()
    figure_error: str | None = None
    figure_time: float = 0.0

    @property
    def failed(self) -> bool:
        """The command or its figure set failed."""
        return self.status not in (0, None) or self.figure_error is not None


STUDIES: tuple[Study, ...] = (
    Study("pendulum-study", "Elastic pendulum: explicit Euler, CVODE statistics, energy error "
          "(seed 001 Tables 1, 5-7)", ("pendulum-study",),
          seed="The `seed` column of each table: verdicts (stable / accurate) of explicit Euler "
               "over k and N, and the seed's CVODE steps and f-evals at rtol = atol = 1e-6.",
          method="Our verdict is an energy criterion (stated above the table); bdf-study judges "
                 "position against a DOP853 reference instead."),
    Study("bdf-study", "Fixed-step BDF1-4, stability regions, CVODE order caps (seed 001 "
          "sections 1.6-1.9, Tables 1-4)",
          ("bdf-study", "--short", "--workers", "0"),
          full_argv=("bdf-study", "--workers", "0"),
          seed="Tables 1-4: verdicts of explicit Euler, BDF2, BDF3, BDF4 over k and N (the "
               "`seed` column); CVODE at order 1: 38 501 steps (k = 10) and 76 856 (k = 50) "
               "against 536 and 1100 at order 5 (`seed_steps`); the rtol = atol = 0.1 "
               "'choppy' traces.",
          method="Accuracy is judged on position against DOP853 at 1e-12 (stated above the "
                 "tables); the short form runs only the cells with a seed verdict and no "
                 "order-1 run at k = 50."),
    Study("squeezer", "Andrew's squeezer: index 1, 2 and 3, positions, velocities, "
          "multipliers, drift (seed 001 section 2)", ("squeezer",),
          seed="The reference end state at t = 0.03 s (Hairer-Wanner), and the seed's plots "
               "of the index-1, -2 and -3 runs and of the index-1 drift.",
          method="`rel. error q` is our end state (index 1 with projection, RK45) against "
                 "that reference; the figures below run each index."),
    Study("squeezer-index3", "Andrew's squeezer: index-3 tolerance-by-suppression grids (seed "
          "001 Tables 8-10)", ("squeezer", "--table"),
          seed="Tables 8 and 9: Assimulo IDA on index 3 (v' and lambda out of the error "
               "test: 843 steps, 1811 f-evals) and index 2 (1603 steps); the seed's "
               "tolerance grid itself is not in benchmarks.md.",
          method="Per tolerance, ours runs IDA with and without suppress-alg and Radau5 with "
                 "and without the index-dependent error scaling, and gives q's error against "
                 "the reference or why the run failed."),
    Study("woodpecker", "Woodpecker toy: state events and impacts (seed 001, Lund FMNN05 "
          "project 3; Tables 15 and 16)", ("woodpecker",),
          seed="22 beak hits over 2 s; Assimulo IDA 7228 steps and 224 state events, Dymola "
               "3239 steps and 177 events (rows `(seed)` of the statistics table).",
          method="Ours is DOP853 at rtol 1e-6 with a hybrid event loop, not a DAE solver: "
                 "step counts are not comparable one to one; beak hits and the mode sequence "
                 "are."),
    Study("lagrange-2d", "Lagrange by sympy: planar elastic double pendulum (the KTH "
          "Lagrange report)", ("lagrange", "2d"),
          seed="The equations of motion with the appendix's parameters (m1 1, m2 0.5, k 50, "
               "l0 0.25, l 0.5, g 9.82), and the q1..q3 and energy plots from q1 = 0.8.",
          method="Ours prints its parameters above the equations; energy drift (conserved "
                 "without friction) is our figure of merit."),
    Study("lagrange-3d", "Lagrange by sympy: 3D pendulum (the KTH Lagrange report)",
          ("lagrange", "3d"),
          seed="The equations of motion from the seed's Lagrangian (whose potential omits "
               "q3); the conservative run, the run with joint friction decaying to the "
               "potential minimum, and the chaos plot of q2.",
          method="Energy drift is our figure of merit; our parameters are chosen (see the "
                 "figures)."),
    Study("structure-lowpass", "Structural analysis: the low-pass filter (seed 000 item 4)",
          ("structure", "lowpass"),
          seed="The seed's matching `assign` list and BLT blocks (benchmarks.md section 6)."),
    Study("structure-pendulum", "Structural analysis: Cartesian pendulum, Pantelides (seed 000 "
          "item 4)", ("structure", "pendulum"),
          seed="Structural index 3; the constraint differentiated twice (vmap/eqmap lists)."),
    Study("structure-squeezer", "Structural analysis: Andrew's squeezer (seed 000 item 4)",
          ("structure", "squeezer"),
          seed="Index 3: the six constraints differentiated twice."),
    *(Study(f"pipeline-{example}", f"Equation pipeline: {example} (seed 000 items 4-5, "
            f"ModiaBase / ModelingToolkit)", ("pipeline", example),
            seed="Each stage as the seed's tools print it (alias elimination, matching, BLT, "
                 "Pantelides, dummy derivatives, tearing) and, for modia-pendulum, its "
                 "statistics log.")
      for example in ("lag", "pendulum", "lowpass", "modia-pendulum")),
    Study("rotations", "Rotations: Cardan vs adaptive Cardan vs quaternion (seed 000 item 1)",
          ("rotations", "--runs", "tumble", "top"), full_argv=("rotations",),
          seed="Qualitative: Cardan angles take larger steps on a body spinning about one "
               "axis; the fixed sequence fails at gimbal lock; Modia3D's adaptive switch and "
               "quaternions do not.",
          method="Every run is an axisymmetric top, judged against its closed form. The "
                 "short form's table leaves out the spin run and its wobble sweep: the "
                 "figures below run them (the pure spin beside the spin run; five "
                 "wobbles with --full)."),
    Study("uncertainty", "Uncertain damped pendulum: linear propagation vs Monte Carlo (seed "
          "000 item 5)", ("uncertainty", "--samples", "200", "--workers", "0"),
          full_argv=("uncertainty", "--samples", "1000", "--workers", "0"),
          seed="Measurements.jl's band of phi(t) (linear propagation only, a figure).",
          method="We add Monte Carlo (200 samples in the short form, 1000 with --full) and "
                 "say where linearisation fails."),
    Study("scene-uncertainty", "Uncertain scene parameters: the same pendulum as a scene with "
          "'value ± sigma' mass and damping (seed 000 item 5)",
          ("scene-uncertainty", "uncertain_pendulum", "--output", "q[pivot]", "--samples", "40",
           "--duration", "3", "--workers", "0", "--plot", "{out}/scene_uncertainty.png"),
          full_argv=("scene-uncertainty", "uncertain_pendulum", "--output", "q[pivot]", "--samples",
                     "1000", "--workers", "0", "--plot", "{out}/scene_uncertainty.png"),
          figures=("scene_uncertainty.png",),
          seed="Measurements.jl's band of phi(t) from parameters written as value ± sigma.",
          method="A scene (config/scenes/uncertain_pendulum.yaml) instead of equations: the "
                 "length is fixed (a URDF joint origin is no scene value); linear band by central "
                 "differences against Monte Carlo through the engine (40 samples over 3 s in the "
                 "short form, 1000 over 10 s with --full)."),
    Study("contact-extremes", "Contact at its extremes (stiffness, mass ratio, tunnelling, "
          "friction cone)", ("contact-extremes", "--table", "light_on_heavy", "--table",
                             "tunnelling", "--table", "grasp"),
          full_argv=("contact-extremes",),
          seed="No seed table: our own measurements (benchmarks.md, contact).",
          method="The short form leaves out the stiffness sweep (2.5 minutes on two busy "
                 "cores); --full runs it."),
    Study("work-precision", "Work-precision on the youBot arm swing (seed 001 Table 6 style)",
          ("work-precision", "--scene", "arm_swing", "--duration", "0.2", "--workers", "0",
           "--out", "{out}/work_precision"),
          full_argv=("work-precision", "--scene", "arm_swing", "--workers", "0",
                     "--out", "{out}/work_precision"),
          figures=("work_precision/work_precision_arm_swing.png",),
          seed="No seed figure for the youBot; the seed's Table 6 compares integrators on "
               "the elastic pendulum the same way (steps, f-evals, CPU time).",
          method="The short form simulates 0.2 s of the scene."),
)
STUDY_NAMES = tuple(study.name for study in STUDIES)


def missing_in_build(argv: Sequence[str]) -> str | None:
    """None if ``youbot-dynamics`` accepts ``argv``; else its one-line usage error (a
    command or option of another branch not merged here)."""
    from youbot_dynamics.cli import COMMANDS, build_parser
    if not argv or argv[0] not in COMMANDS:
        return f"no command {argv[0] if argv else ''!r} in youbot-dynamics"
    errors = io.StringIO()
    try:
        with contextlib.redirect_stderr(errors):
            build_parser((COMMANDS[argv[0]][0],)).parse_args(list(argv))
    except SystemExit:
        return errors.getvalue().strip() or "not accepted"
    return None


def run_study(study: Study, out_dir: str, full: bool) -> StudyResult:
    """Run one study's command with its output captured, then draw its figure set (if it
    has one); status None if this build does not have the command. A command or set that
    raises is reported with its traceback (the page shows it; the other studies still
    run)."""
    from youbot_dynamics.cli import main
    argv = tuple(study.arguments(Path(out_dir), full))
    missing = missing_in_build(argv)
    if missing:
        return StudyResult(study.name, argv, None, "", missing, 0.0)
    output, errors = io.StringIO(), io.StringIO()
    start = time.perf_counter()
    with contextlib.redirect_stdout(output), contextlib.redirect_stderr(errors):
        try:
            status = main(list(argv))
        except Exception:  # a bug in one study: reported on its section
            errors.write(traceback.format_exc())
            status = 1
    wall_time = time.perf_counter() - start
    figures, figure_error, start = (), None, time.perf_counter()
    try:
        figure_set = figure_sets().get(study.name)
        if figure_set is not None:
            with contextlib.redirect_stdout(io.StringIO()):
                figures = tuple(draw_set(figure_set, out_dir, full))
    except Exception:  # a bug in one set: reported on its section
        figure_error = traceback.format_exc()
    return StudyResult(study.name, argv, status, output.getvalue(), errors.getvalue(),
                       wall_time, figures, figure_error, time.perf_counter() - start)


def markdown_rows(text: str) -> list[dict[str, str]]:
    """Every row of every Markdown table in ``text`` as {column: cell}."""
    rows, header = [], None
    for line in text.splitlines():
        cells = [cell.strip() for cell in line.strip().strip("|").split("|")]
        if not line.lstrip().startswith("|"):
            header = None
        elif header is None:
            header = cells
        elif not set("".join(cells)) <= set("-: "):
            rows.append(dict(zip(header, cells)))
    return rows


def verdict_agreement(text: str) -> str | None:
    """Agreement of our verdicts with the seed's over every table row that has both a
    ``seed`` and a ``verdict`` cell (None if no table has both)."""
    pairs = [(row["seed"], row["verdict"], row) for row in markdown_rows(text)
             if row.get("seed", "-") != "-" and row.get("verdict", "-") != "-"]
    if not pairs:
        return None
    differ = [(seed, ours, row) for seed, ours, row in pairs if seed != ours]
    lines = [f"{len(pairs) - len(differ)} of {len(pairs)} verdicts agree with the seed."]
    for seed, ours, row in differ:
        where = ", ".join(f"{key} {row[key]}" for key in ("integrator", "k", "setting",
                                                          "n_steps") if key in row)
        lines.append(f"- {where}: seed {seed!r}, ours {ours!r}")
    return "\n".join(lines)


def output_block(text: str) -> str:
    """A study's output for the page: as it is where it holds Markdown tables, else fenced."""
    if any(line.startswith("|---") for line in text.splitlines()):
        return text.strip()
    return f"```\n{text.strip()}\n```"


def figure_anchor(spec: FigureSpec) -> str:
    """The page anchor of a figure's subsection."""
    return "figure-" + spec.file.rsplit(".", 1)[0].replace("/", "-").replace("_", "-")


def alt_text(caption: str) -> str:
    """A caption as an image's alt text: square brackets (which end the alt text in
    Markdown) written as parentheses."""
    return caption.replace("[", "(").replace("]", ")")


def figure_section(number: int, figure: Figure) -> str:
    """One figure's subsection: caption, the seed's figure or verdict, ours (what the run
    measured, and the PNG), the difference."""
    spec = figure.spec
    return "\n".join([f'<a id="{figure_anchor(spec)}"></a>', "",
                      f"### Figure {number}: {spec.caption}", "",
                      f"**Seed.** {spec.seed}", "", f"**Ours.** {figure.ours}", "",
                      f"![{alt_text(spec.caption)}]({spec.file})", "",
                      f"**Difference.** {figure.difference}", ""])


def section(study: Study, result: StudyResult, out_dir: Path, first_figure: int = 1) -> str:
    """One section of the page: title, command, seed, ours, the difference, the
    command's figures, then the study's figure subsections numbered from
    ``first_figure``."""
    lines = [f"## {study.title}", "", f"`youbot-dynamics {' '.join(result.argv)}`"
             .replace(str(out_dir) + "/", ""), "", f"**Seed.** {study.seed}", ""]
    if result.status is None:
        return "\n".join(lines + [f"**Ours.** Not in this build: {result.errors}", ""])
    if result.status != 0:
        lines += [f"**Ours.** FAILED (exit status {result.status}):", "",
                  output_block(result.errors or result.output), ""]
    else:
        lines += [f"**Ours** ({result.wall_time:.1f} s).", "", output_block(result.output), ""]
        agreement = verdict_agreement(result.output)
        difference = "\n".join(part for part in (agreement, study.method) if part)
        lines += [f"**Difference.** "
                  f"{difference or 'Not computed: read ours against the seed line above.'}", ""]
        lines += [f"![{name}]({name})" for name in study.figures]
    if result.figure_error is not None:
        lines += ["", "**Figures.** FAILED:", "", f"```\n{result.figure_error.strip()}\n```"]
    lines += [figure_section(first_figure + k, figure)
              for k, figure in enumerate(result.figures)]
    return "\n".join(lines + [""])


def page_figures(studies: Sequence[Study], results: Sequence[StudyResult]) -> list[str]:
    """Every PNG the page shows, in page order: the commands' and the figure sets'."""
    files = []
    for study, result in zip(studies, results):
        if result.status == 0:
            files += list(study.figures)
        files += [figure.spec.file for figure in result.figures]
    return files


def report_page(studies: Sequence[Study], results: Sequence[StudyResult], out_dir: Path,
                full: bool, total_time: float) -> str:
    """The whole Markdown page: contents, then one section per study."""
    ran = sum(r.status == 0 for r in results)
    failed = [r.name for r in results if r.failed]
    missing = [r.name for r in results if r.status is None]
    figures = [(result, figure) for result in results for figure in result.figures]
    head = ["# youbot_dynamics: the seed studies side by side", "",
            f"{'Full (the seed sizes)' if full else 'Short'} form; {ran} studies ran, "
            f"{len(failed)} failed{' (' + ', '.join(failed) + ')' if failed else ''}, "
            f"{len(missing)} not in this build"
            f"{' (' + ', '.join(missing) + ')' if missing else ''}; "
            f"{len(page_figures(studies, results))} figures; wall time "
            f"{total_time:.0f} s against "
            f"{sum(r.wall_time + r.figure_time for r in results):.0f} s of the studies' own "
            f"run times added up.", "", "## Contents", "",
            *(f"- [{s.title}](#{s.name})" for s in studies), "", "## Figures", "",
            *(f"{k}. [{figure.spec.file}](#{figure_anchor(figure.spec)}): "
              f"{figure.spec.caption}" for k, (_, figure) in enumerate(figures, start=1)),
            *(f"- [{name}](#{s.name}): written by `{s.name}`"
              for s, r in zip(studies, results) if r.status == 0 for name in s.figures),
            ""]
    body, number = [], 1
    for study, result in zip(studies, results):
        body.append(f'<a id="{study.name}"></a>\n\n' + section(study, result, out_dir, number))
        number += len(result.figures)
    return "\n".join(head + body)


def write_report(out_dir: str | Path, *, full: bool = False,
                 only: Sequence[str] | None = None, workers: int | None = None,
                 scheduler: str | None = None, progress: bool = True
                 ) -> tuple[Path, list[StudyResult]]:
    """Run the studies (all, or those named in ``only``) through the Dask layer, write
    their PNGs and :data:`PAGE` into ``out_dir``; returns the page's path and results."""
    unknown = sorted(set(only or ()) - set(STUDY_NAMES))
    if unknown:
        raise UserInputError(f"--only: unknown studies {', '.join(unknown)}; choose from "
                             f"{', '.join(STUDY_NAMES)}")
    out = Path(out_dir).resolve()
    out.mkdir(parents=True, exist_ok=True)
    studies = [s for s in STUDIES if not only or s.name in only]
    start = time.perf_counter()
    results = map_cases(run_study, [(s, str(out), full) for s in studies], workers=workers,
                        scheduler=scheduler, desc="report", progress=progress)
    page = out / PAGE
    page.write_text(report_page(studies, results, out, full, time.perf_counter() - start),
                    encoding="utf-8")
    return page, results
