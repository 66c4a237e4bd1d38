#!/bin/bash
# A configuration error stops start-up: `systemctl start navd` fails, navd exits with status 2
# and is not restarted (RestartPreventExitStatus=2), and `journalctl -u navd` names the file,
# the key path and the reason.
. /usr/lib/navd-vm/lib.sh
bad=/etc/navd/navd-bad.yaml
sed 's/gating_chi2_threshold: .*/gating_chi2_threshold: -3.0/' /etc/navd/navd.yaml > "$bad"
grep -q "gating_chi2_threshold: -3.0" "$bad" || fail "could not make the bad config"
add_dropin bad-config <<EOT
[Service]
ExecStart=
ExecStart=/usr/bin/navd --config $bad --checkpoints
EOT
if systemctl start navd.service; then fail "navd started with $bad"; fi
sleep 3  # longer than RestartSec=2s: a restart would show in NRestarts
[ "$(navd_prop ExecMainStatus)" = 2 ] || fail "navd exited with $(navd_prop ExecMainStatus), not 2"
[ "$(navd_prop NRestarts)" = 0 ] || fail "navd was restarted $(navd_prop NRestarts) times"
line=$(navd_journal | grep "configuration" | head -1)
note "journal: $line"
echo "$line" | grep -q "$bad" || fail "the journal line does not name $bad"
echo "$line" | grep -q "filter.gating_chi2_threshold" || fail "the journal line does not name the key path"
rm -f "$bad"
