#!/bin/bash
# CAN for real: vcan0 in the guest kernel (modprobe vcan), the HIL player sends the CAN dive's
# DVL and FOG frames (navd_vm_tool can-dive, config/can/dvl_fog_example.yaml) on it while the
# other sensors play on ptys, and navd (the service, config written by the player) reads them
# through SocketCAN: every frame sent is decoded (records and data bytes equal), every
# dvl_velocity frame becomes a measurement, and the filter fuses them (updates > 0).
. /usr/lib/navd-vm/lib.sh
modprobe vcan || fail "modprobe vcan: the kernel has no vcan module"
ip link show vcan0 > /dev/null 2>&1 || ip link add vcan0 type vcan
ip link set vcan0 up || fail "cannot bring vcan0 up"
DIVE=$NAVD_VM_DIR/can-dive start_player
grep -A3 "name: dvl" "$HIL_DIR/navd-hil.yaml" | grep -q "type: can" ||
  fail "the player did not put the DVL on CAN: $(journalctl -u navd-hil-player -o cat | grep dvl)"
sed 's|^\(  *path:\) .*checkpoints$|\1 /var/lib/navd/checkpoints|' "$HIL_DIR/navd-hil.yaml" \
  > /etc/navd/navd-can.yaml
add_dropin can <<EOT
[Service]
ExecStart=
ExecStart=/usr/bin/navd --config /etc/navd/navd-can.yaml
EOT
url=$(sed -n 's/^ *url: *//p' /etc/navd/navd-can.yaml | tr -d '"')
log=/run/navd-vm-can.lcmlog
lcm-logger --lcm-url="$url" --quiet "$log" & logger=$!
systemctl start navd.service || fail "systemctl start navd: $(navd_journal | tail -5)"
wait_for 120 test -s "$HIL_DIR/play.json" || fail "the dive did not finish playing in 120 s"
sleep 2.5  # one more NAVD_HEALTH (1 Hz) after the last frame
kill -INT "$logger"; wait "$logger"
systemctl stop navd.service
health=$(navd_vm_tool health "$log") || fail "no NAVD_HEALTH in $log"
dvl=$(echo "$health" | grep '^dvl ')
note "navd health: $dvl"
field() { echo "$2" | tr ' ' '\n' | sed -n "s/^$1=//p"; }
# The player's report: the dvl sensor's object (flat, no nested braces) of its "sensors" list.
play=$(grep -o '{[^{}]*"name":"dvl"[^{}]*}' "$HIL_DIR/play.json")
json_field() { echo "$play" | sed -n "s/.*\"$1\":\([0-9]*\).*/\1/p"; }
sent=$(json_field messages); sent_bytes=$(json_field bytes); dropped=$(json_field dropped_frames)
[ -n "$sent" ] || fail "cannot read the player's report $HIL_DIR/play.json"
velocity_frames=$(sed -n 's/.*"dvl_velocity_frames":\([0-9]*\).*/\1/p' "$NAVD_VM_DIR/can-dive/frames.json")
note "player: $sent frames, $sent_bytes data bytes, $dropped dropped; dive: $velocity_frames dvl_velocity frames"
[ "$dropped" = 0 ] || fail "the player could not send $dropped frames"
[ "$(field records "$dvl")" = "$sent" ] || fail "navd decoded $(field records "$dvl") frames, $sent sent"
[ "$(field bytes "$dvl")" = "$sent_bytes" ] || fail "navd read $(field bytes "$dvl") bytes, $sent_bytes sent"
[ "$(field decode_errors "$dvl")" = 0 ] || fail "navd counted decode errors on CAN"
[ "$(field measurements "$dvl")" = "$velocity_frames" ] ||
  fail "navd made $(field measurements "$dvl") DVL measurements from $velocity_frames dvl_velocity frames"
[ "$(field updates "$dvl")" -gt 0 ] || fail "the filter fused no CAN DVL measurement"
