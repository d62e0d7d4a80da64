import json, sys, subprocess, collections
eng = json.load(open(sys.argv[2]))["_engine_split"]
syms = []
for line in subprocess.run(["objdump", "-t", sys.argv[3]], capture_output=True, text=True).stdout.splitlines():
    p = line.split()
    if len(p) >= 6 and p[2] == "F":
        off = int(p[0], 16); size = int(p[4], 16)
        name = p[5]
        short = name.split("skidding")[-1][:30] if "skidding" in name else name[-40:]
        if "defects" in name: short = name.split("defects")[-1][:30]
        syms.append((off, size, short))
c = collections.Counter(); offs = collections.Counter(); tot = 0
for line in open(sys.argv[1]):
    parts = line.split()
    ip = int(parts[0], 16)
    tot += 1
    rel = ip - eng
    hit = None
    for off, size, nm in syms:
        if off <= rel < off + size:
            hit = nm; break
    if hit:
        c[hit] += 1
        if "engine" in hit: offs[rel] += 1
    else:
        c["other"] += 1
jit = sum(v for k, v in c.items() if k != "other")
print("samples in compiled kernels", jit)
for k, v in c.most_common():
    if k != "other": print("  %6d %5.1f %%  %s" % (v, 100 * v / jit, k))
json.dump(offs, open(sys.argv[1] + ".engoffs.json", "w"))
