#!/usr/bin/env bash
# The whole load test against a release vigil-server (see loadtest/README.md).
#
#   bash loadtest/run.sh               # full run, about 6-10 minutes
#   QUICK=1 bash loadtest/run.sh       # short run, about 1-2 minutes (provisional figures)
#
# The server is pinned to core $SERVER_CPU and the generator to core
# $GEN_CPU (taskset). Steps, each writing JSON to $RESULTS:
#   1. requests.jsonl     the plan requests (vigil-sim states), generated once
#   2. inproc.json        their in-process plan time, pinned to the server's core
#                         before the server starts
#   3. healthz-sweep.json GET /healthz climbed to its knee: the HTTP stack's ceiling
#   4. fixed.json         plans at $FIXED_RATE/s for $FIXED_DURATION
#   5. plan-sweep.json    plans climbed until p99 > $SLO_MS: the knee
#   6. session-inproc.json   session steps of the same states in process (core
#                            $SERVER_CPU, before the server starts), beside
#                            their stateless plans timed alternately
#   7. session-fixed.json    session steps ($SESSIONS sessions) at $FIXED_RATE/s
#   8. session-sweep.json    session steps climbed until p99 > $SLO_MS
#   9. summary.json       all of it, and the HTTP efficiency
# SESSIONS=0 leaves the session steps out.
# Every setting below can be overridden from the environment.
set -euo pipefail
cd "$(dirname "$0")/.."

QUICK=${QUICK:-0}
if [[ $QUICK == 1 ]]; then
    def_fixed_duration=5s def_fixed_warmup=1s def_step=3s def_step_warmup=1s def_iters=500 def_refine=0
else
    def_fixed_duration=30s def_fixed_warmup=5s def_step=10s def_step_warmup=2s def_iters=3000 def_refine=2
fi
RESULTS=${RESULTS:-loadtest/results}
SERVER_CPU=${SERVER_CPU:-0}
GEN_CPU=${GEN_CPU:-1}
SERVER_CORES=${SERVER_CORES:-1}          # cores in $SERVER_CPU
SCENARIO=${SCENARIO:-paper-v10}
WORKLOAD=${WORKLOAD:---sensors 10 --history 16 --horizon 3 --count 200 --seed 1}
CONNECTIONS=${CONNECTIONS:-32}
ARRIVALS=${ARRIVALS:-poisson}
SLO_MS=${SLO_MS:-2}
FIXED_RATE=${FIXED_RATE:-2000}
FIXED_DURATION=${FIXED_DURATION:-$def_fixed_duration}
FIXED_WARMUP=${FIXED_WARMUP:-$def_fixed_warmup}
STEP_DURATION=${STEP_DURATION:-$def_step}
STEP_WARMUP=${STEP_WARMUP:-$def_step_warmup}
SWEEP_START=${SWEEP_START:-100}
SWEEP_FACTOR=${SWEEP_FACTOR:-1.25}
SWEEP_REFINE=${SWEEP_REFINE:-$def_refine}
HEALTHZ_START=${HEALTHZ_START:-1000}
HEALTHZ_FACTOR=${HEALTHZ_FACTOR:-1.5}
INPROC_ITERATIONS=${INPROC_ITERATIONS:-$def_iters}
SESSIONS=${SESSIONS:-32}                 # sessions of the HTTP session runs; 0: none

for tool in taskset curl cargo; do
    command -v "$tool" >/dev/null || { echo "run.sh: $tool is required" >&2; exit 1; }
done
ncpu=$(nproc)
for cpu in "$SERVER_CPU" "$GEN_CPU"; do
    if [[ $cpu =~ ^[0-9]+$ ]] && (( cpu >= ncpu )); then
        echo "run.sh: core $cpu is needed, this machine has $ncpu" >&2
        exit 1
    fi
done

echo "== building (release)"
cargo build --release --bin vigil-server -p vigil
cargo build --release --bin vigil-loadtest -p vigil-loadtest
bin_dir=${CARGO_TARGET_DIR:-target}/release
server_bin=$bin_dir/vigil-server
lt_bin=$bin_dir/vigil-loadtest

mkdir -p "$RESULTS"
gen() { taskset -c "$GEN_CPU" "$lt_bin" "$@"; }

echo "== generating the requests"
# shellcheck disable=SC2086 # WORKLOAD is a list of options
gen gen --scenario "$SCENARIO" $WORKLOAD --out "$RESULTS/requests.jsonl"

echo "== in-process plan time (core $SERVER_CPU, server not started yet)"
taskset -c "$SERVER_CPU" "$lt_bin" inproc --scenario "$SCENARIO" --requests "$RESULTS/requests.jsonl" \
    --iterations "$INPROC_ITERATIONS" --out "$RESULTS/inproc.json"

if (( SESSIONS > 0 )); then
    echo "== in-process session steps of the same states (core $SERVER_CPU)"
    # shellcheck disable=SC2086 # WORKLOAD is a list of options
    taskset -c "$SERVER_CPU" "$lt_bin" inproc --session --scenario "$SCENARIO" $WORKLOAD \
        --iterations "$INPROC_ITERATIONS" --out "$RESULTS/session-inproc.json"
fi

echo "== starting vigil-server on core $SERVER_CPU"
data_dir=$(mktemp -d)
server_log=$RESULTS/server.log
server_pid=
cleanup() {
    if [[ -n $server_pid ]]; then
        kill "$server_pid" 2>/dev/null || true
        wait "$server_pid" 2>/dev/null || true
    fi
    rm -rf "$data_dir"
}
trap cleanup EXIT
trap 'exit 130' INT TERM
VIGIL_BIND=127.0.0.1:0 VIGIL_DATA_DIR=$data_dir RUST_LOG=${RUST_LOG:-info} \
    taskset -c "$SERVER_CPU" "$server_bin" 2>"$server_log" &
server_pid=$!
addr=
for _ in $(seq 1 200); do
    addr=$(grep -o 'listening on [0-9.]*:[0-9]*' "$server_log" | head -n1 | cut -d' ' -f3 || true)
    [[ -n $addr ]] && break
    kill -0 "$server_pid" 2>/dev/null || { echo "run.sh: the server exited:" >&2; cat "$server_log" >&2; exit 1; }
    sleep 0.05
done
[[ -n $addr ]] || { echo "run.sh: the server did not start:" >&2; cat "$server_log" >&2; exit 1; }
url=http://$addr
for _ in $(seq 1 100); do
    curl -fsS "$url/healthz" >/dev/null 2>&1 && break
    sleep 0.05
done
curl -fsS "$url/healthz" >/dev/null
echo "   $url"

common=(--url "$url" --connections "$CONNECTIONS" --arrivals "$ARRIVALS" --seed 1)
plans=(--scenario "$SCENARIO" --requests "$RESULTS/requests.jsonl")

echo "== /healthz ceiling (sweep from $HEALTHZ_START/s x$HEALTHZ_FACTOR, SLO p99 <= $SLO_MS ms)"
gen "${common[@]}" --endpoint healthz --sweep --sweep-start "$HEALTHZ_START" \
    --sweep-factor "$HEALTHZ_FACTOR" --sweep-refine "$SWEEP_REFINE" --slo-ms "$SLO_MS" \
    --duration "$STEP_DURATION" --warmup "$STEP_WARMUP" --out "$RESULTS/healthz-sweep.json"

echo "== plans at $FIXED_RATE/s for $FIXED_DURATION"
gen "${common[@]}" "${plans[@]}" --rate "$FIXED_RATE" \
    --duration "$FIXED_DURATION" --warmup "$FIXED_WARMUP" --out "$RESULTS/fixed.json"

echo "== plan sweep (from $SWEEP_START/s x$SWEEP_FACTOR, SLO p99 <= $SLO_MS ms)"
gen "${common[@]}" "${plans[@]}" --sweep --sweep-start "$SWEEP_START" \
    --sweep-factor "$SWEEP_FACTOR" --sweep-refine "$SWEEP_REFINE" --slo-ms "$SLO_MS" \
    --duration "$STEP_DURATION" --warmup "$STEP_WARMUP" --out "$RESULTS/plan-sweep.json"

session_files=()
if (( SESSIONS > 0 )); then
    # shellcheck disable=SC2206 # WORKLOAD is a list of options
    steps=(--endpoint session --sessions "$SESSIONS" --scenario "$SCENARIO" $WORKLOAD)
    # The steps are generated: the seed is WORKLOAD's (--seed seeds both the
    # simulated run and the arrivals), not common's.
    session_common=(--url "$url" --connections "$CONNECTIONS" --arrivals "$ARRIVALS")

    echo "== session steps at $FIXED_RATE/s for $FIXED_DURATION ($SESSIONS sessions)"
    gen "${session_common[@]}" "${steps[@]}" --rate "$FIXED_RATE" \
        --duration "$FIXED_DURATION" --warmup "$FIXED_WARMUP" --out "$RESULTS/session-fixed.json"

    echo "== session sweep (from $SWEEP_START/s x$SWEEP_FACTOR, SLO p99 <= $SLO_MS ms)"
    gen "${session_common[@]}" "${steps[@]}" --sweep --sweep-start "$SWEEP_START" \
        --sweep-factor "$SWEEP_FACTOR" --sweep-refine "$SWEEP_REFINE" --slo-ms "$SLO_MS" \
        --duration "$STEP_DURATION" --warmup "$STEP_WARMUP" --out "$RESULTS/session-sweep.json"
    session_files=(--session-inproc "$RESULTS/session-inproc.json"
        --session-fixed "$RESULTS/session-fixed.json" --session-sweep "$RESULTS/session-sweep.json")
fi

echo "== summary"
"$lt_bin" summarize --server-cores "$SERVER_CORES" --inproc "$RESULTS/inproc.json" \
    --healthz-sweep "$RESULTS/healthz-sweep.json" --fixed "$RESULTS/fixed.json" \
    --plan-sweep "$RESULTS/plan-sweep.json" "${session_files[@]}" --out "$RESULTS/summary.json"
echo "results in $RESULTS/"
