"""``youbot-dynamics report`` (studies/report.py): the studies' tables, the seeds'
figures drawn from our runs (studies/figures.py) and one page with a section per study and
a subsection per figure. CI runs a smoke form (a few quick studies, on a local Dask cluster
of two processes, about 40 s on a loaded machine); the whole short form is marked slow."""
from __future__ import annotations

import re
from pathlib import Path

import pytest
from PIL import Image

from youbot_dynamics.cli import main
from youbot_dynamics.studies.figures import all_specs, figure_sets
from youbot_dynamics.studies.report import (PAGE, STUDIES, STUDY_NAMES, Study, markdown_rows,
                                            missing_in_build, run_study, verdict_agreement)

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
    sets; every PNG the page shows is valid; every figure subsection has the seed's part,
    ours with its image, and the difference. Returns the page."""
    page = (out / PAGE).read_text(encoding="utf-8")
    studies = [s for s in STUDIES if s.name in names]
    assert len(studies) == len(names)
    declared = [spec.file for study in studies if study.name in figure_sets()
                for spec in figure_sets()[study.name].specs]
    for study in studies:
        assert f"## {study.title}" in page and f'<a id="{study.name}"></a>' in page
        if missing_in_build(study.arguments(out, False)) is None:
            for figure in study.figures:
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
        assert re.search(r"\*\*Seed\.\*\* \S", text), text
        assert re.search(r"\*\*Ours\.\*\* \S", text), text
        assert re.search(r"\*\*Difference\.\*\* \S", text), text
        assert f"]({file})" in text
    return page


def test_the_figure_sets_declare_the_seeds_figures():
    specs = all_specs()
    files = [spec.file for spec in specs]
    assert len(files) >= 40 and len(set(files)) == len(files)
    assert set(figure_sets()) <= set(STUDY_NAMES)
    assert all(spec.file.endswith(".png") and spec.caption and spec.seed for spec in specs)


def test_smoke_report_on_a_local_cluster(tmp_path, capsys):
    assert main(["report", "--out", str(tmp_path), "--only", *SMOKE, "--workers", "2"]) == 0
    printed = capsys.readouterr().out
    assert all(f"{name} " in printed and "FAILED" not in printed for name in SMOKE)
    page = assert_report(tmp_path, SMOKE)
    assert "4 studies ran, 0 failed" in page
    # the figures' own measurements reached the page: the beak hits, the seed's BLT blocks
    assert "Seed: 22 beak hits over 2 s, ours 22." in page
    assert "Seed blocks [[6], [1, 2, 3, 4], [5]] (an algebraic loop of four); ours the " \
           "same." in page
    # the studies' own figures reached the page: the seed's 22 beak hits beside ours
    assert "beak hits (seed over 2 s: 22)" in page and "structural index 3" in page
    assert page.index("Woodpecker") < page.index("Uncertain")  # the order of STUDIES


def test_a_study_not_in_the_build_is_listed_not_run(tmp_path):
    study = Study("other", "Another branch's study", ("no-such-command", "--x"), seed="-")
    result = run_study(study, str(tmp_path), False)
    assert result.status is None and "no-such-command" in result.errors


def test_verdict_agreement_counts_rows_with_both_cells():
    text = ("| k | setting | seed | verdict |\n|---|---|---|---|\n"
            "| 1 | N=10 | stable | stable |\n| 20 | N=10 | accurate | stable, inaccurate |\n"
            "| 5 | N=10 | - | unstable |\n\nnot a table\n| a | b |\n|---|---|\n| 1 | 2 |\n")
    assert markdown_rows(text)[-1] == {"a": "1", "b": "2"}
    assert verdict_agreement(text) == ("1 of 2 verdicts agree with the seed.\n"
                                       "- k 20, setting N=10: seed 'accurate', ours "
                                       "'stable, inaccurate'")
    assert verdict_agreement("| a |\n|---|\n| 1 |\n") is None


@pytest.mark.slow
def test_short_report_writes_every_figure(tmp_path):
    status = main(["report", "--out", str(tmp_path)])
    page = assert_report(tmp_path, [s.name for s in STUDIES])
    assert status == 0, page
    assert "0 failed" in page
    assert len(figure_subsections(page)) == len(all_specs())


def test_a_figure_set_that_raises_is_reported_failed(tmp_path, monkeypatch):
    from youbot_dynamics.studies import figures

    def broken(out, full):
        raise RuntimeError("a bug in the figures")
    sets = dict(figures.figure_sets())
    sets["structure-lowpass"] = figures.FigureSet("structure-lowpass", (), broken)
    monkeypatch.setattr("youbot_dynamics.studies.report.figure_sets", lambda: sets)
    study = next(s for s in STUDIES if s.name == "structure-lowpass")
    result = run_study(study, str(tmp_path), False)
    assert result.status == 0 and result.failed
    assert "RuntimeError: a bug in the figures" in result.figure_error


def test_list_figures_names_every_figure_without_running(capsys):
    assert main(["report", "--list-figures"]) == 0
    rows = markdown_rows(capsys.readouterr().out)
    commands = [file for study in STUDIES for file in study.figures]
    assert [row["file"] for row in rows] == [spec.file for spec in all_specs()] + commands


def test_a_figure_set_must_write_what_it_declares(tmp_path):
    from youbot_dynamics.studies.figures import FigureSet, FigureSpec, draw_set
    spec = FigureSpec("a.png", "A", "seed")
    lazy = FigureSet("lazy", (spec,), lambda out, full: {"a.png": ("ours", "difference")})
    with pytest.raises(RuntimeError, match="figure set lazy: did not write a.png"):
        draw_set(lazy, tmp_path)


def test_a_study_that_raises_is_reported_failed(tmp_path, monkeypatch):
    from youbot_dynamics.cli import study_commands

    def broken(args):
        raise RuntimeError("a bug in the study")
    monkeypatch.setattr(study_commands, "run_uncertainty", broken)
    study = next(s for s in STUDIES if s.name == "uncertainty")
    result = run_study(study, str(tmp_path), False)
    assert result.status == 1 and "RuntimeError: a bug in the study" in result.errors


@pytest.mark.parametrize("full", [False, True])
def test_every_study_command_line_parses(tmp_path, full):
    """Short and full forms: each command line is accepted, or its whole command belongs
    to a branch not merged here (then the page lists it as missing)."""
    from youbot_dynamics.cli import COMMANDS
    for study in STUDIES:
        argv = study.arguments(tmp_path, full)
        problem = missing_in_build(argv)
        assert problem is None or argv[0] not in COMMANDS, (study.name, problem)
        assert all(str(tmp_path) in a for a in argv if a.endswith(".png")) and not any(
            "{out}" in a for a in argv)
