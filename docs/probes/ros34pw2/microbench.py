"""ns per call of the step's kernels at a settled state (2000 N scene unless given): _rhs,
_w_factor, _w_apply, and the vector work of one extra stage, to put a floor under the cost of a
specialised ROS34PW2 step.  Median of 7 rounds of 20000 calls."""
import sys, time, statistics as st
sys.path.insert(0, str(__import__("pathlib").Path(__file__).resolve().parent))
import numpy as np
from numba import njit
from harness import make_sim, RATE
from bearing_sim_ros import bench
from bearing_sim_ros.physics import skidding as S

@njit(cache=False)
def loop_rhs(N, y, f, p, dtab, wti, wto, film, aux, dg, scr, frc):
    for _ in range(N):
        S._rhs(y, f, 200.0, 0.3, 0.0, -2000.0, p, dtab, wti, wto, film, aux, dg, scr, frc)

@njit(cache=False)
def loop_factor(N, y, aux, p, hg, wsp, wcage):
    for _ in range(N):
        S._w_factor(y, aux, p, hg, 200.0, wsp, wcage)

@njit(cache=False)
def loop_apply(N, p, hg, wsp, wcage, r, k):
    for _ in range(N):
        S._w_apply(p, hg, wsp, wcage, r, k)

isc = int(sys.argv[1]) if len(sys.argv) > 1 else 4
scene = bench.SCENARIOS[isc].build()
sim = make_sim(scene, 1, "orig")
sim.advance(int(0.2 * RATE))
m = sim._model
y = m.y.copy(); f = np.zeros_like(y); nb = m.nb
aux = m._aux0.copy(); dg = m._dg0.copy(); film = m.film.copy()
scr = np.zeros((nb, 5)); frc = np.zeros(4)
wsp = np.zeros((nb, S.NW)); wcage = np.zeros(1)
hg = m.hstep * S.SplitROS2.gamma if hasattr(S, "SplitROS2") else m.hstep * 1.7071
r = np.random.default_rng(0).normal(size=y.size) * 1e-3; k = np.zeros_like(y)
N = 20000
loop_rhs(10, y, f, m.p, m.dtab, m.wti, m.wto, film, aux, dg, scr, frc)
loop_factor(10, y, aux, m.p, hg, wsp, wcage); loop_apply(10, m.p, hg, wsp, wcage, r, k)
res = {"rhs": [], "factor": [], "apply": []}
for _ in range(7):
    t = time.thread_time(); loop_rhs(N, y, f, m.p, m.dtab, m.wti, m.wto, film, aux, dg, scr, frc); res["rhs"].append(time.thread_time() - t)
    t = time.thread_time(); loop_factor(N, y, aux, m.p, hg, wsp, wcage); res["factor"].append(time.thread_time() - t)
    t = time.thread_time(); loop_apply(N, m.p, hg, wsp, wcage, r, k); res["apply"].append(time.thread_time() - t)
print(bench.SCENARIOS[isc].label, "nvar", y.size, " ".join(f"{k_}: {st.median(v) / N * 1e9:.0f} ns" for k_, v in res.items()))
