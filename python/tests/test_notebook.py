"""The example notebook docs/examples/quickstart.ipynb executes without errors."""

from __future__ import annotations

import os
import pathlib
import sys

import pytest

NOTEBOOK = pathlib.Path(__file__).resolve().parents[2] / "docs" / "examples" / "quickstart.ipynb"


def test_quickstart_notebook_runs(tmp_path, monkeypatch):
    nbformat = pytest.importorskip("nbformat")
    nbclient = pytest.importorskip("nbclient")
    pytest.importorskip("matplotlib")
    # The kernel draws with matplotlib's inline backend: no display needed.
    monkeypatch.delenv("MPLBACKEND", raising=False)
    # The sweep cell runs `irtp` from PATH: the install's own console
    # script (pip install ./python), as a pip-only user's PATH has it.
    bindir = pathlib.Path(sys.executable).parent
    assert (bindir / "irtp").exists(), "pip install ./python installs the irtp command"
    monkeypatch.setenv("PATH", f"{bindir}{os.pathsep}{os.environ['PATH']}")
    nb = nbformat.read(NOTEBOOK, as_version=4)
    stored = [c for c in nb.cells if c.cell_type == "code"]
    assert all(c.get("outputs") for c in stored), "the notebook is stored executed"
    for c in stored:
        c.outputs = []
    client = nbclient.NotebookClient(nb, timeout=300, kernel_name="python3",
                                     resources={"metadata": {"path": str(tmp_path)}})
    client.execute()  # raises CellExecutionError on the first failing cell
    errors = [o for c in nb.cells if c.cell_type == "code"
              for o in c.get("outputs", []) if o.get("output_type") == "error"]
    assert errors == []
    images = [o for c in nb.cells if c.cell_type == "code" for o in c.get("outputs", [])
              if "image/png" in o.get("data", {})]
    assert len(images) == 3, "Fig. 2(a), Fig. 7(b) and the sweep's heat map"
