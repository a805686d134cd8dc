#!/usr/bin/env bash
# Three dnserver backends behind HAProxy on loopback, configured by the
# recipe's own file (examples/deploy/haproxy.cfg, docs/deploy.md):
#   - the backends listen with --listen-proxied (PROXY protocol v2, so a
#     token is required) and log each client's own address;
#   - 12 sessions through the balancer spread over the three backends;
#   - a watcher reaches the first session through the port its SESSION
#     advertises (the balancer's port for that backend) and gets frames;
#   - that backend is killed with SIGKILL mid-stream: its clients reconnect
#     through the balancer to another backend and go on, no frame reordered,
#     every frame answered or reported lost (balanced_stream checks);
#   - frames per second before and after;
#   - draining a backend (HAProxy's runtime API) sends new sessions elsewhere.
# Bounded and self-stopping; exit 77 (skip) where haproxy is not installed.
#
#   haproxy_test.sh DNSERVER DN BALANCED_STREAM HAPROXY_CFG
set -euo pipefail
dnserver=$1 dn=$2 balanced=$3 cfg=$4
haproxy_bin=$(command -v haproxy || true)
[ -n "$haproxy_bin" ] || [ ! -x /usr/sbin/haproxy ] || haproxy_bin=/usr/sbin/haproxy
if [ -z "$haproxy_bin" ]; then
  echo "SKIP: haproxy is not installed (scripts/setup.sh installs Debian's haproxy)"
  exit 77
fi

work=$(mktemp -d /tmp/dn-balancer-XXXXXX)
pids=()
cleanup() {
  for p in "${pids[@]}"; do kill -9 "$p" 2>/dev/null || true; done
  wait 2>/dev/null || true
  rm -rf "$work"
}
trap cleanup EXIT
fail() { echo "FAIL: $*"; for f in "$work"/*.log; do echo "--- $f"; tail -5 "$f"; done; exit 1; }
deadline() { echo $(( $(date +%s) + $1 )); }

# Seven free loopback ports: the frontend, three backends, three watch ports.
read -r front b1 b2 b3 w1 w2 w3 < <(python3 -c '
import socket
socks = [socket.socket() for _ in range(7)]
for s in socks: s.bind(("127.0.0.1", 0))
print(*[s.getsockname()[1] for s in socks])')

# Behind a balancer every listener needs the token; the clients and the
# health check present it.
export DN_TOKEN="balancer-test-$$-$RANDOM"
DN_CHECK_HELLO=$(python3 -c '
import os, struct
t, n = os.environ["DN_TOKEN"].encode(), b"haproxy"
p = struct.pack("<IH", 0, len(n)) + n + struct.pack("<H", len(t)) + t
print((b"DNSV" + bytes([1, 8]) + struct.pack("<HIIQ", 1, 0, len(p), 1) + p).hex().upper())')
export DN_CHECK_HELLO

backend_ports=("$b1" "$b2" "$b3") watch_ports=("$w1" "$w2" "$w3") server_pids=()
for i in 0 1 2; do
  "$dnserver" --no-warm-up --listen-proxied "tcp://127.0.0.1:${backend_ports[$i]}" \
    --advertise-url "tcp://127.0.0.1:${watch_ports[$i]}" > "$work/dnserver$i.log" 2>&1 &
  pids+=($!) server_pids+=($!)
done
for i in 0 1 2; do
  end=$(deadline 60)
  until grep -q "event=ready" "$work/dnserver$i.log"; do
    [ "$(date +%s)" -lt "$end" ] || fail "dnserver $i did not start"
    sleep 0.1
  done
done

export DN_FRONTEND="127.0.0.1:$front" DN_B1="127.0.0.1:$b1" DN_B2="127.0.0.1:$b2" DN_B3="127.0.0.1:$b3"
export DN_W1="127.0.0.1:$w1" DN_W2="127.0.0.1:$w2" DN_W3="127.0.0.1:$w3" DN_ADMIN="$work/admin.sock"
"$haproxy_bin" -f "$cfg" -db > "$work/haproxy.log" 2>&1 &
pids+=($!)
# Every backend up by the protocol's own health check (HELLO -> WELCOME).
admin() { python3 - "$DN_ADMIN" "$1" <<'PY'
import socket, sys
s = socket.socket(socket.AF_UNIX)
s.connect(sys.argv[1])
s.sendall(sys.argv[2].encode() + b"\n")
data = b""
while chunk := s.recv(65536):
    data += chunk
print(data.decode(), end="")
PY
}
# Each backend of dn_backends: name, status, check status, current connections.
stat() { admin "show stat" | awk -F, '$1 == "dn_backends" && $2 ~ /^b/ { print $2, $18, $37, $5 }'; }
end=$(deadline 60)
until [ -S "$DN_ADMIN" ] && [ "$(stat 2>/dev/null | grep -c ' UP L7OK')" = 3 ]; do
  [ "$(date +%s)" -lt "$end" ] || fail "haproxy did not see three healthy backends: $(stat 2>&1 | tr '\n' ' ')"
  sleep 0.2
done
echo "haproxy: $(stat | tr '\n' ' ')"
# A placer asks each backend, through its balancer port, how many sessions fit.
for i in 0 1 2; do
  fit=$("$dn" capacity --server "tcp://127.0.0.1:${watch_ports[$i]}" -p passthrough --size 32x18) ||
    fail "dn capacity through the balancer's port for backend $((i + 1)) failed"
  [ "$fit" -ge 4 ] 2>/dev/null || fail "backend $((i + 1)) says $fit passthrough 32x18 sessions fit, fewer than the 4 it will get"
  echo "backend $((i + 1)): $fit more passthrough 32x18 sessions fit"
done

"$balanced" "tcp://$DN_FRONTEND" 12 24 "$work/watch" "$work/kill" > "$work/clients.log" 2>&1 &
clients=$!
pids+=($clients)
watched=0 killed=0
end=$(deadline 240)
while kill -0 "$clients" 2>/dev/null; do
  [ "$(date +%s)" -lt "$end" ] || fail "the clients did not finish"
  if [ -s "$work/watch" ]; then
    # The owner's own `dn watch` command: --server is the session's watch URL.
    read -r -a cmd < "$work/watch"
    # "DN_WATCH_KEY=KEY dn watch ...": the key goes to dn's environment.
    [ "${cmd[0]%%=*}" = DN_WATCH_KEY ] || fail "no watch key in the environment: ${cmd[*]}"
    export "${cmd[0]}"
    cmd=("${cmd[@]:1}")
    [ "${cmd[0]}" = dn ] || fail "no watch command: ${cmd[*]}"
    echo "watching: ${cmd[*]}"
    "$dn" "${cmd[@]:1}" --count 2 --timeout 60 --output "$work/w_%04d.pfm" --quiet || fail "dn watch through the balancer failed"
    [ "$(ls "$work"/w_*.pfm | wc -l)" = 2 ] || fail "dn watch wrote $(ls "$work"/w_*.pfm | wc -l) frames, not 2"
    watched=1
    rm -f "$work/watch"
  fi
  if [ -s "$work/kill" ]; then
    target=$(cat "$work/kill")
    for i in 0 1 2; do
      if [ "$target" = "tcp://127.0.0.1:${watch_ports[$i]}" ]; then
        kill -9 "${server_pids[$i]}"
        wait "${server_pids[$i]}" 2>/dev/null || true  # reaped here, so bash does not report it
        killed=1
        echo "killed backend $((i + 1)) (${backend_ports[$i]}), advertised as $target"
      fi
    done
    [ "$killed" = 1 ] || fail "no backend advertises $target"
    rm -f "$work/kill"
  fi
  sleep 0.05
done
status=0
wait "$clients" || status=$?
cat "$work/clients.log"
[ "$watched" = 1 ] || fail "the watch step never came"
[ "$killed" = 1 ] || fail "the kill step never came"
echo "haproxy after the kill: $(stat | tr '\n' ' ')"

# Maintenance: drain one of the two live backends; new sessions go to the other.
drain=""
for i in 0 1 2; do
  kill -0 "${server_pids[$i]}" 2>/dev/null && { drain=b$((i + 1)); break; }
done
admin "set server dn_backends/$drain state drain" > /dev/null
python3 - "$DN_FRONTEND" "$DN_TOKEN" > "$work/drain.log" 2>&1 <<'PY' &
# Four connections through the balancer, each HELLO -> WELCOME, held open.
import socket, struct, sys, time
host, port = sys.argv[1].rsplit(":", 1)
token, name = sys.argv[2].encode(), b"drain-check"
payload = struct.pack("<IH", 0, len(name)) + name + struct.pack("<H", len(token)) + token
hello = b"DNSV" + bytes([1, 8]) + struct.pack("<HIIQ", 1, 0, len(payload), 1) + payload
conns = []
for _ in range(4):
    c = socket.create_connection((host, int(port)))
    c.sendall(hello)
    assert c.recv(24)[6:8] == b"\x02\x00", "no WELCOME"
    conns.append(c)
print("held", len(conns), flush=True)
time.sleep(30)
PY
holder=$!
pids+=($holder)
end=$(deadline 30)
until grep -q "held 4" "$work/drain.log"; do
  [ "$(date +%s)" -lt "$end" ] || fail "the drain check's connections did not open: $(cat "$work/drain.log")"
  sleep 0.1
done
# One snapshot, printed and checked (two reads of haproxy's counters can differ).
after_drain=$(stat)
echo "draining $drain, then 4 new connections: $(echo "$after_drain" | tr '\n' ' ')"
echo "$after_drain" | awk -v d="$drain" '$1 == d && $4 != 0 { bad = 1 } $1 != d && $2 == "UP" && $4 != 4 { bad = 1 } END { exit bad }' ||
  fail "draining $drain did not send the 4 new connections to the other live backend: $(echo "$after_drain" | tr '\n' ' ')"
kill "$holder" 2>/dev/null || true
[ "$status" = 0 ] || fail "the clients' checks failed"
# The backends saw the clients' own addresses (PROXY), and the checks as LOCAL.
for i in 0 1 2; do
  grep -q "event=connection.proxied .*command=PROXY" "$work/dnserver$i.log" ||
    fail "backend $((i + 1)) logged no forwarded client address"
  grep -q "event=connection.proxied .*command=LOCAL" "$work/dnserver$i.log" ||
    grep -q "event=connection.hello" "$work/dnserver$i.log" || fail "backend $((i + 1)) saw no health check"
done
echo "backend 1 log: $(grep -m1 'event=connection.proxied .*command=PROXY' "$work/dnserver0.log" | cut -c1-200)"
echo "PASS"
