"""Output rates below 15 kHz: the physics does not get coarser with the output.

The tiers' steps and the sensor chain's anti-aliasing were made at 15 kHz.  Below it the
simulator runs the tiers at the smallest whole multiple of the output rate that reaches 15 kHz
and the chain decimates to the output (``simulator.PHYSICS_RATE_MIN``).  Before, a 1 kHz output
meant 1 ms samples for the physics and a chain at 4 kHz that folded the 3.8 kHz pedestal
resonance into the band: 0-400 Hz came out at 25x (skidding) and 3.5x (kinematic) the vertical
level of the same scene at 15 kHz.
"""
from dataclasses import replace

import numpy as np
import pytest
from scipy.signal import welch

from bearing_sim_ros import Simulator, load_scene
from bearing_sim_ros.simulator import PHYSICS_RATE_MIN, physics_rate_factor

FS = 15000.0


def _quiet(name):
    scene = load_scene(name)
    return replace(scene, sensor=replace(scene.sensor, noise_density=0.0))


def _run(scene, fs, fidelity, seconds, settle=0.3, chunk=None):
    sim = Simulator(scene, sample_rate=fs, fidelity=fidelity)
    sim.advance(int(settle * fs))
    n = int(seconds * fs)
    if chunk is None:
        return sim, [sim.advance(n)]
    return sim, [sim.advance(min(chunk, n - k)) for k in range(0, n, chunk)]


def _band_rms(x, fs, hi):
    f, p = welch(x, fs, nperseg=int(fs / 4), axis=0)
    keep = f <= hi
    return np.sqrt(p[keep].sum(axis=0) * (f[1] - f[0]))


def test_the_physics_rate_is_the_output_rate_or_a_whole_multiple_reaching_15_khz():
    assert PHYSICS_RATE_MIN == FS
    assert [physics_rate_factor(fs) for fs in (1000.0, 2000.0, 7000.0, 12000.0, 14999.0, 15000.0, 48000.0)] \
        == [15, 8, 3, 2, 2, 1, 1]
    sim = Simulator(_quiet("er16k_healthy"), sample_rate=1000.0, fidelity="kinematic")
    assert (sim.physics_rate, sim.physics_per_sample, sim.chain_oversample) == (15000.0, 15, 60)
    assert Simulator(_quiet("er16k_healthy"), sample_rate=48000.0).physics_rate == 48000.0


@pytest.mark.parametrize("fidelity", ["kinematic", "skidding"])
def test_a_low_output_rate_samples_the_same_physics(fidelity):
    """At 1 kHz the tier runs at 15 kHz: its contact forces and cage speed at every output sample
    are the 15 kHz run's at the same time, bit for bit; the acceleration differs only by the
    anti-aliasing filter, so its level below the 1 kHz output's passband edge (400 Hz) is the 15
    kHz run's within 1 % (the old 1 ms step: 3.5x and 25x on the vertical axis)."""
    scene = _quiet("er16k_inner_race")
    low, [a] = _run(scene, 1000.0, fidelity, 2.0)
    high, [b] = _run(scene, FS, fidelity, 2.0)
    assert np.array_equal(a.contact_forces, b.contact_forces[::15])
    assert np.array_equal(a.cage_speed, b.cage_speed[::15])
    level_low = _band_rms(a.accel, 1000.0, 400.0)
    level_high = _band_rms(b.accel, FS, 400.0)
    assert level_high.min() > 0.1                  # there is a signal in the band to compare
    np.testing.assert_allclose(level_low, level_high, rtol=0.01)


def test_a_low_output_rate_is_chunk_invariant():
    scene = _quiet("er16k_outer_race")
    _, whole = _run(scene, 2000.0, "kinematic", 0.5)
    _, parts = _run(scene, 2000.0, "kinematic", 0.5, chunk=37)
    for key in ("accel", "contact_forces", "cage_speed"):
        assert np.array_equal(getattr(whole[0], key), np.concatenate([getattr(p, key) for p in parts]))


def test_a_low_output_rates_skid_ratios_are_those_of_its_own_rows():
    """Below 15 kHz each output row is the physics sample at its own time (the first of its
    ``physics_per_sample``), the skidding tier's extras too: each row's cage skid is the row's
    cage speed against pure rolling (skidding.py's eq. 37), on a speed ramp where neighbouring
    physics samples differ.  Extras from another physics sample than the other series passed."""
    from bearing_sim_ros.scene import RPM

    scene = replace(load_scene("er16k_healthy"), shaft_speed=10000 * RPM, radial_load=(0.0, -10.0))
    sim = Simulator(scene, fidelity="skidding", sample_rate=5000.0)
    assert sim.physics_per_sample == 3
    sim.advance(100)
    b = sim.advance(100, shaft_speed=9000 * RPM)
    pure = 0.5 * b.shaft_speed * (1.0 - scene.bearing.diameter_ratio)
    np.testing.assert_allclose(b.extras["cage_skid"], 100.0 * (pure - b.cage_speed) / pure, rtol=0, atol=1e-6)


def test_the_api_takes_a_rate_that_render_and_the_node_refuse_for_their_tables(tmp_path, monkeypatch, capsys):
    """render and the node take multiples of 100 Hz (``messages.batching_error``: a 10 ms table of
    whole samples); the API has no tables, so 15001 Hz runs, in batches of any width, its samples
    contiguous in time.  Render refuses the same rate in one line."""
    from bearing_sim_ros import cli
    from bearing_sim_ros.messages import BATCH_DURATION, STATE_RATE, batching_error

    assert batching_error(15001.0, BATCH_DURATION, STATE_RATE)
    sim = Simulator("er16k_outer_race", sample_rate=15001)
    a, b = sim.advance(150), sim.advance(151)
    assert (a.index0, b.index0, sim.index) == (0, 150, 301)
    assert b.t0 == 150 / 15001.0 and sim.time == 301 / 15001.0
    assert np.isfinite(a.accel).all() and np.isfinite(b.accel).all()
    monkeypatch.chdir(tmp_path)
    assert cli.main(["render", "er16k_outer_race", "--duration", "0.1", "--sample-rate", "15001", "--out", "x.mcap"]) == 2
    assert "multiples of 100 Hz" in capsys.readouterr().err and not any(tmp_path.iterdir())
