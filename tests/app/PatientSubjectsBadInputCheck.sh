#!/bin/sh
# Subjects given to some tests only (docs/measured-data.md#several-subjects): in a manifest,
# bagsim diagnose exits 2 at the test's line and key and writes nothing; with synth-measurement's
# --test NAME@SUBJECT, a test without a subject or a single subject is a usage error (exit 2)
# before any co-simulation.
#   PatientSubjectsBadInputCheck.sh BAGSIM DIR SCENARIO
set -u
bagsim=$1 dir=$2 scenario=$3
rm -rf "$dir" "$dir-diagnosis" "$dir-s" "$dir-s.label"
mkdir -p "$dir"
printf 'time_s,pelvis_tilt_deg\n0,0\n0.1,1\n' > "$dir/tilt.csv"
cat > "$dir/measured.yaml" <<YAML
format: bagsim-measured-data 1
scenario: $scenario
protocol: {kind: patient-on-array}
tests:
  - name: a
    subject: small-woman
    channels: {tilt: tilt.csv}
  - name: b
    channels: {tilt: tilt.csv}
YAML
"$bagsim" diagnose --measured "$dir" 2> "$dir.err"
rc=$?
cat "$dir.err"
test $rc -eq 2 || { echo "exit $rc, not 2"; exit 1; }
grep -q "measured.yaml:8: key 'tests\[1\].subject': the test \"b\" names no subject, the test \"a\" (line 6) names \"small-woman\"; valid: a subject for every test" "$dir.err" ||
    { echo "not the located error"; exit 1; }
test ! -e "$dir-diagnosis" || { echo "the diagnosis wrote output"; exit 1; }
"$bagsim" synth-measurement --scenario "$scenario" --effect none --test 'a@x:array.gas_mass=4g' \
    --test 'b:array.gas_mass=5g' --out "$dir-s" --label-out "$dir-s.label" 2> "$dir.err2"
rc=$?
cat "$dir.err2"
test $rc -eq 2 && grep -q "names no subject" "$dir.err2" || { echo "a test without a subject was taken"; exit 1; }
"$bagsim" synth-measurement --scenario "$scenario" --effect none --test 'a@x:array.gas_mass=4g' \
    --test 'b@x:array.gas_mass=5g' --out "$dir-s" --label-out "$dir-s.label" 2> "$dir.err3"
rc=$?
cat "$dir.err3"
test $rc -eq 2 && grep -q "valid: at least two subjects" "$dir.err3" || { echo "one subject was taken"; exit 1; }
"$bagsim" synth-measurement --scenario "$scenario" --effect none --test 'a@x y:array.gas_mass=4g' \
    --out "$dir-s" --label-out "$dir-s.label" 2> "$dir.err4"
rc=$?
cat "$dir.err4"
test $rc -eq 2 && grep -q "is not a subject's name" "$dir.err4" || { echo "a bad subject's name was taken"; exit 1; }
test ! -e "$dir-s.label" || { echo "a label was written"; exit 1; }
echo "patient subjects bad input check: ok"
