#!/usr/bin/env bash
# Compares two `navtool replay --out` directories of the same dive made on different machines
# (run-vm.sh: the guest's replay against the host's; docs/platform.md "Cross builds and
# emulation" did the same by hand for qemu-user):
#   compare-replay.sh REFERENCE_DIR OTHER_DIR TOLERANCE_M [STATES_TOLERANCE_M]
# For trajectory.csv (delayed-state filter at each image), published.csv (the 10 Hz solution),
# dead_reckoning.csv (the twin) and states.csv (the delayed states): the same number of rows
# and the same time stamps (t_us), and the largest Euclidean difference of (x_m, y_m, z_m)
# between matching rows (columns found by name). Prints one line per file; exit 0 when every
# file matches and every difference is <= its tolerance, 1 otherwise (with the reason).
# The same binary rounds differently on a CPU without the host's AVX2 / FMA (a TCG guest):
# glibc's libm picks its FMA variants by CPU, and the state recovery's packed kernel is cloned
# per instruction set (core/src/recovery/packed_pcg.cpp). states.csv has its own tolerance
# (default TOLERANCE_M) because its means are the recovery's iterate after
# filter.cg_iterations_per_step PCG iterations, not converged, which such differences move more.
set -euo pipefail
ref=$1; other=$2; tol_default_m=$3; tol_states_m=${4:-$3}
status=0
for f in trajectory.csv published.csv dead_reckoning.csv states.csv; do
  tol_m=$tol_default_m
  [ "$f" = states.csv ] && tol_m=$tol_states_m
  for d in "$ref" "$other"; do
    [ -s "$d/$f" ] || { echo "compare-replay.sh: $d/$f is missing or empty" >&2; exit 1; }
  done
  # Both files' header rows name the columns (the same layout: one navtool version's output).
  if ! line=$(awk -F, -v tol="$tol_m" -v name="$f" '
      FNR == 1 {
        for (i = 1; i <= NF; ++i) col[$i] = i
        if (!("t_us" in col) || !("x_m" in col) || !("y_m" in col) || !("z_m" in col)) {
          print name ": no t_us, x_m, y_m, z_m columns"; bad = 1; exit 1 }
        next }
      NR == FNR {
        t[FNR] = $col["t_us"]; x[FNR] = $col["x_m"]; y[FNR] = $col["y_m"]; z[FNR] = $col["z_m"]
        n = FNR; next }
      {
        if (!(FNR in t) || t[FNR] != $col["t_us"]) {
          print name ": row " FNR " t_us " $col["t_us"] " has no match"; bad = 1; exit 1 }
        dx = $col["x_m"] - x[FNR]; dy = $col["y_m"] - y[FNR]; dz = $col["z_m"] - z[FNR]
        d = sqrt(dx * dx + dy * dy + dz * dz)
        if (d > max) { max = d; at = $col["t_us"] }
        m = FNR }
      END {
        if (bad) exit 1
        if (m != n) { print name ": " n - 1 " rows against " m - 1; exit 1 }
        printf "%s: %d rows, max position difference %.3g m (t_us %s), tolerance %g m\n",
               name, n - 1, max, at, tol
        exit !(max <= tol) }' "$ref/$f" "$other/$f"); then
    status=1
  fi
  echo "$line"
done
exit $status
