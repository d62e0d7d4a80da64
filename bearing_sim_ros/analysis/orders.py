"""Computed order tracking of the envelope: a verdict on a stretch whose speed moves (a run-up, a
coast-down, speed steps), where an envelope spectrum in Hz smears every fault line.

A fault line is a fixed number of events per shaft revolution (an *order*): BPFO = Z x cage speed
and BPFI = Z x (shaft - cage speed), so with the cage-to-shaft speed ratio steady their orders
stay put while the speed moves.  The recipe:

1. the shaft angle as a function of signal time, from the recording's ``state`` (JointState
   ``shaft``: angle and speed at ``state_rate``, 50 Hz by default): unwrapped with the speeds
   (at 10000 rpm the shaft turns 3.3 times between two states, more than ``np.unwrap`` can
   tell), then a cubic Hermite curve through the angles with the speeds as slopes, exact for a
   linear ramp and smooth between the states;
2. the envelope of the accelerometer signal in time (the band-pass is in Hz: the structure's
   resonance does not move with the speed), resampled at equal steps of shaft angle, at least
   as finely as the signal samples it everywhere (no aliasing where the shaft is slowest);
3. its spectrum in orders, averaged over segments of as many revolutions as the shaft turns in
   ``envelope.DEFAULT_SEGMENT`` at its mean speed (or ``envelope.CAGE_TURNS`` cage turns where
   those are more, ``envelope.decision_segment``), each line's neighbourhood as many orders as
   20 Hz is at that speed: the same bins per neighbourhood and segments as the detector in Hz
   gives a steady recording, so ``DETECTION_THRESHOLD`` means the same;
4. the lines at the fault orders (BPFO, BPFI and FTF from the cage-to-shaft angle ratio of
   ``state`` over the stretch, 2xBSF from the ball-spin ratio given) by ``envelope.line_at``,
   and the verdict by ``envelope.verdict_of``.

No ROS here: the report (``analysis.report``) passes the ``state`` samples as arrays.
"""
from __future__ import annotations

import math

import numpy as np

from .envelope import (DEFAULT_SEGMENT, DETECTION_THRESHOLD, STEADY_LINES, averaged_spectrum, decision_segment,
                       detector_band, envelope, envelope_band, fault_targets, line_at, shortest_record_s, spread,
                       verdict_of, with_cage)

NEIGHBOURHOOD_HZ = 20.0         # Hz: the detector's neighbourhood in Hz (envelope.line_at's default)
MAX_STATE_GAP_S = 0.1           # s: states further apart than this leave a speed step between them unseen
SLOWEST_SHARE = 0.1             # the shaft's slowest speed over its fastest below which a stretch is not tracked
MAX_SAMPLES_PER_REV = 1 << 16   # bound on the resampled envelope's samples per revolution


def unwrapped_angles(t_s, angles_rad, speeds_rad_s) -> np.ndarray:
    """``angles_rad`` (a joint's recorded angles at ``t_s``, s, wrapped or not) made continuous:
    each step between two samples takes the multiple of 2 pi that brings it nearest to the
    trapezoid integral of ``speeds_rad_s`` over it (the shaft may turn several times between two
    samples); where the angles are missing (NaN), that integral alone."""
    t_s, angles, speeds = (np.asarray(a, dtype=float) for a in (t_s, angles_rad, speeds_rad_s))
    travelled = 0.5 * (speeds[1:] + speeds[:-1]) * np.diff(t_s)
    if not np.all(np.isfinite(angles)):
        return np.concatenate(([0.0], np.cumsum(travelled)))
    step = np.diff(angles)
    step += 2.0 * math.pi * np.round((travelled - step) / (2.0 * math.pi))
    return angles[0] + np.concatenate(([0.0], np.cumsum(step)))


def angle_at(times_s, state_t_s, angles_rad, speeds_rad_s) -> np.ndarray:
    """A joint's angle (rad) at ``times_s`` (s, within ``state_t_s``): the cubic Hermite curve
    through its continuous ``state`` angles (``unwrapped_angles``) with its speeds (rad/s) as slopes."""
    from scipy.interpolate import CubicHermiteSpline

    return CubicHermiteSpline(state_t_s, angles_rad, speeds_rad_s)(times_s)


def _around(state_t_s, start_s: float, end_s: float) -> slice:
    """The ``state`` samples that span [start_s, end_s]: those in it and the nearest on either
    side (a state gives the angle at its stamp; a window's first one comes a state period in)."""
    first = max(0, int(np.searchsorted(state_t_s, start_s, side="right")) - 1)
    last = int(np.searchsorted(state_t_s, end_s, side="left")) + 1
    return slice(first, min(last, len(state_t_s)))


def untrackable(state_t_s, shaft_w, cage_w, start_s: float, end_s: float) -> str:
    """Why the stretch [start_s, end_s) (s of signal) cannot be order tracked with these
    ``state`` samples (stamps s, shaft and cage speeds rad/s), or "": fewer than two states
    spanning at least ``shortest_record_s`` of it (with the nearest on either side), states more than ``MAX_STATE_GAP_S`` apart (a
    low ``state_rate``: a step between two would be drawn as a smooth turn), a shaft that stops,
    reverses or runs slower than ``SLOWEST_SHARE`` of its fastest, or a cage-to-shaft speed ratio
    that moves by more than ``STEADY_LINES`` (a skid that changes: the lines move in orders too)."""
    state_t_s = np.asarray(state_t_s, dtype=float)
    around = _around(state_t_s, start_s, end_s)
    t, shaft, cage = state_t_s[around], np.asarray(shaft_w, float)[around], np.asarray(cage_w, float)[around]
    shortest = shortest_record_s(NEIGHBOURHOOD_HZ)
    if t.size < 2 or t[-1] - t[0] < shortest:
        return (f"{t.size} state sample{'' if t.size == 1 else 's'} in {start_s:.2f}-{end_s:.2f} s: order tracking "
                f"needs the shaft angle over at least {shortest:g} s of it")
    gap = float(np.max(np.diff(t)))
    if gap > MAX_STATE_GAP_S + 1e-9:
        return (f"state samples up to {gap:.3g} s apart: order tracking needs them at most {MAX_STATE_GAP_S:g} s "
                f"apart (state_rate >= {1 / MAX_STATE_GAP_S:g} Hz) to follow the shaft angle")
    sign = np.sign(shaft.mean())
    fastest, slowest = float(np.max(np.abs(shaft))), float(np.min(shaft * sign))
    if sign == 0 or slowest < SLOWEST_SHARE * fastest:
        return (f"the shaft runs from {slowest * sign * 60 / (2 * math.pi):.0f} to "
                f"{fastest * 60 / (2 * math.pi):.0f} rpm in {start_s:.2f}-{end_s:.2f} s: order tracking needs it to turn "
                f"one way at no less than {100 * SLOWEST_SHARE:g} % of its fastest")
    ratio_moves = spread(cage / shaft)
    if ratio_moves > STEADY_LINES:
        return (f"the cage-to-shaft speed ratio moves by {100 * ratio_moves:.1f} % in {start_s:.2f}-{end_s:.2f} s "
                "(the cage's skid changes): the fault lines move in orders of the shaft too")
    return ""


def at_equal_angles(angle, values, per_rev: int) -> np.ndarray:
    """``values`` (taken at the increasing ``angle``, rad) interpolated at equal steps of angle,
    ``per_rev`` per revolution from ``angle[0]``, as many as fit in the span of ``angle``."""
    steps = int((angle[-1] - angle[0]) / (2.0 * math.pi) * per_rev)
    return np.interp(angle[0] + 2.0 * math.pi * np.arange(steps) / per_rev, angle, values)


def order_diagnose(x, fs: float, times_s, state_t_s, shaft_angle, shaft_w, cage_angle, cage_w,
                   per_shaft_hz: dict, balls: int, band="auto", threshold: float = DETECTION_THRESHOLD,
                   spin_shares=None, resonance_hz: float | None = None):
    """The envelope verdict on ``x`` (one channel sampled at ``fs`` Hz, sample ``k`` at signal
    time ``times_s[k]``, s) in orders of the shaft: ``(result, "")``, or ``(None, why not)``
    (``untrackable``).  ``state_t_s`` (s of signal), ``shaft_angle``/``cage_angle`` (rad, NaN
    where not recorded), ``shaft_w``/``cage_w`` (rad/s): the recording's ``state``;
    ``per_shaft_hz``: the fault frequencies at a shaft speed of 1 Hz ({"ftf", "bpfo", "bpfi",
    "bsf"}: the catalog's, or with the recorded ball-spin ratio), of which the cage's three are
    replaced by those of the cage-to-shaft angle ratio over the stretch (``with_cage``, ``balls``).

    The result is ``envelope.verdict_of``'s (``verdict``, ``lines`` with ``expected_hz`` and
    ``found_hz`` in orders, ``scores``) with ``orders`` ({"bpfo", "bpfi", "2bsf", "ftf": order}),
    ``start_s``/``end_s`` (the stretch the states cover), ``shaft_rpm`` (slowest, fastest),
    ``revolutions``, ``spectrum`` (orders, amplitude in the units of ``x``) and ``band`` (the
    envelope's band-pass, Hz).  ``band`` "auto": ``envelope.detector_band`` of the lines in Hz at
    the fastest shaft speed of the stretch (``resonance_hz``: the structure's resonator, Hz, where
    known); where none serves them, ``(None, why)``.

    ``spin_shares``: the balls' spin at each state sample as a share of ``per_shaft_hz``'s BSF
    (None: that BSF throughout).  Steady (a spread up to ``STEADY_LINES``), their mean moves BSF;
    where it moves more, the 2xBSF line is judged on the envelope resampled at equal steps of the
    balls' spin angle (the shaft's speed times the share, integrated), at its order there
    (``ball_tracked`` True): on the skidding tier a step from 1000 to 2000 rpm takes the balls'
    skid from 4.8 % to 3 %, the line moves 2 % in orders of the shaft, out of the +-1 % search,
    and a 0.6 mm ball pit scored x3.5 there (x12 on the balls' angle)."""
    x = np.asarray(x, dtype=float)
    times_s = np.asarray(times_s, dtype=float)
    state_t_s = np.asarray(state_t_s, dtype=float)
    start, end = float(times_s[0]), float(times_s[-1])
    why = untrackable(state_t_s, shaft_w, cage_w, start, end)
    if why:
        return None, why
    around = _around(state_t_s, start, end)
    t, shaft_w, cage_w = state_t_s[around], np.asarray(shaft_w, float)[around], np.asarray(cage_w, float)[around]
    shares = None if spin_shares is None else np.asarray(spin_shares, dtype=float)[around]
    ball_tracked = shares is not None and spread(shares) > STEADY_LINES
    if shares is not None and not ball_tracked and np.all(np.isfinite(shares)) and shares.mean() > 0:
        per_shaft_hz = {**per_shaft_hz, "bsf": per_shaft_hz["bsf"] * float(shares.mean())}
    shaft = unwrapped_angles(t, np.asarray(shaft_angle, float)[around], shaft_w)
    cage = unwrapped_angles(t, np.asarray(cage_angle, float)[around], cage_w)
    ratio = abs((cage[-1] - cage[0]) / (shaft[-1] - shaft[0]))
    if isinstance(band, str) and band == "auto":
        # the band-pass is in Hz: it must serve the lines where they are highest, at the fastest
        fastest = float(np.abs(shaft_w).max()) / (2.0 * math.pi)
        at_fastest = {key: value * fastest for key, value in per_shaft_hz.items()}
        band, why = detector_band(with_cage(at_fastest, balls, fastest, ratio * fastest), fs, resonance_hz)
        if band is None:
            return None, why
    band = envelope_band(fs, band)
    # the envelope in time over the whole stretch (the band-pass is in Hz), then the samples the
    # states span (no extrapolation of the angle before the first or after the last)
    env = envelope(x, fs, band)
    covered = (times_s >= t[0]) & (times_s <= t[-1])
    sign = 1.0 if shaft_w.mean() > 0 else -1.0        # the angle increasing for the resampling
    angle = sign * angle_at(times_s[covered], t, shaft, shaft_w)
    if np.any(np.diff(angle) <= 0):
        return None, (f"the shaft angle drawn through the states does not increase everywhere in {start:.2f}-{end:.2f} s "
                      "(a speed change too abrupt for the state rate)")
    revolutions = (angle[-1] - angle[0]) / (2.0 * math.pi)
    speeds_hz = np.abs(shaft_w) / (2.0 * math.pi)
    mean_hz = revolutions / (times_s[covered][-1] - times_s[covered][0])
    # samples per revolution: at least the signal's rate where the shaft is slowest
    per_rev = int(min(MAX_SAMPLES_PER_REV, math.ceil(fs / max(float(speeds_hz.min()), SLOWEST_SHARE * speeds_hz.max()))))
    resampled = at_equal_angles(angle, env[covered], per_rev)
    # the detector's resolution and neighbourhood in Hz, at the mean speed, in orders; segments of
    # at least CAGE_TURNS cage turns as in Hz (envelope.decision_segment: the lines' cage and shaft
    # sidebands resolved below about 1000 rpm)
    neighbourhood = NEIGHBOURHOOD_HZ / mean_hz
    targets = fault_targets(with_cage(per_shaft_hz, balls, 1.0, ratio))
    segment_revs = decision_segment(targets, DEFAULT_SEGMENT * mean_hz)
    # up to 3.3 x the highest line, as the report's plot of it shows
    max_order = 3.3 * max(targets.values()) + 2 * neighbourhood
    orders, spec = averaged_spectrum(resampled - resampled.mean(), per_rev, max_order, segment_revs)
    lines = {name: line_at(orders, spec, order, neighbourhood_hz=neighbourhood) for name, order in targets.items()}
    if ball_tracked:
        # the balls' spin angle in "shaft revolutions at per_shaft_hz's BSF": 2xBSF holds still
        # there while the skid moves (no recorded angle: the integral of the speeds)
        ball_w = shaft_w * shares
        ball = unwrapped_angles(t, np.full(t.size, np.nan), ball_w)
        ball_angle = sign * angle_at(times_s[covered], t, ball, ball_w)
        if np.all(np.diff(ball_angle) > 0):
            ball_env = at_equal_angles(ball_angle, env[covered], per_rev)
            ball_orders, ball_spec = averaged_spectrum(ball_env - ball_env.mean(), per_rev, max_order, segment_revs)
            lines["2bsf"] = line_at(ball_orders, ball_spec, targets["2bsf"], neighbourhood_hz=neighbourhood)
        else:
            ball_tracked = False
    result = verdict_of(lines, threshold)
    rpm = 60.0 * speeds_hz
    return {**result, "orders": targets, "start_s": float(times_s[covered][0]), "end_s": float(times_s[covered][-1]),
            "shaft_rpm": (float(rpm.min()), float(rpm.max())), "revolutions": float(revolutions),
            "spectrum": (orders, spec), "ball_tracked": bool(ball_tracked), "band": band}, ""
