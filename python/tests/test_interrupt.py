"""Ctrl-C during a long computation: KeyboardInterrupt within a second,
nothing written; the next call in the same session runs."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import textwrap
import time

import pytest

SCRIPT = textwrap.dedent(
    """
    import signal
    import sys
    import irtp
    # Python's own Ctrl-C handler, even if this process inherited SIGINT
    # ignored (POSIX does that to jobs started with `&` by a script).
    signal.signal(signal.SIGINT, signal.default_int_handler)
    print("started", flush=True)
    try:
        irtp.simulate(particles=10**9, t_max=1000.0, samples=11, out=sys.argv[1], threads=2,
                      max_work=1e20)
    except KeyboardInterrupt:
        print("KeyboardInterrupt", flush=True)
        sys.exit(42)
    print("finished", flush=True)
    """
)


# A search on a fine 2-D mesh: its time goes to banded factorisations and
# solves, which poll the process's stop request, not a progress observer.
SEARCH = textwrap.dedent(
    """
    import signal
    import sys
    import irtp
    signal.signal(signal.SIGINT, signal.default_int_handler)
    print("started", flush=True)
    try:
        irtp.mfpt(xt=1.0, reset_position=0.0, v0=0.0, rate=1.0, cells_x=96, cells_v=48,
                  max_work=1e20, max_memory=2e10, out=sys.argv[1])
    except KeyboardInterrupt:
        print("KeyboardInterrupt", flush=True)
        # The stop request is withdrawn: the next call runs to its answer.
        r = irtp.mfpt(v0=0.0, vt=1.0)
        print("next tau", r.tau, flush=True)
        sys.exit(42)
    print("finished", flush=True)
    """
)


def interrupt(script: str, out) -> tuple:
    """Run `script`, SIGINT it 1.5 s after it started computing; its
    (stdout, stderr, exit code, seconds from the signal to its exit)."""
    proc = subprocess.Popen([sys.executable, "-c", script, str(out)],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        assert proc.stdout.readline().strip() == "started"
        time.sleep(1.5)
        assert proc.poll() is None, "the run ended before the signal"
        sent = time.monotonic()
        proc.send_signal(signal.SIGINT)
        proc.wait(timeout=30)
        elapsed = time.monotonic() - sent
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    stdout, stderr = proc.communicate()
    return stdout, stderr, proc.returncode, elapsed


@pytest.mark.skipif(sys.platform == "win32", reason="POSIX signals")
def test_sigint_interrupts_a_long_simulate(tmp_path):
    out = tmp_path / "run"
    stdout, stderr, code, elapsed = interrupt(SCRIPT, out)
    assert "KeyboardInterrupt" in stdout, stderr
    assert code == 42, stderr
    assert elapsed < 1.0, f"exited {elapsed:.2f} s after SIGINT"
    assert not out.exists()
    assert os.listdir(tmp_path) == [], "a partial output was left behind"


@pytest.mark.skipif(sys.platform == "win32", reason="POSIX signals")
def test_sigint_interrupts_a_search_mesh_solve_and_the_next_call_runs(tmp_path):
    out = tmp_path / "run"
    stdout, stderr, code, elapsed = interrupt(SEARCH, out)
    assert "KeyboardInterrupt" in stdout, stderr
    assert code == 42, stderr
    assert elapsed < 2.0, f"exited {elapsed:.2f} s after SIGINT"
    tau = float(stdout.split("next tau")[1].split()[0])
    assert tau > 0.0, stdout
    assert not out.exists()
