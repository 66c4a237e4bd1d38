#!/bin/bash
# The unit's hardening holds for navd: (1) the running navd has no capability at all and
# NoNewPrivs set; (2) a probe run under navd.service itself (same user and every sandbox
# directive; only ExecStart and Type are swapped by a drop-in) can write its state and log
# directories but no navd-owned directory elsewhere (ProtectSystem=strict, ProtectHome), and
# can open a serial port (DeviceAllow) but no navd-owned node of a block device or of a
# character device outside DeviceAllow (DevicePolicy=closed).
. /usr/lib/navd-vm/lib.sh
start_player --hold
systemctl start navd.service || fail "systemctl start navd: $(navd_journal | tail -5)"
pid=$(navd_pid)
for cap in CapEff CapPrm CapInh CapBnd CapAmb; do
  value=$(sed -n "s/^$cap:\t*//p" /proc/"$pid"/status)
  [ "$value" = 0000000000000000 ] || fail "navd (pid $pid) $cap is $value, not empty"
done
[ "$(sed -n 's/^NoNewPrivs:\t*//p' /proc/"$pid"/status)" = 1 ] || fail "navd has NoNewPrivs 0"
note "running navd (pid $pid, user $(ps -o user= -p "$pid")): no capability, NoNewPrivs 1"
systemctl stop navd.service navd-hil-player.service
# Targets the navd user may use by file permissions, so only the sandbox can refuse them:
# navd-owned directories outside StateDirectory/LogsDirectory, and navd-owned device nodes of
# a block device (the VM's disk) and a character device outside DeviceAllow (vcs, major 7).
denied_dirs="/etc/navd-probe /usr/local/navd-probe /var/navd-probe /srv/navd-probe /home/navd-probe"
for dir in $denied_dirs; do install -d -o navd -g navd -m 0750 "$dir"; done
mknod -m 0600 /dev/navd-probe-vda b "$((16#$(stat -c %t /dev/vda)))" "$((16#$(stat -c %T /dev/vda)))"
mknod -m 0600 /dev/navd-probe-vcs c 7 0
chown navd:navd /dev/navd-probe-vda /dev/navd-probe-vcs
cleanup() { rm -rf $denied_dirs /dev/navd-probe-vda /dev/navd-probe-vcs; }
trap cleanup EXIT
add_dropin probe <<EOT
[Service]
Type=oneshot
ExecStart=
ExecStart=/usr/lib/navd-vm/sandbox-probe /var/lib/navd/checkpoints /var/log/navd $denied_dirs \
  -- /dev/ttyS1 /dev/navd-probe-vda /dev/navd-probe-vcs
EOT
systemctl start navd.service || fail "the sandbox probe failed to run: $(navd_journal | tail -5)"
result=/var/log/navd/sandbox-probe.txt
[ -s "$result" ] || fail "the probe wrote no result"
expect() {
  grep -qx "$1" "$result" || fail "expected '$1', probe says '$(grep "^${1% *} " "$result")'"
  note "$1"
}
expect "write /var/lib/navd/checkpoints ok"
expect "write /var/log/navd ok"
for dir in $denied_dirs; do expect "write $dir denied"; done
expect "open /dev/ttyS1 ok"
for dev in /dev/navd-probe-vda /dev/navd-probe-vcs; do expect "open $dev denied"; done
expect "CapBnd 0000000000000000"
