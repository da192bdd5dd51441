#!/usr/bin/env bash
# The Python package's tests, run as a new user would: a fresh virtual
# environment, `pip install "./python[test]"` (maturin builds the extension
# from this checkout), then pytest, which also executes the example notebook
# and compares every function bit for bit with the CLI.
#
# The extension is built in cargo's dev profile (opt-level 3, as the Rust
# tests), sharing the workspace's target directory and compiled
# dependencies with `cargo test`; a user's `pip install ./python` builds the
# release profile. IRTP_PY_PROFILE=release tests that build instead.
set -euo pipefail
cd "$(dirname "$0")/.."
venv="${IRTP_VENV:-target/py-venv}"
rm -rf "$venv"
if ! python3 -m venv "$venv"; then
  # Debian's python3 ships venv separately.
  sudo_=""; [ "$(id -u)" -ne 0 ] && sudo_="sudo"
  $sudo_ apt-get install -y python3-venv
  rm -rf "$venv"
  python3 -m venv "$venv"
fi
"$venv/bin/python" -m pip install --quiet --upgrade pip
MATURIN_PEP517_ARGS="--profile ${IRTP_PY_PROFILE:-dev}" \
  "$venv/bin/python" -m pip install --quiet "./python[test]"
# The CLI the bit-identity tests compare with (the same crate, this
# checkout): built here unless IRTP_BIN names one (CI passes the binary its
# `cargo test` built, which is the same build).
if [ -z "${IRTP_BIN:-}" ]; then
  cargo build --locked --bin irtp
  IRTP_BIN=target/debug/irtp
fi
IRTP_BIN="$IRTP_BIN" IRTP_REQUIRE_CLI=1 "$venv/bin/python" -m pytest -q python/tests "$@"
