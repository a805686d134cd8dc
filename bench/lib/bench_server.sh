# Shared by the benchmark scripts (sourced, not run): a dnserver of their
# own on a unix socket, and reading a --summary TSV by column name.
#
# start_bench_server NAME BIN DN LOG: starts BIN/server/dnserver on
# /tmp/dnserver-NAME-$$.sock with its log in LOG, stops it on exit, waits
# until it listens and its warm-up has compiled every pipeline (nothing is
# timed while the warm-up compiles in the background, docs/server.md), then
# sets server (the pid), server_url and device (the Vulkan device it names).
start_bench_server() {
  local name=$1 bin=$2 dn=$3 log=$4
  local socket="/tmp/dnserver-$name-$$.sock"
  "$bin/server/dnserver" --listen "unix://$socket" --log-level warn 2> "$log" &
  server=$!
  trap 'kill -TERM $server 2>/dev/null || true; wait $server 2>/dev/null || true' EXIT
  for _ in $(seq 1 300); do [ -S "$socket" ] && break; sleep 0.1; done
  [ -S "$socket" ] || { echo "$name: dnserver did not start:" >&2; cat "$log" >&2; exit 1; }
  server_url="unix://$socket"
  for _ in $(seq 1 3000); do "$dn" stats --server "$server_url" 2>/dev/null | grep -Eq '^warm_up_done +1$' && break; sleep 0.1; done
  device=$("$dn" ping --server "$server_url" --count 1 | sed -n '1s/.* on //p')
}

# column FILE NAME: the value under NAME in the second line of a two-line TSV.
column() { awk -F'\t' -v name="$2" 'NR == 1 { for (i = 1; i <= NF; ++i) if ($i == name) c = i } NR == 2 { print $c }' "$1"; }
