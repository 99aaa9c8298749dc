"""Figures as text: a table cell (``-`` for an unknown figure) and a Markdown table, as the
commands and the studies print them (and the report's page shows them)."""
from __future__ import annotations

import math
from typing import Any, Iterable, Sequence

import numpy as np


def cell(value: object, digits: int = 4) -> str:
    """A figure for a statistics or study table: '-' when not known (None or NaN), integers
    and text as they are, other numbers to ``digits`` significant digits."""
    if value is None or (isinstance(value, float) and math.isnan(value)):
        return "-"
    if isinstance(value, (str, bool, int, np.integer)):
        return str(value)
    return f"{value:.{digits}g}"


def markdown_table(header: Sequence[str], rows: Iterable[Sequence[Any]], digits: int = 4) -> str:
    """A markdown table; cells formatted with :func:`cell`."""
    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    lines += ["| " + " | ".join(cell(value, digits) for value in row) + " |" for row in rows]
    return "\n".join(lines)


def records_table(rows: Sequence[dict], digits: int = 4) -> str:
    """A markdown table over the union of the rows' keys, in first-seen order (a key a row
    lacks: -)."""
    keys = list(dict.fromkeys(key for row in rows for key in row))
    return markdown_table(keys, [[row.get(key) for key in keys] for row in rows], digits)
