import sys, time, json, ctypes
import numpy as np
from bearing_sim_ros.bench import SCENARIOS
from bearing_sim_ros.simulator import Simulator
import bearing_sim_ros.physics.skidding as S
k = int(sys.argv[1]); n = int(sys.argv[2]); solver = sys.argv[3] if len(sys.argv) > 3 else "default"
kw = {} if solver == "default" else {"solver": "rk4", "rk4_step": 5e-6}
sim = Simulator(SCENARIOS[k].build(), sample_rate=15000.0, fidelity="skidding", seed=0, **kw)
sim.advance(3000)
model = sim._model
s0 = model._speed; l = np.array(sim._radial_load, dtype=float)
# function addresses of the compiled kernels
out = {}
for name in ("_engine_split", "_rhs", "_engine", "_step", "_record"):
    disp = getattr(S, name)
    for sig, cres in disp.overloads.items():
        lib = cres.library
        fname = cres.fndesc.mangled_name
        addr = lib.get_pointer_to_function(fname)
        out[name] = addr
print(json.dumps(out), file=open("/tmp/hR_probe/addrs.json", "w"))
t0 = time.thread_time()
model.advance(n, s0, s0, l, l)
print("cpu", time.thread_time() - t0)
