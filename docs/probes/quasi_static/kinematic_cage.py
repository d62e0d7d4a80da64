"""Probe (2026-11-28): how much of the kinematic tier's difference from the skidding reference is
the cage speed?

The kinematic tier puts its balls where pure rolling puts them; the skidding reference's cage runs
slower by its skid.  Here the kinematic tier runs once as it is and once with its cage speed per
shaft speed (``kinematic.P_CAGE``) set to the reference's mean cage speed over the same 0.5 s, and
both are measured against the reference with the bench's scenarios and metrics (0.2 s settling,
0.5 s at 15 kHz, sensor noise off, seed 0).  What is left with the right cage speed is the rest of
the model's difference: the massless balls (no tractions on the races, no centrifugal load, no
radial inertia at the defects), the contacts in series.  Results: docs/solvers.md, "Measured:
what eliminating the balls' fast modes would cost".

    python docs/probes/quasi_static/kinematic_cage.py      # about 2 minutes once compiled

The references are the unpatched code's ``"reference"`` solver (RK4 at 1/32 of an internal
sample); runs cached by ``probe.py run --div 32 --only S=1`` (QS_PROBE_OUT, /tmp/qs_probe: the
patch at S = 1 gives the same bits) are used when present.
"""
import os
from pathlib import Path

from bearing_sim_ros import bench
from bearing_sim_ros.physics import kinematic as kin
from bearing_sim_ros.simulator import Simulator
from cached import cached_run   # this folder (the script's) is first on the import path

RATE, SETTLE, SECONDS = 15000.0, 0.2, 0.5          # bench.study(quick=False)
CACHE = Path(os.environ.get("QS_PROBE_OUT", "/tmp/qs_probe"))


def reference(isc: int, scene) -> bench.Run:
    cached = CACHE / f"sc{isc}_S1_d32.npz"
    if cached.exists():
        return cached_run(cached)[0]
    cpu, batch = bench._timed_run(bench.reference_config(), scene, RATE, SETTLE, SECONDS)
    return bench._as_run(batch, [cpu], SECONDS)


def main() -> None:
    print("| scenario | kinematic tier | RMS % | lines % | cage speed % | 20 ms waveform % | error % |")
    print("| --- | --- | ---: | ---: | ---: | ---: | ---: |")
    for isc, sc in enumerate(bench.SCENARIOS):
        scene = sc.build()
        ref = reference(isc, scene)
        for label, cage_of_reference in (("as it is", False), ("the reference's cage speed", True)):
            sim = Simulator(scene, sample_rate=RATE, fidelity="kinematic", seed=0)
            if cage_of_reference:
                sim._model.geo[kin.P_CAGE] = ref.cage_speed / scene.shaft_speed
            sim.advance(int(SETTLE * RATE))
            run = bench._as_run(sim.advance(int(SECONDS * RATE)), [1.0], SECONDS)
            e = bench.errors(run, ref, scene, RATE)
            print(f"| {sc.label} | {label} | {100 * e['rms']:.2f} | {100 * e['lines']:.2f} | "
                  f"{100 * e['cage']:.3f} | {100 * e['waveform']:.1f} | {100 * e['error']:.2f} |", flush=True)


if __name__ == "__main__":
    main()
