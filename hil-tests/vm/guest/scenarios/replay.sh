#!/bin/bash
# `navtool replay` inside the guest of the short simulated dive the host made
# (install-navd.sh: /usr/lib/navd-vm/replay-dive). Passes when the replay exits 0 with no
# error, replays every image of the dive and keeps delayed states. Its output files stay in
# /var/lib/navd-vm/replay-out: run-vm.sh reads them from the disk after the VM stopped and
# compares them with the host's replay of the same dive (compare-replay.sh), which is how an
# arm64 guest's arithmetic is checked against amd64's.
. /usr/lib/navd-vm/lib.sh
dive=$NAVD_VM_DIR/replay-dive
out=/var/lib/navd-vm/replay-out
summary=$out/summary.json
rm -rf "$out"; mkdir -p "$(dirname "$out")"
t0=$(now_s)
navtool replay "$dive" --as-fast-as-possible --out "$out" > /run/navd-vm-replay.log 2>&1 ||
  fail "navtool replay $dive exited $?: $(tail -5 /run/navd-vm-replay.log)"
note "navtool replay of $dive in $(elapsed_s "$t0") s"
field() { grep -o "\"$1\":[^,}]*" "$summary" | head -1 | cut -d: -f2; }
[ "$(field error)" = '""' ] || fail "the replay reports an error: $(field error)"
images=$(( $(wc -l < "$dive/images.csv") - 1 ))
[ "$(field images)" = "$images" ] || fail "replayed $(field images) images, the dive has $images"
[ "$(field delayed_states)" -gt 0 ] || fail "no delayed state after the replay"
note "images $(field images), delayed states $(field delayed_states), links accepted $(field links_accepted), published NEES mean $(field published_nees_mean)"
for f in trajectory.csv published.csv states.csv dead_reckoning.csv; do
  [ -s "$out/$f" ] || fail "the replay wrote no $out/$f"
done
