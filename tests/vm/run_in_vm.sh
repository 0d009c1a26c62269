#!/usr/bin/env bash
# Runs a command inside a QEMU VM that boots Debian's kernel with a virtual camera driver
# loaded, so that kincal's capture code meets a real driver: vivid (V4L2, in Debian's
# kernel package) or vimc (a media-controller camera that libcamera drives; built out of
# tree by tests/vm/build_vimc.sh for exactly this kernel).
#
#   tests/vm/run_in_vm.sh CACHE_DIR vivid|vimc "MODULE_PARAMS" COMMAND [ARGS...]
#
# libcamera ignores devices that udev has not initialised, and learns of cameras that come
# and go from udev's events: with vimc the VM runs udevd (package udev) as a real system
# does.
#
# The host's root file system is shared read-only over virtio-9p and becomes the VM's root
# (switch_root) (so the build tree and its shared libraries are used as they are), with
# a fresh tmpfs on /run for scratch files (TMPDIR=/run). The kernel package is fetched once
# with `apt-get download` into CACHE_DIR. Exit status: the command's, or 2 when the VM
# could not be built or booted (a missing ingredient is a failure, never a skip).
set -euo pipefail
cache=$1 driver=$2 driver_params=$3
shift 3
case $driver in vivid | vimc) ;; *) echo "run_in_vm: driver must be vivid or vimc, got '$driver'" >&2; exit 2 ;; esac
cmd=$(printf '%q ' "$@")
mkdir -p "$cache"
cache=$(cd "$cache" && pwd)

die() { echo "run_in_vm: $*" >&2; exit 2; }
for tool in qemu-system-x86_64 cpio depmod modprobe apt-get apt-cache dpkg-deb; do
  command -v "$tool" >/dev/null || die "missing $tool (scripts/setup installs qemu-system-x86 busybox-static cpio kmod)"
done
bb=/bin/busybox
[ -x "$bb" ] && ! ldd "$bb" >/dev/null 2>&1 || die "needs a static /bin/busybox (package busybox-static)"

# 1. The kernel: the package linux-image-amd64 depends on, unpacked, depmod'ed.
if [ ! -f "$cache/kernel/ok" ] || [ ! -f "$cache/kernel/version" ]; then
  rm -rf "$cache/kernel" && mkdir -p "$cache/kernel"
  pkg=$(apt-cache depends linux-image-amd64 2>/dev/null | awk '/Depends: linux-image-[0-9]/ {print $2; exit}')
  [ -n "$pkg" ] || die "cannot resolve linux-image-amd64 (apt-get update?)"
  (cd "$cache/kernel" && apt-get download "$pkg" >/dev/null 2>&1) || die "apt-get download $pkg failed"
  dpkg-deb -x "$cache"/kernel/*.deb "$cache/kernel/root" || die "cannot unpack $pkg"
  dpkg-deb -f "$cache"/kernel/*.deb Version > "$cache/kernel/version"
  rm -f "$cache"/kernel/*.deb
  kver=$(ls "$cache/kernel/root/lib/modules")
  depmod -b "$cache/kernel/root" "$kver" || die "depmod failed"
  touch "$cache/kernel/ok"
fi
root=$cache/kernel/root
kver=$(ls "$root/lib/modules")
vmlinuz=$(ls "$root"/boot/vmlinuz-*)
if [ "$driver" = vimc ]; then
  "$(dirname "$0")/build_vimc.sh" "$cache" "$kver" "$(cat "$cache/kernel/version")" || die "no vimc module"
fi

# 2. The initramfs: static busybox, the modules (with dependencies, in load order), /init.
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
ird=$work/initramfs
mkdir -p "$ird"/{bin,dev,proc,sys,host,mods}
cp "$bb" "$ird/bin/busybox"
for a in sh mount umount insmod switch_root poweroff sleep cat echo mkdir ls rmmod; do ln -s busybox "$ird/bin/$a"; done
: > "$ird/mods/order"
if [ "$driver" = vivid ]; then
  mods="virtio_pci 9pnet_virtio 9p vivid"
else  # vimc's dependencies from the kernel package, then vimc.ko itself
  mods="virtio_pci 9pnet_virtio 9p mc videodev videobuf2-common videobuf2-v4l2 videobuf2-memops"
  mods="$mods videobuf2-vmalloc videobuf2-dma-contig v4l2-tpg"
fi
for m in $mods; do
  modprobe -d "$root" -S "$kver" --show-depends "$m" 2>/dev/null | awk '$1 == "insmod" {print $2}' |
    while read -r path; do
      name=$(basename "$path")
      if ! grep -qx "$name" "$ird/mods/order"; then cp "$path" "$ird/mods/"; echo "$name" >> "$ird/mods/order"; fi
    done
done
if [ "$driver" = vivid ]; then
  grep -qx vivid.ko "$ird/mods/order" || die "the kernel package has no vivid module"
else
  grep -qx v4l2-tpg.ko "$ird/mods/order" || die "the kernel package has no v4l2-tpg module"
  cp "$cache/vimc/$kver/vimc.ko" "$ird/mods/" && echo vimc.ko >> "$ird/mods/order"
fi
udev_start=""
if [ "$driver" = vimc ]; then
  [ -x /lib/systemd/systemd-udevd ] || die "missing /lib/systemd/systemd-udevd (scripts/setup installs udev)"
  udev_start="/lib/systemd/systemd-udevd --daemon --resolve-names=never && udevadm trigger --action=add && udevadm settle --timeout=30 &&"
fi
printf '%s\n' "$cmd" > "$ird/cmd"
printf '%s\n' "$PWD" > "$ird/cwd"
cat > "$ird/init" <<INIT
#!/bin/sh
mount -t proc proc /proc; mount -t sysfs sys /sys; mount -t devtmpfs dev /dev
for m in \$(cat /mods/order); do
  case \$m in $driver.ko) insmod /mods/\$m $driver_params ;; *) insmod /mods/\$m ;; esac || echo "run_in_vm: insmod \$m failed"
done
mount -t 9p -o trans=virtio,version=9p2000.L,ro,msize=262144,cache=loose host /host || echo "run_in_vm: 9p mount failed"
mount --bind /dev /host/dev; mount -t proc proc /host/proc; mount -t sysfs sys /host/sys
mount -t tmpfs tmp /host/run
cp /mods/*.ko /bin/busybox /host/run/ 2>/dev/null
echo "run_in_vm: booted, running: \$(cat /cmd)"
# The host's root becomes the VM's (switch_root, not chroot: udevadm refuses to work in a
# chroot); the command runs in its init, which powers the VM off.
cat > /host/run/init.sh <<VMINIT
export TMPDIR=/run KINCAL_IN_VM=1 KINCAL_VM_MODULES=/run KINCAL_VM_DRIVER=$driver KINCAL_VM_DRIVER_PARAMS='$driver_params'
$udev_start cd \$(cat /cwd) && \$(cat /cmd)
echo "KINCAL_VM_EXIT=\\\$?"
/run/busybox poweroff -f
VMINIT
exec switch_root /host /bin/sh /run/init.sh
INIT
chmod +x "$ird/init"
(cd "$ird" && find . | cpio -o -H newc --quiet) > "$work/initramfs.cpio"

# 3. Boot. TCG (KVM is not used: it hangs on some hosts); the serial console is our output.
log=$work/console.log
timeout 900 qemu-system-x86_64 -accel tcg -m 1536 -smp 2 -nographic -no-reboot \
  -kernel "$vmlinuz" -initrd "$work/initramfs.cpio" \
  -append "console=ttyS0 panic=-1 quiet loglevel=3" \
  -virtfs local,path=/,mount_tag=host,security_model=none,readonly=on,multidevs=remap \
  </dev/null >"$log" 2>&1 || true
tr -d '\r' < "$log" | grep -v "^KINCAL_VM_EXIT=" || true
rc=$(tr -d '\r' < "$log" | sed -n 's/^KINCAL_VM_EXIT=\([0-9]*\).*/\1/p' | tail -1)
[ -n "$rc" ] || die "the VM did not report an exit status (boot failed?)"
exit "$rc"
