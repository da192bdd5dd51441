"""Docs that run: every ```python block of README.md and docs/*.md is executed
as printed, each file's blocks in order in one namespace (a later block may use
an earlier one's names), in a temporary working directory."""

from __future__ import annotations

import pathlib
import re

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[2]
DOCS = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]
BLOCK = re.compile(r"^```python\n(.*?)^```", re.S | re.M)


def blocks(path: pathlib.Path) -> list[str]:
    return BLOCK.findall(path.read_text())


def test_the_docs_have_python_examples():
    assert sum(len(blocks(p)) for p in DOCS) >= 8


@pytest.mark.parametrize("doc", [p for p in DOCS if blocks(p)], ids=lambda p: p.name)
def test_python_blocks_run(doc, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    namespace: dict = {"__name__": "__docs__"}
    for i, code in enumerate(blocks(doc)):
        try:
            exec(compile(code, f"{doc.name} block {i + 1}", "exec"), namespace)
        except Exception as e:  # noqa: BLE001 - reported with its place
            pytest.fail(f"{doc.name}, python block {i + 1}: {type(e).__name__}: {e}\n{code}")
