"""The source-document ledger: every figure, table and checkable claim of the four source
documents, the document's value beside ours, and a verdict.

The rows live in ``ledger_data/doc000.yaml`` ... ``doc003.yaml`` (one file per document,
shipped with the package), each a YAML list of rows with the fields of :class:`Row`:

- ``id``: unique, lowercase, the document number first (``002-unicycle-friction``);
- ``document``: "000" | "001" | "002" | "003" (the file it sits in);
- ``item``: the document's own label ("Fig. 22", "Table 6", "p. 12 claim");
- ``quantity``: what is compared, with units; ``document_value``: as the document prints it;
- ``our_value``: what our code produces now (text with units); null only on a
  ``tool-specific`` row (a Dymola GUI, a licence count: nothing of ours to compare);
- ``verdict``: ``agree`` | ``differs-explained`` | ``tool-specific``;
- ``reason``: why they differ, with numbers (required unless the verdict is agree);
- ``evidence``: the test node id(s) (``test/studies/test_x.py::test_y``) asserting our
  value, or ``study NAME`` and the figure that shows it;
- ``figure`` (optional): the report figure (its file name without .png) drawing the
  document's value beside ours.

:func:`load_ledger` reads every ``doc*.yaml`` of the folder and refuses (LedgerError, naming
the file and the row) a row that breaks these rules; that the evidence exists in the source
tree is test/studies/test_ledger.py's check (tests do not ship with the package).
"""
from __future__ import annotations

import re
from collections import Counter
from dataclasses import asdict, dataclass, fields
from pathlib import Path
from typing import Iterable, Sequence

import yaml

from youbot_dynamics.errors import UserInputError

#: The folder of the ledger's YAML files (package data).
LEDGER_DATA = Path(__file__).with_name("ledger_data")
#: The four source documents, by number.
DOCUMENTS = ("000", "001", "002", "003")
#: The verdicts a row may carry, in the order the summary counts them.
VERDICTS = ("agree", "differs-explained", "tool-specific")
#: A row id: the document number, a hyphen, then lowercase letters, digits, '-', '.', '_'.
ID_PATTERN = re.compile(r"^(\d{3})-[a-z0-9][a-z0-9._-]*$")
#: A test node id inside an evidence string: file::function (a class and [parameters] allowed).
NODE_ID = re.compile(r"(test/[\w/]+\.py)::([\w]+(?:::[\w]+)?)(\[[^\]\s]*\])?")


class LedgerError(UserInputError):
    """A ledger file or row that breaks the format: names the file and the row."""


@dataclass(frozen=True)
class Row:
    """One ledger row (module docstring); ``our_value`` None only on tool-specific rows."""

    id: str
    document: str
    item: str
    quantity: str
    document_value: str
    our_value: str | None
    verdict: str
    reason: str | None = None
    evidence: str = ""
    figure: str | None = None

    def as_json(self) -> dict:
        """The row's fields as a JSON object."""
        return asdict(self)

    @property
    def node_ids(self) -> list[tuple[str, str]]:
        """The (file, function) of every test node id named in ``evidence``."""
        return [(match[1], match[2]) for match in NODE_ID.finditer(self.evidence)]


#: Fields every row must give (non-empty text); ``our_value`` must be present (null allowed).
REQUIRED = ("id", "document", "item", "quantity", "document_value", "verdict", "evidence")
FIELD_NAMES = tuple(field.name for field in fields(Row))


def field_problems(record: dict) -> list[str]:
    """Unknown fields, missing required text, a missing our_value."""
    problems = [f"unknown field {key!r}" for key in record if key not in FIELD_NAMES]
    problems += [f"{key} is missing or empty" for key in REQUIRED
                 if not isinstance(record.get(key), str) or not record[key].strip()]
    if "our_value" not in record:
        problems.append("our_value is missing (null only for a tool-specific row)")
    elif record["our_value"] is not None and not isinstance(record["our_value"], (str, int, float)):
        problems.append(f"our_value must be text (with units), got {type(record['our_value']).__name__}")
    return problems


def verdict_problems(record: dict) -> list[str]:
    """A verdict outside VERDICTS, a difference without a reason, an empty value of ours on
    a row that is not tool-specific."""
    verdict, problems = record.get("verdict"), []
    if verdict is not None and verdict not in VERDICTS:
        problems.append(f"verdict {verdict!r} is none of {', '.join(VERDICTS)}")
    if verdict != "agree" and not str(record.get("reason") or "").strip():
        problems.append(f"a {verdict} row needs a reason (the evidence for the difference)")
    if "our_value" in record and record["our_value"] is None and verdict != "tool-specific":
        problems.append("our_value is null on a row that is not tool-specific")
    return problems


def place_problems(record: dict, document: str) -> list[str]:
    """An id not of the form '<document>-<name>' or of another document, a row in another
    document's file, evidence that names neither a test node id nor a study."""
    row_id, problems = record.get("id"), []
    if isinstance(row_id, str) and row_id and not ID_PATTERN.match(row_id):
        problems.append(f"id {row_id!r} is not lowercase '<document>-<name>'")
    elif isinstance(row_id, str) and row_id and row_id[:3] != document:
        problems.append(f"id {row_id!r} does not start with its document number {document}")
    if record.get("document") not in (None, document):
        problems.append(f"document {record.get('document')!r} in the file of document {document}")
    evidence = str(record.get("evidence") or "")
    if evidence and not NODE_ID.search(evidence) and not evidence.startswith("study "):
        problems.append(f"evidence {evidence!r} names no test node id (test/...py::test_name) "
                        "and no `study NAME`")
    return problems


def row_problems(record: object, document: str) -> list[str]:
    """What is wrong with one row (a YAML mapping) of ``document``'s file; [] if nothing."""
    if not isinstance(record, dict):
        return [f"a row must be a mapping of {', '.join(FIELD_NAMES)}, got {type(record).__name__}"]
    return field_problems(record) + verdict_problems(record) + place_problems(record, document)


def read_document(path: Path) -> list[Row]:
    """The rows of one ``docNNN.yaml`` (LedgerError naming the file and every bad row)."""
    document = path.stem.removeprefix("doc")
    if document not in DOCUMENTS:
        raise LedgerError(f"{path}: no source document {document!r}; the files are "
                          f"{', '.join(f'doc{d}.yaml' for d in DOCUMENTS)}")
    try:
        records = yaml.safe_load(path.read_text(encoding="utf-8"))
    except yaml.YAMLError as error:
        raise LedgerError(f"{path}: not valid YAML: {error}") from None
    if not isinstance(records, list) or not records:
        raise LedgerError(f"{path}: expected a non-empty YAML list of rows")
    errors = [f"{path}: row {k + 1} ({record.get('id', '?') if isinstance(record, dict) else '?'}): "
              f"{problem}" for k, record in enumerate(records)
              for problem in row_problems(record, document)]
    if errors:
        raise LedgerError("\n".join(errors))
    return [Row(**{**record, "our_value": None if record["our_value"] is None
                   else str(record["our_value"])}) for record in records]


def load_ledger(folder: Path | str = LEDGER_DATA) -> list[Row]:
    """Every row of every ``doc*.yaml`` in ``folder``, document by document, in file order;
    LedgerError if a file is bad or an id repeats."""
    paths = sorted(Path(folder).glob("doc*.yaml"))
    if not paths:
        raise LedgerError(f"{folder}: no ledger file (doc000.yaml ... doc003.yaml)")
    rows = [row for path in paths for row in read_document(path)]
    repeated = sorted(name for name, count in Counter(row.id for row in rows).items() if count > 1)
    if repeated:
        raise LedgerError(f"{folder}: ids used more than once: {', '.join(repeated)}")
    return rows


def select(rows: Iterable[Row], documents: Sequence[str] = (), verdicts: Sequence[str] = ()
           ) -> list[Row]:
    """The rows of the given documents and verdicts (empty: all)."""
    return [row for row in rows if (not documents or row.document in documents)
            and (not verdicts or row.verdict in verdicts)]


def summary(rows: Sequence[Row]) -> dict[str, dict[str, int]]:
    """Row counts per document and verdict (every verdict listed, zeros included), plus
    "all" over the documents."""
    counts = {document: {verdict: 0 for verdict in VERDICTS}
              for document in dict.fromkeys(row.document for row in rows)}
    counts["all"] = {verdict: 0 for verdict in VERDICTS}
    for row in rows:
        counts[row.document][row.verdict] += 1
        counts["all"][row.verdict] += 1
    return counts


def as_json(rows: Sequence[Row]) -> dict:
    """The rows and their summary as one JSON object."""
    return {"rows": [row.as_json() for row in rows], "summary": summary(rows)}


def table_cell(value: object) -> str:
    """A value as a Markdown table cell: '-' for None, '|' escaped, one line."""
    return "-" if value is None else " ".join(str(value).replace("|", "\\|").split())


def summary_table(rows: Sequence[Row]) -> str:
    """The counts per document and verdict as a Markdown table."""
    lines = ["| document | rows | " + " | ".join(VERDICTS) + " |",
             "|---|---|" + "---|" * len(VERDICTS)]
    for document, counts in summary(rows).items():
        label = "all" if document == "all" else f"document {document}"
        lines.append(f"| {label} | {sum(counts.values())} | "
                     + " | ".join(str(counts[v]) for v in VERDICTS) + " |")
    return "\n".join(lines)


def rows_table(rows: Sequence[Row], figure_link=None) -> str:
    """The rows as a Markdown table (item, quantity, document, ours, verdict, reason,
    evidence); ``figure_link(name)`` (optional) turns a row's figure into a link, or None."""
    lines = ["| id | item | quantity | document | ours | verdict | reason | evidence |",
             "|---|---|---|---|---|---|---|---|"]
    for row in rows:
        evidence = table_cell(row.evidence)
        link = figure_link(row.figure) if figure_link and row.figure else None
        if row.figure:
            evidence += f"; figure {link or table_cell(row.figure)}"
        lines.append("| " + " | ".join([row.id, table_cell(row.item), table_cell(row.quantity),
                                         table_cell(row.document_value), table_cell(row.our_value),
                                         row.verdict, table_cell(row.reason), evidence]) + " |")
    return "\n".join(lines)


def text(rows: Sequence[Row], figure_link=None) -> str:
    """The summary, then one table per document (Markdown)."""
    parts = [summary_table(rows)]
    for document in dict.fromkeys(row.document for row in rows):
        parts += [f"### Document {document}", rows_table(select(rows, [document]), figure_link)]
    return "\n\n".join(parts)
