"""The envelope detector's band against fast fault lines: the numbers of docs/envelope_band.md.
Run from the repository: ``python docs/probes/envelope_band/probe.py [part ...]``, parts ``fast``
(a 6000-size bearing with an inner-race pit at 30 000-50 000 rpm), ``scan`` (bands tried at
40 000 rpm), ``low_rate`` (the ER-16K at 1-8 kHz of sample rate), ``resonance`` (the ER-16K's
inner pit at 15 kHz in bands with and without its 3.8 kHz resonator), ``length`` (records of
0.4-1 s at 40 000 rpm); all by default, a few minutes.
"""
import dataclasses
import math
import sys
from pathlib import Path

from bearing_sim_ros import Simulator, load_scene
from bearing_sim_ros.analysis import envelope as env

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "custom_bearings"))
from probe import scene as custom_scene  # noqa: E402  (the 6000-size scene of README "Limitations")

PIT = [{"kind": "inner", "width_mm": 1.0, "depth_mm": 0.1}]


def record(s, tier, fs, seconds=1.0, skip=0.2, axis=-1):
    """``seconds`` of ``s`` on ``tier`` at ``fs`` Hz after ``skip`` s, one axis."""
    return Simulator(s, fidelity=tier, seed=0, sample_rate=fs).advance(int((seconds + skip) * fs)).accel[int(skip * fs):, axis]


def said(d):
    return f"{d['verdict']} {({k: round(v, 1) for k, v in d['scores'].items()})}"


def fast():
    """The fixed 2-5 kHz band against the band the detector chooses, 1 s after 0.2 s."""
    for rpm, tiers, fs in [(30000, ("kinematic",), 15000.0), (40000, ("kinematic", "skidding"), 15000.0),
                           (50000, ("kinematic",), 15000.0), (40000, ("kinematic", "skidding"), 20000.0)]:
        s = custom_scene("6000-size", rpm, 300, PIT)
        ff, res = s.fault_frequencies(), s.structure.resonator_hz
        band, why = env.detector_band(ff, fs, res)
        for tier in tiers:
            y = record(s, tier, fs)
            print(f"{rpm} rpm {tier} at {fs:g} Hz, BPFI {ff['bpfi']:.0f} Hz: 2-5 kHz {said(env.diagnose(y, fs, ff, (2000.0, 5000.0)))}; "
                  f"chosen {band and env.band_words(band)} {said(env.diagnose(y, fs, ff, resonance_hz=res)) if band else why}")


def scan():
    """Every band from 2 to 6.75 kHz in 0.5 kHz steps at 40 000 rpm, 15 kHz, kinematic tier:
    the BPFO line (Z x shaft - BPFI) wins in each."""
    s = custom_scene("6000-size", 40000, 300, PIT)
    ff, fs = s.fault_frequencies(), 15000.0
    y = record(s, "kinematic", fs)
    for lo in range(2000, 6001, 500):
        row = []
        for hi in range(lo + 1000, 7001, 500):
            lines = env.fault_lines(y, fs, ff, band=(lo, min(hi, 6750)))
            row.append(f"{min(hi, 6750)}: {env.verdict_of(lines)['verdict']} x{lines['bpfo'].prominence:.0f}/"
                       f"x{lines['bpfi'].prominence:.0f}")
        print(lo, " | ".join(row))


def low_rate():
    """The ER-16K's scenes at 1600-8000 rpm at 1-8 kHz: the clipped default band's verdict and
    the chosen band's (2 s after 0.2 s, the vertical axis, kinematic tier, seed 1)."""
    for name in ("er16k_outer_race", "er16k_inner_race", "er16k_healthy"):
        base = load_scene(name)
        for rpm in (1600, 4000, 8000):
            s = dataclasses.replace(base, shaft_speed=rpm * 2 * math.pi / 60)
            ff, res = s.fault_frequencies(), s.structure.resonator_hz
            for fs in (1000.0, 2000.0, 4000.0, 8000.0):
                y = Simulator(s, fidelity="kinematic", seed=1, sample_rate=fs).advance(int(2.2 * fs)).accel[int(0.2 * fs):, 1]
                band, _why = env.detector_band(ff, fs, res)
                print(f"{name} {rpm} rpm at {fs:g} Hz: clipped {env.band_words(env.envelope_band(fs))} "
                      f"{said(env.diagnose(y, fs, ff, (2000.0, 5000.0)))} | chosen "
                      f"{env.band_words(band) + ' ' + said(env.diagnose(y, fs, ff, band)) if band else 'none: no verdict'}")


def resonance():
    """``er16k_inner_race`` at 4000-10 000 rpm, 15 kHz: bands with the 3.8 kHz resonator inside
    and without it (2 s after 0.2 s, the vertical axis, kinematic tier, seed 1)."""
    base = load_scene("er16k_inner_race")
    for rpm in (4000, 6000, 8000, 10000):
        s = dataclasses.replace(base, shaft_speed=rpm * 2 * math.pi / 60)
        ff, fs = s.fault_frequencies(), 15000.0
        y = Simulator(s, fidelity="kinematic", seed=1, sample_rate=fs).advance(int(2.2 * fs)).accel[int(0.2 * fs):, 1]
        print(f"{rpm} rpm: " + " | ".join(f"{env.band_words(band)} {said(env.diagnose(y, fs, ff, band))}"
                                          for band in [(2000.0, 5000.0), (3000.0, 6750.0), (1000.0, 6750.0),
                                                       (900.0, 1800.0), (1800.0, 3600.0)]))


def length():
    """The 6000-size bearing at 40 000 rpm, kinematic tier, 15 kHz: records of 0.4-1 s from one
    run, in 2-5 kHz and in 3.375-6.75 kHz (an octave under 0.9 x Nyquist)."""
    s = custom_scene("6000-size", 40000, 300, PIT)
    ff, fs = s.fault_frequencies(), 15000.0
    y = Simulator(s, fidelity="kinematic", seed=0, sample_rate=fs).advance(int(1.2 * fs)).accel[:, -1]
    for start, seconds in [(0.1, 0.4), (0.2, 0.5), (0.6, 0.4), (0.2, 0.8), (0.2, 1.0)]:
        part = y[int(start * fs):int((start + seconds) * fs)]
        print(f"{seconds:g} s from {start:g} s: " + " | ".join(
            f"{env.band_words(band)} {said(env.diagnose(part, fs, ff, band))}" for band in [(2000.0, 5000.0), (3375.0, 6750.0)]))


if __name__ == "__main__":
    parts = {"fast": fast, "scan": scan, "low_rate": low_rate, "resonance": resonance, "length": length}
    for name in sys.argv[1:] or parts:
        parts[name]()
