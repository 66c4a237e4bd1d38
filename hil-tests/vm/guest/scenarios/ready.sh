#!/bin/bash
# `systemctl start navd` returns once navd sent READY=1 (Type=notify: sensors open, filter
# initialised) and navd then publishes NAVD_SOLUTION and NAVD_HEALTH on LCM (lcm.url of
# /etc/navd/navd.yaml, udpm on lo), at 10 Hz and 1 Hz, and can receive there.
. /usr/lib/navd-vm/lib.sh
start_player --hold
t0=$(now_s)
systemctl start navd.service || fail "systemctl start navd: $(navd_journal | tail -5)"
note "systemctl start navd returned after $(elapsed_s "$t0") s"
[ "$(navd_prop ActiveState)" = active ] || fail "navd is $(navd_prop ActiveState), not active"
[ "$(navd_prop StatusText)" != "" ] || fail "navd sent no STATUS= line"
note "status: $(navd_prop StatusText)"
log=/run/navd-vm-lcm.log
url=$(sed -n 's/^ *url: *//p' /etc/navd/navd.yaml | tr -d '"')
timeout -s INT 10 lcm-logger --lcm-url="$url" --quiet "$log" || true
solutions=$(grep -a -o NAVD_SOLUTION "$log" | wc -l)
health=$(grep -a -o NAVD_HEALTH "$log" | wc -l)
note "LCM in 10 s: $solutions NAVD_SOLUTION, $health NAVD_HEALTH"
# 10 Hz and 1 Hz over 10 s, with margin for the logger's own start-up under emulation (2-3 s
# measured at load 6).
[ "$solutions" -ge 40 ] || fail "only $solutions NAVD_SOLUTION messages in 10 s (10 Hz expected)"
[ "$health" -ge 4 ] || fail "only $health NAVD_HEALTH messages in 10 s (1 Hz expected)"
# navd also receives (NAV_REGISTRATION from the vision stage): its LCM set up its receive side.
if navd_journal | grep -q "LCM cannot receive"; then
  fail "navd cannot receive on LCM: $(navd_journal | grep "LCM cannot receive")"
fi
