"""Hash of accelerations, contact forces and cage speeds over 0.3 s, chunked, for four scenes."""
import sys, hashlib
import numpy as np
from bearing_sim_ros.bench import SCENARIOS
from bearing_sim_ros.simulator import Simulator
sr = 15000.0
for k in (2, 1, 4, 6, 5, 7):
    scene = SCENARIOS[k].build()
    sim = Simulator(scene, sample_rate=sr, fidelity="skidding", seed=0)
    h = hashlib.sha256()
    chunks = [4, 12, 28, 400, 1556, 2500]
    for c in chunks:
        b = sim.advance(c)
        h.update(np.ascontiguousarray(b.accel).tobytes())
        h.update(np.ascontiguousarray(b.cage_speed).tobytes())
        h.update(np.ascontiguousarray(b.contact_forces).tobytes())
        for key in sorted(b.extras):
            v = b.extras[key]
            if isinstance(v, np.ndarray):
                h.update(key.encode()); h.update(np.ascontiguousarray(v).tobytes())
    print(SCENARIOS[k].label, h.hexdigest()[:16], sorted(b.extras.keys()) if k == 2 else "", flush=True)
