#!/bin/bash
# `systemctl stop navd` (SIGTERM) ends navd within 2 s (journal times, below), exit status 0,
# and navd writes its final checkpoint on the way out (checkpoint.path,
# /var/lib/navd/checkpoints). The periodic checkpoints are set to once an hour here, so the
# only checkpoint is the one written at stop.
. /usr/lib/navd-vm/lib.sh
sed 's|^\(  *period_s:\) .*|\1 3600|' /etc/navd/navd.yaml > /etc/navd/navd-stop.yaml
add_dropin stop <<EOT
[Service]
ExecStart=
ExecStart=/usr/bin/navd --config /etc/navd/navd-stop.yaml --checkpoints
EOT
start_player --hold
systemctl start navd.service || fail "systemctl start navd: $(navd_journal | tail -5)"
sleep 4
checkpoints() { find "$CKPT_DIR" -name '*.ckpt' -printf '%f\n' | sort; }
[ -z "$(checkpoints)" ] || fail "checkpoints before the stop: $(checkpoints)"
t0=$(now_s)
systemctl stop navd.service
wall_s=$(elapsed_s "$t0")
# The journal's times (CLOCK_MONOTONIC): from the earlier of systemd's "Stopping" and navd's
# "signal 15" line to systemd's "Stopped" (navd gone). The systemctl client itself takes
# seconds to start under emulation, so its wall time is only reported.
mono() {
  journalctl -u navd.service -o short-monotonic --no-pager --after-cursor="$SCENARIO_CURSOR" |
    grep "$1" | tail -1 | sed 's/^\[ *\([0-9.]*\)\].*/\1/'
}
stopping=$(mono "Stopping navd.service"); signalled=$(mono "navd: signal 15")
stopped=$(mono "Stopped navd.service")
[ -n "$stopping" ] && [ -n "$signalled" ] && [ -n "$stopped" ] ||
  fail "no Stopping / signal 15 / Stopped lines for navd in the journal"
stop_s=$(awk -v a="$stopping" -v s="$signalled" -v b="$stopped" \
  'BEGIN{if (s < a) a = s; printf "%.3f", b - a}')
note "navd stopped in $stop_s s (journal; systemctl stop returned after $wall_s s)"
less_than "$stop_s" 2.0 || fail "stop took $stop_s s (limit 2 s)"
[ "$(navd_prop ExecMainStatus)" = 0 ] || fail "navd exited with $(navd_prop ExecMainStatus)"
[ "$(navd_prop Result)" = success ] || fail "service result $(navd_prop Result)"
final=$(checkpoints)
[ "$(echo "$final" | grep -c .)" = 1 ] || fail "expected one checkpoint written at stop, found: '$final'"
note "final checkpoint $final ($(stat -c %s "$CKPT_DIR/$final") bytes)"
rm -f /etc/navd/navd-stop.yaml
