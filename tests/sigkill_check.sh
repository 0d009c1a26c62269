#!/usr/bin/env bash
# Nothing lost to a crash: kincald is killed with SIGKILL while recording; the log must read
# back, every event whole and decodable, up to the last flush (record.flush_every_s); the
# checkpoint (written by rename) must be a whole, loadable file; the killed log must replay
# and --resume must start from the checkpoint.
#   tests/sigkill_check.sh KINCALD PYTHON LCM_TYPES_DIR CONFIG WORK_DIR
set -euo pipefail
kincald=$1 python=$2 types=$3 config=$4 work=$5
rm -rf "$work" && mkdir -p "$work"
"$kincald" --config "$config" --lcm-url memq:// --record "$work/killed.lcm" --checkpoint "$work/ck.json" -q &
pid=$!
# Killed once the log holds 60 frames' worth and the first checkpoint exists (polled, not a
# fixed sleep: a loaded machine or a sanitizer build runs slower), at most 120 s.
want=$((60 * (640 * 480 + 200)))
for _ in $(seq 600); do
  size=$(stat -c %s "$work/killed.lcm" 2>/dev/null || echo 0)
  if ((size >= want)) && [ -f "$work/ck.json" ]; then break; fi
  sleep 0.2
done
kill -KILL "$pid"
wait "$pid" 2>/dev/null || true
"$python" - "$types" "$work/killed.lcm" "$work/ck.json" "$(dirname "$0")/../scripts" <<'PY'
import json, os, sys
sys.path.insert(0, sys.argv[1])
sys.path.insert(0, sys.argv[4])
import lcm
from kincal_lcm_types import message_types
types = message_types()  # every kincal message by its LCM fingerprint, whatever its channel
path = sys.argv[2]
size = os.path.getsize(path)
counts, end = {}, 0
log = lcm.EventLog(path, "r")
for ev in log:
    types[bytes(ev.data[:8])].decode(ev.data)  # raises if not whole, or not a kincal message
    counts[ev.channel] = counts.get(ev.channel, 0) + 1
    end = log.tell()
frame_bytes = 640 * 480 + 200
print(f"sigkill: {sum(counts.values())} whole events {counts}; {size - end} bytes after the last one")
assert counts.get("KINCAL_FRAME", 0) >= 45, "less than 1.5 s of frames survived"
assert size - end < 2 * frame_bytes * 16, "more than the flush interval lost"
ck = json.load(open(sys.argv[3]))
assert ck["format"] == "kincal-checkpoint" and len(ck["values"]) == 3, ck
print("sigkill: checkpoint whole:", dict(zip(ck["names"], ck["values"])))
PY
"$kincald" --replay "$work/killed.lcm" --fast --lcm-url memq:// --config "$config" -q | grep "final estimate"
"$kincald" --config "$config" --lcm-url memq:// --fast --duration 3 --resume "$work/ck.json" 2>&1 | grep "resumed 3 of 3 parameters"
echo "sigkill_check: ok"
