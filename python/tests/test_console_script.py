"""The wheel's ``irtp`` command (``[project.scripts]``, ``irtp._cli:main``)
is the Rust binary's command line: the same version line, the same output
and exit status, installed by ``pip install ./python`` alone."""

from __future__ import annotations

import pathlib
import subprocess
import sys

import pytest

SCRIPT = pathlib.Path(sys.executable).parent / "irtp"


def run(exe, *argv):
    return subprocess.run([str(exe), *argv], capture_output=True, text=True, timeout=300)


def test_console_script_is_installed_beside_python():
    assert SCRIPT.exists(), f"no irtp command in {SCRIPT.parent}"


@pytest.mark.parametrize("argv", [
    ["--version"],
    ["fp", "stationary", "--cells", "400", "--json"],
    ["fp", "stationary", "--cells", "3"],        # bad input: one line, exit 2
    ["simulate", "--particles", "0"],            # bad input
    ["nonsense"],                                # clap's refusal
])
def test_console_script_matches_the_binary(cli, argv):
    got, want = run(SCRIPT, *argv), run(cli.path, *argv)
    assert got.returncode == want.returncode, got.stderr
    assert got.stderr == want.stderr
    if "--json" in argv:
        import json
        from conftest import strip
        g, w = json.loads(got.stdout), json.loads(want.stdout)
        assert strip(g["results"]) == strip(w["results"])
    else:
        assert got.stdout == want.stdout
