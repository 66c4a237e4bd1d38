#!/usr/bin/env bash
# Installs navd into the VM's root filesystem the way README.md "Running on a vehicle" says,
# plus the scenario runner (hil-tests/vm/README.md):
#   install-navd.sh SOURCE_DIR BUILD_DIR ROOT [BIN_DIR]
# BUILD_DIR: the host's build, whose navtool and navd_vm_tool make the dives and the config;
# BIN_DIR: the guest's binaries (default BUILD_DIR/bin; for the arm64 guest the cross build's,
# cross-build-arm64.sh).
# 1. navd, navtool and navd_vm_tool from BIN_DIR to /usr/bin;
# 2. systemd/navd.service, navd.sysusers, navd.tmpfiles to their places, then
#    systemd-sysusers and systemd-tmpfiles --create (on the root, --root=);
# 3. /etc/navd/navd.yaml: the config `navtool hil-play` writes for the VM's dive (serial
#    sensors on the player's ptys in /run/navd-hil), checkpoints in /var/lib/navd/checkpoints
#    every 2 s;
# 4. navd is not enabled: each scenario starts it after the player (guest/lib.sh).
set -euo pipefail
src=$1; build=$2; root=$3; bin=${4:-$2/bin}
vm=$src/hil-tests/vm
install -m 0755 "$bin/navd" "$bin/navtool" "$root/usr/bin/"
# NAV_VM_UNIT: another unit file (the failure demonstrations of README.md)
install -m 0644 "${NAV_VM_UNIT:-$src/systemd/navd.service}" "$root/lib/systemd/system/navd.service"
install -D -m 0644 "$src/systemd/navd.sysusers" "$root/usr/lib/sysusers.d/navd.conf"
install -D -m 0644 "$src/systemd/navd.tmpfiles" "$root/usr/lib/tmpfiles.d/navd.conf"
systemd-sysusers --root="$root"
systemd-tmpfiles --create --root="$root" "$root/usr/lib/tmpfiles.d/navd.conf"
install -D -m 0644 "$vm/guest/navd-hil.conf" "$root/etc/systemd/system/navd.service.d/hil.conf"

# The dive the player plays: a short simulated survey (same seed: same bytes every run).
lib=$root/usr/lib/navd-vm
mkdir -p "$lib/scenarios"
"$build/bin/navtool" simulate --config "$src/config/sim.yaml" --out "$lib/dive" \
  --images "${NAV_VM_DIVE_IMAGES:-40}" --seed 7 > /dev/null
# The watchdog scenario's dive, played with its camera: frames of 160 x 128 px (the intrinsics
# scaled by 1/8 alike: the same field of view), so that the player's fake GigE camera fills a
# frame in the emulated CPU's time; at 1280 x 1024 its GVCP answers wait so long that navd's
# Aravis declares the camera lost (heartbeat) and no image arrives.
sed -e 's/^\(      f[xy]:\) 1000.0/\1 125.0/' -e 's/^\(      cx:\) 640.0/\1 80.0/' \
    -e 's/^\(      cy:\) 512.0/\1 64.0/' "$src/config/sim.yaml" > "$lib/camera-sim.yaml"
[ "$(grep -cE '^      (fx: 125|fy: 125|cx: 80|cy: 64)\.0' "$lib/camera-sim.yaml")" = 4 ] || {
  echo "install-navd.sh: config/sim.yaml's camera intrinsics are not the 1000/640/512 expected" >&2
  exit 1; }
"$build/bin/navtool" simulate --config "$lib/camera-sim.yaml" --out "$lib/camera-dive" \
  --images 20 --seed 7 > /dev/null
rm "$lib/camera-sim.yaml"
# The navd config hil-play writes for it (without a reader: --no-wait at high speed), with
# the VM's paths.
gen=$(mktemp -d)
"$build/bin/navtool" hil-play "$lib/dive" --no-camera --no-wait --speed 1000 \
  --serial-dir "$gen/hil" --config-out "$gen/navd.yaml" > /dev/null 2>&1
mkdir -p "$root/etc/navd"
sed -e "s|$gen/hil|/run/navd-hil|g" \
    -e 's|^\(  *path:\) .*checkpoints$|\1 /var/lib/navd/checkpoints|' \
    -e 's|^\(  *period_s:\) .*|\1 2|' "$gen/navd.yaml" > "$root/etc/navd/navd.yaml"
if ! grep -q "device: /run/navd-hil/dvl" "$root/etc/navd/navd.yaml" ||
   ! grep -q "path: /var/lib/navd/checkpoints" "$root/etc/navd/navd.yaml"; then
  echo "install-navd.sh: the generated /etc/navd/navd.yaml lacks the VM's paths" >&2; exit 1
fi

# The CAN dive: a shorter survey whose DVL (and a FOG) are frames of config/can's example
# table on vcan0 (navd_vm_tool can-dive), and navd's config for it.
install -D -m 0644 "$src/config/can/dvl_fog_example.yaml" "$root/etc/navd/can/dvl_fog_example.yaml"
"$build/bin/navtool" simulate --config "$src/config/sim.yaml" --out "$gen/sim" --images 4 \
  --seed 7 > /dev/null
mkdir -p "$lib/can-dive"
"$build/bin/navd_vm_tool" can-dive "$gen/sim" "$lib/can-dive" "$src/config/can/dvl_fog_example.yaml" \
  > "$lib/can-dive/frames.json"
# The player writes navd's CAN config in the guest (the host has no SocketCAN to play on).
sed -i "s|$src/config/can/|/etc/navd/can/|" "$lib/can-dive/config.yaml"
grep -q "signals_file: /etc/navd/can/dvl_fog_example.yaml" "$lib/can-dive/config.yaml" || {
  echo "install-navd.sh: the CAN dive's config does not name the installed signal table" >&2
  exit 1; }
rm -rf "$gen"
# The replay scenario's dive: replayed by the guest's navtool and compared with the host's
# replay of the same dive (run-vm.sh, compare-replay.sh).
"$build/bin/navtool" simulate --config "$src/config/sim.yaml" --out "$lib/replay-dive" \
  --images "${NAV_VM_REPLAY_IMAGES:-14}" --seed 7 > /dev/null
if [ -x "$bin/navd_vm_tool" ]; then
  install -m 0755 "$bin/navd_vm_tool" "$root/usr/bin/"
else
  echo "install-navd.sh: no $bin/navd_vm_tool: the watchdog and can scenarios cannot run" >&2
fi

install -m 0644 "$vm/guest/lib.sh" "$lib/lib.sh"
install -m 0755 "$vm/guest/run-scenarios" "$vm/guest/sandbox-probe" "$lib/"
install -m 0755 "$vm/guest/scenarios/"*.sh "$lib/scenarios/"
install -m 0644 "$vm/guest/navd-vm-runner.service" "$root/etc/systemd/system/"
mkdir -p "$root/etc/systemd/system/multi-user.target.wants"
ln -sf /etc/systemd/system/navd-vm-runner.service \
  "$root/etc/systemd/system/multi-user.target.wants/navd-vm-runner.service"
