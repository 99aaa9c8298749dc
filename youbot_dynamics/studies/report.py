"""Every study in one report: the source documents' figures or verdicts, ours, and the
difference, after the ledger (studies/ledger.py) as the first page.

The page opens with the ledger: the row counts per document and verdict, then every row,
its figure linked to the figure's subsection where the report drew it. Then it is a loop over the catalogue (studies/catalog.py): each :class:`Section` runs its
study through the study's own module (``run(config)``) and returns the text ``youbot-dynamics
study NAME`` prints with the study's result; then its figure set (studies/figures.py: the
document's figures from our runs, each declared with its caption and the document's figure
or verdict) draws from that result into the report folder.
The sections are independent cases of :func:`youbot_dynamics.accuracy.sweeps.map_cases` (a
local Dask cluster by default, ``scheduler`` for a real one, serial with ``workers=0``);
the page (``report.md``) is assembled in the order of the catalogue, whatever order they
finished in. A section that raises is reported with its traceback; the others still run.
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
from youbot_dynamics.studies import ledger
from youbot_dynamics.studies.catalog import FIGURE_SETS, SECTION_NAMES, SECTIONS, Section
from youbot_dynamics.studies.figures import Figure, FigureSpec, draw_set

#: Name of the Markdown page in the report folder.
PAGE = "report.md"


@dataclass(frozen=True)
class SectionResult:
    """What one section's study printed (``output``; ``errors``: the traceback of a study
    that raised), whether it ran, its wall time (s); the figures its set drew
    (``figure_error``: why the set failed, its traceback) and the time that took (s)."""

    name: str
    command: str
    ok: bool
    output: str
    errors: str
    wall_time: float
    figures: tuple[Figure, ...] = ()
    figure_error: str | None = None
    figure_time: float = 0.0

    @property
    def failed(self) -> bool:
        """The study or its figure set failed."""
        return not self.ok or self.figure_error is not None


def section_by_name(name: str) -> Section:
    """The catalogue's section of that name."""
    return SECTIONS[SECTION_NAMES.index(name)]


def run_section(name: str, out_dir: str, full: bool) -> SectionResult:
    """Run one section's study (stdout and stderr kept off the terminal), then draw its
    figure set from the study's result. A study or set that raises is reported with its
    traceback (the set then runs the cases it needs itself)."""
    section, out = section_by_name(name), Path(out_dir)
    errors, start = "", time.perf_counter()
    with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()):
        try:
            output, result = section.run(out, full)
        except Exception:  # a bug in one study: reported on its section
            output, result, errors = "", None, traceback.format_exc()
    wall_time = time.perf_counter() - start
    figures, figure_error, start = (), None, time.perf_counter()
    try:
        if name in FIGURE_SETS:
            with contextlib.redirect_stdout(io.StringIO()):
                figures = tuple(draw_set(FIGURE_SETS[name], out, full, result))
    except Exception:  # a bug in one set: reported on its section
        figure_error = traceback.format_exc()
    return SectionResult(name, section.command_line(full), not errors, output, errors,
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


#: The column names a study's table gives the source document's verdict under.
DOCUMENT_COLUMNS = ("document", "seed")


def verdict_agreement(text: str) -> str | None:
    """Agreement of our verdicts with the source document's over every table row that has
    both a document cell (a column of :data:`DOCUMENT_COLUMNS`) and a ``verdict`` cell (None
    if no table has both)."""
    pairs = []
    for row in markdown_rows(text):
        theirs = next((row[key] for key in DOCUMENT_COLUMNS if row.get(key, "-") != "-"), None)
        if theirs is not None and row.get("verdict", "-") != "-":
            pairs.append((theirs, row["verdict"], row))
    if not pairs:
        return None
    differ = [(theirs, ours, row) for theirs, ours, row in pairs if theirs != ours]
    lines = [f"{len(pairs) - len(differ)} of {len(pairs)} verdicts agree with the source document."]
    for theirs, ours, row in differ:
        where = ", ".join(f"{key} {row[key]}" for key in ("integrator", "k", "setting",
                                                          "n_steps") if key in row)
        lines.append(f"- {where}: document {theirs!r}, ours {ours!r}")
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
    """One figure's subsection: caption, the source document's figure or verdict, ours (what
    the run measured, and the PNG), the difference."""
    spec = figure.spec
    return "\n".join([f'<a id="{figure_anchor(spec)}"></a>', "",
                      f"### Figure {number}: {spec.caption}", "",
                      f"**Source document.** {spec.seed}", "", f"**Ours.** {figure.ours}", "",
                      f"![{alt_text(spec.caption)}]({spec.file})", "",
                      f"**Difference.** {figure.difference}", ""])


def section_text(section: Section, result: SectionResult, first_figure: int = 1) -> str:
    """One section of the page: title, command, the source document's part, ours, the
    difference, the files
    its run wrote, then the study's figure subsections numbered from ``first_figure``."""
    lines = [f"## {section.title}", "", f"`{result.command}`", "",
             f"**Source document.** {section.seed}", ""]
    if not result.ok:
        lines += ["**Ours.** FAILED:", "", output_block(result.errors), ""]
    else:
        lines += [f"**Ours** ({result.wall_time:.1f} s).", "", output_block(result.output), ""]
        agreement = verdict_agreement(result.output)
        difference = "\n".join(part for part in (agreement, section.method) if part)
        lines += [f"**Difference.** "
                  f"{difference or 'Not computed: read ours against the source document line above.'}", ""]
        lines += [f"![{name}]({name})" for name in section.files]
    if result.figure_error is not None:
        lines += ["", "**Figures.** FAILED:", "", f"```\n{result.figure_error.strip()}\n```"]
    lines += [figure_section(first_figure + k, figure)
              for k, figure in enumerate(result.figures)]
    return "\n".join(lines + [""])


def page_figures(sections: Sequence[Section], results: Sequence[SectionResult]) -> list[str]:
    """Every PNG the page shows, in page order: the sections' runs' and the figure sets'."""
    files = []
    for section, result in zip(sections, results):
        if result.ok:
            files += list(section.files)
        files += [figure.spec.file for figure in result.figures]
    return files


#: The anchor of the ledger's page.
LEDGER_ANCHOR = "ledger"


def ledger_page(results: Sequence[SectionResult]) -> list[str]:
    """The ledger as the page's first part: what it is, the counts per document and verdict,
    every row; a row's figure links to its subsection where this report drew it."""
    anchors = {Path(figure.spec.file).stem: figure_anchor(figure.spec)
               for result in results for figure in result.figures}

    def link(name: str) -> str | None:
        return f"[{name}](#{anchors[name]})" if name in anchors else None
    rows = ledger.load_ledger()
    return [f'<a id="{LEDGER_ANCHOR}"></a>', "", "## The source-document ledger", "",
            f"Every figure, table and checkable claim of the four source documents ({len(rows)} "
            "rows): the document's value, ours, and the verdict (agree; differs-explained, with "
            "the reason; tool-specific, nothing of ours to compare), with the test that asserts "
            "our value (`youbot-dynamics study ledger`).", "",
            ledger.text(rows, link), ""]


def page_head(sections: Sequence[Section], results: Sequence[SectionResult], full: bool,
              total_time: float) -> list[str]:
    """The page's title, summary line, contents and list of figures."""
    failed = [r.name for r in results if r.failed]
    figures = [figure for result in results for figure in result.figures]
    form = "Full (the source documents' sizes)" if full else "Short"
    return ["# youbot_dynamics: the source documents' studies side by side", "",
            f"{form} form; "
            f"{sum(r.ok for r in results)} studies ran, "
            f"{len(failed)} failed{' (' + ', '.join(failed) + ')' if failed else ''}; "
            f"{len(page_figures(sections, results))} figures; wall time "
            f"{total_time:.0f} s against "
            f"{sum(r.wall_time + r.figure_time for r in results):.0f} s of the studies' own "
            f"run times added up.", "", *ledger_page(results), "## Contents", "",
            f"- [The source-document ledger](#{LEDGER_ANCHOR})",
            *(f"- [{s.title}](#{s.name})" for s in sections), "", "## Figures", "",
            *(f"{k}. [{figure.spec.file}](#{figure_anchor(figure.spec)}): "
              f"{figure.spec.caption}" for k, figure in enumerate(figures, start=1)),
            *(f"- [{name}](#{s.name}): written by `{s.name}`"
              for s, r in zip(sections, results) if r.ok for name in s.files),
            ""]


def report_page(sections: Sequence[Section], results: Sequence[SectionResult], full: bool,
                total_time: float) -> str:
    """The whole Markdown page: contents, then one section per study."""
    body, number = [], 1
    for section, result in zip(sections, results):
        body.append(f'<a id="{section.name}"></a>\n\n' + section_text(section, result, number))
        number += len(result.figures)
    return "\n".join(page_head(sections, results, full, total_time) + body)


def write_report(out_dir: str | Path, *, full: bool = False,
                 only: Sequence[str] | None = None, workers: int | None = None,
                 scheduler: str | None = None, progress: bool = True
                 ) -> tuple[Path, list[SectionResult]]:
    """Run the sections (all, or those named in ``only``) through the Dask layer, write
    their PNGs and :data:`PAGE` into ``out_dir``; returns the page's path and results."""
    unknown = sorted(set(only or ()) - set(SECTION_NAMES))
    if unknown:
        raise UserInputError(f"--only: unknown studies {', '.join(unknown)}; choose from "
                             f"{', '.join(SECTION_NAMES)}")
    out = Path(out_dir).resolve()
    out.mkdir(parents=True, exist_ok=True)
    sections = [s for s in SECTIONS if not only or s.name in only]
    start = time.perf_counter()
    results = map_cases(run_section, [(s.name, str(out), full) for s in sections],
                        workers=workers, scheduler=scheduler, desc="report", progress=progress)
    page = out / PAGE
    page.write_text(report_page(sections, results, full, time.perf_counter() - start),
                    encoding="utf-8")
    return page, results
