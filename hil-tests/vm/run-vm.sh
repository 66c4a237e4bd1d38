#!/usr/bin/env bash
# Builds the navd test VM image, boots it under QEMU and runs scenarios inside it
# (hil-tests/vm/README.md). One command:
#   hil-tests/vm/run-vm.sh [--arch amd64|arm64] [--build DIR] [--target-bin DIR] [--cache DIR]
#                          [--scenarios a,b,c] [--timeout-s S] [--break watchdog|hardening]
# --arch: the guest (default amd64 under qemu-system-x86_64; arm64: qemu-system-aarch64 -M
# virt, its base made as arm64.sh says, default scenarios ready,replay, timeout 3600 s);
# --build: the host's Release build, whose navtool and navd_vm_tool make the dives (default
# build); --target-bin: the guest's navd, navtool and navd_vm_tool (default BUILD/bin for amd64,
# build-arm64/bin for arm64: cross-build-arm64.sh);
# --cache: NAV_VM_CACHE or ~/.cache/navd-vm (base image, kept between runs and checkouts);
# --scenarios: default ready,stop,watchdog,hardening,config_error (hil-tests/vm/guest/scenarios);
# with `replay` the guest's replay output is then compared with the host's replay of the same
# dive (compare-replay.sh, 1 mm, 5 mm for the delayed states; verdict line replay_vs_host).
# --break: installs a deliberately broken copy of systemd/navd.service (the failure
# demonstrations of the README): watchdog = without WatchdogSec=, hardening = without
# ProtectSystem=strict; the scenario of that name must then FAIL (exit 1).
# Prints the times (image, boot, each scenario) and one verdict per scenario; exit 0 when all
# pass, 1 when one fails or the VM does not finish, 77 (skip) when this machine cannot run the
# VM (not root, or a missing tool: qemu-system-x86_64 or -aarch64, debootstrap, mkfs.ext4,
# depmod; for arm64 also aarch64-linux-gnu-gcc and cpio), with the reason.
set -euo pipefail
src=$(cd "$(dirname "$0")/../.." && pwd)
build=$src/build
cache=""
scenarios=""
timeout_s=""
break_feature=""
arch=amd64
target_bin=""
while [ $# -gt 0 ]; do
  case "$1" in
    --arch) arch=$2; shift 2 ;;
    --target-bin) target_bin=$2; shift 2 ;;
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
case "$arch" in
  amd64) tools="qemu-system-x86_64"
         target_bin=${target_bin:-$build/bin}
         scenarios=${scenarios:-ready,stop,watchdog,hardening,config_error}
         timeout_s=${timeout_s:-900} ;;
  arm64) tools="qemu-system-aarch64 aarch64-linux-gnu-gcc cpio"
         target_bin=${target_bin:-$src/build-arm64/bin}
         scenarios=${scenarios:-ready,replay}
         timeout_s=${timeout_s:-3600} ;;
  *) echo "run-vm.sh: --arch '$arch': not amd64 or arm64" >&2; exit 2 ;;
esac
skip() { echo "run-vm.sh: SKIP: $*"; exit 77; }
[ "$(id -u)" = 0 ] || skip "needs root (debootstrap, chroot and file ownership in the image)"
if [ "$arch" = arm64 ] && ! command -v qemu-system-aarch64 aarch64-linux-gnu-gcc cpio > /dev/null
then
  # Only this long scenario needs them, so scripts/install-deps (the CI's) does not install them.
  echo "run-vm.sh: installing the arm64 guest's tools" >&2
  DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends \
    qemu-system-arm gcc-aarch64-linux-gnu libc6-dev-arm64-cross cpio
fi
for tool in $tools debootstrap mkfs.ext4 depmod; do
  command -v "$tool" > /dev/null || skip "$tool not installed (scripts/install-deps)"
done
for bin in "$build/bin/navtool" "$build/bin/navd_vm_tool" "$target_bin/navd" \
           "$target_bin/navtool"; do
  [ -x "$bin" ] || { echo "run-vm.sh: $bin not built" >&2; exit 1; }
done
mkdir -p "$cache"
t_start=$(date +%s.%N)
secs() { awk -v a="$1" -v b="$(date +%s.%N)" 'BEGIN{printf "%.1f", b - a}'; }

base=$("$src/hil-tests/vm/build-base.sh" --arch "$arch" "$cache" "$build/bin/navd" \
  "$build/bin/navtool")
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
"$src/hil-tests/vm/install-navd.sh" "$src" "$build" "$root" "$target_bin"
rm -rf "$work/replay-dive"; cp -r "$root/usr/lib/navd-vm/replay-dive" "$work/"
disk=$work/disk.img
mkfs.ext4 -q -F -L navd-vm -d "$root" "$disk" "$(( $(du -sm "$root" | cut -f1) + 400 ))M"
rm -rf "$root"
t_image=$(secs "$t_start")
echo "run-vm.sh: image ready in $t_image s"

console=$work/console.log
results=$work/results.log
: > "$results"
t_boot=$(date +%s.%N)
if [ "$arch" = amd64 ]; then
  qemu-system-x86_64 -m 1536 -smp 2 -display none -monitor none -no-reboot \
    -kernel "$base/vmlinuz" -initrd "$base/initrd.img" \
    -append "root=/dev/vda rw console=ttyS0 edd=off panic=-1 navd_vm.scenarios=$scenarios" \
    -drive "file=$disk,if=virtio,format=raw" -nic none \
    -serial "file:$console" -serial "file:$results" &
else
  # shellcheck source=arm64.sh
  . "$src/hil-tests/vm/arm64.sh"
  # The virt board has one UART (the console): the verdicts go to a virtio console.
  arm64_qemu "$disk" -- -kernel "$base/vmlinuz" -initrd "$base/initrd.img" \
    -append "root=/dev/vda rw console=ttyAMA0 panic=-1 navd_vm.scenarios=$scenarios \
navd_vm.results=/dev/hvc0" -serial "file:$console" \
    -device virtio-serial-pci -chardev "file,id=results,path=$results" \
    -device virtconsole,chardev=results &
fi
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
if [[ ",$scenarios," == *,replay,* ]]; then
  # The guest's replay output (left on its disk) against the host's replay of the same dive.
  "$build/bin/navtool" replay "$work/replay-dive" --as-fast-as-possible --out "$work/replay-host" \
    > "$work/replay-host.log" 2>&1
  rm -rf "$work/replay-out"
  debugfs -R "rdump /var/lib/navd-vm/replay-out $work" "$disk" 2> /dev/null
  if "$src/hil-tests/vm/compare-replay.sh" "$work/replay-host" "$work/replay-out" 0.001 0.005
  then
    echo "RESULT replay_vs_host PASS"; passed=$((passed + 1))
  else
    echo "RESULT replay_vs_host FAIL"; failed=$((failed + 1))
  fi
fi
echo "$passed passed, $failed failed"
[ "$failed" = 0 ] && [ "$passed" -gt 0 ]
