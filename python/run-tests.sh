#!/usr/bin/env bash
# The Python package's tests, run as a new user would: a fresh virtual
# environment, `pip install "./python[test]"` (maturin builds the release
# extension from this checkout), then pytest, which also executes the
# example notebook and compares every function bit for bit with the CLI.
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
"$venv/bin/python" -m pip install --quiet "./python[test]"
# The CLI the bit-identity tests compare with (the same crate, this checkout).
cargo build --locked --bin irtp
IRTP_BIN=target/debug/irtp IRTP_REQUIRE_CLI=1 "$venv/bin/python" -m pytest -q python/tests "$@"
