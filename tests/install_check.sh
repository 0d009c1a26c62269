#!/usr/bin/env bash
# `cmake --install` into a scratch prefix, then use what was installed: kincald runs its
# default (simulated) configuration from PREFIX/share/kincal, kincal export works, the LCM
# Python module imports, and the systemd unit, every layer's library and LCM sources are in
# place.
#   tests/install_check.sh BUILD_DIR PYTHON
set -euo pipefail
build=$1 python=$2
prefix=$build/install-test
rm -rf "$prefix"
cmake --install "$build" --prefix "$prefix" >/dev/null
for layer in core io estimation vision sim analysis plan daemon; do
  [ -e "$prefix/lib/libkincal_$layer.so" ] || { echo "install_check: missing lib/libkincal_$layer.so"; exit 1; }
done
for f in bin/kincal bin/kincald lib/systemd/system/kincald.service \
         share/kincal/config/kincald_sim.yaml share/kincal/config/kincald_v4l2.yaml \
         share/kincal/lcm/params_t.lcm include/kincal/daemon/daemon.h include/kincal/lcmtypes/kincal/params_t.hpp \
         lib/python3/dist-packages/kincal/params_t.py share/kincal/scripts/kincal_watch.py \
         share/kincal/scripts/kincal_import.py share/kincal/scripts/kincal_controls.py \
         share/kincal/python/kincal/controls_t.py; do
  [ -e "$prefix/$f" ] || { echo "install_check: missing $f"; exit 1; }
done
grep -q "ExecStart=.*/kincald --config" "$prefix/lib/systemd/system/kincald.service"
cd "$prefix"
bin/kincald --fast --duration 5 --lcm-url memq:// --checkpoint "$prefix/ck.json" -q | tee "$prefix/out.txt"
grep -q "^  r_l = " "$prefix/out.txt"
bin/kincal export --checkpoint "$prefix/ck.json" | grep -q "^  d: {value: 0.14"
PYTHONPATH=$prefix/lib/python3/dist-packages "$python" -c "from kincal import params_t, pose_t, health_t; print('python module ok')"
# kincal import runs the installed script, which finds the installed LCM types.
KINCAL_PYTHON=$python bin/kincal import --help | grep -q "usage: kincal import"
KINCAL_PYTHON=$python "$python" share/kincal/scripts/kincal_controls.py --help | grep -q -- "--listen"
echo "install_check: ok"
