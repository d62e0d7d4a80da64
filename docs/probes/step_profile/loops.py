import re, sys
ins = []
for l in open(sys.argv[1]):
    m = re.match(r"\s*(\d*)\s+([0-9a-f]{5})\s+(\S+)\s*(.*)", l)
    if m:
        ins.append((int(m.group(2), 16), int(m.group(1) or 0), m.group(3), m.group(4)))
tot = sum(n for _, n, _, _ in ins)
loops = []
for a, n, op, arg in ins:
    if op.startswith("j"):
        t = re.match(r"([0-9a-f]+)", arg)
        if t:
            t = int(t.group(1), 16)
            if t < a:
                loops.append((t, a))
# attribute each sample to the innermost loop containing it, else "straight"
att = {}
for a, n, op, arg in ins:
    if not n: continue
    best = None
    for t, e in loops:
        if t <= a <= e and (best is None or e - t < best[1] - best[0]):
            best = (t, e)
    att[best] = att.get(best, 0) + n
rows = sorted(att.items(), key=lambda kv: -kv[1])
for k, n in rows[:25]:
    if k is None:
        print("%5d %4.1f%%  outside loops" % (n, 100 * n / tot)); continue
    t, e = k
    seg = [op for a, _, op, _ in ins if t <= a <= e]
    nd = sum(1 for op in seg if "div" in op); ns = sum(1 for op in seg if "sqrt" in op); nc = sum(1 for op in seg if op == "call")
    print("%5d %4.1f%%  loop %05x-%05x (%d instr, div %d sqrt %d call %d)" % (n, 100 * n / tot, t, e, len(seg), nd, ns, nc))
