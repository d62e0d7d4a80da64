"""Markdown confusion table from before/after JSON of confusion.py."""
import json, sys
B = {}
for f in sys.argv[1].split(","):
    B.update(json.load(open(f)))
A = json.load(open(sys.argv[2]))
KEY = {"outer": "bpfo", "inner": "bpfi", "ball": "2bsf"}
def right(geom, state, v):
    return v == state or (state == "healthy" and geom == "er16k" and v == "outer")
rows = []
wrong_b = wrong_a = 0
for geom in ("er16k", "6205"):
    for tier in ("kinematic", "skidding"):
        for load in ("50.0", "1000.0"):
            for rpm in ("300", "600", "1000", "1800", "3000", "6000"):
                cells = []
                for state in ("healthy", "outer", "inner", "ball"):
                    tag = f"{geom}_{state}_{rpm}_{load}_{tier}"
                    b, a = B[tag], A[tag]
                    L = b["lines"]
                    vb, va = b["verdict"], a["verdict"]
                    wrong_b += not right(geom, state, vb); wrong_a += not right(geom, state, va)
                    v = vb if vb == va else f"{vb} -> {va}"
                    if not right(geom, state, vb) or not right(geom, state, va):
                        v = f"**{v}**"
                    p = "/".join(f"{L[k][3]:.1f}" if L[k][3] < 100 else f"{L[k][3]:.0f}" for k in KEY.values())
                    cells.append(f"{v} {p}")
                rows.append(f"| {geom} | {tier} | {float(load):g} | {rpm} | " + " | ".join(cells) + " |")
print("| bearing | tier | load N | rpm | healthy | outer | inner | ball |")
print("|---|---|---|---|---|---|---|---|")
print("\n".join(rows))
print(f"\nwrong before: {wrong_b}, after: {wrong_a} of {len(rows) * 4}")
