"""The Python examples of the README and of docs/python.md run as written and print what the
text says they print."""
from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
EXAMPLE = re.compile(r"```python\n(.*?)```\s*```text\n(.*?)```", re.S)


def readme_examples() -> list[tuple[str, str]]:
    """(code, expected output) of every ```python block of the README's "Python API" section
    that is followed by a ```text block."""
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    section = text.split("## Python API", 1)[1].split("\n## ", 1)[0]
    return EXAMPLE.findall(section)


def examples() -> list[tuple[str, str]]:
    """The README's examples, then every such pair of docs/python.md."""
    return readme_examples() + EXAMPLE.findall((ROOT / "docs" / "python.md").read_text(encoding="utf-8"))


def test_the_readme_and_the_api_page_have_examples():
    assert len(readme_examples()) >= 1
    assert len(examples()) >= 2


@pytest.mark.parametrize("index", range(len(examples())))
def test_example_prints_what_the_text_says(index, tmp_path):
    code, expected = examples()[index]
    environment = {**os.environ, "PYTHONPATH": str(ROOT)}
    done = subprocess.run([sys.executable, "-c", code], cwd=tmp_path, env=environment,
                          capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == expected.strip()
