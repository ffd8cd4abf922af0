#!/bin/sh
# A patient run that kept steps short of what it asks for is partial, and says so everywhere:
#   PartialRunCheck.sh BAGSIM DIR SCENARIO relaxed|coupling
# relaxed: the coarse supine scenario's first 50 ms, every bag step relaxed (Newton not tried)
#   with 3 sub-steps at the most, no Newton polish and no quasi-static fallback, so that some
#   run out (docs/solver.md#relaxed-stepping-the-equilibrium-found-by-the-film-in-time-for-the-patients-bags);
# coupling: the same 50 ms with quasi-static bags and two implicit passes a step at the most,
#   the macro step 5 ms and the smallest 2.5 ms, so that the coupling keeps steps without its
#   fixed point (coupling.keep_unconverged, docs/cosim.md#the-schemes).
# Checks: exit 3; the INCOMPLETE marker kept with status partial; summary.txt counts the steps
# and their largest residual; verdict.csv's row ('bag films relaxed' or 'coupling converged')
# fails with the count. The same run stopped at 25 ms and resumed exits 3 and writes the same
# verdict.csv (the checkpoint carries the tally). For coupling, keep_unconverged: false stops
# the run (exit 1).
set -u
bagsim=$1 dir=$2 scenario=$3 kind=$4
rm -rf "$dir" && mkdir -p "$dir" || exit 1
case $kind in
relaxed)
    set -- --quiet --set bag.stepping=relaxed --set bag.dynamic.newton_first=false \
        --set bag.dynamic.relax_substeps=3 --set bag.dynamic.newton_polish=0 \
        --set bag.dynamic.quasi_static_fallback=false
    row='bag films relaxed'
    said='^relaxed bags: [1-9][0-9]* bag steps were kept unrelaxed .*the largest residual [0-9.e+-]+ N [(]bag [0-9]+.*the run is partial' ;;
coupling)
    set -- --quiet --set coupling.max_iterations=2 --set coupling.macro_step=5ms \
        --set coupling.min_macro_step=2.5ms
    row='coupling converged'
    said='^coupling: [1-9][0-9]* macro steps were kept without a fixed point .*the largest [|]H[(]x[)] - x[|] [0-9.e+-]+ N against [0-9.e+-]+ N at [0-9.]+ s.*the run is partial' ;;
*) echo "PartialRunCheck: unknown kind '$kind'; valid: relaxed, coupling"; exit 2 ;;
esac
set -- "$@" --set run.settle_time=0.05s --set coupling.threads=2 --set output.checkpoint_every=0.02s
fail() { echo "PartialRunCheck ($kind): $*"; exit 1; }
"$bagsim" run "$scenario" --out "$dir/whole" "$@"
rc=$?
[ $rc -eq 3 ] || fail "the whole run exited $rc, expected 3 (partial)"
grep -q '^status: partial' "$dir/whole/INCOMPLETE" || fail "the marker does not say partial"
grep -Eq "$said" "$dir/whole/summary.txt" || fail "summary.txt does not count the steps"
grep -Eq "^$row,fail,[1-9]" "$dir/whole/verdict.csv" || fail "verdict.csv has no failing '$row' row"
# The marker's reason (what a study's table shows) counts the same steps as verdict.csv.
n=$(grep "^$row" "$dir/whole/verdict.csv" | cut -d, -f3)
grep -Eq "(^|; )$n (bag steps were kept unrelaxed|macro steps were kept without a fixed point)" \
    "$dir/whole/INCOMPLETE" || fail "the marker does not count the $n steps: $(cat "$dir/whole/INCOMPLETE")"
"$bagsim" run "$scenario" --out "$dir/resumed" "$@" --stop-after 0.025s
rc=$?
[ $rc -eq 130 ] || fail "the stopped run exited $rc, expected 130"
"$bagsim" run --resume "$dir/resumed" --quiet
rc=$?
[ $rc -eq 3 ] || fail "the resumed run exited $rc, expected 3 (partial)"
cmp "$dir/whole/verdict.csv" "$dir/resumed/verdict.csv" || fail "the resumed run's verdict differs"
if [ "$kind" = coupling ]; then
    "$bagsim" run "$scenario" --out "$dir/stops" "$@" --set coupling.keep_unconverged=false
    rc=$?
    [ $rc -eq 1 ] || fail "with keep_unconverged false the run exited $rc, expected 1 (failed)"
    grep -q 'did not converge' "$dir/stops/INCOMPLETE" || fail "the failed run's marker does not say why"
fi
echo "PartialRunCheck ($kind): ok ($(grep "^$row" "$dir/whole/verdict.csv" | cut -d, -f3) steps)"
