#!/usr/bin/env bash
# The Python package's checks, as CI runs them (.ci/run):
#  1. the committed generated code is what openapi/openapi.json generates;
#  2. the hand-written code passes ruff's lints (pyproject.toml's [tool.ruff]);
#  3. `pip install ./clients/python[stonesoup,test]` works in a fresh virtual
#     environment (CLIENT_VENV, default target/python-client-venv);
#  4. its tests pass against a real vigil-server (the release build, brought
#     up to date here), Stone Soup's included.
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
root="$(cd "$here/../.." && pwd)"
target="${CARGO_TARGET_DIR:-$root/target}"
CLIENT_VENV="${CLIENT_VENV:-$target/python-client-venv}"

bash "$here/regenerate.sh" --check
# The pinned ruff that regenerate.sh installed beside the generator.
(cd "$here" && "${GENERATOR_VENV:-$target/python-generate-venv}/bin/ruff" check --config pyproject.toml \
    . ../../examples/stonesoup ../../examples/python/client_tour.py)

rm -rf "$CLIENT_VENV"
python3 -m venv "$CLIENT_VENV"
"$CLIENT_VENV/bin/pip" install --quiet --disable-pip-version-check "$here[stonesoup,test]"
# setuptools builds the wheel in the source tree: leave nothing behind.
rm -rf "$here/build" "$here"/*.egg-info

(cd "$root" && cargo build --release --bin vigil-server)
# The tests import the installed package, not the source tree.
cd "$here"
VIGIL_SERVER="$target/release/vigil-server" "$CLIENT_VENV/bin/pytest" -q -p no:cacheprovider
