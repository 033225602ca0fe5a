#!/usr/bin/env bash
# Fuzzes a release vigil-server on a loopback port with Schemathesis, driven
# by the server's own OpenAPI document, and fails on any 5xx (but a documented
# 503 with Retry-After, see hooks.py), any response
# the document does not describe (status, content type, body schema), any
# schema-invalid request accepted (refused with a 4xx of
# .ci/schemathesis/schemathesis.toml's list), and any schema-valid request
# refused except for the rules listed in .ci/schemathesis/hooks.py.
#
# Bounded: a fixed seed, EXAMPLES examples per operation (default 30), and
# MAX_TIME seconds (default 180). Installs Schemathesis into a virtual
# environment of its own (VENV, default target/schemathesis-venv).
set -euo pipefail
cd "$(dirname "$0")/../.."

EXAMPLES="${EXAMPLES:-30}"
MAX_TIME="${MAX_TIME:-180}"
SEED="${SEED:-20261123}"
TARGET="${CARGO_TARGET_DIR:-target}"
VENV="${VENV:-$TARGET/schemathesis-venv}"
HOOKS="${HOOKS:-.ci/schemathesis/hooks.py}"

if [ ! -x "$VENV/bin/schemathesis" ]; then
    python3 -m venv "$VENV"
    "$VENV/bin/pip" install --quiet --disable-pip-version-check \
        -r .ci/schemathesis/requirements.txt
fi

cargo build --release --bin vigil-server
data="$(mktemp -d)"
log="$data/server.log"
# Port 0: the server picks a free port and logs it.
VIGIL_DATA_DIR="$data/store" "$TARGET/release/vigil-server" --bind 127.0.0.1:0 >"$log" 2>&1 &
server=$!
trap 'kill "$server" 2>/dev/null || true; wait "$server" 2>/dev/null || true; rm -rf "$data"' EXIT

address=""
for _ in $(seq 1 100); do
    address="$(grep -oE '127\.0\.0\.1:[0-9]+' "$log" | head -n 1 || true)"
    if [ -n "$address" ] && python3 -c "import sys, urllib.request; urllib.request.urlopen(sys.argv[1], timeout=2)" "http://$address/healthz" 2>/dev/null; then
        break
    fi
    sleep 0.1
done
if [ -z "$address" ]; then
    echo "vigil-server did not start:" >&2
    cat "$log" >&2
    exit 1
fi

SCHEMATHESIS_HOOKS="$HOOKS" "$VENV/bin/schemathesis" \
    --config-file .ci/schemathesis/schemathesis.toml \
    run \
    "http://$address/openapi.json" \
    --checks all \
    --exclude-checks positive_data_acceptance,not_a_server_error \
    --max-examples "$EXAMPLES" \
    --seed "$SEED" \
    --workers 1 \
    --max-time "$MAX_TIME" \
    --request-timeout 30 \
    --suppress-health-check all \
    --no-color
