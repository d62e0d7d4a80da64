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


def test_chunked_processing_equals_one_call():
    rng = np.random.default_rng(0)
    x = rng.standard_normal((3000 * M + 200, 2))
    a = AccelerometerChain(Sensor(noise_density=1e-3, resonance_hz=22000.0), FS, M, 1)
    b = AccelerometerChain(Sensor(noise_density=1e-3, resonance_hz=22000.0), FS, M, 1)
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
