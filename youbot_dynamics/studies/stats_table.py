"""The integrator statistics of a study's runs as a text table, in the columns of the
document 001's Tables 15 and 16 (steps, f-evals, J-evals, state events, CPU time in s)."""
from __future__ import annotations

from youbot_dynamics.io.text_tables import cell

#: (key of IntegratorStats.as_dict(), column title), as in document 001's Tables 15 and 16.
STAT_COLUMNS = (("steps", "steps"), ("rhs_evals", "f-evals"), ("jac_evals", "J-evals"),
                ("events", "state events"), ("wall_time", "CPU time (s)"))


def stats_table(rows: dict[str, dict]) -> str:
    """A text table: one row per run (name -> statistics dict), the document's columns."""
    header = f"{'run':<24}" + "".join(f"{title:>14}" for _, title in STAT_COLUMNS)
    lines = [header]
    for name, stats in rows.items():
        lines.append(f"{name:<24}" + "".join(f"{cell(stats.get(key)):>14}" for key, _ in STAT_COLUMNS))
    return "\n".join(lines)
