import json, sys, statistics as st, collections
names = {4: "2000 N", 1: "inner", 2: "outer", 6: "CWRU"}
def load(f):
    d = collections.defaultdict(list)   # (tag, scene) -> list of per-process medians
    cur = collections.defaultdict(list)
    order = []
    for l in open(f):
        if not l.startswith("{"): continue
        j = json.loads(l)
        order.append(j)
    # group consecutive lines of one process: same tag consecutive
    procs = []
    for j in order:
        if not procs or procs[-1][0] != j["tag"] or len(procs[-1][1]) == 12:
            procs.append((j["tag"], []))
        procs[-1][1].append(j)
    for tag, js in procs:
        by = collections.defaultdict(list)
        for j in js: by[j["scene"]].append(j["cpu"])
        for s, v in by.items(): d[(tag, s)].append(st.median(v))
    return d
for f in sys.argv[1:]:
    d = load(f)
    print(f)
    for s in (4, 1, 2, 6):
        o, n = d[("old", s)], d[("new", s)]
        ratios = sorted(a / b for a, b in zip(o, n))
        print("  %-7s old %.1f ms [%.1f-%.1f]  new %.1f ms [%.1f-%.1f]  old/new per round median %.3f [%.3f-%.3f] n=%d" % (
            names[s], 1e3 * st.median(o), 1e3 * min(o), 1e3 * max(o), 1e3 * st.median(n), 1e3 * min(n), 1e3 * max(n),
            st.median(ratios), ratios[0], ratios[-1], len(o)))
