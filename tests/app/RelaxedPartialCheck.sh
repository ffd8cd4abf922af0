#!/bin/sh
# A patient run whose relaxed bags kept steps unrelaxed is partial, and says so everywhere
# (docs/solver.md#relaxed-stepping-the-equilibrium-found-by-the-film-in-time-for-the-patients-bags):
# the coarse supine scenario's first 50 ms, every step relaxed (Newton not tried) with 3
# sub-steps at the most and no Newton polish, so that some run out.
#   RelaxedPartialCheck.sh BAGSIM DIR SCENARIO
# Checks: exit 3; the INCOMPLETE marker kept with status partial; summary.txt counts the steps
# and their largest residual; verdict.csv's row 'bag films relaxed' fails with the count. The
# same run stopped at 25 ms and resumed exits 3 and writes the same verdict.csv (the checkpoint
# carries the tally).
set -u
bagsim=$1 dir=$2 scenario=$3
rm -rf "$dir" && mkdir -p "$dir" || exit 1
set -- --quiet --set bag.stepping=relaxed --set bag.dynamic.newton_first=false \
    --set bag.dynamic.relax_substeps=3 --set bag.dynamic.newton_polish=0 \
    --set bag.dynamic.quasi_static_fallback=false \
    --set run.settle_time=0.05s --set coupling.threads=2 \
    --set output.checkpoint_every=0.02s
fail() { echo "RelaxedPartialCheck: $*"; exit 1; }
"$bagsim" run "$scenario" --out "$dir/whole" "$@"
rc=$?
[ $rc -eq 3 ] || fail "the whole run exited $rc, expected 3 (partial)"
grep -q '^status: partial' "$dir/whole/INCOMPLETE" || fail "the marker does not say partial"
grep -Eq '^relaxed bags: [1-9][0-9]* bag steps were kept unrelaxed .*the largest residual [0-9.e+-]+ N [(]bag [0-9]+.*the run is partial' \
    "$dir/whole/summary.txt" || fail "summary.txt does not count the unrelaxed steps"
grep -Eq '^bag films relaxed,fail,[1-9]' "$dir/whole/verdict.csv" ||
    fail "verdict.csv has no failing 'bag films relaxed' row"
"$bagsim" run "$scenario" --out "$dir/resumed" "$@" --stop-after 0.025s
rc=$?
[ $rc -eq 130 ] || fail "the stopped run exited $rc, expected 130"
"$bagsim" run --resume "$dir/resumed" --quiet
rc=$?
[ $rc -eq 3 ] || fail "the resumed run exited $rc, expected 3 (partial)"
cmp "$dir/whole/verdict.csv" "$dir/resumed/verdict.csv" || fail "the resumed run's verdict differs"
echo "RelaxedPartialCheck: ok ($(grep '^bag films relaxed' "$dir/whole/verdict.csv" | cut -d, -f3) unrelaxed steps)"
