#!/bin/sh
# The which part on a measured stiffness curve (docs/diagnosis.md#which-on-a-stiffness-curve),
# on the taut tiny rig at 4.0, 4.25 and 4.5 g, with curves made from the model's own:
# 1. any curve: the model's curve is compared, the which part runs (the candidates that act on
#    a curve ranked, the others listed not applicable); a second run finds every curve in the
#    cache (0 simulations);
# 2. the model's own stiffness: `none`;
# 3. the model's stiffness through a series compliance of 0.1 mm/N: machine-compliance (or its
#    twin bed-compliance) named, 0.1 mm/N back;
# 4. the model's dense curve re-read 0.1 g further on (the bag holds 0.1 g more than the
#    flowmeter reads): a gas-mass shift named, the flowmeter's offset back;
# 5. bad options: exit 2, nothing run.
#   StiffnessCurveDiagnosisCheck.sh BAGSIM DIR SCENARIO
set -u
bagsim=$1 dir=$2 scenario=$3
rm -rf "$dir" "$dir-diagnosis" "$dir-cache"
mkdir -p "$dir"
fail() { echo "$1"; exit 1; }
printf 'format: bagsim-measured-data 1\nscenario: %s\nprotocol: {block: 50 mm, rate: 10 mm/min, peak_force: 20 N, room_temperature: 23 degC}\nstiffness: k.csv\n' "$scenario" > "$dir/measured.yaml"
printf 'gas_mass_g,stiffness_N/mm,stage\n4.0,1.5,1\n4.25,2.5,1\n4.5,3.5,0\n' > "$dir/k.csv"
run() {  # run NAME: the diagnosis of $dir into $dir-diagnosis, the cache shared
    "$bagsim" diagnose --measured "$dir" --cache "$dir-cache" --threads 2 --force > "$dir.$1.out" 2> "$dir.$1.err"
    rc=$?
    cat "$dir.$1.out"
    test $rc -eq 0 || { cat "$dir.$1.err"; fail "$1: exit $rc"; }
}
json="$dir-diagnosis/diagnosis.json"

run any
python3 - "$json" <<'PY' || fail "any: diagnosis.json"
import json, sys
d = json.load(open(sys.argv[1]))
w = d["stiffness_which"]
assert d["where"] is None and d["verdict"] == w["verdict"], d["verdict"]
names = [c["effect"] for c in w["candidates"]]
assert sorted(names) == ["bag-volume", "bed-compliance", "flowmeter-bias", "gas-temperature", "machine-compliance"], names
na = [n["effect"] for n in w["not_applicable"]]
assert "pressure-sensor" in na and "viscoelasticity" in na and "film-stiffness" in na and len(na) == 8, na
assert w["gas_masses_g"] == [4, 4.25, 4.5]
c = w["candidates"][0]
assert [f["held_out_gas_mass"] for f in c["folds"]] == ["4 g", "4.25 g", "4.5 g"]
assert c["heldout_metrics"]["stiffness"]["unit"] == "N/mm"
PY
run again
grep -q '(0 simulations' "$dir.again.out" || fail "again: the curves were not all found in the cache"

# The model's own stiffness at the masses, and through a compliance of 0.1 mm/N.
python3 - "$dir-diagnosis/stiffness.csv" "$dir" <<'PY' || fail "the model's curve"
import csv, sys
rows = list(csv.DictReader(open(sys.argv[1])))
k = {r["gas_mass_g"]: float(r["simulated_N_per_mm"]) for r in rows}
def write(name, f):
    with open(sys.argv[2] + "/" + name, "w") as o:
        o.write("gas_mass_g,stiffness_N/mm\n")
        for m, v in k.items():
            o.write("%s,%.10g\n" % (m, f(v)))
write("own.csv", lambda v: v)
write("series.csv", lambda v: v / (1 + 0.1 * v))
PY
cp "$dir/own.csv" "$dir/k.csv"
run own
grep -q '^verdict: none' "$dir.own.out" || fail "own: not none"

cp "$dir/series.csv" "$dir/k.csv"
run series
python3 - "$json" <<'PY' || fail "series: diagnosis.json"
import json, sys
w = json.load(open(sys.argv[1]))["stiffness_which"]
c = w["candidates"][0]
# The two compliances are one spring in series on a curve: the verdict names both.
assert sorted(w["verdict"].split(" or ")) == ["bed-compliance", "machine-compliance"], w["verdict"]
assert w["explained"] == "fully" and len(w["rivals"]) == 1, (w["explained"], w["rivals"])
assert abs(c["parameters"]["compliance"]["value"] - 0.1) < 0.002, c["parameters"]
assert c["excess_shrink"] > 0.95, c["excess_shrink"]
PY

# The dense curve (the cache's two let-downs) re-read at m + 0.1 g: offset -0.1 g.
python3 - "$dir-cache" "$dir" <<'PY' || fail "the shifted curve"
import glob, sys
pts = []
for f in glob.glob(sys.argv[1] + "/dense*.csv"):
    for line in open(f).read().splitlines()[1:]:
        m, k = line.split(",")[:2]
        pts.append((float(m), float(k)))
pts.sort()
def at(m):
    for (m0, k0), (m1, k1) in zip(pts, pts[1:]):
        if m0 - 1e-12 <= m <= m1 + 1e-12:
            return k0 + (k1 - k0) * (m - m0) / (m1 - m0)
    raise ValueError(m)
with open(sys.argv[2] + "/k.csv", "w") as o:
    o.write("gas_mass_g,stiffness_N/mm\n")
    for g in (4.0, 4.25, 4.5):
        o.write("%g,%.10g\n" % (g, at((g + 0.1) * 1e-3) * 1e-3))
PY
run shift
python3 - "$json" <<'PY' || fail "shift: diagnosis.json"
import json, sys
w = json.load(open(sys.argv[1]))["stiffness_which"]
named = w["verdict"].split(" or ")
assert set(named) <= {"flowmeter-bias", "gas-temperature", "bag-volume"}, w["verdict"]
c = {x["effect"]: x for x in w["candidates"]}
f = c["flowmeter-bias"]
assert abs(f["parameters"]["offset"]["value"] + 0.1) < 0.005, f["parameters"]
assert f["excess_shrink"] > 0.95, f["excess_shrink"]
# Named alone only when the others are told apart; else with its rivals.
assert "flowmeter-bias" in named, w["verdict"]
assert named[1:] == w["rivals"], (named, w["rivals"])
PY

# Bad options: exit 2 naming what is valid, before anything runs.
"$bagsim" diagnose --measured "$dir" --curve-volumes 4 > /dev/null 2> "$dir.bad.err"
rc=$?
test $rc -eq 2 && grep -q "curve-volumes '4' is not valid; valid: an odd count from 3 to 41" "$dir.bad.err" ||
    { cat "$dir.bad.err"; fail "--curve-volumes 4: exit $rc"; }
"$bagsim" diagnose --measured "$dir" --curve-step 2g > /dev/null 2> "$dir.bad.err"
rc=$?
test $rc -eq 2 && grep -q "curve-step '2g' is not valid; valid: a mass with its unit from 0.01 g to 1 g" "$dir.bad.err" ||
    { cat "$dir.bad.err"; fail "--curve-step 2g: exit $rc"; }
echo "ok"
