#!/usr/bin/env bash
# Builds the navd test VM image, boots it under QEMU and runs scenarios inside it
# (hil-tests/vm/README.md). One command:
#   hil-tests/vm/run-vm.sh [--build DIR] [--cache DIR] [--scenarios a,b,c] [--timeout-s S]
#                          [--break watchdog|hardening]
# --build: the Release build whose bin/navd and bin/navtool are installed (default build);
# --cache: NAV_VM_CACHE or ~/.cache/navd-vm (base image, kept between runs and checkouts);
# --scenarios: default ready,stop,watchdog,hardening,config_error (hil-tests/vm/guest/scenarios).
# --break: installs a deliberately broken copy of systemd/navd.service (the failure
# demonstrations of the README): watchdog = without WatchdogSec=, hardening = without
# ProtectSystem=strict; the scenario of that name must then FAIL (exit 1).
# Prints the times (image, boot, each scenario) and one verdict per scenario; exit 0 when all
# pass, 1 when one fails or the VM does not finish, 77 (skip) when this machine cannot run the
# VM (not root, or no qemu-system-x86_64 / debootstrap / mkfs.ext4), with the reason.
set -euo pipefail
src=$(cd "$(dirname "$0")/../.." && pwd)
build=$src/build
cache=""
scenarios=ready,stop,watchdog,hardening,config_error
timeout_s=900
break_feature=""
while [ $# -gt 0 ]; do
  case "$1" in
    --build) build=$2; shift 2 ;;
    --cache) cache=$2; shift 2 ;;
    --scenarios) scenarios=$2; shift 2 ;;
    --timeout-s) timeout_s=$2; shift 2 ;;
    --break) break_feature=$2; shift 2 ;;
    *) echo "run-vm.sh: unknown argument '$1' (see the header of $0)" >&2; exit 2 ;;
  esac
done
build=$(cd "$build" && pwd)
cache=${cache:-${NAV_VM_CACHE:-${XDG_CACHE_HOME:-$HOME/.cache}/navd-vm}}
skip() { echo "run-vm.sh: SKIP: $*"; exit 77; }
[ "$(id -u)" = 0 ] || skip "needs root (debootstrap, chroot and file ownership in the image)"
for tool in qemu-system-x86_64 debootstrap mkfs.ext4; do
  command -v "$tool" > /dev/null || skip "$tool not installed (scripts/install-deps)"
done
for bin in navd navtool navd_vm_tool; do
  [ -x "$build/bin/$bin" ] || { echo "run-vm.sh: $build/bin/$bin not built" >&2; exit 1; }
done
mkdir -p "$cache"
t_start=$(date +%s.%N)
secs() { awk -v a="$1" -v b="$(date +%s.%N)" 'BEGIN{printf "%.1f", b - a}'; }

base=$("$src/hil-tests/vm/build-base.sh" "$cache" "$build/bin/navd" "$build/bin/navtool")
echo "run-vm.sh: base image $base ($(secs "$t_start") s)"

work=$cache/run
rm -rf "$work"; mkdir -p "$work"
if [ -n "$break_feature" ]; then
  case "$break_feature" in
    watchdog) removed='^WatchdogSec=' ;;
    hardening) removed='^ProtectSystem=strict$' ;;
    *) echo "run-vm.sh: --break '$break_feature': not watchdog or hardening" >&2; exit 2 ;;
  esac
  grep -q "$removed" "$src/systemd/navd.service" ||
    { echo "run-vm.sh: --break: systemd/navd.service has no line $removed" >&2; exit 1; }
  export NAV_VM_UNIT=$work/navd-broken.service
  grep -v "$removed" "$src/systemd/navd.service" > "$NAV_VM_UNIT"
  echo "run-vm.sh: --break $break_feature: the unit without $removed (the $break_feature scenario must FAIL)"
fi
root=$work/root
mkdir "$root"
tar -C "$root" -xf "$base/root.tar"
"$src/hil-tests/vm/install-navd.sh" "$src" "$build" "$root"
disk=$work/disk.img
mkfs.ext4 -q -F -L navd-vm -d "$root" "$disk" "$(( $(du -sm "$root" | cut -f1) + 400 ))M"
rm -rf "$root"
t_image=$(secs "$t_start")
echo "run-vm.sh: image ready in $t_image s"

console=$work/console.log
results=$work/results.log
: > "$results"
t_boot=$(date +%s.%N)
qemu-system-x86_64 -m 1536 -smp 2 -display none -monitor none -no-reboot \
  -kernel "$base/vmlinuz" -initrd "$base/initrd.img" \
  -append "root=/dev/vda rw console=ttyS0 edd=off panic=-1 navd_vm.scenarios=$scenarios" \
  -drive "file=$disk,if=virtio,format=raw" -nic none \
  -serial "file:$console" -serial "file:$results" &
qemu=$!
booted=""
deadline=$(( $(date +%s) + timeout_s ))
while kill -0 "$qemu" 2>/dev/null; do
  if [ -z "$booted" ] && grep -q "^NAVD-VM BOOTED" "$results"; then
    booted=$(secs "$t_boot")
    echo "run-vm.sh: booted, scenario runner up after $booted s (guest uptime $(sed -n 's/^NAVD-VM BOOTED //p' "$results" | tr -d '\r') s)"
  fi
  if [ "$(date +%s)" -ge "$deadline" ]; then
    echo "run-vm.sh: the VM did not finish in $timeout_s s; last console lines:"
    kill "$qemu"; tail -20 "$console"; exit 1
  fi
  sleep 1
done
wait "$qemu" || true
tr -d '\r' < "$results" | sed -n 's/^NAVD-VM //p' | grep -v "^BOOTED"
echo "run-vm.sh: total $(secs "$t_start") s (image $t_image s, boot ${booted:-?} s)"
done_line=$(tr -d '\r' < "$results" | grep "^NAVD-VM DONE" || true)
if [ -z "$done_line" ]; then
  echo "run-vm.sh: the VM stopped before the scenarios finished; last console lines:"
  tail -30 "$console"; exit 1
fi
read -r _ _ passed failed <<< "$done_line"
echo "$passed passed, $failed failed"
[ "$failed" = 0 ] && [ "$passed" -gt 0 ]
