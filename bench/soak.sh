#!/usr/bin/env bash
# The soak: SESSIONS sessions over the server's pipelines in turn (64x36
# frames, each session on a connection of its own) stream for MINUTES
# minutes while the server's resident memory (/proc/PID/status VmRSS) and
# device bytes (STATS device_bytes) are sampled; prints a table and a verdict
# (bench/soak_client.cpp) and exits non-zero if any frame was lost or
# reordered or the server's RSS grew by more than the bound (32 MB) after the
# first 20 % of the run (at most 60 s). A run whose server passes 4096 MB of
# RSS is stopped there (--max-rss-mb), so a leak cannot take the machine.
#   bench/soak.sh [SESSIONS] [MINUTES] [-- soak_client options: --size WxH --pipelines a,b --in-flight N
#                                        --interval S --max-rss-growth-mb M --max-rss-mb M]
# Environment:
#   DN_BUILD_DIR       build tree with the binaries (default build)
#   DN_SOAK_SECONDS    run this many seconds instead of MINUTES (short runs, the ctest smoke run)
#   DN_SOAK_SERVER     URL of a server already running (default: start one on a free loopback port);
#   DN_SOAK_SERVER_PID its pid, for the RSS column (without it RSS is not sampled)
#   DN_SOAK_NO_WARM_UP=1  start the server with --no-warm-up and do not wait for it (the smoke run)
set -euo pipefail
cd "$(dirname "$0")/.."
sessions=${1:-64}
minutes=${2:-10}
shift $(( $# < 2 ? $# : 2 ))
[ "${1:-}" = "--" ] && shift
build=${DN_BUILD_DIR:-build}
seconds=${DN_SOAK_SECONDS:-$((minutes * 60))}
for b in "$build/server/dnserver" "$build/client/dn" "$build/bench/soak_client"; do
  [ -x "$b" ] || { echo "soak: $b not found; build first (cmake --build $build)" >&2; exit 2; }
done

url=${DN_SOAK_SERVER:-}
pid=${DN_SOAK_SERVER_PID:-0}
if [ -z "$url" ]; then
  log=$(mktemp /tmp/dn-soak-server.XXXXXX.log)
  # Port 0: the kernel picks a free one, which the server logs (event=listen url=...).
  warm=--warm-up
  [ "${DN_SOAK_NO_WARM_UP:-0}" = 1 ] && warm=--no-warm-up
  "$build/server/dnserver" --listen tcp://127.0.0.1:0 --max-sessions "$sessions" $warm --log-level info 2> "$log" &
  pid=$!
  trap 'kill -TERM $pid 2>/dev/null || true; wait $pid 2>/dev/null || true; rm -f "$log"' EXIT
  for _ in $(seq 1 600); do
    url=$(sed -n 's/.*event=listen .*url=\(tcp:[^ ]*\).*/\1/p' "$log" | head -n 1)
    [ -n "$url" ] && break
    kill -0 $pid 2>/dev/null || { echo "soak: dnserver exited:" >&2; cat "$log" >&2; exit 1; }
    sleep 0.1
  done
  [ -n "$url" ] || { echo "soak: dnserver did not listen:" >&2; cat "$log" >&2; exit 1; }
  # Nothing is measured while the warm-up compiles every pipeline in the background (docs/server.md).
  for _ in $(seq 1 6000); do
    [ "$warm" = --no-warm-up ] && break
    "$build/client/dn" stats --server "$url" 2>/dev/null | grep -Eq '^warm_up_done +1$' && break
    sleep 0.1
  done
  echo "soak: dnserver pid $pid on $url (--max-sessions $sessions $warm)"
fi

echo "soak: $sessions sessions for $seconds s on $(nproc) cores, $(date -u '+%Y-%m-%d %H:%M UTC')"
"$build/bench/soak_client" --server "$url" --server-pid "$pid" --sessions "$sessions" --seconds "$seconds" "$@"
