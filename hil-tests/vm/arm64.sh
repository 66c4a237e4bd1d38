# The arm64 guest's pieces shared by build-base.sh and run-vm.sh (hil-tests/vm/README.md
# "arm64 guest"); sourced, defines functions only.
#
# Debian's arm64 kernel has virtio_blk and ext4 as modules, and a machine without binfmt_misc
# cannot run an arm64 root's programs (no chroot, no initramfs-tools for it), so the base is
# made in two boots' worth of steps:
#  1. `debootstrap --foreign` unpacks the packages on the host (arm64_first_initrd then makes
#     a small initramfs from the unpacked kernel package: the disk and filesystem modules in
#     modules.dep order and a static aarch64 /init, guest/first-boot-init.c);
#  2. the guest boots that kernel and initramfs with init=/navd-vm-stage2, which runs
#     debootstrap's second stage (the maintainer scripts, among them initramfs-tools making the
#     guest's own initrd in /boot) and writes the finished root as a tar archive onto its second
#     virtio disk (arm64_second_stage reads it back).
# Later boots use the guest's own initrd, like the amd64 guest.

# The disk and filesystem drivers of a virtio root (virtio-mmio and -pci transports, ext4 with
# its metadata checksums: crc32c, which the kernel would otherwise ask modprobe for).
ARM64_BOOT_MODULES="virtio_mmio virtio_pci virtio_blk crc32c_generic ext4"

# arm64_qemu DISK... -- QEMU_ARGS...: qemu-system-aarch64 on the `virt` board (TCG, -cpu max
# with the implementation-defined pointer-authentication algorithm, several times faster to
# emulate than QARMA), 2 CPUs, 1.5 GB, the disks as virtio, no network device, the first serial
# port (PL011, ttyAMA0) as console; the caller adds -kernel/-initrd/-append and the outputs.
arm64_qemu() {
  local drives=()
  while [ $# -gt 0 ] && [ "$1" != -- ]; do
    drives+=(-drive "file=$1,if=virtio,format=raw"); shift
  done
  shift
  qemu-system-aarch64 -M virt -cpu max,pauth-impdef=on -smp 2 -m 1536 -display none \
    -monitor none -no-reboot "${drives[@]}" -nic none "$@"
}

# arm64_first_initrd KERNEL_DEB OUT_DIR: OUT_DIR/vmlinuz and OUT_DIR/first-initrd.img (cpio,
# newc) with /init = guest/first-boot-init.c built static for aarch64, /modules = the load
# order of ARM64_BOOT_MODULES and their dependencies (host depmod on the unpacked modules).
arm64_first_initrd() {
  local deb=$1 out=$2 here kdir kver dep m d order=() seen=" "
  here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
  kdir=$(mktemp -d)
  dpkg-deb -x "$deb" "$kdir"
  kver=$(ls "$kdir/lib/modules")
  depmod -b "$kdir" "$kver"
  mkdir -p "$out/initramfs"
  for m in $ARM64_BOOT_MODULES; do
    dep=$(grep -E "/$m\.ko(\.[a-z]+)?:" "$kdir/lib/modules/$kver/modules.dep") || {
      echo "arm64.sh: $deb has no module $m" >&2; rm -rf "$kdir"; return 1; }
    # modules.dep: "module: deps", a dependency before what needs it when read backwards.
    for d in $(echo "${dep#*:}" | tr ' ' '\n' | tac) "${dep%%:*}"; do
      case "$seen" in *" $d "*) continue ;; esac
      seen="$seen$d "; order+=("$d")
    done
  done
  for d in "${order[@]}"; do
    install -D -m 0644 "$kdir/lib/modules/$kver/$d" "$out/initramfs/lib/modules/$d"
    echo "/lib/modules/$d"
  done > "$out/initramfs/modules"
  aarch64-linux-gnu-gcc -static -Os -Wall -Werror -o "$out/initramfs/init" \
    "$here/guest/first-boot-init.c"
  (cd "$out/initramfs" && find . | cpio -o -H newc --quiet) > "$out/first-initrd.img"
  cp "$kdir"/boot/vmlinuz-* "$out/vmlinuz"
  rm -rf "$kdir" "$out/initramfs"
}

# The first boot's init (a file in the root; the kernel command line cannot pass arguments).
arm64_stage2_script() {
  cat <<'EOF'
#!/bin/sh
# First boot of the arm64 base (hil-tests/vm/arm64.sh): debootstrap's second stage, then the
# root as a tar archive on /dev/vdb, then power off. Markers on the console for the host.
export PATH=/usr/sbin:/usr/bin:/sbin:/bin
mount -t proc proc /proc
echo "NAVD-VM STAGE2 START $(cut -d' ' -f1 /proc/uptime)"
if /debootstrap/debootstrap --second-stage; then
  mount -t proc proc /proc 2>/dev/null  # debootstrap unmounts it on exit
  echo "NAVD-VM STAGE2 DONE $(cut -d' ' -f1 /proc/uptime)"
  rm -f /navd-vm-stage2
  if tar -C / --one-file-system -cf /dev/vdb .; then
    echo "NAVD-VM STAGE2 TAR $(cut -d' ' -f1 /proc/uptime)"
  fi
else
  mount -t proc proc /proc 2>/dev/null
  echo "NAVD-VM STAGE2 FAILED"; tail -30 /debootstrap/debootstrap.log
fi
sync
echo o > /proc/sysrq-trigger
sleep 30  # the power-off; were it to fail, init's exit panics and QEMU (-no-reboot) ends
EOF
}

# arm64_second_stage ROOT OUT_DIR TIMEOUT_S: ROOT (a `debootstrap --foreign` root, configured)
# booted once as above; on return ROOT holds the finished root, OUT_DIR/first-boot.log the
# console. Needs OUT_DIR/vmlinuz and first-initrd.img (arm64_first_initrd).
arm64_second_stage() {
  local root=$1 out=$2 timeout_s=$3 disk=$2/stage2.img tarimg=$2/stage2.tar qemu deadline
  # debootstrap --foreign in a container that cannot mount proc links /proc to the host's
  # (/proc -> /proc): a loop once the root is the guest's own; the guest mounts a real one.
  if [ -L "$root/proc" ]; then rm "$root/proc"; mkdir -m 0555 "$root/proc"; fi
  arm64_stage2_script > "$root/navd-vm-stage2"
  chmod 0755 "$root/navd-vm-stage2"
  mkfs.ext4 -q -F -L navd-vm -d "$root" "$disk" "$(( $(du -sm "$root" | cut -f1) + 1500 ))M"
  rm -f "$tarimg"; truncate -s 3G "$tarimg"
  arm64_qemu "$disk" "$tarimg" -- -kernel "$out/vmlinuz" -initrd "$out/first-initrd.img" \
    -append "console=ttyAMA0 rw panic=-1 init=/navd-vm-stage2" \
    -serial "file:$out/first-boot.log" &
  qemu=$!
  deadline=$(( $(date +%s) + timeout_s ))
  while kill -0 "$qemu" 2>/dev/null; do
    if [ "$(date +%s)" -ge "$deadline" ]; then
      kill "$qemu"; echo "arm64.sh: the first boot did not end in $timeout_s s" >&2; break
    fi
    sleep 2
  done
  wait "$qemu" || true
  if ! grep -q "^NAVD-VM STAGE2 TAR" "$out/first-boot.log"; then
    echo "arm64.sh: debootstrap's second stage in the guest failed; last console lines of $out/first-boot.log:" >&2
    tail -40 "$out/first-boot.log" >&2; return 1
  fi
  grep "^NAVD-VM STAGE2" "$out/first-boot.log" | tr -d '\r' >&2
  rm -rf "$root"; mkdir -p "$root"
  tar -C "$root" -xf "$tarimg"
  rm -f "$disk" "$tarimg"
}
