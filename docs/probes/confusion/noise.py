"""White noise through envelope.diagnose at a bearing's lines: python noise.py SCENE RPM SECONDS N
(the highest score of each record, how many reach x4 and the verdicts)."""
import numpy as np, sys, time
from bearing_sim_ros import load_scene
from bearing_sim_ros.analysis.envelope import diagnose
sc = load_scene(sys.argv[1]); rpm = float(sys.argv[2]); secs = float(sys.argv[3]); n = int(sys.argv[4])
fr = sc.bearing.fault_frequencies(rpm / 60)
rng = np.random.default_rng(1)
fs = 15000.0
mx = []; over = 0; verdicts = {}
t0 = time.time()
for i in range(n):
    d = diagnose(rng.standard_normal(int(secs * fs)), fs, fr)
    m = max(d["scores"].values()); mx.append(m); over += m >= 4
    verdicts[d["verdict"]] = verdicts.get(d["verdict"], 0) + 1
mx = np.array(mx)
print(sys.argv[1:], f"max {mx.max():.2f} p99 {np.percentile(mx, 99):.2f} over4 {over}/{n} {verdicts} {time.time()-t0:.0f}s")
