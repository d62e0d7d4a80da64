"""The kinematic tier's centrifugal law on preloaded and small-play bearings with its ball state
exact for lightly loaded balls (``physics.kinematic._ball_state``, where two passes were 25-31 %
off the quasi-static law for balls whose inner contact carries less than F_c); docs/fidelity_rms_gap.md,
"Light preload: which tier was wrong".  Run from the repository: ``python
docs/probes/centrifugal_gate/preload.py`` (the reference runs cached in $CENTRIFUGAL_GATE_CACHE as
``probe.py``'s).  preload.txt is its output with the law first measured, a Newton step and a third
pass (the patch of 98417ff, not kept); preload_table.txt with the law as taken, a table per bearing
and speed (``held_ball_table``), against the same references read from preload.txt's four digits.
fresh.txt has the same points with the two-pass law.

The points are ``fresh.py``'s where the force was measured against the reference below 0.01
(preloaded, ``PRELOAD_MORE``, small play and the lower end), measured as there (healthy, noise
off, 0.6 s after 0.3 s at 15 kHz; the skidding tier's ``solver="reference"`` against the
kinematic tier with massless balls and with the force); the skidding tier did not change.
"""
import importlib.util

from bearing_sim_ros.fidelity import clearance_ratio

_spec = importlib.util.spec_from_file_location("fresh", "docs/probes/centrifugal_gate/fresh.py")
fresh = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(fresh)
gate = fresh.gate

POINTS = [p for p in fresh.POINTS + fresh.PRELOAD_MORE if p[3] != "large"]


def main():
    print(f"window: {gate.SECONDS} s after {gate.SETTLE} s, {gate.FS:.0f} Hz, seed {gate.SEED}, sensor noise off, "
          "healthy; errors kinematic / reference - 1 (massless -> with F_c)")
    print("| group | bearing@C_r, load | C_r / D | rpm | F_c / Q_max | reference RMS x, y (m/s^2) | accel_y error "
          "| accel_x error | closer |")
    print("|---|---|---|---|---|---|---|---|---|")
    for which, load, target, group in POINTS:
        rpm, s = fresh.point(which, load, target)
        rx, ry, err = fresh.errors(s)
        closer = "force" if abs(err["force"][0]) < abs(err["massless"][0]) else "massless"
        print(f"| {group} | {which} {load} N | {clearance_ratio(s):.4f} | {rpm} | {fresh.ratio(s):.4f} | "
              f"{rx:.4g}, {ry:.4g} | {err['massless'][0]:+.2%} -> {err['force'][0]:+.2%} "
              f"| {err['massless'][1]:+.2%} -> {err['force'][1]:+.2%} | {closer} |", flush=True)


if __name__ == "__main__":
    main()
