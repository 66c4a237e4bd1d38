#!/usr/bin/env bash
# Builds the cached base root filesystem of the navd test VM (hil-tests/vm/README.md):
# Debian 12 minbase with systemd, udev, kmod, iproute2, the distribution kernel (for vcan.ko and
# an initrd that mounts a virtio disk), can-utils, lcm-logger and the runtime libraries of the
# given binaries: the Debian packages that own the shared objects `ldd` lists for them.
#   build-base.sh [--arch amd64|arm64] CACHE_DIR BINARY...
# Writes CACHE_DIR/base-<arch>-<key>/{root.tar,vmlinuz,initrd.img,packages.txt} and prints
# that directory on stdout. The key is a hash of the package list and the scripts, so the slow
# debootstrap (~2 min; arm64 with its second stage in the guest: arm64.sh) runs again only when
# an input changes. BINARY: amd64 (host) builds of navd and navtool also for an arm64 base (the
# same sources link the same Debian packages; the arm64 binaries cannot be run through ldd
# here). Needs root (debootstrap, chroot, file ownership).
set -euo pipefail
arch=amd64
if [ "${1:-}" = --arch ]; then arch=$2; shift 2; fi
cache=$1; shift
suite=bookworm
mirror=${NAV_VM_MIRROR:-http://deb.debian.org/debian}
here=$(cd "$(dirname "$0")" && pwd)
case "$arch" in
  amd64|arm64) kernel_pkg=linux-image-$arch ;;
  *) echo "build-base.sh: --arch '$arch': not amd64 or arm64" >&2; exit 2 ;;
esac

# Runtime packages: owners of the libraries the binaries load (host and guest are Debian 12).
runtime_packages() {
  local libs
  libs=$(for bin in "$@"; do ldd "$bin"; done | awk '/=> \//{print $3}' | sort -u |
    xargs -r readlink -f)
  # One dpkg query for all (one per library takes minutes); /lib and /usr/lib are the same
  # directory (merged /usr) but dpkg records the path the package shipped.
  # shellcheck disable=SC2086,SC2046
  { dpkg -S $libs 2>/dev/null; dpkg -S $(echo "$libs" | sed 's|^/usr/lib/|/lib/|') 2>/dev/null || true; } |
    cut -d: -f1 | sort -u
}
# libquadmath0 (gfortran's, pulled in by the amd64 LAPACK) is built for x86 only.
libs=$(runtime_packages "$@" | { if [ "$arch" = arm64 ]; then grep -vx libquadmath0; else cat; fi; } |
  tr '\n' ',' | sed 's/,$//')
if [ -z "$libs" ]; then echo "build-base.sh: no runtime package found for $*" >&2; exit 1; fi
include="systemd,systemd-sysv,udev,kmod,iproute2,procps,$kernel_pkg,initramfs-tools"
include="$include,can-utils,liblcm-bin,$libs"
# Drops what the VM never loads, to shrink the image (1 GB -> ~0.5 GB) and its copies: kernel
# modules but CAN's and virtio_console's (the arm64 guest's verdict port; the initrd holds the
# disk's), /boot (copied out), the GL drivers and the LLVM they use (navd links no GL), apt
# lists, documentation. The host's depmod indexes the rest (also for an arm64 root).
trim_root() {
  local root=${1:?trim_root needs the root directory} modules
  modules=$(ls -d "$root"/usr/lib/modules/*)
  find "$modules/kernel" -name '*.ko*' ! -path '*/net/can/*' ! -name 'virtio_console.ko*' -delete
  depmod -b "$root" "$(basename "$modules")"
  rm -rf "${root:?}"/boot/* "$root"/var/lib/apt/lists/* "$root"/var/cache/apt/archives/*.deb \
    "$root"/usr/share/doc "$root"/usr/share/man "$root"/usr/share/locale \
    "$root"/usr/lib/*-linux-gnu/dri "$root"/usr/lib/*-linux-gnu/libLLVM-*.so*
}
key=$( (echo "$arch $suite $include"; cat "$0" "$here/arm64.sh" "$here/guest/first-boot-init.c") |
  sha256sum | cut -c1-16)
out="$cache/base-$arch-$key"
if [ -f "$out/root.tar" ] && [ -f "$out/vmlinuz" ] && [ -f "$out/initrd.img" ]; then
  echo "$out"; exit 0
fi
rm -rf "$out"; mkdir -p "$out"
root="$out/root"
echo "build-base.sh: debootstrap $suite ($arch) into $root" >&2
start=$(date +%s)
foreign=""; [ "$arch" = arm64 ] && foreign=--foreign
# The downloaded packages are kept beside the bases (a rebuild after a script change fetches
# only what changed).
mkdir -p "$cache/debootstrap-debs"
debootstrap --arch="$arch" $foreign --variant=minbase --include="$include" \
  --cache-dir="$cache/debootstrap-debs" "$suite" "$root" "$mirror" \
  > "$out/debootstrap.log" 2>&1 || {
  echo "build-base.sh: debootstrap failed, last lines of $out/debootstrap.log:" >&2
  tail -20 "$out/debootstrap.log" >&2; exit 1; }
if [ "$arch" = arm64 ]; then
  # shellcheck source=arm64.sh
  . "$here/arm64.sh"
  echo "build-base.sh: unpacked in $(( $(date +%s) - start )) s; second stage in the guest" >&2
  arm64_first_initrd "$(ls "$root"/var/cache/apt/archives/linux-image-[0-9]*_arm64.deb)" "$out"
  arm64_second_stage "$root" "$out" "${NAV_VM_STAGE2_TIMEOUT_S:-5400}"
  rm -f "$out/vmlinuz" "$out/first-initrd.img"
fi
# Guest configuration: root on the virtio disk, no network device (LCM stays on lo), nothing
# periodic that competes with the scenarios for the emulated CPU.
echo "navd-vm" > "$root/etc/hostname"
echo "/dev/vda / ext4 rw,noatime 0 1" > "$root/etc/fstab"
for unit in apt-daily.timer apt-daily-upgrade.timer dpkg-db-backup.timer e2scrub_all.timer \
            fstrim.timer systemd-tmpfiles-clean.timer; do
  ln -sf /dev/null "$root/etc/systemd/system/$unit"
done
echo "$include" | tr ',' '\n' > "$out/packages.txt"
ls "$root"/boot/vmlinuz-* "$root"/boot/initrd.img-* > /dev/null || {
  echo "build-base.sh: the $arch root has no /boot/vmlinuz-* or initrd.img-* ($kernel_pkg and initramfs-tools did not finish)" >&2
  exit 1; }
cp "$(ls "$root"/boot/vmlinuz-* | head -1)" "$out/vmlinuz"
cp "$(ls "$root"/boot/initrd.img-* | head -1)" "$out/initrd.img"
trim_root "$root"
tar -C "$root" -cf "$out/root.tar" .
rm -rf "$root"
echo "build-base.sh: base image in $(( $(date +%s) - start )) s" >&2
echo "$out"
