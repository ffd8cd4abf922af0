#!/bin/sh
# The withheld-effect check on a patient (docs/diagnosis.md#a-patient-on-the-array):
# synthetic data of the short coarse supine scenario with an effect put in, then
# bagsim diagnose on them with the instrument candidates; the verdict, the parameters, the
# units and the output files are checked.
#   PatientDiagnosisCheck.sh BAGSIM DIR SCENARIO sensor|none
set -u
bagsim=$1 dir=$2 scenario=$3 case=$4
rm -rf "$dir" "$dir.label" "$dir.label.truth-run" "$dir-diagnosis"
if [ "$case" = sensor ]; then
    effect="--effect bag-pressure-sensor --param lag=0.1s --param offset=0.3kPa"
    expect=bag-pressure-sensor
else
    effect="--effect none"
    expect=none
fi
"$bagsim" synth-measurement --scenario "$scenario" $effect --out "$dir" --label-out "$dir.label" --quiet || exit 1
# The data name neither the effect nor its parameters; the label does.
if grep -rqi 'bag-pressure-sensor\|lag' "$dir"; then echo "the data name the effect"; exit 1; fi
grep -q "^effect: " "$dir.label" || exit 1
"$bagsim" diagnose --measured "$dir" > "$dir.out"
rc=$?
cat "$dir.out"
test $rc -eq 0 || exit 1
grep -q "^verdict: $expect" "$dir.out" || { echo "verdict is not $expect"; exit 1; }
python3 - "$dir-diagnosis/diagnosis.json" "$case" <<'PY' || exit 1
import json, sys
d = json.load(open(sys.argv[1]))
assert d["kind"] == "patient-on-array"
assert [c["channel"] for c in d["where"]["channels"]] == ["mat", "pelvis-tilt", "thorax-tilt", "bag-pressure"]
assert [c["unit"] for c in d["where"]["channels"]] == ["mmHg", "deg", "deg", "kPa"]
regimes = {r["regime"] for r in d["where"]["regimes"] if r["channel"] == "mat"}
assert "sacrum" in regimes or "heel_r" in regimes, regimes  # the mat split by body region
assert any(r.startswith("time ") for r in regimes)
assert len(d["time_windows_s"]) == 4
c = d["candidates"][0]
if sys.argv[2] == "sensor":
    assert d["verdict"] == "bag-pressure-sensor" and c["effect"] == "bag-pressure-sensor"
    assert abs(c["parameters"]["lag"]["value"] - 0.1) < 0.03, c["parameters"]
    assert abs(c["parameters"]["offset"]["value"] - 0.3) < 0.03, c["parameters"]
    m = c["heldout_metrics"]["bag-pressure"]
    assert m["after"]["rmse"] < 0.5 * m["before"]["rmse"], m
    assert len(c["folds"]) == 3 and "held_out_window" in c["folds"][0]
else:
    assert d["verdict"] == "none"
    assert all(k["score"] <= 0 for k in d["candidates"])
PY
head -1 "$dir-diagnosis/residuals.csv" | grep -qx 'channel,unit,part,time_s,sensel_row,sensel_column,measured,simulated,residual' || exit 1
grep -q "<h2>Verdict: $expect</h2>" "$dir-diagnosis/report.html" || exit 1
test -s "$dir-diagnosis/runs/model/results.h5" && test -s "$dir-diagnosis/runs/half-macro-step/results.h5" || exit 1
echo "patient diagnosis check ($case): ok"
