"""Ctrl-C during a long computation: KeyboardInterrupt within a second,
nothing written."""

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


@pytest.mark.skipif(sys.platform == "win32", reason="POSIX signals")
def test_sigint_interrupts_a_long_simulate(tmp_path):
    out = tmp_path / "run"
    proc = subprocess.Popen([sys.executable, "-c", SCRIPT, str(out)],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        assert proc.stdout.readline().strip() == "started"
        time.sleep(1.5)
        assert proc.poll() is None, "the simulation ended before the signal"
        sent = time.monotonic()
        proc.send_signal(signal.SIGINT)
        proc.wait(timeout=10)
        elapsed = time.monotonic() - sent
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    stdout, stderr = proc.communicate()
    assert "KeyboardInterrupt" in stdout, stderr
    assert proc.returncode == 42, stderr
    assert elapsed < 1.0, f"exited {elapsed:.2f} s after SIGINT"
    assert not out.exists()
    assert os.listdir(tmp_path) == [], "a partial output was left behind"
