"""``youbot-dynamics report`` (analysis/report.py): the studies' PNGs and one page with a
section per study. CI runs a smoke form (a few quick studies, on a local Dask cluster of
two processes); the whole short form is marked slow (about 4 minutes on a loaded 2-core
machine)."""
from __future__ import annotations

from pathlib import Path

import pytest

from youbot_dynamics.analysis.report import (PAGE, STUDIES, Study, markdown_rows,
                                             missing_in_build, run_study, verdict_agreement)
from youbot_dynamics.cli import main

PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"
SMOKE = ("structure-lowpass", "structure-pendulum", "woodpecker", "uncertainty")


def assert_report(out: Path, names) -> str:
    """Every figure of the named studies that this build has is a PNG file; the page has
    a section titled for each named study; returns the page."""
    page = (out / PAGE).read_text(encoding="utf-8")
    studies = [s for s in STUDIES if s.name in names]
    assert len(studies) == len(names)
    for study in studies:
        assert f"## {study.title}" in page and f'<a id="{study.name}"></a>' in page
        if missing_in_build(study.arguments(out, False)) is None:
            for figure in study.figures:
                assert (out / figure).read_bytes()[:8] == PNG_SIGNATURE, figure
    return page


def test_smoke_report_on_a_local_cluster(tmp_path, capsys):
    assert main(["report", "--out", str(tmp_path), "--only", *SMOKE, "--workers", "2"]) == 0
    printed = capsys.readouterr().out
    assert all(f"{name} " in printed and "FAILED" not in printed for name in SMOKE)
    page = assert_report(tmp_path, SMOKE)
    assert "4 studies ran, 0 failed" in page
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
