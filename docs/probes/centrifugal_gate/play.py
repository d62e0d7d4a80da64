"""Where, in radial play, the kinematic tier's centrifugal force starts to help: the ER-16K and the
6205 (catalog bearings, the same 7.94 mm balls) at six radial clearances spanning C_r / D
0.0008-0.0057 (their own 45 and 10 um among them), each at operating points of F_c / Q_max about
0.002, 0.005, 0.01 and 0.02; docs/fidelity_rms_gap.md, "The gate measured between 0.005 and
0.015", its subsection "Where in the play" (2026-11-30).  Run from the repository:
``python docs/probes/centrifugal_gate/play.py`` (8 min 33 s on 2 cores shared with another run, most of
it the skidding reference, cached in $CENTRIFUGAL_GATE_CACHE as ``probe.py``'s); play.txt is its
output.

Each point as ``probe.py`` measures (its ``build``, ``run`` and ``reference``): healthy, sensor
noise off, seed 1 only, 0.6 s after 0.3 s at 15 kHz, the skidding tier's ``solver="reference"``
against the kinematic tier with massless balls (``CENTRIFUGAL_GATE`` inf) and with the force (0).
The speed for a target ratio is solved from the ratio's speed^2 law at the point's load and
clearance (the support's share k_s C_r changes W) and rounded to 10 rpm; the ratio reached is
printed.  Besides C_r / D the table gives C_r / delta_max, the play over the Hertz deflection of
the most loaded ball at Q_max = 5 W / Z with the series stiffness K (delta_max = (Q_max / K)^(2/3)),
a play that also involves the load.
"""
import importlib.util
import math

import numpy as np

import bearing_sim_ros.physics.kinematic as kinematic
from bearing_sim_ros import load_scene
from bearing_sim_ros.fidelity import bearing_load, clearance_ratio
from bearing_sim_ros.scene import shipped_scenes

_spec = importlib.util.spec_from_file_location("centrifugal_gate", "docs/probes/centrifugal_gate/probe.py")
gate = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(gate)

CLEARANCES_UM = (6.35, 10.0, 16.0, 24.0, 34.0, 45.0)    # C_r / D 0.0008, 0.0013, 0.002, 0.003, 0.0043, 0.0057
TARGETS = (0.002, 0.005, 0.01, 0.02)                     # F_c / Q_max aimed at
# (bearing, downward load N): each bearing at a moderate load; the ER-16K at 1000 N too, so that
# C_r / delta_max and C_r / D come apart (the same clearances, a 2.9x larger deflection)
LOADS = (("ER-16K", 200), ("6205", 1000), ("ER-16K", 1000))


def play_over_deflection(scene):
    """C_r / delta_max (dimensionless): the radial clearance over the Hertz deflection (m) of the
    most loaded ball at Q_max = 5 W / Z (W the balls' share of the load, ``bearing_load``; K the
    bearing's series stiffness, N / m^1.5).  0 for a preloaded bearing."""
    b = scene.bearing
    q_max = 5.0 * max(bearing_load(scene, scene.radial_load), 1e-3) / b.balls
    return max(b.radial_clearance, 0.0) / (q_max / b.combined_stiffness) ** (2.0 / 3.0)


def ratio(scene):
    """F_c / Q_max of ``scene`` at its operating point (``kinematic.centrifugal_ratio``)."""
    return kinematic.centrifugal_ratio(scene, scene.radial_load, scene.shaft_speed)


def point(which, load, target):
    """The healthy scene of ``which`` at ``load`` (N) whose speed puts F_c / Q_max near ``target``."""
    r1000 = ratio(gate.build(which, 1000, load))
    rpm = int(round(1000.0 * math.sqrt(target / r1000), -1))
    return rpm, gate.build(which, rpm, load)


def main():
    print("shipped scenes (F_c / Q_max, C_r / D, C_r / delta_max): " + ", ".join(
        f"{n} {ratio(s):.4f} {clearance_ratio(s):.4f} {play_over_deflection(s):.2f}"
        for n, s in ((n, load_scene(n)) for n in shipped_scenes())), flush=True)
    print(f"window: seed {gate.SEED} only, {gate.SECONDS} s after {gate.SETTLE} s, {gate.FS:.0f} Hz, sensor noise off, "
          "healthy; errors kinematic / reference - 1 (massless -> with F_c); closer: the law whose |accel_y error| "
          "is smaller")
    print("| bearing, load | C_r (um) | C_r / D | C_r / delta_max | rpm | F_c / Q_max | reference RMS y (m/s^2) "
          "| accel_y error | accel_x error | closer |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    rows = []
    for which, load in LOADS:
        for cr in CLEARANCES_UM:
            for target in TARGETS:
                rpm, s = point(f"{which}@{cr:g}um", load, target)
                rx, ry, _rc = gate.reference(s)
                err = {}
                for label, g in (("massless", math.inf), ("force", 0.0)):
                    kx, ky, _kc, held = gate.run(s, "kinematic", g)
                    assert held == (label == "force"), (which, cr, rpm, label, held)
                    err[label] = (ky / ry - 1.0, kx / rx - 1.0)
                force = abs(err["force"][0]) < abs(err["massless"][0])
                row = (which, load, cr, clearance_ratio(s), play_over_deflection(s), rpm, ratio(s), ry,
                       err["massless"], err["force"], force)
                rows.append(row)
                print(f"| {which} {load} N | {cr:g} | {row[3]:.4f} | {row[4]:.2f} | {rpm} | {row[6]:.4f} | {ry:.4g} "
                      f"| {err['massless'][0]:+.2%} -> {err['force'][0]:+.2%} "
                      f"| {err['massless'][1]:+.2%} -> {err['force'][1]:+.2%} | {'force' if force else 'massless'} |",
                      flush=True)
    summary(rows)


def summary(rows):
    """Per clearance and load, at how many points the force was closer; and the best rule "the
    force where X <= x0 and F_c / Q_max >= r0" (X C_r / D or C_r / delta_max; small play is where
    the force helped), x0 and r0 searched over the points' own values, scored by the points it
    puts on the wrong side."""
    print("\nthe force closer (accel_y), per load and clearance:")
    for which, load in LOADS:
        cells = []
        for cr in CLEARANCES_UM:
            sel = [r for r in rows if r[0] == which and r[1] == load and r[2] == cr]
            cells.append(f"{cr:g} um {sum(r[10] for r in sel)}/{len(sel)}")
        print(f"  {which} {load} N: " + ", ".join(cells))
    force = np.array([r[10] for r in rows])
    rat = np.array([r[6] for r in rows])
    for name, col in (("C_r / D", 3), ("C_r / delta_max", 4)):
        x = np.array([r[col] for r in rows])
        best = None
        for x0 in np.unique(x):
            for r0 in np.unique(np.concatenate([[0.0], rat])):
                pred = (x <= x0) & (rat >= r0)      # small play: force
                wrong = int(np.sum(pred != force))
                if best is None or wrong < best[0]:
                    best = (wrong, x0, r0)
        print(f"best rule 'force where {name} <= x0 and F_c / Q_max >= r0': x0 {best[1]:.4g}, r0 {best[2]:.4f}, "
              f"{best[0]} of {len(rows)} points on the wrong side")


if __name__ == "__main__":
    main()
