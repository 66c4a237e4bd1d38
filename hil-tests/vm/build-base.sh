#!/usr/bin/env bash
# Builds the cached base root filesystem of the navd test VM (hil-tests/vm/README.md):
# Debian 12 minbase with systemd, udev, kmod, iproute2, the distribution kernel (for vcan.ko and
# an initrd that mounts a virtio disk), can-utils, lcm-logger and the runtime libraries of the
# given binaries: the Debian packages that own the shared objects `ldd` lists for them.
#   build-base.sh CACHE_DIR BINARY...
# Writes CACHE_DIR/base-<key>/{root.tar,vmlinuz,initrd.img,packages.txt} and prints that
# directory on stdout. The key is a hash of the package list and this script, so the slow
# debootstrap (~2 min) runs again only when an input changes. Needs root (debootstrap, chroot).
set -euo pipefail
cache=$1; shift
suite=bookworm
mirror=${NAV_VM_MIRROR:-http://deb.debian.org/debian}
arch=amd64  # an arm64 guest would also need navd cross-built against an arm64 sysroot
kernel_pkg=linux-image-amd64

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
libs=$(runtime_packages "$@" | tr '\n' ',' | sed 's/,$//')
if [ -z "$libs" ]; then echo "build-base.sh: no runtime package found for $*" >&2; exit 1; fi
include="systemd,systemd-sysv,udev,kmod,iproute2,procps,$kernel_pkg,initramfs-tools"
include="$include,can-utils,liblcm-bin,$libs"
# Drops what the VM never loads, to shrink the image (1 GB -> ~0.5 GB) and its copies: kernel
# modules but CAN's (the initrd holds the disk's), /boot (copied out), the GL drivers and the
# LLVM they use (navd links no GL), apt lists, documentation.
trim_root() {
  local root=${1:?trim_root needs the root directory} modules
  modules=$(ls -d "$root"/usr/lib/modules/*)
  find "$modules/kernel" -name '*.ko*' ! -path '*/net/can/*' -delete
  chroot "$root" depmod -a "$(basename "$modules")"
  rm -rf "${root:?}"/boot/* "$root"/var/lib/apt/lists/* "$root"/var/cache/apt/archives/*.deb \
    "$root"/usr/share/doc "$root"/usr/share/man "$root"/usr/share/locale \
    "$root"/usr/lib/*-linux-gnu/dri "$root"/usr/lib/*-linux-gnu/libLLVM-*.so*
}
key=$( (echo "$arch $suite $include"; cat "$0") | sha256sum | cut -c1-16)
out="$cache/base-$arch-$key"
if [ -f "$out/root.tar" ] && [ -f "$out/vmlinuz" ] && [ -f "$out/initrd.img" ]; then
  echo "$out"; exit 0
fi
rm -rf "$out"; mkdir -p "$out"
root="$out/root"
echo "build-base.sh: debootstrap $suite ($arch) into $root" >&2
start=$(date +%s)
debootstrap --arch="$arch" --variant=minbase --include="$include" "$suite" "$root" "$mirror" \
  > "$out/debootstrap.log" 2>&1 || {
  echo "build-base.sh: debootstrap failed, last lines of $out/debootstrap.log:" >&2
  tail -20 "$out/debootstrap.log" >&2; exit 1; }
# Guest configuration: root on the virtio disk, no network device (LCM stays on lo), nothing
# periodic that competes with the scenarios for the emulated CPU.
echo "navd-vm" > "$root/etc/hostname"
echo "/dev/vda / ext4 rw,noatime 0 1" > "$root/etc/fstab"
for unit in apt-daily.timer apt-daily-upgrade.timer dpkg-db-backup.timer e2scrub_all.timer \
            fstrim.timer systemd-tmpfiles-clean.timer; do
  ln -sf /dev/null "$root/etc/systemd/system/$unit"
done
echo "$include" | tr ',' '\n' > "$out/packages.txt"
cp "$(ls "$root"/boot/vmlinuz-* | head -1)" "$out/vmlinuz"
cp "$(ls "$root"/boot/initrd.img-* | head -1)" "$out/initrd.img"
trim_root "$root"
tar -C "$root" -cf "$out/root.tar" .
rm -rf "$root"
echo "build-base.sh: base image in $(( $(date +%s) - start )) s" >&2
echo "$out"
