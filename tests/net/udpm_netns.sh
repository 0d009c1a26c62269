#!/usr/bin/env bash
# kincald over real LCM UDP multicast, in a private network namespace: loopback with the
# multicast flag and a 224.0.0.0/4 route (this host's own `lo` has neither). The simulated
# robot publishes its controls over UDP, the daemon receives them over UDP, and the Python
# subscriber (scripts/kincal_watch.py, LCM's Python bindings) must see the parameters
# converge to the simulated truth.
#
#   tests/net/udpm_netns.sh KINCALD PYTHON LCM_TYPES_DIR CONFIG
set -euo pipefail
kincald=$1 python=$2 types=$3 config=$4
here=$(cd "$(dirname "$0")/../.." && pwd)
if [ "${KINCAL_IN_NETNS:-}" != 1 ]; then
  command -v unshare >/dev/null && command -v ip >/dev/null || { echo "udpm_netns: needs unshare and ip (iproute2)"; exit 2; }
  exec unshare --net --map-root-user env KINCAL_IN_NETNS=1 "$0" "$@"
fi
ip link set lo up
ip link set lo multicast on
ip route add 224.0.0.0/4 dev lo
url="udpm://239.255.76.67:7667?ttl=0"
"$python" "$here/scripts/kincal_watch.py" --url "$url" --lcm-types "$types" --timeout 90 --idle-timeout 3 \
  --expect r_l=0.0310 --expect r_r=0.0313 --expect d=0.148 &
watch=$!
sleep 1
"$kincald" --config "$config" --lcm-url "$url" --duration 30 --speed 4 -q
wait "$watch"
