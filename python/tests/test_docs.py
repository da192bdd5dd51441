"""Docs that run: every ```python block of README.md and of the pages under
docs/ is executed as printed, each file's blocks in order in one namespace (a
later block may use an earlier one's names), in a temporary working directory
where examples/ is the repository's, with the changes
docs/reference/conventions.md states for the documented CLI commands: at most 4000 particles and
`reproduce` with `quick=True` (the module's functions are wrapped for the
test, so `import irtp` in a block sees them). A file whose blocks run the
CLI (`subprocess.run(["irtp", ...])`) finds the CLI under test ($IRTP_BIN) as
`irtp` on PATH; matplotlib draws with the Agg backend."""

from __future__ import annotations

import functools
import inspect
import os
import pathlib
import re

import irtp
import pytest

MAX_PARTICLES = 4000

ROOT = pathlib.Path(__file__).resolve().parents[2]
# README.md and every page under docs/ but for docs/figures (reproduce's output).
DOCS = [
    ROOT / "README.md",
    *sorted(p for p in (ROOT / "docs").rglob("*.md") if "figures" not in p.parts),
]
BLOCK = re.compile(r"^```python\n(.*?)^```", re.S | re.M)


def blocks(path: pathlib.Path) -> list[str]:
    return BLOCK.findall(path.read_text())


def test_the_docs_have_python_examples():
    assert sum(len(blocks(p)) for p in DOCS) >= 8


def reduced(f):
    """`f` with `particles` capped and `reproduce` quick."""

    @functools.wraps(f)
    def call(*args, **kwargs):
        if "particles" in kwargs:
            kwargs["particles"] = min(kwargs["particles"], MAX_PARTICLES)
        if f.__name__ == "reproduce":
            kwargs["quick"] = True
        return f(*args, **kwargs)

    return call


def reduce_sizes(monkeypatch):
    for name in irtp.__all__:
        f = getattr(irtp, name)
        if inspect.isfunction(f) or inspect.isbuiltin(f):
            monkeypatch.setattr(irtp, name, reduced(f))


def test_sizes_are_reduced(monkeypatch):
    reduce_sizes(monkeypatch)
    res = irtp.simulate(particles=1_000_000, t_max=2, burn_in=1)
    assert res.params["particles"] == MAX_PARTICLES


def cli_on_path(request, tmp_path, monkeypatch) -> None:
    """The CLI under test as `irtp` on PATH, for blocks that run it (a sweep
    before `irtp.load_sweep`); skipped like the CLI tests when it is missing."""
    cli = request.getfixturevalue("cli")
    bin_dir = tmp_path / "_bin"
    bin_dir.mkdir()
    (bin_dir / "irtp").symlink_to(cli.path)
    monkeypatch.setenv("PATH", f"{bin_dir}{os.pathsep}{os.environ.get('PATH', '')}")


@pytest.mark.parametrize("doc", [p for p in DOCS if blocks(p)], ids=lambda p: p.name)
def test_python_blocks_run(doc, tmp_path, monkeypatch, request):
    if any('"irtp"' in code for code in blocks(doc)):
        cli_on_path(request, tmp_path, monkeypatch)
    monkeypatch.setenv("MPLBACKEND", "Agg")
    # The repository's example plans at their documented paths.
    (tmp_path / "examples").symlink_to(ROOT / "examples")
    monkeypatch.chdir(tmp_path)
    reduce_sizes(monkeypatch)
    namespace: dict = {"__name__": "__docs__"}
    for i, code in enumerate(blocks(doc)):
        try:
            exec(compile(code, f"{doc.name} block {i + 1}", "exec"), namespace)
        except Exception as e:  # noqa: BLE001 - reported with its place
            pytest.fail(f"{doc.name}, python block {i + 1}: {type(e).__name__}: {e}\n{code}")
