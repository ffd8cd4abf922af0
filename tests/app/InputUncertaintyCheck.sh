#!/bin/sh
# The protocol's stated input uncertainties in the validation uncertainty on the taut tiny rig
# (docs/diagnosis.md#the-protocols-input-uncertainties).
#   InputUncertaintyCheck.sh BAGSIM DIR SCENARIO raise|bias
# raise: data with no effect, the manifest stating a gas-mass uncertainty of 0.02 g, against the
#   same data stating none: the pressure's input uncertainty equals the one two plain runs of
#   the scenario at the gas masses +- 0.02 g give at the measured samples (their curves'
#   pressure at the measured displacement on the sample's branch, half the difference, RMS),
#   within 2 %; the validation uncertainty grows by root sum square; the RMSE is the same.
# bias: a flowmeter reading 0.03 g high; stated 0.05 g the data are called none, not stated the
#   bias is found.
set -u
bagsim=$1 dir=$2 scenario=$3 case=$4
rm -rf "$dir" && mkdir -p "$dir" || exit 1
if [ "$case" = raise ]; then
    for s in stated plain; do
        opt=""; [ $s = stated ] && opt="--gas-mass-uncertainty 0.02g"
        "$bagsim" synth-measurement --scenario "$scenario" --effect none $opt --out "$dir/$s" \
            --label-out "$dir/$s.label" --quiet || exit 1
        "$bagsim" diagnose --measured "$dir/$s" --where-only --threads 2 > "$dir/$s.out" || exit 1
    done
    cat "$dir/stated.out"
    grep -q "^  stated gas mass uncertainty: 0.02 g (every test)$" "$dir/stated.out" || exit 1
    grep -q "^  stated room temperature uncertainty: not stated$" "$dir/stated.out" || exit 1
    grep -q "^  stated gas mass uncertainty: not stated$" "$dir/plain.out" || exit 1
    for sign in plus minus; do
        if [ $sign = plus ]; then m="[4.52 g, 4.27 g, 4.02 g]"; else m="[4.48 g, 4.23 g, 3.98 g]"; fi
        "$bagsim" run "$scenario" --out "$dir/$sign" --quiet --set "test.gas_masses=$m" \
            --set test.unload=true > /dev/null || exit 1
    done
    python3 - "$dir" <<'PY' || exit 1
import csv, json, math, sys
d = sys.argv[1]
def load(name):
    return json.load(open(f"{d}/{name}-diagnosis/diagnosis.json"))["where"]
stated, plain = load("stated"), load("plain")
ch = lambda w, c: [x for x in w["channels"] if x["channel"] == c][0]
def interp(x, y, q):  # linear, the end segments extended
    i = 1
    while i < len(x) - 1 and x[i] < q: i += 1
    return y[i - 1] + (y[i] - y[i - 1]) * (q - x[i - 1]) / (x[i] - x[i - 1])
def branches(run, k):
    rows = [r for r in csv.DictReader(open(f"{d}/{run}/load_displacement.csv"))]
    masses = sorted({r["gas_mass_g"] for r in rows}, key=float, reverse=True)
    mine = [r for r in rows if r["gas_mass_g"] == masses[k]]
    out = {}
    for b in ("loading", "unloading"):
        pts = sorted((float(r["displacement_mm"]), float(r["pressure_kPa"])) for r in mine if r["branch"] == b)
        xs, ys = [], []
        for x, y in pts:
            if xs and x <= xs[-1]: continue
            xs.append(x); ys.append(y)
        out[b] = (xs, ys)
    if len(out["unloading"][0]) < 2: out["unloading"] = out["loading"]
    return out
s2, n = 0.0, 0
for k in range(3):
    m = list(csv.DictReader(open(f"{d}/stated/test{k + 1}-machine.csv")))
    mt = [float(r["time_s"]) for r in m]; md = [float(r["displacement_mm"]) for r in m]
    turn = mt[md.index(max(md))]
    bp, bm = branches("plus", k), branches("minus", k)
    for r in csv.DictReader(open(f"{d}/stated/test{k + 1}-pressure.csv")):
        t = float(r["time_s"])
        x = md[0] if t <= mt[0] else md[-1] if t >= mt[-1] else interp(mt, md, t)
        b = "loading" if t <= turn else "unloading"
        dp = 0.5 * (interp(*bp[b], x) - interp(*bm[b], x))
        s2 += dp * dp; n += 1
estimate = math.sqrt(s2 / n)
p = ch(stated, "pressure")
print(f"pressure: input_uncertainty_gas_mass {p['input_uncertainty_gas_mass']:.5g} kPa, from two plain runs {estimate:.5g} kPa ({100 * (p['input_uncertainty_gas_mass'] / estimate - 1):+.2f} %)")
assert abs(p["input_uncertainty_gas_mass"] / estimate - 1) < 0.02
for c in ("force", "pressure"):
    a, b = ch(stated, c), ch(plain, c)
    print(f"{c}: validation {b['validation_uncertainty']:.5g} -> {a['validation_uncertainty']:.5g} {a['unit']} (gas mass term {a['input_uncertainty_gas_mass']:.5g}, temperature term {a['input_uncertainty_temperature']:.3g})")
    assert b["input_uncertainty_gas_mass"] == 0 and a["input_uncertainty_temperature"] == 0
    assert a["input_uncertainty_gas_mass"] > 5 * b["validation_uncertainty"]
    assert abs(a["validation_uncertainty"] ** 2 - b["validation_uncertainty"] ** 2 - a["input_uncertainty_gas_mass"] ** 2) < 1e-4 * a["validation_uncertainty"] ** 2
    assert abs(a["rmse"] - b["rmse"]) < 1e-9
si = stated["stated_input_uncertainties"]
assert si[0]["input"] == "gas_mass" and si[0]["stated"] and si[0]["standard_uncertainty"] == [0.02] * 3
assert si[1]["input"] == "room_temperature" and not si[1]["stated"] and si[1]["text"] == "not stated"
PY
    grep -q "<th>gas mass</th><th>room temperature</th>" "$dir/stated-diagnosis/report.html" || exit 1
    grep -q "Stated standard uncertainties: gas mass 0.02 g (every test); room temperature not stated." \
        "$dir/stated-diagnosis/report.html" || exit 1
else
    for s in stated plain; do
        opt=""; [ $s = stated ] && opt="--gas-mass-uncertainty 0.05g"
        "$bagsim" synth-measurement --scenario "$scenario" --effect flowmeter-bias --param offset=0.03g \
            $opt --out "$dir/$s" --label-out "$dir/$s.label" --quiet || exit 1
        "$bagsim" diagnose --measured "$dir/$s" --candidates flowmeter-bias,pressure-sensor \
            --threads 2 > "$dir/$s.out" || exit 1
        cat "$dir/$s.out"
    done
    grep -q "^verdict: none " "$dir/stated.out" || { echo "stated: not none"; exit 1; }
    grep -q "^verdict: flowmeter-bias " "$dir/plain.out" || { echo "plain: not found"; exit 1; }
    python3 - "$dir/plain-diagnosis/diagnosis.json" <<'PY' || exit 1
import json, sys
c = json.load(open(sys.argv[1]))["candidates"][0]
assert c["effect"] == "flowmeter-bias" and abs(c["parameters"]["offset"]["value"] - 0.03) < 0.003, c["parameters"]
PY
fi
echo "ok"
