import sys, time, dataclasses, math
import numpy as np
from bearing_sim_ros import Simulator, load_scene
from bearing_sim_ros.scene import Defect
from bearing_sim_ros.analysis.envelope import diagnose, with_cage, fault_lines

DEFECTS = {
    "outer": Defect(kind="outer", width=0.6e-3, depth=0.25e-3, length=0.6e-3, angle=-math.pi/2),
    "inner": Defect(kind="inner", width=0.6e-3, depth=0.25e-3, length=0.6e-3, angle=-math.pi/2),
    "ball": Defect(kind="ball", width=0.6e-3, depth=0.25e-3, length=0.6e-3, angle=0.0),
}

def run(kind, rpm, tier, seconds=4.0, base="er16k_skidding", settle=0.5):
    scene = load_scene(base)
    defects = () if kind == "healthy" else (DEFECTS[kind],)
    scene = dataclasses.replace(scene, shaft_speed=rpm * 2 * math.pi / 60, defects=defects, fidelity=tier)
    sim = Simulator(scene, fidelity=tier)
    fs = sim.sample_rate
    sim.advance(int(settle * fs))
    b = sim.advance(int(seconds * fs))
    shaft_hz = rpm / 60
    fr = scene.bearing.fault_frequencies(shaft_hz)
    cage_hz = abs(float(np.mean(b.cage_speed))) / (2 * math.pi)
    fr = with_cage(fr, scene.bearing.balls, shaft_hz, cage_hz)
    if "ball_skid" in b.extras:
        fr = {**fr, "bsf": fr["bsf"] * (1 - float(np.nanmean(b.extras["ball_skid"])) / 100)}
    out = {}
    for ax in (0, 1):
        d = diagnose(b.accel[:, ax], fs, fr)
        for f, s in d["scores"].items():
            out[f] = max(out.get(f, 0), s)
    return out, fr, b

if __name__ == "__main__":
    tiers = sys.argv[1].split(",")
    rpms = [float(r) for r in sys.argv[2].split(",")]
    kinds = sys.argv[3].split(",")
    for tier in tiers:
        for rpm in rpms:
            for kind in kinds:
                t0 = time.time()
                s, fr, _ = run(kind, rpm, tier)
                print(f"{tier:9s} {rpm:6.0f} {kind:7s} outer={s['outer']:7.1f} inner={s['inner']:7.1f} ball={s['ball']:7.1f}  ftf={fr['ftf']:.2f}Hz ({time.time()-t0:.0f}s)", flush=True)
