#!/usr/bin/env bash
# Builds the vimc module (the virtual media-controller camera) out of tree for the kernel the
# test VM boots: Debian builds it for no kernel of its own. Everything comes from Debian's
# packages at exactly the kernel image's version: the driver's folder from linux-source-6.1,
# the headers (linux-headers-KVER, -common) and linux-kbuild-6.1. Cached under CACHE/vimc;
# fails (exit 2) with a message naming what could not be had.
#
#   tests/vm/build_vimc.sh CACHE KVER VERSION      -> CACHE/vimc/KVER/vimc.ko
set -euo pipefail
cache=$1 kver=$2 version=$3
out=$cache/vimc/$kver
die() { echo "build_vimc: $*" >&2; exit 2; }
[ -f "$out/vimc.ko" ] && exit 0
for tool in make gcc apt-get dpkg-deb xz tar; do
  command -v "$tool" >/dev/null || die "missing $tool (scripts/setup installs build-essential xz-utils)"
done
series=${version%%.*}.$(echo "$version" | cut -d. -f2)  # 6.1.192-2 -> 6.1
# PKG=VERSION, or, when the archive no longer has that exact version, its newest of the same
# upstream version (6.1.192-*): Debian keeps only the newest linux-kbuild and linux-source
# of a release, and a new Debian revision of them (6.1.192-3) can come out while the kernel
# image is still 6.1.192-2. Same upstream version, same driver source and tools; the
# vermagic check below still holds the module to the kernel.
pick() {
  local pkg=$1 have
  have=$(apt-cache madison "$pkg" 2>/dev/null | awk -F'|' '{gsub(/ /, "", $2); print $2}')
  if grep -qxF "$version" <<<"$have"; then echo "$pkg=$version"; return; fi
  local same
  same=$(awk -v p="${version%-*}-" 'index($0, p) == 1' <<<"$have" | sort -V | tail -1)
  echo "$pkg=${same:-$version}"
}
work=$cache/vimc/work
rm -rf "$work" && mkdir -p "$work"
pkgs=("$(pick "linux-source-$series")" "$(pick "linux-headers-$kver")"
      "$(pick "linux-headers-${kver%-*}-common")" "$(pick "linux-kbuild-$series")")
(cd "$work" && apt-get download "${pkgs[@]}" >/dev/null 2>&1) ||
  die "apt-get download ${pkgs[*]} failed (apt-get update? the packages must match the VM's kernel $kver)"
for deb in "$work"/linux-headers-*.deb "$work"/linux-kbuild-*.deb; do
  dpkg-deb -x "$deb" "$work/root" || die "cannot unpack $deb"
done
# Only the driver's folder from the source tarball.
dpkg-deb --fsys-tarfile "$work"/linux-source-*.deb | tar -x -O "./usr/src/linux-source-$series.tar.xz" |
  tar -xJ -C "$work" "linux-source-$series/drivers/media/test-drivers/vimc" ||
  die "cannot extract drivers/media/test-drivers/vimc from linux-source-$series"
headers=$work/root/usr/src/linux-headers-$kver
# The headers' Makefile includes the -common one by absolute path: point it into our copy.
sed -i "s|^include /usr/src/|include $work/root/usr/src/|" "$headers/Makefile"
src=$work/linux-source-$series/drivers/media/test-drivers/vimc
make -C "$headers" M="$src" CONFIG_VIDEO_VIMC=m modules >"$work/build.log" 2>&1 ||
  { tail -20 "$work/build.log" >&2; die "building vimc.ko failed (log: $work/build.log)"; }
magic=$(modinfo -F vermagic "$src/vimc.ko" | awk '{print $1}')
[ "$magic" = "$kver" ] || die "vimc.ko's vermagic '$magic' is not the kernel's '$kver'"
mkdir -p "$out" && cp "$src/vimc.ko" "$out/"
rm -rf "$work"
echo "build_vimc: built vimc.ko for $kver ($version)"
