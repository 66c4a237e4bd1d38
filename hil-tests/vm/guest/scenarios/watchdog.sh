#!/bin/bash
# A stuck navd (SIGSTOP) stops sending WATCHDOG=1; systemd kills it after WatchdogSec=5s and
# restarts it (Restart=on-failure, RestartSec=2s); the new navd resumes from the newest
# checkpoint the stopped navd wrote, with every measurement and every delayed state it held.
# The camera dive plays with its camera (the player's fake GigE camera on lo, 160 x 128 px
# frames: install-navd.sh), so navd keeps delayed states. Counts (navd_vm_tool): N_stop = the
# stopped navd's last NAVD_SOLUTION, N_ckpt = the newest checkpoint, N_resume = the new navd's
# first NAVD_SOLUTION; passes when N_stop = N_ckpt > 0 and N_ckpt <= N_resume <= N_ckpt + the
# frames the camera can have served between the SIGSTOP and that first NAVD_SOLUTION. SIGSTOP
# comes right after a fresh checkpoint; when an image was fused between that checkpoint and the
# SIGSTOP (N_stop != N_ckpt: the periodic checkpoint's loss window, not the restart's), navd is
# continued and stopped again after the next checkpoint (3 tries).
. /usr/lib/navd-vm/lib.sh
DIVE=$NAVD_VM_DIR/camera-dive WITH_CAMERA=1 start_player --hold
# The player's config (with the camera) on the image's checkpoint directory, every 2 s; camera
# frames into navd's RuntimeDirectory (ProtectSystem=strict leaves /run/navd-hil read-only).
config=/etc/navd/navd-camera.yaml
sed -e 's|^\(  *path:\) .*checkpoints$|\1 /var/lib/navd/checkpoints|' \
    -e 's|^\(  *period_s:\) .*|\1 2|' -e 's|^\(  *image_dir:\) .*|\1 /run/navd/images|' \
    "$HIL_DIR/navd-hil.yaml" > "$config"
grep -q "type: camera_gige" "$config" || fail "the player's config has no camera"
add_dropin camera <<EOT
[Service]
ExecStart=
ExecStart=/usr/bin/navd --config $config --checkpoints
EOT
url=$(sed -n 's/^ *url: *//p' "$config" | tr -d '"')
log=/run/navd-vm-watchdog.lcmlog
lcm-logger --lcm-url="$url" --quiet --flush-interval=50 "$log" & logger=$!
trap 'kill -INT $logger 2>/dev/null' EXIT
systemctl start navd.service || fail "systemctl start navd: $(navd_journal | tail -5)"
pid=$(navd_pid)
newest_ckpt() { find "$CKPT_DIR" -name '*.ckpt' -printf '%f\n' | sort | tail -1; }
field() { echo "$2" | tr ' ' '\n' | sed -n "s/^$1=//p"; }
ckpt_has_states() {
  local c; c=$(navd_vm_tool checkpoint "$config" "$CKPT_DIR" 2> /dev/null) &&
    [ "$(field delayed_states "$c")" -gt 0 ]
}
# Decoding a checkpoint costs the emulated CPU ~0.5 s: polled every 3 s, not wait_for's 0.2 s
# (the camera's GigE heartbeat needs the CPU).
polls=0
until ckpt_has_states; do
  polls=$((polls + 1))
  [ "$polls" -lt 40 ] || fail "no checkpoint with a delayed state in 40 polls (~2 min): $(navd_journal | tail -5)"
  sleep 3
done
for try in 1 2 3; do
  seen=$(newest_ckpt)
  new_ckpt() { [ "$(newest_ckpt)" != "$seen" ]; }
  wait_for 20 new_ckpt ||
    fail "no new checkpoint 20 s after $seen"
  kill -STOP "$pid"
  t_stop_us=$(date +%s%6N)
  sleep 0.5  # lcm-logger flushes every 50 ms
  n_stop=$(navd_vm_tool solutions "$log" | awk -v t="$t_stop_us" '$1 < t {n = $3} END {print n}')
  newest=$(newest_ckpt)
  ckpt=$(navd_vm_tool checkpoint "$config" "$CKPT_DIR") || fail "the newest checkpoint $newest does not decode"
  n_ckpt=$(field delayed_states "$ckpt")
  note "try $try: navd pid $pid stopped (SIGSTOP); its last NAVD_SOLUTION has $n_stop delayed states, newest checkpoint $newest $n_ckpt"
  [ "$n_stop" = "$n_ckpt" ] && break
  [ "$try" = 3 ] && fail "3 tries: the stopped navd's delayed states ($n_stop) never matched its newest checkpoint's ($n_ckpt)"
  kill -CONT "$pid"
done
[ "$n_ckpt" -gt 0 ] || fail "the checkpoint holds no delayed state"
t0=$(now_s)
restarted() { [ "$(navd_prop NRestarts)" -ge 1 ] && [ "$(navd_prop ActiveState)" = active ] &&
              [ "$(navd_pid)" != "$pid" ] && [ "$(navd_pid)" != 0 ]; }
wait_for 30 restarted || fail "navd not restarted 30 s after SIGSTOP (NRestarts \
$(navd_prop NRestarts), state $(navd_prop ActiveState)): $(navd_journal | tail -5)"
note "restarted as pid $(navd_pid) $(elapsed_s "$t0") s after SIGSTOP"
# The killed navd's TIOCEXCL stays on the player's ptys (their masters stay open), unlike on a
# real serial port, whose last close ends it: cleared here, or the new navd's open()s get EBUSY
# (navd_vm_tool tty-release); navd retries within its 5 s reconnect back-off.
navd_vm_tool tty-release $(find "$HIL_DIR" -maxdepth 1 -type l -lname '/dev/pts/*') ||
  fail "cannot clear the exclusive mode of the player's ptys"
journalctl -u navd.service --no-pager --after-cursor="$SCENARIO_CURSOR" | grep -q "Watchdog timeout" ||
  fail "the journal has no watchdog timeout for navd"
resumed=$(navd_journal | grep "navd: resumed from" | tail -1)
[ -n "$resumed" ] || fail "the restarted navd did not resume from a checkpoint: $(navd_journal | tail -5)"
note "$resumed"
echo "$resumed" | grep -q "$CKPT_DIR/$newest" ||
  fail "resumed from another checkpoint than the newest one the stopped navd wrote ($newest)"
applied=$(echo "$resumed" | sed -n 's/.*(\([0-9]*\) measurements applied).*/\1/p')
[ "${applied:-0}" = "$(field applied "$ckpt")" ] ||
  fail "the resumed navd applied ${applied:-?} measurements, the checkpoint holds $(field applied "$ckpt")"
# The stopped navd publishes nothing: every NAVD_SOLUTION after the SIGSTOP is the new navd's.
first_new() { navd_vm_tool solutions "$log" 2> /dev/null | awk -v t="$t_stop_us" '$1 > t {print $1, $3; exit}'; }
has_new() { [ -n "$(first_new)" ]; }
wait_for 30 has_new ||
  fail "the restarted navd published no NAVD_SOLUTION in 30 s"
read -r t_resume_us n_resume <<< "$(first_new)"
# The restarted navd may fuse frames that arrive before its first NAVD_SOLUTION: at most one per
# image interval of the dive (images.csv) since the SIGSTOP, plus one. Fewer states than the
# checkpoint's is a lost map.
interval_us=$(awk -F, 'NR > 2 && (m == "" || $2 - p < m) {m = $2 - p} NR > 1 {p = $2} END {print m}' \
  "$NAVD_VM_DIR/camera-dive/images.csv")
[ "${interval_us:-0}" -gt 0 ] || fail "no image interval in $NAVD_VM_DIR/camera-dive/images.csv"
new_max=$(( (t_resume_us - t_stop_us) / interval_us + 1 ))
note "delayed states: stopped navd $n_stop, checkpoint $n_ckpt, restarted navd's first NAVD_SOLUTION $n_resume" \
  "($(( (t_resume_us - t_stop_us) / 1000 )) ms after the SIGSTOP: at most $new_max new frames)"
[ "$n_resume" -ge "$n_ckpt" ] ||
  fail "the restarted navd has $n_resume delayed states, fewer than its checkpoint's $n_ckpt"
[ "$n_resume" -le $((n_ckpt + new_max)) ] ||
  fail "the restarted navd has $n_resume delayed states: more than its checkpoint's $n_ckpt plus" \
    "the $new_max frames the camera can have served since the SIGSTOP"
