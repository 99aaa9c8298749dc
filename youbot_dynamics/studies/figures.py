"""What every study's figures share: the declared figure, the figure set, matplotlib set-up.

A *figure set* belongs to one study of the report (studies/report.py, whose catalogue lists
the sets of every study): it declares its
figures up front (:class:`FigureSpec`: PNG file name, caption, what the document shows or
says), and its function ``draw(result, out_dir, full) -> {file: (ours, difference)}``
draws from the study's ``result`` (what its ``run(config)`` returned in the report; None:
not run) where that holds what the figures need, runs the cases it lacks, writes every
declared PNG into ``out_dir`` and says for each what our run measured and how that
differs from the document. ``full`` runs the document's sizes; the default
(short) form keeps every set to seconds. The declared list is what the report's page and
its test enumerate, so a set that does not write one of its files is an error here, not a
missing image on the page.

Plots: matplotlib with the Agg backend, small PNGs (DPI dots per inch); several panels in
one PNG only where the seed drew them together.
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Callable

#: Resolution of every figure (dots per inch): small PNGs, readable at page width.
DPI = 90


@dataclass(frozen=True)
class FigureSpec:
    """A declared figure: PNG ``file`` (name in the report folder), ``caption`` (what it
    shows) and ``seed`` (the seed's figure or verdict it stands beside)."""

    file: str
    caption: str
    seed: str


@dataclass(frozen=True)
class Figure:
    """A drawn figure: its spec, what our run measured (``ours``) and the difference from
    the seed."""

    spec: FigureSpec
    ours: str
    difference: str


@dataclass(frozen=True)
class FigureSet:
    """The figures of one study: its name, the declared specs in page order and the
    drawing function ``draw(result, out_dir, full) -> {file: (ours, difference)}``."""

    name: str
    specs: tuple[FigureSpec, ...]
    draw: Callable[[object, Path, bool], dict[str, tuple[str, str]]]


def specs(*rows: tuple[str, str, str]) -> tuple[FigureSpec, ...]:
    """FigureSpecs from (file, caption, seed) rows."""
    return tuple(FigureSpec(*row) for row in rows)


def heading(text: str) -> str:
    """``text`` with its first letter upper case (the rest as it is), for captions."""
    return text[:1].upper() + text[1:]


def pyplot():
    """matplotlib.pyplot on the Agg backend (no display needed)."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    return plt


def panels(rows: int = 1, columns: int = 1, size: tuple[float, float] = (7.5, 4.0),
           sharex: bool = True):
    """A new figure of rows x columns axes (a single axis when 1 x 1), grid on."""
    plt = pyplot()
    figure, axes = plt.subplots(rows, columns, figsize=size, sharex=sharex, squeeze=False)
    for axis in axes.flat:
        axis.grid(True, alpha=0.3)
    return figure, (axes[0, 0] if rows == columns == 1 else axes.ravel())


def save(figure, path: Path | str, title: str | None = None) -> None:
    """Write ``figure`` as a PNG at DPI (title on top if given) and close it."""
    if title:
        figure.suptitle(title, fontsize=10)
    figure.tight_layout()
    figure.savefig(path, dpi=DPI)
    pyplot().close(figure)


def draw_set(figure_set: FigureSet, out_dir: Path | str, full: bool = False,
             result: object = None) -> list[Figure]:
    """Draw one set into ``out_dir``; its figures in declared order. RuntimeError naming
    the set and the files if it did not write exactly its declared PNGs."""
    out = Path(out_dir)
    drawn = figure_set.draw(result, out, full)
    declared = [spec.file for spec in figure_set.specs]
    missing = [name for name in declared if name not in drawn or not (out / name).is_file()]
    extra = sorted(set(drawn) - set(declared))
    if missing or extra:
        raise RuntimeError(f"figure set {figure_set.name}: "
                           + (f"did not write {', '.join(missing)}" if missing else "")
                           + ("; " if missing and extra else "")
                           + (f"wrote undeclared {', '.join(extra)}" if extra else ""))
    return [Figure(spec, *drawn[spec.file]) for spec in figure_set.specs]
