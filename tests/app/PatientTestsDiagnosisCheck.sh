#!/bin/sh
# Leave one test out on a patient's data (docs/diagnosis.md#several-tests-leave-one-test-out):
# two tests of the coarse supine scenario at 4.0 g and 5.0 g (its settle cut to 0.2 s), the
# bags' sensors' lag and offset put in every test; bagsim diagnose must fold over the tests
# (each test held out in turn, named), run each test's model at its own gas mass, and name the
# sensor with its parameters.
#   PatientTestsDiagnosisCheck.sh BAGSIM DIR SCENARIO
set -u
bagsim=$1 dir=$2 scenario=$3
rm -rf "$dir" "$dir.label" "$dir.label.truth-run" "$dir-diagnosis" "$dir.yaml"
sed 's/^  settle_time: 0.4 s /  settle_time: 0.2 s /' "$scenario" > "$dir.yaml"
grep -q '^  settle_time: 0.2 s ' "$dir.yaml" || { echo "the scenario's settle time was not cut"; exit 1; }
"$bagsim" synth-measurement --scenario "$dir.yaml" --effect bag-pressure-sensor --param lag=0.1s \
    --param offset=0.3kPa --test gas-4.0g:array.gas_mass=4.0g --test gas-5.0g:array.gas_mass=5.0g \
    --out "$dir" --label-out "$dir.label" --quiet || exit 1
if grep -rqi 'bag-pressure-sensor\|lag' "$dir"; then echo "the data name the effect"; exit 1; fi
grep -q '^tests:' "$dir/measured.yaml" && grep -q 'array.gas_mass: 5.0g' "$dir/measured.yaml" || exit 1
"$bagsim" diagnose --measured "$dir" > "$dir.out"
rc=$?
grep -v "^    bag-pressure test" "$dir.out"
test $rc -eq 0 || exit 1
grep -q "^verdict: bag-pressure-sensor" "$dir.out" || { echo "verdict is not bag-pressure-sensor"; exit 1; }
grep -q "leave one test out of 2" "$dir.out" || { echo "the folds are not the tests"; exit 1; }
python3 - "$dir-diagnosis" <<'PY' || exit 1
import csv, json, sys
out = sys.argv[1]
d = json.load(open(out + "/diagnosis.json"))
assert d["fold_kind"] == "test", d["fold_kind"]
assert d["tests"] == ["gas-4.0g", "gas-5.0g"], d["tests"]
assert d["simulations"] == 4, d["simulations"]  # each test's model and half macro step
regimes = {r["regime"] for r in d["where"]["regimes"]}
assert "test gas-4.0g" in regimes and "test gas-5.0g" in regimes, regimes
c = d["candidates"][0]
assert d["verdict"] == "bag-pressure-sensor" and c["effect"] == "bag-pressure-sensor"
assert [f["held_out_test"] for f in c["folds"]] == ["gas-4.0g", "gas-5.0g"], c["folds"]
for f in c["folds"]:  # each fold fitted on the other test alone
    assert abs(f["parameters"]["lag"]["value"] - 0.1) < 0.03, f
    assert abs(f["parameters"]["offset"]["value"] - 0.3) < 0.03, f
    assert f["excess_after"] < 0.5 * f["excess_before"], f
m = c["heldout_metrics"]["bag-pressure"]
assert m["after"]["rmse"] < 0.5 * m["before"]["rmse"], m
# Each test's model ran at the test's gas mass.
for name, grams in (("gas-4.0g", 4.0), ("gas-5.0g", 5.0)):
    rows = list(csv.DictReader(open(out + "/runs/" + name + "/model/bags.csv")))
    assert abs(float(rows[0]["mass_g"]) - grams) < 1e-6, (name, rows[0])
    rows = list(csv.DictReader(open(out + "/runs/" + name + "/half-macro-step/bags.csv")))
    assert abs(float(rows[0]["mass_g"]) - grams) < 1e-6, (name, rows[0])
PY
head -1 "$dir-diagnosis/residuals.csv" | grep -qx 'test,channel,unit,part,time_s,sensel_row,sensel_column,measured,simulated,residual' || exit 1
grep -q "<h2>Verdict: bag-pressure-sensor</h2>" "$dir-diagnosis/report.html" || exit 1
grep -q "leave one test out" "$dir-diagnosis/report.html" || exit 1
echo "patient leave-one-test-out check: ok"
