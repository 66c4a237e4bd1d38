#!/bin/bash
# `systemctl stop navd` (SIGTERM) ends navd within 2 s, exit status 0, and navd writes its
# final checkpoint on the way out (checkpoint.path, /var/lib/navd/checkpoints). The periodic
# checkpoints are set to once an hour here, so the only checkpoint is the one written at stop.
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
stop_s=$(elapsed_s "$t0")
note "systemctl stop navd took $stop_s s"
less_than "$stop_s" 2.0 || fail "stop took $stop_s s (limit 2 s)"
[ "$(navd_prop ExecMainStatus)" = 0 ] || fail "navd exited with $(navd_prop ExecMainStatus)"
[ "$(navd_prop Result)" = success ] || fail "service result $(navd_prop Result)"
final=$(checkpoints)
[ "$(echo "$final" | grep -c .)" = 1 ] || fail "expected one checkpoint written at stop, found: '$final'"
note "final checkpoint $final ($(stat -c %s "$CKPT_DIR/$final") bytes)"
rm -f /etc/navd/navd-stop.yaml
