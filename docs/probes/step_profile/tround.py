"""One timing round in this process: for each scene, CPU time (thread) of Simulator.advance over
0.5 s after 0.2 s settling, noise off (bench set-up). Prints JSON lines."""
import sys, time, json
from bearing_sim_ros.bench import SCENARIOS, Config
import bearing_sim_ros
which = sys.argv[1]           # "default" or "rk4"
idx = [int(a) for a in sys.argv[2].split(",")]
sr = 15000.0
if which == "default":
    cfg = Config("default", "x", "skidding", (("solver", "default"),))
else:
    cfg = Config("rk4", "x", "skidding", (("solver", "rk4"), ("rk4_step", 5e-6)))
for k in idx * int(sys.argv[4] if len(sys.argv) > 4 else 1):
    sc = SCENARIOS[k]
    scene = sc.build()
    sim = cfg.simulator(scene, sr, 0)
    sim.advance(int(0.2 * sr))
    t0 = time.thread_time()
    sim.advance(int(0.5 * sr))
    dt = time.thread_time() - t0
    print(json.dumps({"tag": sys.argv[3], "cfg": which, "scene": k, "cpu": dt}), flush=True)
