"""The ``irtp`` command of the wheel (``[project.scripts]``): the Rust
binary's command line, run by the extension (``irtp_cli::run_cli``), so
``pip install ./python`` alone gives the whole tool, at the same version."""

from __future__ import annotations

import signal
import sys

from . import _irtp


def main() -> None:
    """Run ``irtp`` with this process's arguments and exit with its status.
    A closed pipe (``irtp ... | head``) ends it quietly, as it ends the
    binary (this process runs nothing else)."""
    if hasattr(signal, "SIGPIPE"):
        signal.signal(signal.SIGPIPE, signal.SIG_DFL)
    sys.exit(_irtp.cli_main(["irtp", *sys.argv[1:]]))
