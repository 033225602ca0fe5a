#!/usr/bin/env bash
# Regenerates vigil_client/generated from openapi/openapi.json with the
# pinned openapi-python-client (requirements-generate.txt, generator.yaml and
# the two templates that keep the code importable on Python 3.10).
#
#   bash clients/python/regenerate.sh           rewrite vigil_client/generated
#   bash clients/python/regenerate.sh --check   fail if it differs from what
#                                               the document generates (CI)
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
root="$(cd "$here/../.." && pwd)"
GENERATOR_VENV="${GENERATOR_VENV:-${CARGO_TARGET_DIR:-$root/target}/python-generate-venv}"

if ! cmp -s "$here/requirements-generate.txt" "$GENERATOR_VENV/requirements-generate.txt" 2>/dev/null; then
    python3 -m venv "$GENERATOR_VENV"
    "$GENERATOR_VENV/bin/pip" install --quiet --disable-pip-version-check -r "$here/requirements-generate.txt"
    cp "$here/requirements-generate.txt" "$GENERATOR_VENV/requirements-generate.txt"
fi

out="$(mktemp -d)"
trap 'rm -rf "$out"' EXIT
# The generator runs ruff from PATH as its post hook (no cache left behind).
RUFF_NO_CACHE=true PATH="$GENERATOR_VENV/bin:$PATH" openapi-python-client generate \
    --path "$root/openapi/openapi.json" \
    --config "$here/generator.yaml" \
    --custom-template-path "$here/templates" \
    --meta none \
    --fail-on-warning \
    --output-path "$out/generated" >"$out/log" 2>&1 || { cat "$out/log"; exit 1; }

target="$here/vigil_client/generated"
if [ "${1:-}" = "--check" ]; then
    if ! diff -r "$out/generated" "$target"; then
        echo "clients/python/vigil_client/generated differs from openapi/openapi.json: run bash clients/python/regenerate.sh" >&2
        exit 1
    fi
    echo "clients/python: the generated code matches openapi/openapi.json"
else
    rm -rf "$target"
    cp -r "$out/generated" "$target"
    echo "clients/python: regenerated vigil_client/generated"
fi
