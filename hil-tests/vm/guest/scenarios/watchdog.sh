#!/bin/bash
# A stuck navd (SIGSTOP) stops sending WATCHDOG=1; systemd kills it after WatchdogSec=5s and
# restarts it (Restart=on-failure, RestartSec=2s); the new navd resumes from the newest
# checkpoint the stopped navd wrote, with every measurement that checkpoint held.
. /usr/lib/navd-vm/lib.sh
start_player --hold
systemctl start navd.service || fail "systemctl start navd: $(navd_journal | tail -5)"
wait_for 20 sh -c "ls $CKPT_DIR | grep -q '\.ckpt$'" || fail "no periodic checkpoint in 20 s"
sleep 1
pid=$(navd_pid)
t0=$(now_s)
kill -STOP "$pid"
# A stopped navd writes nothing more: this is the checkpoint the restarted one must resume from.
newest=$(find "$CKPT_DIR" -name '*.ckpt' -printf '%f\n' | sort | tail -1)
note "navd pid $pid stopped (SIGSTOP); newest checkpoint $newest"
restarted() { [ "$(navd_prop NRestarts)" -ge 1 ] && [ "$(navd_prop ActiveState)" = active ] &&
              [ "$(navd_pid)" != "$pid" ] && [ "$(navd_pid)" != 0 ]; }
wait_for 30 restarted || fail "navd not restarted 30 s after SIGSTOP (NRestarts \
$(navd_prop NRestarts), state $(navd_prop ActiveState)): $(navd_journal | tail -5)"
note "restarted as pid $(navd_pid) $(elapsed_s "$t0") s after SIGSTOP"
journalctl -u navd.service --no-pager --after-cursor="$SCENARIO_CURSOR" | grep -q "Watchdog timeout" ||
  fail "the journal has no watchdog timeout for navd"
resumed=$(navd_journal | grep "navd: resumed from" | tail -1)
[ -n "$resumed" ] || fail "the restarted navd did not resume from a checkpoint: $(navd_journal | tail -5)"
note "$resumed"
echo "$resumed" | grep -q "$CKPT_DIR/$newest" ||
  fail "resumed from another checkpoint than the newest one the stopped navd wrote ($newest)"
applied=$(echo "$resumed" | sed -n 's/.*(\([0-9]*\) measurements applied).*/\1/p')
[ "${applied:-0}" -gt 0 ] || fail "the resumed checkpoint applied no measurement"
