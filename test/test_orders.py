"""Order tracking of the envelope (``analysis.orders``) on synthetic signals whose speed ramps."""
from __future__ import annotations

import math

import numpy as np
import pytest

from bearing_sim_ros.analysis import orders
from bearing_sim_ros.analysis.envelope import NO_BAND, NoBand, diagnose

FS = 15000.0
CAGE_RATIO = 0.397          # cage speed over shaft speed (ER-16K at pure rolling)
BALLS = 9
# fault frequencies at a shaft speed of 1 Hz: FTF, BPFO = Z FTF, BPFI = Z (1 - FTF), BSF
PER_SHAFT_HZ = {"ftf": CAGE_RATIO, "bpfo": BALLS * CAGE_RATIO, "bpfi": BALLS * (1 - CAGE_RATIO), "bsf": 2.32}


def _ramp(f0_hz: float, f1_hz: float, duration_s: float):
    """(shaft angle rad, shaft speed rad/s) as functions of t (s) of a linear ramp f0 -> f1."""
    rate = (f1_hz - f0_hz) / duration_s
    return (lambda t: 2 * math.pi * (f0_hz * t + 0.5 * rate * t * t),
            lambda t: 2 * math.pi * (f0_hz + rate * t))


def _impacts(angle, duration_s: float, per_rev: float, seed: int = 0) -> np.ndarray:
    """A signal at FS Hz: a 3.8 kHz ring (decaying in 1 ms) at every 1/``per_rev`` of a shaft
    revolution along ``angle`` (t), plus white noise."""
    t = np.arange(int(duration_s * FS)) / FS
    theta = angle(t)
    hits = np.flatnonzero(np.diff(np.floor(theta / (2 * math.pi) * per_rev)) > 0) + 1
    train = np.zeros(t.size)
    train[hits] = 1.0
    k = np.arange(int(0.005 * FS)) / FS
    ring = np.exp(-k / 1e-3) * np.sin(2 * math.pi * 3800.0 * k)
    noise = np.random.default_rng(seed).normal(0.0, 0.05, t.size)
    return np.convolve(train, ring)[:t.size] + noise, t


def _state(angle, speed, duration_s: float, rate_hz: float = 50.0):
    """``state`` at ``rate_hz`` as the node gives it: stamps s, shaft and cage angles wrapped to
    [0, 2 pi) (as a JointState may), their speeds."""
    t = np.arange(1, int(duration_s * rate_hz) + 1) / rate_hz
    return (t, np.mod(angle(t), 2 * math.pi), speed(t), np.mod(CAGE_RATIO * angle(t), 2 * math.pi),
            CAGE_RATIO * speed(t))


def test_the_angle_is_unwrapped_with_the_speeds_where_the_shaft_turns_several_times_between_states():
    """At 10000 rpm the shaft turns 3.3 times between two 50 Hz states: ``np.unwrap`` cannot tell
    those turns, the speeds can; a linear ramp's angle (a parabola) is exact on the Hermite curve."""
    angle, speed = _ramp(100.0, 200.0, 2.0)
    t, shaft, shaft_w, _, _ = _state(angle, speed, 2.0)
    assert np.max(np.abs(np.unwrap(shaft) - angle(t))) > 100.0
    unwrapped = orders.unwrapped_angles(t, shaft, shaft_w)
    assert np.allclose(unwrapped - unwrapped[0], angle(t) - angle(t[0]), atol=1e-9)
    between = np.linspace(t[0], t[-1], 5001)
    assert np.allclose(orders.angle_at(between, t, unwrapped, shaft_w) - unwrapped[0],
                       angle(between) - angle(t[0]), atol=1e-8)
    # without recorded angles (another tool's JointState): the speeds' integral
    assert np.allclose(orders.unwrapped_angles(t, np.full(t.size, np.nan), shaft_w), angle(t) - angle(t[0]))


@pytest.mark.parametrize("fault, per_rev", [("outer", PER_SHAFT_HZ["bpfo"]), ("inner", PER_SHAFT_HZ["bpfi"])])
def test_a_fault_line_smeared_by_a_ramp_in_hz_stands_in_orders(fault, per_rev):
    """Impacts at BPFO (or BPFI) of a shaft ramped from 1000 to 3000 rpm over 4 s: the envelope
    spectrum in Hz smears the line over 120 Hz and finds none; in orders it stands at its order,
    far above the threshold, the other lines at the floor."""
    angle, speed = _ramp(1000 / 60, 3000 / 60, 4.0)
    x, t = _impacts(angle, 4.0, per_rev)
    mean_hz = {k: v * 2000 / 60 for k, v in PER_SHAFT_HZ.items()}
    assert diagnose(x, FS, mean_hz)["verdict"] == "healthy"
    state_t, shaft, shaft_w, cage, cage_w = _state(angle, speed, 4.0)
    result, why = orders.order_diagnose(x, FS, t, state_t, shaft, shaft_w, cage, cage_w, PER_SHAFT_HZ, BALLS)
    assert why == "" and result["verdict"] == fault, result["scores"]
    key = {"outer": "bpfo", "inner": "bpfi"}[fault]
    assert result["lines"][key].found_hz == pytest.approx(per_rev, rel=2e-3)
    assert result["scores"][fault] > 50 and max(v for k, v in result["scores"].items() if k != fault) < 4
    assert result["shaft_rpm"] == (pytest.approx(1010), pytest.approx(3000))      # the states at 0.02 .. 4 s
    assert result["start_s"] == pytest.approx(0.02) and result["revolutions"] == pytest.approx(133.3 - 0.3, abs=0.2)


def test_noise_alone_is_healthy_in_orders():
    angle, speed = _ramp(1000 / 60, 3000 / 60, 4.0)
    x = np.random.default_rng(3).normal(0.0, 1.0, int(4.0 * FS))
    t = np.arange(x.size) / FS
    result, why = orders.order_diagnose(x, FS, t, *_state(angle, speed, 4.0), PER_SHAFT_HZ, BALLS)
    assert why == "" and result["verdict"] == "healthy", result["scores"]


def test_what_cannot_be_order_tracked_says_why():
    """Too few or too sparse states (a low state_rate), a shaft that slows to a stop, a cage
    whose skid changes (the lines move in orders too): no result, one line saying why."""
    angle, speed = _ramp(1000 / 60, 3000 / 60, 4.0)
    t, _, shaft_w, _, cage_w = _state(angle, speed, 4.0)
    assert orders.untrackable(t, shaft_w, cage_w, 0.0, 4.0) == ""
    assert "0 state samples" in orders.untrackable(t[:0], shaft_w[:0], cage_w[:0], 0.0, 4.0)
    sparse = slice(None, None, 10)       # 5 Hz
    assert "state samples up to 0.2 s apart" in orders.untrackable(t[sparse], shaft_w[sparse], cage_w[sparse], 0.0, 4.0)
    stopping = shaft_w[::-1] - shaft_w.min() + 1.0
    assert "order tracking needs it to turn one way" in orders.untrackable(t, stopping, CAGE_RATIO * stopping, 0.0, 4.0)
    skidding = cage_w * np.linspace(1.0, 0.93, t.size)
    assert "the cage-to-shaft speed ratio moves by 6.5 %" in orders.untrackable(t, shaft_w, skidding, 0.0, 4.0)
    x, times = _impacts(angle, 4.0, PER_SHAFT_HZ["bpfo"])
    assert orders.order_diagnose(x, FS, times, t[sparse], np.full(t[sparse].size, np.nan), shaft_w[sparse],
                                 np.full(t[sparse].size, np.nan), cage_w[sparse], PER_SHAFT_HZ, BALLS)[0] is None


def test_where_no_band_serves_the_lines_the_reason_says_so_by_its_type():
    """A run-up from 2000 to 3000 rpm sampled at 1 kHz: at its fastest the fault lines leave the
    envelope detector no band under 0.9 x Nyquist, and ``order_diagnose``'s reason is a
    ``envelope.NoBand`` (the monitor counts such windows apart by that type, not by its words);
    a reason of the states (too sparse to track) is not."""
    angle, speed = _ramp(2000 / 60, 3000 / 60, 2.0)
    x, times = _impacts(angle, 2.0, PER_SHAFT_HZ["bpfo"])
    state = _state(angle, speed, 2.0)
    result, why = orders.order_diagnose(x[::15], 1000.0, times[::15], *state, PER_SHAFT_HZ, BALLS)
    assert result is None and isinstance(why, NoBand) and why.startswith(NO_BAND + ": "), why
    sparse = tuple(column[::10] for column in state)
    result, why = orders.order_diagnose(x, FS, times, *sparse, PER_SHAFT_HZ, BALLS)
    assert result is None and "state samples up to 0.2 s apart" in why and not isinstance(why, NoBand), why


def _ratio_state(angle, speed, duration_s: float, cage_ratio: float, rate_hz: float = 50.0):
    """``_state`` with the cage at ``cage_ratio`` of the shaft speed."""
    t = np.arange(1, int(duration_s * rate_hz) + 1) / rate_hz
    return (t, np.mod(angle(t), 2 * math.pi), speed(t), np.mod(cage_ratio * angle(t), 2 * math.pi),
            cage_ratio * speed(t))


def test_a_skidding_cages_lines_are_found_at_the_orders_the_recorded_cage_gives():
    """A cage that runs steadily 7 % slower than pure rolling (a skidding tier at high speed and
    light load) puts BPFO at Z x 0.369 = 3.32 orders, not the catalog's 3.57: the orders come
    from the recorded cage-to-shaft angle ratio, and the line is found there, far above the
    threshold (at the catalog's order, 7 % off, the +-1 % search finds nothing)."""
    skid_ratio = 0.93 * CAGE_RATIO
    angle, speed = _ramp(1000 / 60, 3000 / 60, 4.0)
    x, t = _impacts(angle, 4.0, BALLS * skid_ratio)
    result, why = orders.order_diagnose(x, FS, t, *_ratio_state(angle, speed, 4.0, skid_ratio), PER_SHAFT_HZ, BALLS)
    assert why == "" and result["verdict"] == "outer", result["scores"]
    assert result["orders"]["bpfo"] == pytest.approx(BALLS * skid_ratio, rel=1e-6)
    assert result["orders"]["ftf"] == pytest.approx(skid_ratio, rel=1e-6)
    assert result["orders"]["bpfi"] == pytest.approx(BALLS * (1 - skid_ratio), rel=1e-6)
    assert result["lines"]["bpfo"].found_hz == pytest.approx(BALLS * skid_ratio, rel=2e-3)


def test_a_shaft_that_turns_the_other_way_is_order_tracked_alike():
    """A run-up of a reversed shaft (negative angles and speeds in ``state``, as a negative
    shaft_speed gives them) strikes the defect as often per revolution: the same verdict, the line
    at its order and the speeds as positive rpm."""
    forward, forward_speed = _ramp(1000 / 60, 3000 / 60, 4.0)
    x, t = _impacts(forward, 4.0, PER_SHAFT_HZ["bpfo"])

    def backward(time):
        return -forward(time)

    def backward_speed(time):
        return -forward_speed(time)

    result, why = orders.order_diagnose(x, FS, t, *_state(backward, backward_speed, 4.0), PER_SHAFT_HZ, BALLS)
    assert why == "" and result["verdict"] == "outer", (why, result and result["scores"])
    assert result["lines"]["bpfo"].found_hz == pytest.approx(PER_SHAFT_HZ["bpfo"], rel=2e-3)
    assert result["shaft_rpm"] == (pytest.approx(1010), pytest.approx(3000))


def test_a_stretch_is_tracked_from_its_first_sample_with_the_state_before_it():
    """A window cut from a longer recording (1.01 - 3.01 s, states every 20 ms): the state just
    before its first sample (1.00 s) gives the angle there, so the stretch tracked starts at the
    window's first sample, not at the next state 10 ms in; the angles made continuous start at
    the recorded first angle."""
    angle, speed = _ramp(1000 / 60, 3000 / 60, 4.0)
    x, t = _impacts(angle, 4.0, PER_SHAFT_HZ["bpfo"])
    window = (t >= 1.01) & (t < 3.01)
    state = _state(angle, speed, 4.0)
    result, why = orders.order_diagnose(x[window], FS, t[window], *state, PER_SHAFT_HZ, BALLS)
    assert why == "" and result["verdict"] == "outer"
    assert result["start_s"] == pytest.approx(t[window][0]) and result["end_s"] == pytest.approx(t[window][-1])
    state_t, shaft, shaft_w = state[0], state[1], state[2]
    assert orders.unwrapped_angles(state_t, shaft, shaft_w)[0] == shaft[0]


def test_states_over_less_than_the_shortest_record_are_not_tracked():
    """States that span less than ``shortest_record_s`` (0.2 s) of a stretch leave its envelope
    spectrum no neighbourhood around a line: not tracked, saying why."""
    angle, speed = _ramp(1000 / 60, 3000 / 60, 4.0)
    t, _, shaft_w, _, cage_w = _state(angle, speed, 4.0)
    assert "6 state samples in 0.00-0.12 s: order tracking needs the shaft angle over at least 0.2 s" in \
        orders.untrackable(t[:6], shaft_w[:6], cage_w[:6], 0.0, 0.12)


def test_at_a_steady_speed_the_scores_in_orders_are_those_in_hz():
    """At a steady 1800 rpm the resampled envelope is the envelope at 30 x its samples per
    revolution, its segments the detector's 1 s (30 revolutions) and each line's neighbourhood the
    detector's +-20 Hz (+-0.67 orders): the scores in orders are the detector's in Hz (the
    threshold means the same), for the fault line and the floor's lines alike."""
    angle, speed = _ramp(30.0, 30.0, 4.0)
    x, t = _impacts(angle, 4.0, PER_SHAFT_HZ["bpfo"])
    result, why = orders.order_diagnose(x, FS, t, *_state(angle, speed, 4.0), PER_SHAFT_HZ, BALLS)
    in_hz = diagnose(x[t >= 0.02], FS, {k: 30.0 * v for k, v in PER_SHAFT_HZ.items()})
    assert why == "" and result["verdict"] == in_hz["verdict"] == "outer"
    for fault, score in in_hz["scores"].items():
        assert result["scores"][fault] == pytest.approx(score, rel=0.03), (fault, result["scores"], in_hz["scores"])


def test_at_300_rpm_a_ball_pit_whose_cage_sidebands_crowd_its_line_stands_in_orders_as_in_hz():
    """A ball pit meets the load zone once per cage turn: impacts at 2xBSF per revolution whose
    strength follows the cage angle (sin^8: strongest at the bottom, none in the top half).  At
    300 rpm the cage turns 1.985 times a second and those sidebands, 1.985 Hz apart, fill 1 s
    segments' bins (1 Hz, the Hann lobe +-2 Hz) and the floor beside the line: x2.2 in orders and
    in Hz, no fault.  In segments of 8 cage turns (envelope.decision_segment: 20 revolutions, the
    whole 4 s) the line stands above its sidebands, x9.3, "ball", in orders as in Hz (BPFI, 5.427
    orders, x7.7, sits on the line's second cage sideband here: 4.64 + 2 x 0.397)."""
    angle, speed = _ramp(5.0, 5.0, 4.0)
    t = np.arange(int(4.0 * FS)) / FS
    per_rev = 2 * PER_SHAFT_HZ["bsf"]
    hits = np.flatnonzero(np.diff(np.floor(angle(t) / (2 * math.pi) * per_rev)) > 0) + 1
    train = np.zeros(t.size)
    train[hits] = np.maximum(0.0, -np.sin(CAGE_RATIO * angle(t[hits]))) ** 8      # half strength within +-24 deg of the bottom
    k = np.arange(int(0.005 * FS)) / FS
    x = np.convolve(train, np.exp(-k / 1e-3) * np.sin(2 * math.pi * 3800.0 * k))[:t.size]
    x += np.random.default_rng(0).normal(0.0, 0.05, t.size)
    result, why = orders.order_diagnose(x, FS, t, *_state(angle, speed, 4.0), PER_SHAFT_HZ, BALLS)
    in_hz = diagnose(x[t >= 0.02], FS, {k: 5.0 * v for k, v in PER_SHAFT_HZ.items()})
    assert why == "" and result["verdict"] == in_hz["verdict"] == "ball", (result["scores"], in_hz["scores"])
    assert result["scores"]["ball"] == pytest.approx(in_hz["scores"]["ball"], rel=0.1)
