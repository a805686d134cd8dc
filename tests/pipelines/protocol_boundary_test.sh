#!/usr/bin/env bash
# The protocol stops at the session (docs/server.md, "Layers"): of it the
# pipelines see only the channel table and binary16 (dn/protocol/channels.hpp,
# half.hpp); no file under server/pipelines includes another protocol header
# or names a message, an error code, a frame or its flags.
#   protocol_boundary_test.sh <source root>
set -euo pipefail
cd "$1"
fail=0
includes=$(grep -rnE '#include [<"]dn/protocol/' server/pipelines | grep -vE 'dn/protocol/(channels|half)\.hpp' || true)
if [ -n "$includes" ]; then
  echo "server/pipelines includes protocol headers beyond channels.hpp and half.hpp:"
  echo "$includes" | sed 's/^/  /'
  fail=1
fi
names=$(grep -rnE 'protocol::(Frame|FrameInfo|PlaneView|ErrorCode|ChannelDecl|Parameter|OpenSession|Session|MotionConvention|kFrame[A-Za-z]*|kFlag[A-Za-z]*)\b' \
          server/pipelines || true)
if [ -n "$names" ]; then
  echo "server/pipelines names protocol messages or codes:"
  echo "$names" | sed 's/^/  /'
  fail=1
fi
exit $fail
