"""Tables as CSV: one header row of column names, then one row per sample (SI units)."""
from __future__ import annotations

import csv
from pathlib import Path
from typing import Sequence

import numpy as np


def write_csv(path: str | Path, names: Sequence[str], table: np.ndarray) -> None:
    """Write ``table`` (k, m) under the column ``names`` (m) to ``path``."""
    with open(path, "w", newline="", encoding="utf-8") as handle:
        writer = csv.writer(handle)
        writer.writerow(names)
        writer.writerows(np.asarray(table).tolist())
