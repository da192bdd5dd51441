#!/usr/bin/env bash
# Build the documentation site: bash docs/build.sh [--check]
#
# Needs target/debug/irtp (cargo build, or cargo test) or $IRTP_BIN, and
# python3. Makes target/docs/venv with docs/requirements.txt, stages docs/
# into target/docs/src with the generated pages (command reference, Python
# API, reproduction report) and the tutorials' figures (each tutorial script
# run at its reduced size), then `mkdocs build --strict` into
# target/docs/site. --check then opens the built site in headless Chromium
# (docs/tools/browser_check.py). Nothing it writes is tracked by git.
set -euo pipefail
cd "$(dirname "$0")/.."
root=$PWD
t0=$SECONDS
export IRTP_BIN="${IRTP_BIN:-target/debug/irtp}"
case "$IRTP_BIN" in /*) ;; *) IRTP_BIN="$root/$IRTP_BIN" ;; esac
[ -x "$IRTP_BIN" ] || { echo "docs: no irtp binary at $IRTP_BIN: run cargo build first (or set IRTP_BIN)" >&2; exit 2; }

# The tutorial scripts, each drawing docs/tutorials/figures/NAME.png.
TUTORIALS=(fig2 deff optimal_rate search noise sweep_xarray new_medium)

venv=target/docs/venv
if ! "$venv/bin/python" -c 'import mkdocs, matplotlib, xarray, playwright' 2>/dev/null; then
  python3 -m venv "$venv"
  "$venv/bin/pip" install -q --disable-pip-version-check -r docs/requirements.txt
fi
py="$venv/bin/python"
echo "docs: venv ready ($(( SECONDS - t0 )) s)"

src=target/docs/src
rm -rf "$src" target/docs/site
mkdir -p "$src"
# docs/ without the generators; REPRODUCTION.md as a page, its image paths
# made relative to docs/.
tar -C docs --exclude=./tools --exclude='*/__pycache__' -cf - . | tar -C "$src" -xf -
sed -e 's#](docs/#](#g' -e 's#(REPRODUCTION.md)#(reproduction.md)#g' REPRODUCTION.md >"$src/reproduction.md"
"$py" docs/tools/gen_cli.py "$IRTP_BIN" "$src/reference/cli.md"
"$py" docs/tools/gen_python_api.py python/irtp/__init__.pyi "$src/reference/python-api.md"

export IRTP_DOCS_FIGURES="$root/$src/tutorials/figures"
export MPLBACKEND=Agg
for t in "${TUTORIALS[@]}"; do
  s=$SECONDS
  "$py" "docs/tutorials/$t.py" >/dev/null
  [ -f "$IRTP_DOCS_FIGURES/$t.png" ] || { echo "docs: tutorial $t drew no figure" >&2; exit 1; }
  echo "docs: tutorial $t ($(( SECONDS - s )) s)"
done

"$venv/bin/mkdocs" build --strict 2>&1 | { grep -v "^INFO    -  \(Cleaning\|Building\|Documentation built\)" || true; }
echo "docs: site built in target/docs/site ($(( SECONDS - t0 )) s in all)"

if [ "${1:-}" = "--check" ]; then
  "$py" docs/tools/browser_check.py target/docs/site target/docs/screenshots
  echo "docs: browser check passed ($(( SECONDS - t0 )) s in all)"
fi
