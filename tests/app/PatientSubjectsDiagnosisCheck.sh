#!/bin/sh
# Leave one subject out on a patient's data (docs/diagnosis.md#several-subjects-leave-one-subject-out):
# two subjects of different builds (a 1.55 m, 50 kg woman and a 1.90 m, 110 kg man) on the coarse
# supine scenario (its settle cut to 0.2 s), one test each, the bags' sensors' lag and offset put
# in both; bagsim diagnose must fold over the subjects (each held out in turn, named, with its
# test), run each test's model with its subject's build, and bring the lag and offset back in
# each fold from the other subject alone.
#   PatientSubjectsDiagnosisCheck.sh BAGSIM DIR SCENARIO
set -u
bagsim=$1 dir=$2 scenario=$3
rm -rf "$dir" "$dir.label" "$dir.label.truth-run" "$dir-diagnosis" "$dir.yaml"
sed 's/^  settle_time: 0.4 s /  settle_time: 0.2 s /' "$scenario" > "$dir.yaml"
grep -q '^  settle_time: 0.2 s ' "$dir.yaml" || { echo "the scenario's settle time was not cut"; exit 1; }
"$bagsim" synth-measurement --scenario "$dir.yaml" --effect bag-pressure-sensor --param lag=0.1s \
    --param offset=0.3kPa \
    --test woman@small-woman:patient.sex=female,patient.height=1.55m,patient.mass=50kg \
    --test man@tall-man:patient.height=1.90m,patient.mass=110kg \
    --out "$dir" --label-out "$dir.label" --quiet || exit 1
if grep -rqi 'bag-pressure-sensor\|lag' "$dir"; then echo "the data name the effect"; exit 1; fi
grep -q '^    subject: tall-man$' "$dir/measured.yaml" || { echo "the manifest names no subject"; exit 1; }
grep -q '^subjects: \[small-woman, tall-man\]$' "$dir.label" || { echo "the label lists no subjects"; exit 1; }
"$bagsim" diagnose --measured "$dir" > "$dir.out"
rc=$?
grep -v "^    bag-pressure subject" "$dir.out"
test $rc -eq 0 || exit 1
grep -q "^verdict: bag-pressure-sensor" "$dir.out" || { echo "verdict is not bag-pressure-sensor"; exit 1; }
grep -q "leave one subject out of 2" "$dir.out" || { echo "the folds are not the subjects"; exit 1; }
python3 - "$dir-diagnosis" <<'PY' || exit 1
import csv, json, sys
out = sys.argv[1]
d = json.load(open(out + "/diagnosis.json"))
assert d["fold_kind"] == "subject", d["fold_kind"]
assert d["subjects"] == ["small-woman", "tall-man"], d["subjects"]
assert d["tests"] == ["woman", "man"] and d["test_subjects"] == ["small-woman", "tall-man"], d
assert d["simulations"] == 4, d["simulations"]  # each test's model and half macro step
regimes = {r["regime"] for r in d["where"]["regimes"]}
assert "subject small-woman" in regimes and "subject tall-man" in regimes, regimes
c = d["candidates"][0]
assert d["verdict"] == "bag-pressure-sensor" and c["effect"] == "bag-pressure-sensor"
assert [f["held_out_subject"] for f in c["folds"]] == ["small-woman", "tall-man"], c["folds"]
assert [f["held_out_tests"] for f in c["folds"]] == [["woman"], ["man"]], c["folds"]
for f in c["folds"]:  # each fold fitted on the other subject alone
    assert abs(f["parameters"]["lag"]["value"] - 0.1) < 0.03, f
    assert abs(f["parameters"]["offset"]["value"] - 0.3) < 0.03, f
    assert f["excess_after"] < 0.5 * f["excess_before"], f
m = c["heldout_metrics"]["bag-pressure"]
assert m["after"]["rmse"] < 0.5 * m["before"]["rmse"], m
PY
# Each test's runs carry its subject's weight (50 kg and 110 kg times 9.80665 m/s^2).
for run in model half-macro-step; do
    grep -q "of his 490.33 N" "$dir-diagnosis/runs/woman/$run/summary.txt" || { echo "woman/$run is not her build"; exit 1; }
    grep -q "of his 1078.73 N" "$dir-diagnosis/runs/man/$run/summary.txt" || { echo "man/$run is not his build"; exit 1; }
done
head -1 "$dir-diagnosis/residuals.csv" | grep -qx 'subject,test,channel,unit,part,time_s,sensel_row,sensel_column,measured,simulated,residual' || exit 1
grep -q "<h2>Verdict: bag-pressure-sensor</h2>" "$dir-diagnosis/report.html" || exit 1
grep -q "leave one subject out" "$dir-diagnosis/report.html" || exit 1
grep -q "<h3>subject tall-man</h3>" "$dir-diagnosis/report.html" || exit 1
echo "patient leave-one-subject-out check: ok"
