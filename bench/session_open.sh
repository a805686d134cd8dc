#!/usr/bin/env bash
# Session open latency, cold and warm, with the frame latency of a client
# streaming meanwhile (bench/session_open_bench.cpp). Cold: Mesa's shader
# cache off, no warm-up, no disk cache, so the first open compiles every
# kernel. Warm: after the server's warm-up has finished; then every pipeline
# in every input form, fp32 and fp16, at 256x144: its first frame against its
# steady state (bench/session_open_first_frames.cpp; fails above 3x or when a
# kernel is compiled).
#   bench/session_open.sh [BUILD_DIR] [PIPELINE] [WxH] [OPENS]
set -euo pipefail
cd "$(dirname "$0")/.."
build=${1:-build}
pipeline=${2:-svgf}
size=${3:-640x360}
opens=${4:-5}
port=$((7900 + RANDOM % 90))
url=tcp://127.0.0.1:$port
cache=$(mktemp -d)
trap 'kill $server 2>/dev/null && wait $server 2>/dev/null; rm -rf "$cache"' EXIT

wait_for() {  # wait_for KEY: until STATS shows KEY = 1 (or the server answers, for "ping")
  for _ in $(seq 600); do
    if [ "$1" = ping ]; then "$build/client/dn" ping --server "$url" >/dev/null 2>&1 && return 0
    else "$build/client/dn" stats --server "$url" 2>/dev/null | grep -Eq "^$1[[:space:]:=]+1(\.0+)?$" && return 0; fi
    sleep 0.2
  done
  echo "server did not reach $1" >&2
  exit 1
}

echo "== cold: MESA_SHADER_CACHE_DISABLE=true dnserver --no-warm-up --no-disk-cache"
MESA_SHADER_CACHE_DISABLE=true "$build/server/dnserver" --listen "$url" --no-warm-up --no-disk-cache \
  --log-level warn & server=$!
wait_for ping
"$build/bench/session_open_bench" --server "$url" --pipeline "$pipeline" --size "$size" --opens "$opens"
kill $server; wait $server 2>/dev/null || true

echo "== warm: dnserver --cache-dir (warm-up finished)"
"$build/server/dnserver" --listen "$url" --cache-dir "$cache/dn" --log-level warn & server=$!
wait_for ping
wait_for warm_up_done
"$build/bench/session_open_bench" --server "$url" --pipeline "$pipeline" --size "$size" --opens "$opens"
"$build/client/dn" stats --server "$url" | grep -E "warm_up|kernel|session_build" || true
echo "== warm: each pipeline and input form's first frame against its steady state (256x144)"
"$build/bench/session_open_first_frames" --server "$url" --size 256x144
