"""The source-document ledger (studies/ledger.py, ledger_data/doc*.yaml): every row has a
verdict, every difference a reason, every evidence test exists in this tree, every figure is
one the report draws; the loader refuses broken rows naming file and row; the YAML ships
with the package; ``study ledger`` prints the rows and their counts."""
from __future__ import annotations

import ast
import fnmatch
import json
from pathlib import Path

import pytest

import youbot_dynamics.cli as cli
from youbot_dynamics.studies import ledger
from youbot_dynamics.studies.catalog import SECTIONS, all_specs

REPO = Path(__file__).resolve().parents[2]


@pytest.fixture(scope="module")
def rows() -> list[ledger.Row]:
    return ledger.load_ledger()


def test_all_four_documents_have_rows(rows):
    assert {row.document for row in rows} == set(ledger.DOCUMENTS)
    assert sorted(path.name for path in ledger.LEDGER_DATA.glob("doc*.yaml")) == [
        f"doc{document}.yaml" for document in ledger.DOCUMENTS]


def test_every_row_has_a_verdict_and_every_difference_a_reason(rows):
    for row in rows:
        assert row.verdict in ledger.VERDICTS, row.id
        if row.verdict != "agree":
            assert row.reason and row.reason.strip(), f"{row.id}: {row.verdict} without a reason"
        assert row.our_value is not None or row.verdict == "tool-specific", row.id


def test_ids_are_unique_and_carry_their_document(rows):
    assert len({row.id for row in rows}) == len(rows)
    assert all(row.id.startswith(row.document + "-") for row in rows)


def defined_tests(path: Path) -> set[str]:
    """Module-level test functions and Class::method names of a test file."""
    names = set()
    for node in ast.parse(path.read_text(encoding="utf-8")).body:
        if isinstance(node, ast.FunctionDef):
            names.add(node.name)
        elif isinstance(node, ast.ClassDef):
            names |= {f"{node.name}::{item.name}" for item in node.body if isinstance(item, ast.FunctionDef)}
    return names


def test_every_evidence_test_exists(rows):
    """Each node id in an evidence string names a file of this tree and a test in it; a row
    citing `study NAME` names a study of ``youbot-dynamics study``."""
    from youbot_dynamics.cli.study_commands import STUDIES
    missing = []
    for row in rows:
        for file, function in row.node_ids:
            path = REPO / file
            if not path.is_file() or function not in defined_tests(path):
                missing.append(f"{row.id}: {file}::{function}")
        if not row.node_ids:
            assert row.evidence.split()[1] in STUDIES, row.id
    assert not missing, missing


def test_every_figure_is_one_the_report_draws(rows):
    drawn = {Path(spec.file).stem for spec in all_specs()}
    drawn |= {Path(file).stem for section in SECTIONS for file in section.files}
    unknown = [f"{row.id}: {row.figure}" for row in rows if row.figure and row.figure not in drawn]
    assert not unknown, unknown


ROW = {"id": "002-x", "document": "002", "item": "Eq. 1", "quantity": "q", "document_value": "1",
       "our_value": "1", "verdict": "agree", "reason": None,
       "evidence": "test/studies/test_ledger.py::test_all_four_documents_have_rows"}


@pytest.mark.parametrize("change, message", [
    ({"verdict": None}, "verdict is missing"),
    ({"verdict": "differs"}, "verdict 'differs' is none of"),
    ({"verdict": "differs-explained"}, "needs a reason"),
    ({"verdict": "tool-specific", "reason": " "}, "needs a reason"),
    ({"our_value": None}, "our_value is null on a row that is not tool-specific"),
    ({"quantity": ""}, "quantity is missing"),
    ({"id": "003-x"}, "does not start with its document number 002"),
    ({"document": "001"}, "in the file of document 002"),
    ({"evidence": "trust me"}, "names no test node id"),
    ({"colour": "red"}, "unknown field 'colour'"),
])
def test_a_broken_row_is_refused_naming_file_and_row(tmp_path, change, message):
    (tmp_path / "doc002.yaml").write_text(json.dumps([{**ROW, **change}]), encoding="utf-8")
    with pytest.raises(ledger.LedgerError, match=message) as error:
        ledger.load_ledger(tmp_path)
    assert "doc002.yaml: row 1" in str(error.value)


def test_repeated_ids_empty_folders_and_bad_files_are_refused(tmp_path):
    with pytest.raises(ledger.LedgerError, match="no ledger file"):
        ledger.load_ledger(tmp_path)
    (tmp_path / "doc002.yaml").write_text(json.dumps([ROW, ROW]), encoding="utf-8")
    with pytest.raises(ledger.LedgerError, match="ids used more than once: 002-x"):
        ledger.load_ledger(tmp_path)
    (tmp_path / "doc002.yaml").write_text("[unclosed", encoding="utf-8")
    with pytest.raises(ledger.LedgerError, match="not valid YAML"):
        ledger.load_ledger(tmp_path)
    (tmp_path / "doc009.yaml").write_text(json.dumps([ROW]), encoding="utf-8")
    with pytest.raises(ledger.LedgerError, match="no source document '009'"):
        ledger.read_document(tmp_path / "doc009.yaml")


def test_setup_ships_every_ledger_file():
    """setup.py's package_data globs (relative to youbot_dynamics/studies) match every
    doc*.yaml, and MANIFEST.in takes them into the source distribution."""
    tree = ast.parse((REPO / "setup.py").read_text(encoding="utf-8"))
    package_data = next(keyword.value for node in ast.walk(tree) if isinstance(node, ast.Call)
                        for keyword in node.keywords if keyword.arg == "package_data")
    globs = [element.value for value in package_data.values for element in value.elts]
    files = [path.relative_to(REPO / "youbot_dynamics" / "studies").as_posix()
             for path in ledger.LEDGER_DATA.glob("doc*.yaml")]
    assert files and all(any(fnmatch.fnmatch(file, glob) for glob in globs) for file in files)
    assert "recursive-include youbot_dynamics/studies/ledger_data *.yaml" in \
        (REPO / "MANIFEST.in").read_text(encoding="utf-8")


def test_summary_counts_every_row_once(rows):
    counts = ledger.summary(rows)
    assert sum(counts["all"].values()) == len(rows)
    assert sum(sum(c.values()) for document, c in counts.items() if document != "all") == len(rows)


def test_study_ledger_json_text_and_filters(capsys, rows):
    assert cli.main(["study", "ledger", "--json"]) == 0
    record = json.loads(capsys.readouterr().out)
    assert len(record["rows"]) == len(rows)
    assert set(record["rows"][0]) >= {"document", "item", "quantity", "document_value", "our_value",
                                      "verdict", "reason", "id", "evidence", "figure"}
    assert cli.main(["study", "ledger", "--json", "--document", "002", "--verdict", "agree"]) == 0
    selected = json.loads(capsys.readouterr().out)
    assert selected["rows"] and {(r["document"], r["verdict"]) for r in selected["rows"]} == {("002", "agree")}
    assert selected["summary"]["all"]["agree"] == len(selected["rows"])
    assert cli.main(["study", "ledger", "--document", "002"]) == 0
    text = capsys.readouterr().out
    assert "| document 002 |" in text and "### Document 002" in text and "002-unicycle-parameters" in text
    assert cli.main(["study", "ledger", "--verdict", "differs"]) == 2
    assert "invalid choice: 'differs'" in capsys.readouterr().err


def test_a_rows_figure_links_to_its_subsection_where_drawn():
    row = ledger.Row(**{**ROW, "figure": "woodpecker_z"})
    linked = ledger.rows_table([row], lambda name: f"[{name}](#figure-{name})")
    assert "; figure [woodpecker_z](#figure-woodpecker_z) |" in linked
    assert "; figure woodpecker_z |" in ledger.rows_table([row], lambda name: None)
    assert ledger.table_cell("a | b\nc") == "a \\| b c" and ledger.table_cell(None) == "-"
