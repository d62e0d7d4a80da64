"""Accelerometer chain: anti-aliasing, noise density, clipping, sensor resonance, delay."""
import math

import numpy as np
import pytest

from bearing_sim_ros.physics.sensor import AccelerometerChain
from bearing_sim_ros.scene import Sensor

FS = 15000.0
M = 4


def feed(chain, signal_fn, seconds=1.0):
    n = int(seconds * FS)
    t = np.arange((n + chain.lookahead_samples) * M) / (FS * M)
    x = signal_fn(t)
    acc = np.stack([x, x], axis=1)
    head = chain.lookahead_samples * M
    chain.prime(acc[:head])
    return chain.process(acc[head:], 0)


def test_tone_above_nyquist_does_not_fold_back():
    # 9 kHz at a 15 kHz output would alias to 6 kHz; the chain must remove it (>= 60 dB)
    chain = AccelerometerChain(Sensor(), FS, M, 0)
    out = feed(chain, lambda t: 100.0 * np.sin(2 * math.pi * 9000.0 * t))
    assert np.std(out[200:, 1]) < 100.0 / math.sqrt(2) * 1e-3
    for f_hz in (7600.0, 11000.0, 20000.0):
        chain = AccelerometerChain(Sensor(), FS, M, 0)
        out = feed(chain, lambda t: np.sin(2 * math.pi * f_hz * t))
        assert np.std(out[200:, 1]) < 1.5e-3, f_hz


def test_passband_tone_keeps_amplitude_and_time():
    chain = AccelerometerChain(Sensor(), FS, M, 0)
    f_hz = 3000.0
    out = feed(chain, lambda t: np.sin(2 * math.pi * f_hz * t))
    t_out = np.arange(out.shape[0]) / FS
    expect = np.sin(2 * math.pi * f_hz * t_out)
    # the FIR delay is compensated: sample k is the value at k / FS
    np.testing.assert_allclose(out[100:-100, 1], expect[100:-100], atol=2e-3)


def test_noise_density_is_what_the_scene_says():
    density = 1e-3
    chain = AccelerometerChain(Sensor(noise_density=density), FS, M, 5)
    out = feed(chain, lambda t: 0.0 * t, seconds=2.0)
    # white over 0..FS/2: variance = density^2 * FS / 2
    assert np.std(out[:, 1]) == pytest.approx(density * math.sqrt(FS / 2), rel=0.05)
    assert abs(np.corrcoef(out[:-1, 1], out[1:, 1])[0, 1]) < 0.05      # white
    assert abs(np.corrcoef(out[:, 0], out[:, 1])[0, 1]) < 0.05         # axes independent


def test_clipping_at_the_sensor_range():
    chain = AccelerometerChain(Sensor(range=10.0), FS, M, 0)
    out = feed(chain, lambda t: 50.0 * np.sin(2 * math.pi * 100.0 * t))
    assert out.max() == pytest.approx(10.0) and out.min() == pytest.approx(-10.0)


def test_noisy_samples_never_exceed_the_range_and_are_independent():
    """The sensor saturates after its noise is added: with 0.05 m/s^2/sqrt(Hz) (sigma 4.3 m/s^2
    at 15 kHz) on a 50 m/s^2 tone and a 10 m/s^2 range, no sample lies outside +-10 m/s^2, and
    the range is reached on both sides.  Without signal the noise is white in the strong sense:
    a sample tells nothing about the next one, so no function of one (x, y, x^2, y^2, |a|^2, its
    direction atan2(y, x)) correlates with any of the next (|r| < 0.03, 5 standard errors for
    30000 samples), not only the samples themselves."""
    chain = AccelerometerChain(Sensor(range=10.0, noise_density=0.05), FS, M, 3)
    out = feed(chain, lambda t: 50.0 * np.sin(2 * math.pi * 100.0 * t))
    assert np.abs(out).max() <= 10.0 and out.max() == 10.0 and out.min() == -10.0
    chain = AccelerometerChain(Sensor(noise_density=1e-3), FS, M, 5)
    out = feed(chain, lambda t: 0.0 * t, seconds=2.0)
    x, y = out[:, 0], out[:, 1]
    features = [x, y, x * x, y * y, x * x + y * y, np.arctan2(y, x)]
    for f in features:
        for g in features:
            r = np.corrcoef(f[:-1], g[1:])[0, 1]
            assert abs(r) < 0.03, r


def test_sensor_resonance_lifts_its_band():
    """A mounted resonance at 6.5 kHz raises a 6 kHz tone by the analog |H| = w^2 / |w^2 - W^2 +
    2 j zeta w W| (5.74 at zeta 0.05; the damping sets it: 4.2 at twice the damping) and leaves
    500 Hz almost unchanged."""
    def gain(f_hz, sensor):
        chain = AccelerometerChain(sensor, FS, M, 0)
        out = feed(chain, lambda t: np.sin(2 * math.pi * f_hz * t))
        return np.std(out[500:, 1]) * math.sqrt(2)

    def analog(f_hz, sensor):
        w, s = 2 * math.pi * sensor.resonance_hz, 2j * math.pi * f_hz
        return abs(w * w / (s * s + 2 * sensor.damping_ratio * w * s + w * w))
    res = Sensor(resonance_hz=6500.0, damping_ratio=0.05)
    assert gain(500.0, res) == pytest.approx(analog(500.0, res), rel=0.02)
    assert gain(6000.0, res) == pytest.approx(analog(6000.0, res), rel=0.02)


def _assert_chunks_equal_one_call(sensor, seed):
    """3000 output samples of white input through two chains of ``sensor``: in one call, and in
    chunks of 7, 150, 1, 842 and the rest: the same bits."""
    x = np.random.default_rng(seed).standard_normal((3000 * M + 200, 2))
    a, b = AccelerometerChain(sensor, FS, M, 1), AccelerometerChain(sensor, FS, M, 1)
    head = a.lookahead_samples * M
    a.prime(x[:head])
    b.prime(x[:head])
    whole = a.process(x[head:head + 3000 * M], 0)
    parts, i = [], 0
    for n in (7, 150, 1, 842):
        parts.append(b.process(x[head + i * M:head + (i + n) * M], i))
        i += n
    parts.append(b.process(x[head + i * M:head + 3000 * M], i))
    np.testing.assert_array_equal(np.concatenate(parts), whole)


def test_chunked_processing_equals_one_call():
    _assert_chunks_equal_one_call(Sensor(noise_density=1e-3, resonance_hz=22000.0), 0)


def test_sensor_resonance_gain_in_band_does_not_depend_on_the_internal_rate():
    """A 22 kHz sensor (seed 000) lifts a 5 kHz tone by |H(5 kHz)| = 1.054: the same at 4x and 16x
    the output rate (the former bilinear design gave 1.01 at 4x: its pre-warping at the
    resonance compressed the band below it)."""
    res = Sensor(resonance_hz=22000.0, damping_ratio=0.05)
    w, s = 2 * math.pi * 22000.0, 2j * math.pi * 5000.0
    expect = abs(w * w / (s * s + 2 * 0.05 * w * s + w * w))
    for m in (4, 16):
        chain = AccelerometerChain(res, FS, m, 0)
        n = int(FS)
        t = np.arange((n + chain.lookahead_samples) * m) / (FS * m)
        x = np.sin(2 * math.pi * 5000.0 * t)
        head = chain.lookahead_samples * m
        chain.prime(np.stack([x[:head], x[:head]], axis=1))
        out = chain.process(np.stack([x[head:], x[head:]], axis=1), 0)
        gain = np.std(out[1000:, 1]) * math.sqrt(2)
        assert gain == pytest.approx(expect, rel=2e-3), m


def test_resonance_design_matches_the_analog_response_over_the_band():
    from scipy.signal import freqz

    from bearing_sim_ros.physics.sensor import design_resonance

    f = np.linspace(0.0, 0.5 * FS, 200)
    w, s = 2 * math.pi * 22000.0, 2j * math.pi * f
    analog = w * w / (s * s + 2 * 0.05 * w * s + w * w)
    for rate, tol in ((60000.0, 2e-3), (480000.0, 1e-5)):
        b, a = design_resonance(22000.0, 0.05, rate, 0.5 * FS)
        _, digital = freqz(b, a, worN=f, fs=rate)
        assert np.max(np.abs(digital / analog - 1)) < tol, rate


def test_vectorised_fir_gives_the_bits_of_the_plain_loop():
    """The FIR is compiled with the SLP vectoriser; lane-wise packing must not change a bit."""
    from numba import njit

    from bearing_sim_ros.physics.sensor import _polyphase

    chain = AccelerometerChain(Sensor(), FS, M, 0)
    flat = np.random.default_rng(2).standard_normal(2 * (3000 * M + chain.taps.size + 8))
    fast, plain = np.empty((3000, 2)), np.empty((3000, 2))
    _polyphase(flat, chain._taps2, M, 0, 3000, fast)
    njit(_polyphase.py_func)(flat, chain._taps2, M, 0, 3000, plain)
    np.testing.assert_array_equal(fast, plain)


@pytest.mark.parametrize("m, first", [(4, 0), (4, 7), (8, 3), (2, 5), (3, 1)])
def test_fir_reads_the_same_taps_on_both_paths(m, first):
    """Decimations that are multiples of 4 read the buffer through one view of the whole stretch,
    others through a view per output sample: both give, bit for bit, the documented sum (eight
    lanes accumulated in tap order, then paired) for any start row."""
    from bearing_sim_ros.physics.sensor import _polyphase

    chain = AccelerometerChain(Sensor(), FS, m, 0)
    taps2 = chain._taps2
    n_out = 503             # not a multiple of 4: the four-output passes and the rest
    flat = np.random.default_rng(m).standard_normal(2 * (first + n_out * m) + taps2.size + 16)
    got = np.empty((n_out, 2))
    _polyphase(flat, taps2, m, first, n_out, got)
    want = np.empty((n_out, 2))
    for i in range(n_out):
        seg = flat[2 * (first + i * m):2 * (first + i * m) + taps2.size].reshape(taps2.shape)
        lanes = np.cumsum(taps2 * seg, axis=0)[-1]          # sequential, in tap order
        want[i, 0] = (lanes[0] + lanes[2]) + (lanes[4] + lanes[6])
        want[i, 1] = (lanes[1] + lanes[3]) + (lanes[5] + lanes[7])
    np.testing.assert_array_equal(got, want)


def test_the_sensor_resonance_lifts_the_horizontal_axis_as_the_vertical():
    """Both axes go through the same mounted resonance: a 6 kHz tone on x under a 6.5 kHz sensor
    comes out at the analog |H| = w^2 / |w^2 - W^2 + 2 j zeta w W| (5.74 at zeta 0.05), as on
    y, and the same input on both gives the same samples on both (their recursions are separate
    lines of one loop; the resonance tests above read y only)."""
    res = Sensor(resonance_hz=6500.0, damping_ratio=0.05)
    w, s = 2 * math.pi * 6500.0, 2j * math.pi * 6000.0
    analog = abs(w * w / (s * s + 2 * 0.05 * w * s + w * w))
    out = feed(AccelerometerChain(res, FS, M, 0), lambda t: np.sin(2 * math.pi * 6000.0 * t))
    assert np.std(out[500:, 0]) * math.sqrt(2) == pytest.approx(analog, rel=0.02)
    np.testing.assert_array_equal(out[:, 0], out[:, 1])


@pytest.mark.parametrize("axes, column", [(("x",), 0), (("y",), 1)])
def test_a_one_axis_sensor_outputs_that_axis(axes, column):
    """A sensor with one axis outputs one column, that axis's: the same samples (physics, noise
    and all, for one seed) as that column of the two-axis sensor, not the two columns under one
    name.  Which column is which is the physics': the pit at 6 o'clock under a downward load and
    the scene's unit resonator act vertically, so y carries most of the signal (6.8x x's RMS)."""
    import dataclasses

    from bearing_sim_ros import Simulator, load_scene

    scene = load_scene("er16k_outer_race")
    both = Simulator(scene, fidelity="kinematic", seed=4).advance(300)
    one = Simulator(dataclasses.replace(scene, sensor=dataclasses.replace(scene.sensor, axes=axes)),
                    fidelity="kinematic", seed=4).advance(300)
    assert one.accel_channels == (f"accel_{axes[0]}",) and one.accel.shape == (300, 1)
    np.testing.assert_array_equal(one.accel[:, 0], both.accel[:, column])
    assert np.std(both.accel[:, 1]) > 3 * np.std(both.accel[:, 0])


def test_the_chain_starts_at_rest():
    """Before t = 0 the sensor mount is at rest: no input gives exactly 0 from the first output
    sample on, whose FIR reaches back before t = 0 (a buffer not zeroed there made a start
    transient in the first lookahead samples)."""
    chain = AccelerometerChain(Sensor(resonance_hz=22000.0), FS, M, 0)
    out = feed(chain, lambda t: 0.0 * t, seconds=0.1)
    assert chain.lookahead_samples > 10
    np.testing.assert_array_equal(out, 0.0)


def test_the_noise_of_two_seeds_is_independent():
    """Each seed draws its own noise: between seeds 1 and 2 neither the samples nor their squared
    magnitudes x^2 + y^2 correlate (|r| < 0.03, 5 standard errors for 30000 samples); a seed
    that reached only one of the two uniforms of a Box-Muller pair gave every seed the same
    magnitudes (r = 1), only their directions differed."""
    a = feed(AccelerometerChain(Sensor(noise_density=1e-3), FS, M, 1), lambda t: 0.0 * t, seconds=2.0)
    b = feed(AccelerometerChain(Sensor(noise_density=1e-3), FS, M, 2), lambda t: 0.0 * t, seconds=2.0)
    for f, g in ((a[:, 0], b[:, 0]), (a[:, 1], b[:, 1]), ((a * a).sum(axis=1), (b * b).sum(axis=1))):
        assert abs(np.corrcoef(f, g)[0, 1]) < 0.03


def _complex_gain(sensor, f_hz, m=M):
    """The chain's complex gain at ``f_hz`` (a 1 s tone through it; its sine and cosine parts
    fitted after the start), and the sensor's analog H there."""
    chain = AccelerometerChain(sensor, FS, m, 0)
    n = int(FS)
    t = np.arange((n + chain.lookahead_samples) * m) / (FS * m)
    x = np.sin(2 * math.pi * f_hz * t)
    head = chain.lookahead_samples * m
    chain.prime(np.stack([x[:head], x[:head]], axis=1))
    out = chain.process(np.stack([x[head:], x[head:]], axis=1), 0)[1000:, 1]
    t_out = np.arange(1000, n) / FS
    basis = np.stack([np.sin(2 * math.pi * f_hz * t_out), np.cos(2 * math.pi * f_hz * t_out)], axis=1)
    sin_part, cos_part = np.linalg.lstsq(basis, out, rcond=None)[0]
    w, s = 2 * math.pi * sensor.resonance_hz, 2j * math.pi * f_hz
    return complex(sin_part, cos_part), w * w / (s * s + 2 * sensor.damping_ratio * w * s + w * w)


@pytest.mark.parametrize("resonance_hz", [27000.0, 30000.0, 45000.0, 100000.0])
@pytest.mark.parametrize("damping_ratio", [0.02, 0.3])
def test_a_resonance_above_the_chains_reach_still_lifts_the_band(resonance_hz, damping_ratio):
    """A sensor resonance at or above 0.45 x the internal rate (27 kHz at 15 kHz output, 4x)
    cannot be a biquad there; it was left out, the sensor taken as ideal (a 30 kHz sensor's 4 %
    at 6 kHz lost).  Its lift over the band is folded into the anti-aliasing taps: the chain's
    complex gain (magnitude and phase) at 1, 4 and 6 kHz is the analog H's within 3e-4 (the
    anti-aliasing filter's own ripple), where leaving it out was 0.4 to 5 % off."""
    sensor = Sensor(resonance_hz=resonance_hz, damping_ratio=damping_ratio)
    for f_hz in (1000.0, 4000.0, 6000.0):
        got, analog = _complex_gain(sensor, f_hz)
        assert abs(got - analog) < 3e-4, (f_hz, got, analog)
    assert abs(_complex_gain(sensor, 6000.0)[1] - 1.0) > 4e-3      # the test can fail: there is a lift


def test_the_resonances_lift_is_continuous_across_the_biquads_reach():
    """Just below 0.45 x the internal rate the resonance is a biquad, just above it the folded
    FIR: a 26.9 and a 27.1 kHz sensor lift 6 kHz as the analog responses do (5.3 % and 5.2 %),
    where the step was from 5.3 % to none."""
    below, above = (_complex_gain(Sensor(resonance_hz=f, damping_ratio=0.05), 6000.0) for f in (26900.0, 27100.0))
    assert abs(below[0] - below[1]) < 1e-3 and abs(above[0] - above[1]) < 1e-3, (below, above)
    assert abs(abs(below[0]) - abs(above[0])) < 2e-3


def test_chunked_processing_equals_one_call_with_the_folded_resonance():
    """The folded resonance reaches ahead (the lookahead grows by one output sample): chunks of
    any size still give the one call's bits, and the delay is still compensated (a 3 kHz tone
    through a 100 kHz sensor is where its analog response puts it: 3e-3 rad behind)."""
    sensor = Sensor(noise_density=1e-3, resonance_hz=40000.0)
    assert (AccelerometerChain(sensor, FS, M, 1).lookahead_samples
            == AccelerometerChain(Sensor(), FS, M, 1).lookahead_samples + 1)
    _assert_chunks_equal_one_call(sensor, 3)
    sensor = Sensor(resonance_hz=100000.0)
    out = feed(AccelerometerChain(sensor, FS, M, 0), lambda t: np.sin(2 * math.pi * 3000.0 * t))
    w, s = 2 * math.pi * sensor.resonance_hz, 2j * math.pi * 3000.0
    analog = w * w / (s * s + 2 * sensor.damping_ratio * w * s + w * w)
    expect = abs(analog) * np.sin(2 * math.pi * 3000.0 * np.arange(out.shape[0]) / FS + np.angle(analog))
    np.testing.assert_allclose(out[100:-100, 1], expect[100:-100], atol=5e-4)


def test_the_band_fitted_resonance_taps_match_the_analog_response_over_the_band():
    """``resonance_band_taps``' docstring: at 60 kHz over 7.5 kHz, within 3e-5 of H for 27 kHz to
    1 MHz and damping ratios 0.02 to 0.7 (the fit alone, without the anti-aliasing filter)."""
    from bearing_sim_ros.physics.sensor import RESONANCE_TAPS_REACH, resonance_band_taps

    rate, band = 60000.0, 7500.0
    f = np.linspace(0.0, band, 301)
    delays = np.arange(-RESONANCE_TAPS_REACH, RESONANCE_TAPS_REACH + 1)
    for f_res in (27000.0, 30000.0, 60000.0, 1e6):
        for zeta in (0.02, 0.1, 0.7):
            g = resonance_band_taps(f_res, zeta, rate, band)
            w, s = 2 * math.pi * f_res, 2j * math.pi * f
            analog = w * w / (s * s + 2 * zeta * w * s + w * w)
            fitted = np.exp(-2j * math.pi * np.outer(f, delays) / rate) @ g
            assert np.max(np.abs(fitted - analog)) < 3e-5, (f_res, zeta)


def test_the_antialias_taps_are_scipys_kaiser_design_bit_for_bit():
    """``design_antialias`` writes out ``scipy.signal.kaiserord`` and ``firwin`` (importing
    ``scipy.signal`` cost 0.4-1.7 s of every process's start): the same taps to the last bit for
    every decimation from 1 to 128, so that no sample moves."""
    from scipy.signal import firwin, kaiserord

    from bearing_sim_ros.physics.sensor import AA_ATTEN_DB, AA_PASS, AA_STOP, design_antialias

    for m in range(1, 129):
        numtaps, beta = kaiserord(AA_ATTEN_DB, 2.0 * (AA_STOP - AA_PASS) / m)
        d = int(math.ceil((numtaps - 1) / 2 / m)) * m
        expected = firwin(2 * d + 1, (AA_PASS + AA_STOP) / m, window=("kaiser", beta))
        assert np.array_equal(design_antialias(m), expected), m


def test_a_simulator_starts_without_importing_scipy_signal():
    """A node, a render or a run builds a Simulator, and nothing of it needs ``scipy.signal``
    (the envelope analysis of ``monitor``, ``report`` and ``run``'s summary imports it when it
    runs): its import was the largest single part of a start with the kernels cached."""
    import subprocess
    import sys

    code = ("import sys; from bearing_sim_ros import Simulator; "
            "import bearing_sim_ros.nodes.bearing_sim_node, bearing_sim_ros.recording.render; "
            "sim = Simulator('er16k_outer_race'); sim.prepare_switches(); sim.advance(150); "
            "print(sorted(m for m in sys.modules if m.startswith('scipy.signal')))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=600)
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip() == "[]", out.stdout
