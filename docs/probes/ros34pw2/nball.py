"""x1 with the balls/cage in k sub-steps per structure step (straight structure path), ROS2 vs
ROS34PW2: how far is each from the k -> inf floor (the structure's own error at x1)?"""
import sys
sys.path.insert(0, str(__import__("pathlib").Path(__file__).resolve().parent))
import numpy as np
from harness import make_sim, reference, RATE, SETTLE, SECONDS, tab
from bearing_sim_ros import bench
for isc in [int(a) for a in sys.argv[1:]] or [4, 7]:
    sc = bench.SCENARIOS[isc]; scene = sc.build(); ref = reference(isc)
    for meth in ("ros2", "ros34pw2"):
        row = []
        for k in (1, 2, 4, 8, 16):
            sim = make_sim(scene, 1, meth)
            sim._model.nball = k
            sim.advance(int(SETTLE * RATE))
            b = sim.advance(int(SECONDS * RATE))
            e = bench.errors(bench._as_run(b, [1.0], SECONDS), ref, scene, RATE)
            row.append(f"k={k}: {e['error']:.2%}")
        print(f"{sc.label} x1 {meth}: " + ", ".join(row), flush=True)
