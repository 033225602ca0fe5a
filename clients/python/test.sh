#!/usr/bin/env bash
# The Python package's checks, as CI runs them (.ci/run):
#  1. the committed generated code is what openapi/openapi.json generates;
#  2. `pip install ./clients/python[stonesoup,test]` works in a fresh virtual
#     environment (VENV, default target/python-client-venv);
#  3. its tests pass against a real vigil-server (the release build, brought
#     up to date here), Stone Soup's included.
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
root="$(cd "$here/../.." && pwd)"
target="${CARGO_TARGET_DIR:-$root/target}"
VENV="${VENV:-$target/python-client-venv}"

bash "$here/regenerate.sh" --check

rm -rf "$VENV"
python3 -m venv "$VENV"
"$VENV/bin/pip" install --quiet --disable-pip-version-check "$here[stonesoup,test]"
# setuptools builds the wheel in the source tree: leave nothing behind.
rm -rf "$here/build" "$here"/*.egg-info

(cd "$root" && cargo build --release --bin vigil-server)
# The tests import the installed package, not the source tree.
cd "$here"
VIGIL_SERVER="$target/release/vigil-server" "$VENV/bin/pytest" -q -p no:cacheprovider
