"""``youbot-dynamics report`` (studies/report.py over studies/catalog.py): the studies'
tables, the source documents' figures drawn from our runs (studies/figures.py) and one page with a
section per study and a subsection per figure. CI runs a smoke form (a few quick studies, on a local Dask cluster
of two processes, about 40 s on a loaded machine); the whole short form is marked slow."""
from __future__ import annotations

import re
from pathlib import Path

import pytest
from PIL import Image

from youbot_dynamics.cli import main
from youbot_dynamics.studies.catalog import FIGURE_SETS, SECTION_NAMES, SECTIONS, all_specs
from youbot_dynamics.studies.report import PAGE, markdown_rows, run_section, verdict_agreement

PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"
SMOKE = ("structure-lowpass", "structure-pendulum", "woodpecker", "uncertainty")
#: Smallest PNG taken as a drawn figure: an empty 80-dpi canvas with axes is about 8 kB,
#: our smallest figure (the low-pass BLT matrix) about 14 kB.
MIN_PNG_BYTES = 5_000


def assert_png(path: Path) -> None:
    """A decodable PNG of a plausible figure's size in pixels and bytes."""
    assert path.read_bytes()[:8] == PNG_SIGNATURE, path
    assert path.stat().st_size > MIN_PNG_BYTES, (path, path.stat().st_size)
    with Image.open(path) as image:
        image.verify()
    with Image.open(path) as image:
        width, height = image.size
    assert 200 <= width <= 1400 and 150 <= height <= 1400, (path, image.size)


def figure_subsections(page: str) -> list[str]:
    """The page's figure subsections, each from its heading to the next heading."""
    return re.findall(r"^### Figure \d+: .*?(?=^##|\Z)", page, flags=re.M | re.S)


def assert_report(out: Path, names) -> str:
    """The page has a section titled for each named study and lists every figure of their
    sets; every PNG the page shows is valid; every figure subsection has the source
    document's part,
    ours with its image, and the difference. Returns the page."""
    page = (out / PAGE).read_text(encoding="utf-8")
    sections = [s for s in SECTIONS if s.name in names]
    assert len(sections) == len(names)
    declared = [spec.file for section in sections if section.name in FIGURE_SETS
                for spec in FIGURE_SETS[section.name].specs]
    for section in sections:
        assert f"## {section.title}" in page and f'<a id="{section.name}"></a>' in page
        for figure in section.files:
            assert_png(out / figure)
    shown = re.findall(r"!\[[^\]]*\]\(([^)]+)\)", page)
    assert set(declared) <= set(shown), set(declared) - set(shown)
    listed = re.findall(r"^\d+\. \[([^\]]+)\]\(#figure-", page, flags=re.M)
    assert listed == declared
    for file in shown:
        assert_png(out / file)
    subsections = figure_subsections(page)
    assert len(subsections) == len(declared)
    for text, file in zip(subsections, declared):
        assert re.search(r"\*\*Source document\.\*\* \S", text), text
        assert re.search(r"\*\*Ours\.\*\* \S", text), text
        assert re.search(r"\*\*Difference\.\*\* \S", text), text
        assert f"]({file})" in text
    return page


def test_the_catalogue_and_the_commands_say_source_document_not_seed(capsys):
    """The report's own words (section titles, the documents' parts, methods) and the help of
    `study` and `report` name the documents as source documents or by number."""
    for section in SECTIONS:
        for text in (section.title, section.seed, section.method):
            assert not re.search(r"\bseeds?\b", text, re.I), (section.name, text)
    for argv in (["study", "--help"], ["report", "--help"]):
        assert main(argv) == 0
        assert not re.search(r"\bseeds?\b", capsys.readouterr().out, re.I), argv


def test_the_figure_sets_declare_the_documents_figures():
    specs = all_specs()
    files = [spec.file for spec in specs]
    assert len(files) >= 40 and len(set(files)) == len(files)
    assert set(FIGURE_SETS) <= set(SECTION_NAMES)
    assert all(spec.file.endswith(".png") and spec.caption and spec.seed for spec in specs)


def test_smoke_report_on_a_local_cluster(tmp_path, capsys):
    assert main(["report", "--out", str(tmp_path), "--only", *SMOKE, "--workers", "2"]) == 0
    printed = capsys.readouterr().out
    assert all(f"{name} " in printed and "FAILED" not in printed for name in SMOKE)
    page = assert_report(tmp_path, SMOKE)
    assert "4 studies ran, 0 failed" in page
    # the ledger is the first page: its counts and rows before the contents and the studies
    ledger_at = page.index("## The source-document ledger")
    assert ledger_at < page.index("## Contents") < page.index("## Structural analysis")
    assert "| all |" in page[ledger_at:] and "002-unicycle-parameters" in page
    # the figures' own measurements reached the page: the beak hits, document 000's BLT blocks
    assert "22 beak hits over 2 s, ours 22." in page
    assert "Document blocks [6], [2, 4, 3, 1], [5] (an algebraic loop of four); ours " \
           "[[6], [1, 2, 3, 4], [5]], the same sets (either matching)." in page
    # the studies' own figures reached the page: the document's 22 beak hits beside ours
    assert re.search(r"beak hits \(\w+ over 2 s: 22\)", page) and "structural index 3" in page
    assert page.index("Woodpecker") < page.index("Uncertain")  # the order of SECTIONS


@pytest.mark.parametrize("column", ["document", "seed"])
def test_verdict_agreement_counts_rows_with_both_cells(column):
    text = (f"| k | setting | {column} | verdict |\n|---|---|---|---|\n"
            "| 1 | N=10 | stable | stable |\n| 20 | N=10 | accurate | stable, inaccurate |\n"
            "| 5 | N=10 | - | unstable |\n\nnot a table\n| a | b |\n|---|---|\n| 1 | 2 |\n")
    assert markdown_rows(text)[-1] == {"a": "1", "b": "2"}
    assert verdict_agreement(text) == ("1 of 2 verdicts agree with the source document.\n"
                                       "- k 20, setting N=10: document 'accurate', ours "
                                       "'stable, inaccurate'")
    assert verdict_agreement("| a |\n|---|\n| 1 |\n") is None


@pytest.mark.slow
def test_short_report_writes_every_figure(tmp_path):
    status = main(["report", "--out", str(tmp_path)])
    page = assert_report(tmp_path, SECTION_NAMES)
    assert status == 0, page
    assert "0 failed" in page
    assert len(figure_subsections(page)) == len(all_specs())


def test_a_figure_set_that_raises_is_reported_failed(tmp_path, monkeypatch):
    from youbot_dynamics.studies import figures

    def broken(result, out, full):
        raise RuntimeError("a bug in the figures")
    monkeypatch.setitem(FIGURE_SETS, "structure-lowpass",
                        figures.FigureSet("structure-lowpass", (), broken))
    result = run_section("structure-lowpass", str(tmp_path), False)
    assert result.ok and result.failed
    assert "RuntimeError: a bug in the figures" in result.figure_error


def test_list_figures_names_every_figure_without_running(capsys):
    assert main(["report", "--list-figures"]) == 0
    rows = markdown_rows(capsys.readouterr().out)
    commands = [file for section in SECTIONS for file in section.files]
    assert [row["file"] for row in rows] == [spec.file for spec in all_specs()] + commands


def test_a_figure_set_must_write_what_it_declares(tmp_path):
    from youbot_dynamics.studies.figures import FigureSet, FigureSpec, draw_set
    spec = FigureSpec("a.png", "A", "seed")
    lazy = FigureSet("lazy", (spec,), lambda result, out, full: {"a.png": ("ours", "difference")})
    with pytest.raises(RuntimeError, match="figure set lazy: did not write a.png"):
        draw_set(lazy, tmp_path)


def test_a_study_that_raises_is_reported_failed(tmp_path, monkeypatch):
    from youbot_dynamics.studies import uncertain_pendulum

    def broken(config):
        raise RuntimeError("a bug in the study")
    monkeypatch.setattr(uncertain_pendulum, "run", broken)
    result = run_section("uncertainty", str(tmp_path), False)
    assert not result.ok and result.failed and "RuntimeError: a bug in the study" in result.errors


@pytest.mark.parametrize("full", [False, True])
def test_every_section_command_line_parses(full):
    """Short and full forms: the command line each section shows is one the command line
    accepts (the section runs the study directly; the line is how a user reproduces it)."""
    from youbot_dynamics.cli import COMMANDS, build_parser
    for section in SECTIONS:
        argv = section.command_line(full).split()[1:]
        assert argv[0] in COMMANDS, section.name
        build_parser((COMMANDS[argv[0]][0],)).parse_args(argv)


def test_report_imports_no_command_line():
    """The report runs the studies, never the command line (the layering: studies/ is
    below cli/)."""
    import subprocess
    import sys
    code = ("import sys, youbot_dynamics.studies.report\n"
            "print(sorted(m for m in sys.modules if m.startswith('youbot_dynamics.cli')))")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          check=True, cwd=Path(__file__).resolve().parents[2])
    assert done.stdout.strip() == "[]"
