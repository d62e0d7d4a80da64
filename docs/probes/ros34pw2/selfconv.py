"""Engine-level order check: x1, straight structure path, the balls/cage in k sub-steps per
structure step; the difference of the sensor signal (0.1 s from the start, 15 kHz) from ROS2 at
k = 128 (the k -> inf limit of both methods: the same ball ODE with the same forcing), relative
RMS.  Event sub-steps as usual, in ROS2 for both (without them the default diverges)."""
import sys
sys.path.insert(0, str(__import__("pathlib").Path(__file__).resolve().parent))
import numpy as np
from harness import make_sim, RATE
from bearing_sim_ros import bench
T = 0.1
for isc in [int(a) for a in sys.argv[1:]] or [3, 4]:
    scene = bench.SCENARIOS[isc].build()
    def run(meth, k):
        sim = make_sim(scene, 1, meth)
        sim._model.nball = k
        return sim.advance(int(T * RATE)).accel[:, -1].copy()
    ref = run("ros2", 128)
    nr = np.sqrt(np.mean(ref ** 2))
    for meth in ("ros2", "ros34pw2/ros2"):
        errs = [np.sqrt(np.mean((run(meth, k) - ref) ** 2)) / nr for k in (1, 2, 4, 8, 16)]
        ords = [np.log2(errs[i] / errs[i + 1]) for i in range(len(errs) - 1)]
        print(bench.SCENARIOS[isc].label, meth, "rel diff k=1..16:", " ".join(f"{e:.2e}" for e in errs),
              " orders", " ".join(f"{o:.2f}" for o in ords), flush=True)
