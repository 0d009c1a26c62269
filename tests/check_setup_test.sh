#!/usr/bin/env bash
# The setup guard (scripts/check_setup) on this machine, then on copies of scripts/setup
# with one package taken out: each time the guard must fail and name that package.
#   tests/check_setup_test.sh SCRATCH_DIR
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
scratch=$1
mkdir -p "$scratch"
"$root/scripts/check_setup" || { echo "check_setup_test: the guard fails on this machine"; exit 1; }
# libclang-rt-14-dev: the sanitizer runtimes (issue 13's failure); qemu-system-x86: a tool a
# test runs; libceres-dev: a library the build links.
# A library is named by the package that holds its file (libceres3 for libceres.so.3).
for case in libclang-rt-14-dev:libclang-rt-14-dev qemu-system-x86:qemu-system-x86 libceres-dev:libceres; do
  pkg=${case%%:*} named=${case#*:}
  sed "s/\(^\|[[:space:]]\)$pkg\([[:space:]]\|$\)/\1\2/" "$root/scripts/setup" > "$scratch/setup-without-$pkg"
  if grep -qw -- "$pkg" "$scratch/setup-without-$pkg"; then
    echo "check_setup_test: could not take $pkg out of scripts/setup"; exit 1
  fi
  status=0
  "$root/scripts/check_setup" --setup "$scratch/setup-without-$pkg" > "$scratch/out-$pkg" 2>&1 || status=$?
  if [ "$status" -ne 1 ] || ! grep -q "add $named[^ ]* to its package list" "$scratch/out-$pkg"; then
    echo "check_setup_test: without $pkg the guard exited $status and said:"; cat "$scratch/out-$pkg"; exit 1
  fi
  echo "without $pkg: $(grep -c "add $named" "$scratch/out-$pkg") file(s) named, e.g.: $(head -1 "$scratch/out-$pkg")"
done
echo "check_setup_test: ok"
