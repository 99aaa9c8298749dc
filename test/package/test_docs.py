"""The README is a short guide and the pages under docs/ hold together: the README within
300 lines of at most 100 characters, no internal words, every relative link and anchor
resolves, every file named with its folder exists, and docs/benchmarks.md is the page bench/summary.py makes of bench/results.json."""
from __future__ import annotations

import json
import re
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
DOCS = ROOT / "docs"
PAGES = [ROOT / "README.md", *sorted(DOCS.glob("*.md"))]
LINK = re.compile(r"\]\(([^)\s]+)\)")
#: A file named in code style with its folder: `dynamics/friction.py`, `config/scenes/grasp.yaml`.
NAMED_FILE = re.compile(r"`([\w.-]+(?:/[\w.-]+)+\.(?:py|yaml|sh|txt|urdf))`")
#: Words that mean something only inside the project's history: the source documents called
#: by an internal name, issue numbers.
INTERNAL = re.compile(r"\bthe seeds?\b|\bseeds?'s?(?=\W)|\bseed \d{3}\b|\bissue[- #]?\d+", re.I)


def heading_anchors(path: Path) -> set[str]:
    """GitHub's anchors of the Markdown headings in ``path`` (lower case, punctuation
    dropped, spaces to hyphens)."""
    anchors = set()
    in_code = False
    for line in path.read_text(encoding="utf-8").splitlines():
        if line.startswith("```"):
            in_code = not in_code
        elif not in_code and line.startswith("#"):
            title = line.lstrip("#").strip().lower()
            anchors.add(re.sub(r"[^\w\- ]", "", title).replace(" ", "-"))
    return anchors


def test_the_readme_is_a_short_guide():
    lines = (ROOT / "README.md").read_text(encoding="utf-8").splitlines()
    assert len(lines) <= 300
    assert [n for n, line in enumerate(lines, 1) if len(line) > 100] == []
    text = "\n".join(lines)
    for needed in ("make run", "make test", "use_sim_time:=true", "docs/node.md", "## Contents"):
        assert needed in text


@pytest.mark.parametrize("path", PAGES, ids=lambda p: p.name)
def test_no_internal_words(path):
    text = path.read_text(encoding="utf-8")
    assert [m.group(0) for m in INTERNAL.finditer(text)] == []


@pytest.mark.parametrize("path", PAGES, ids=lambda p: p.name)
def test_relative_links_and_anchors_resolve(path):
    broken = []
    for target in LINK.findall(path.read_text(encoding="utf-8")):
        if re.match(r"[a-z]+:", target):
            continue  # http(s), mailto: not checked here
        file, _, anchor = target.partition("#")
        linked = (path.parent / file).resolve() if file else path
        if not linked.exists():
            broken.append(target)
        elif anchor and linked.suffix == ".md" and anchor not in heading_anchors(linked):
            broken.append(target)
    assert broken == []


@pytest.mark.parametrize("path", PAGES, ids=lambda p: p.name)
def test_named_files_exist(path):
    """Files named with their folder exist, from the repository's root or the package's."""
    named = set(NAMED_FILE.findall(path.read_text(encoding="utf-8")))
    assert sorted(f for f in named if not ((ROOT / f).exists() or (ROOT / "youbot_dynamics" / f).exists())) == []


def test_the_benchmarks_page_is_the_latest_results_page():
    sys.path.insert(0, str(ROOT / "bench"))
    try:
        from benchmarks_page import PAGE, RESULTS, page
    finally:
        sys.path.remove(str(ROOT / "bench"))
    assert PAGE.read_text(encoding="utf-8") == page(json.loads(RESULTS.read_text(encoding="utf-8")))
