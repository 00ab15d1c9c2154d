"""Before/after: two builds of `propid diagnose` (e.g. the one-effect-at-a-time diagnosis of
1b2a04f against today's) on the independent stand's 23 diagnosis cases x 2 seeds, judged by ONE
simplified rule for both (it reads either build's JSON; tests/tests/diagnose_independent.rs is
the stricter judge of today's build alone: it also asks a transient to be localised and compares
the drag at the top speed):
right = every effect the stand hid is named (or, where the stand lists an equivalent, named as
that or left as an ambiguity between the two) within 10 % of its value, nothing else named, and
the extended J within 2 % (and c2 within 2 % unless the drag law's exponent is the effect);
a load transient: 'unexplained' and nothing named; clean: 'nothing wrong'.
"silently wrong" = says the model explains the data (nothing wrong or effects named, no
ambiguity) while J or c2 is off by more than 2 %.

usage: python3 tests/independent_stand/stand.py --all --seed 1 --out DIR   (and --seed 2)
       python3 tests/independent_stand/before_after.py OLD_PROPID NEW_PROPID DIR
prints the table and each build's tally."""
import json, subprocess, sys, os

CASES = ["clean","clean_chirp","torque_lag_8ms","torque_lag_15ms","force_offset","viscous",
 "coulomb_reversing","drag_exponent_1p8","drag_exponent_2p2","force_sensor_lag",
 "force_sensor_2nd_order","acceleration_lag","braking","lag_offset","lag_viscous",
 "lag_coulomb_reversing","drag_exponent_offset","braking_lag","sensor_filter_drag_exponent",
 "large_clean","large_torque_lag_25ms","transient_late","transient_early"]

def run(binary, tsv):
    out = subprocess.run([binary, "diagnose", tsv, "--format", "json"], capture_output=True, text=True)
    try:
        return json.loads(out.stdout)
    except Exception:
        return {"verdict": {"kind": "error"}}

def judge(d, truth):
    ideal = truth["ideal_report"]
    kind = d["verdict"]["kind"] if isinstance(d["verdict"], dict) else str(d["verdict"])
    named = {e.get("name", e.get("effect")): e["value"] for e in d.get("effects", [])}
    ambs = []
    if d.get("ambiguity"):
        a = d["ambiguity"]; ambs.append((set(a["between"]), a.get("values", [None])[0]))
    for a in d.get("ambiguities") or []:
        vals = [e["value"] for e in a.get("alternative_effects", [])]
        ambs.append((set(a["between"]), vals[0] if vals else None))
    ext = d.get("extended") or {}
    J = ext.get("inertia", ext.get("mass")); c2 = ext.get("c2")
    want = ideal["effects"]; eq = {a["instead_of"]: a["name"] for a in ideal.get("equivalent_alternatives", [])}
    exponent = any(n == "drag_exponent" for n in want)
    J_ok = J is not None and abs(J / ideal["J"] - 1) <= 0.02
    c2_ok = exponent or (c2 is not None and abs(c2 / ideal["c2"] - 1) <= 0.02)
    explained = kind in ("nothing_wrong", "explained")
    if J is not None and c2 is not None and explained and not (J_ok and c2_ok):
        return "silently wrong"
    if ideal.get("unexplained"):
        return "right" if kind == "unexplained" and not named else "limit"
    if not want:
        return "right" if kind == "nothing_wrong" else "limit"
    satisfied = set()
    for name, spec in want.items():
        v = spec["value"]
        for n in (name, eq.get(name)):
            if n in named and abs(named[n] / v - 1) <= 0.10:
                satisfied.add(name)
        for between, val in ambs:
            if name in between and eq.get(name) in between and val is not None and abs(val / v - 1) <= 0.10:
                satisfied.add(name)
    allowed = set(want) | set(eq.values())
    extra = set(named) - allowed
    return "right" if satisfied == set(want) and not extra and J_ok and c2_ok else "limit"

old, new, stand = sys.argv[1], sys.argv[2], sys.argv[3]
rows = []; tally = {"old": {}, "new": {}}
for case in CASES:
    for seed in (1, 2):
        base = os.path.join(stand, f"{case}-seed{seed}")
        truth = json.load(open(base + ".json"))
        r = {}
        for tag, b in (("old", old), ("new", new)):
            r[tag] = judge(run(b, base + ".tsv"), truth)
            tally[tag][r[tag]] = tally[tag].get(r[tag], 0) + 1
        rows.append((case, seed, r["old"], r["new"]))
print("| case | seed | one at a time (1b2a04f) | today (main) |\n|---|---|---|---|")
for case, seed, o, n in rows:
    print(f"| {case} | {seed} | {o} | {n} |")
for tag in ("old", "new"):
    print(tag, dict(sorted(tally[tag].items())))
