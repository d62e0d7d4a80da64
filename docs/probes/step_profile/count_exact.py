import sys, numpy as np
from bearing_sim_ros.bench import SCENARIOS
from bearing_sim_ros.simulator import Simulator
import bearing_sim_ros.physics.skidding as S
for k in [int(a) for a in sys.argv[1:]]:
    sim = Simulator(SCENARIOS[k].build(), sample_rate=15000.0, fidelity="skidding", seed=0)
    sim.advance(3000)
    model = sim._model
    s0 = model._speed; l = np.array(sim._radial_load, dtype=float)
    ex = 0; dr = 0; steps = 0
    prev = model.film.copy()
    for it in range(3000):
        model.advance(2, s0, s0, l, l)
        f = model.film
        ex += np.count_nonzero(f[:, [S.F_IUI0, S.F_IUO0]] != prev[:, [S.F_IUI0, S.F_IUO0]])
        dr += np.count_nonzero(f[:, S.F_IW0] != prev[:, S.F_IW0])
        prev = f.copy()
        steps += 1
    print(SCENARIOS[k].label, "exact film evals per step %.2f, drag refresh per step %.3f" % (ex / steps, dr / steps))
