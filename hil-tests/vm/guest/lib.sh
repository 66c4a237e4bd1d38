# Shell helpers for the scenarios run inside the navd test VM (sourced by run-scenarios and
# every scenarios/*.sh). The image layout (hil-tests/vm/README.md):
#   /usr/lib/navd-vm/dive        a simulated dive that `navtool hil-play` plays into ptys
#   /run/navd-hil                the ptys (links named after the sensors), owned by navd
#   /etc/navd/navd.yaml          navd's config, its serial devices are those links
# Each scenario prints what it checks and exits 0 (pass) or non-zero (fail, with the reason).
NAVD_VM_DIR=/usr/lib/navd-vm
HIL_DIR=/run/navd-hil
DROPIN_DIR=/run/systemd/system/navd.service.d
CKPT_DIR=/var/lib/navd/checkpoints

fail() { echo "FAIL: $*"; exit 1; }
note() { echo "  $*"; }
now_s() { date +%s.%N; }
elapsed_s() { awk -v a="$1" -v b="$(now_s)" 'BEGIN{printf "%.2f", b - a}'; }
# Floating comparison a < b.
less_than() { awk -v a="$1" -v b="$2" 'BEGIN{exit !(a < b)}'; }

# wait_for TIMEOUT_S COMMAND...: polls COMMAND every 0.2 s until it succeeds; 1 on timeout.
wait_for() {
  local deadline; deadline=$(awk -v t="$1" -v n="$(now_s)" 'BEGIN{printf "%.3f", n + t}'); shift
  until "$@"; do
    less_than "$(now_s)" "$deadline" || return 1
    sleep 0.2
  done
}

navd_prop() { systemctl show -p "$1" --value navd.service; }
navd_pid() { navd_prop MainPID; }

# The HIL player as the navd user (so the ptys it opens belong to navd) in a transient unit;
# its playback report (JSON) goes to $HIL_DIR/play.json when it ends. Plays $DIVE (default the
# dive above). Extra args: hil-play's. With WITH_CAMERA=1 it also serves the dive's camera
# (Aravis' fake GigE camera on lo, triggered at the image times); otherwise --no-camera.
start_player() {
  local camera=--no-camera
  [ -n "${WITH_CAMERA:-}" ] && camera=""
  mkdir -p "$HIL_DIR"; chown navd:navd "$HIL_DIR"; rm -f "$HIL_DIR/play.json"
  systemd-run --quiet --unit=navd-hil-player -p User=navd -p Group=navd \
    /bin/sh -c "/usr/bin/navtool hil-play ${DIVE:-$NAVD_VM_DIR/dive} $camera \
      --serial-dir $HIL_DIR --config-out $HIL_DIR/navd-hil.yaml --json $* \
      > $HIL_DIR/play.json.part && mv $HIL_DIR/play.json.part $HIL_DIR/play.json"
  wait_for 30 test -e "$HIL_DIR/navd-hil.yaml" || fail "the HIL player made no pty in 30 s: \
$(journalctl -u navd-hil-player --no-pager | tail -5)"
}

# A drop-in for navd.service under /run (gone at reboot), then daemon-reload. Drop-ins apply
# in file-name order across directories: "zz-" sorts after the image's hil.conf, so an
# ExecStart= here replaces that one.
add_dropin() {
  mkdir -p "$DROPIN_DIR"; cat > "$DROPIN_DIR/zz-$1.conf"; systemctl daemon-reload
}

# Puts the machine back to the state after boot: navd and the player stopped, no scenario
# drop-in, no checkpoint, a fresh journal cursor is taken by the caller.
reset_state() {
  systemctl stop navd.service navd-hil-player.service 2>/dev/null || true
  systemctl reset-failed navd.service navd-hil-player.service 2>/dev/null || true
  rm -rf "$DROPIN_DIR" "$HIL_DIR"
  systemctl daemon-reload
  rm -f "$CKPT_DIR"/* /var/log/navd/*.txt
}

# journalctl -u navd since this scenario started ($SCENARIO_CURSOR, set by run-scenarios).
navd_journal() { journalctl -u navd.service --no-pager -o cat --after-cursor="$SCENARIO_CURSOR"; }
