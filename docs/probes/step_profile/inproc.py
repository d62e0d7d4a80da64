"""In-process interleaved timing of package variants (renamed copies): per step of the engine,
CPU time of the thread, median over rounds.  usage: inproc.py solver N rounds scenes v1,v2,..."""
import sys, time, json, importlib, statistics as st
import numpy as np
sys.path.insert(0, "/tmp/hR_pk")
solver, N, R = sys.argv[1], int(sys.argv[2]), int(sys.argv[3])
scenes = [int(a) for a in sys.argv[4].split(",")]
names = sys.argv[5].split(",")
mods = {n: (importlib.import_module(f"v_{n}.bench"), importlib.import_module(f"v_{n}.simulator")) for n in names}
kw = {} if solver == "default" else {"solver": "rk4", "rk4_step": 5e-6}
for k in scenes:
    sims = {}
    for n, (bench, simmod) in mods.items():
        sim = simmod.Simulator(bench.SCENARIOS[k].build(), sample_rate=15000.0, fidelity="skidding", seed=0, **kw)
        sim.advance(3000)
        sims[n] = sim
    res = {n: [] for n in names}
    for r in range(R):
        order = names if r % 2 == 0 else names[::-1]
        for n in order:
            model = sims[n]._model
            s0 = model._speed; l = np.array(sims[n]._radial_load, dtype=float)
            c0 = model.counters[0]
            t0 = time.thread_time()
            model.advance(N, s0, s0, l, l)
            dt = time.thread_time() - t0
            res[n].append(dt / (model.counters[0] - c0) * 1e9)
    b = res[names[0]]
    mb = st.median(b)
    print(json.dumps({"scene": k, "res": res}), file=open("/tmp/hR_probe/inproc_last.jsonl", "a"))
    print(k, bench.SCENARIOS[k].label, "%s %.0f ns [%.0f-%.0f]" % (names[0], mb, min(b), max(b)))
    for n in names[1:]:
        v = res[n]
        diffs = sorted(v[i] - b[i] for i in range(R))
        print("   %-8s %.0f ns, paired diff median %+.0f [q25 %+.0f, q75 %+.0f]" % (n, st.median(v), st.median(diffs), diffs[R // 4], diffs[(3 * R) // 4]))
    sys.stdout.flush()
