"""The skidding tier (issue 3): contract, physics, hard cases, seed 000's numbers and trends.

Most tests drive ``SkiddingModel`` with the accelerometer chain directly, so that a solver setting
(``method=``) can be compared with another on the same scene; one test goes through ``Simulator``.
Sensor noise is off everywhere except in the envelope-line test.
"""
from __future__ import annotations

import re
from dataclasses import replace

import numpy as np
import pytest
from conftest import small_bearing

from bearing_sim_ros import Simulator, load_scene
from bearing_sim_ros.analysis.envelope import fault_lines
from bearing_sim_ros.errors import UserError
from bearing_sim_ros.physics import integrators as it
from bearing_sim_ros.physics import skidding as sk
from bearing_sim_ros.physics.kinematic import KinematicModel
from bearing_sim_ros.physics.sensor import AccelerometerChain
from bearing_sim_ros.scene import RPM

FS = 15000.0
G = 9.80665


def make_scene(name="er16k_skidding", rpm=None, load=None, lub=None, **changes):
    sc = load_scene(name)
    changes.setdefault("sensor", replace(sc.sensor, noise_density=0.0))
    if rpm is not None:
        changes["shaft_speed"] = rpm * RPM
    if load is not None:
        changes["radial_load"] = (0.0, -float(load))
    if lub:
        changes["lubrication"] = replace(sc.lubrication, **lub)
    return replace(sc, **changes)


class Run:
    """Output of :func:`run`: accel at the output rate (through the sensor chain), raw accel at
    the internal rate, and the per-output-sample series of the tier."""

    def __init__(self, model, chain):
        self.model = model
        self.chain = chain
        self.index = 0
        self.parts = []

    def cat(self, key):
        return np.concatenate([p[key] for p in self.parts], axis=0)


def run(sc, segments, method=None, solver="default", chunk=0.01):
    """Drive the tier through ``segments`` = [(seconds, rpm, load_N)]: speed and load ramp
    linearly from the previous point to the segment's over its duration."""
    w = sc.shaft_speed
    load = np.array(sc.radial_load, dtype=float)
    model = sk.SkiddingModel(sc, FS, 0, w, load, solver=solver, method=method)
    chain = AccelerometerChain(sc.sensor, FS, 4, 0)
    chain.prime(np.zeros((chain.lookahead_samples * 4, 2)))
    out = Run(model, chain)
    for seconds, rpm, load_n in segments:
        w1, l1 = rpm * RPM, np.array([0.0, -float(load_n)])
        pieces = max(1, int(round(seconds / chunk)))
        n = int(round(seconds * FS / pieces))
        for k in range(pieces):
            a, b = k / pieces, (k + 1) / pieces
            s0, s1 = w + (w1 - w) * a, w + (w1 - w) * b
            q0, q1 = load + (l1 - load) * a, load + (l1 - load) * b
            o = model.advance(4 * n, s0, s1, q0, q1)
            acc = chain.process(o.accel, out.index)
            out.index += n
            out.parts.append({"accel": acc, "raw": o.accel, "cage": o.cage_speed, "qi": o.inner_force,
                              "qo": o.outer_force, "bskid": o.extras["ball_skid"],
                              "cskid": o.extras["cage_skid"], "speed": np.linspace(s0, s1, n, endpoint=False),
                              "rho": np.tile(model.y[sk.NS0 + sk.B_R::sk.NBV][:model.nb], (1, 1)),
                              "pocket": np.tile(_pocket_offsets(model), (1, 1))})
        w, load = w1, l1
    return out


def _pocket_offsets(model):
    y = model.y
    th = y[sk.NS0 + sk.B_TH::sk.NBV][:model.nb]
    return th - y[10] - 2 * np.pi * np.arange(model.nb) / model.nb


def rms(x):
    return np.sqrt(np.mean(np.asarray(x) ** 2, axis=0))


def check_bounded(r, sc, max_load_n):
    """Finite and physically bounded: accelerations, contact loads, cage speed, balls in their
    pockets and within the clearance band."""
    acc, raw = r.cat("accel"), r.cat("raw")
    assert np.all(np.isfinite(acc)) and np.all(np.isfinite(raw))
    assert np.max(np.abs(acc)) <= sc.sensor.range             # the sensor may saturate (+-50 g)
    assert np.max(np.abs(raw)) < 20 * sc.sensor.range          # the pedestal itself stays sane
    q = np.concatenate([r.cat("qi"), r.cat("qo")])
    assert np.all(np.isfinite(q)) and np.all(q >= 0.0)
    w_total = max(max_load_n + sc.structure.shaft_mass * G, 20.0)
    assert q.max() < 10.0 * w_total                       # impacts included
    cage, speed = r.cat("cage"), r.cat("speed")
    theory = sc.bearing.cage_speed(1.0) * np.abs(speed)
    assert np.all(np.abs(cage) <= 1.3 * theory + 0.1 * theory.max() + 1.0)
    b = sc.bearing
    rho = r.cat("rho") - 0.5 * b.pitch_diameter
    assert np.all(np.abs(rho) < abs(b.radial_clearance) + 60e-6)
    assert np.all(np.abs(r.cat("pocket")) < 0.25 * 2 * np.pi / b.balls)


FLOOR = 0.01   # m/s^2: an RMS change below this is three times under the sensor's 350 ug resolution


def check_converged(sc, segments, skip=0.0, tol=0.01, floor=FLOOR):
    """Halving the default solver's step changes the output RMS acceleration (each axis) by less
    than ``tol`` (or less than ``floor`` where the signal itself is tiny, e.g. with preload) and
    the mean cage speed by less than ``tol``."""
    a = run(sc, segments)
    halved = 2 * sk.DEFAULT_OVERSAMPLE / sk.SkiddingModel.decimation     # steps per internal sample
    b = run(sc, segments, method=it.SplitROS2(per_sample=halved))
    k = int(skip * FS)
    ra, rb = rms(a.cat("accel")[k:]), rms(b.cat("accel")[k:])
    assert np.all(np.abs(ra - rb) < tol * rb + floor), (ra, rb)
    ca, cb = a.cat("cage")[k:].mean(), b.cat("cage")[k:].mean()
    scale = sc.bearing.cage_speed(1.0) * np.abs(a.cat("speed")[k:]).mean()
    assert abs(ca - cb) < tol * max(scale, 1.0), (ca, cb)
    return a


# ---------------------------------------------------------------------------------------------
# contract
def test_simulator_contract_and_chunk_invariance():
    sc = make_scene()
    sim = Simulator(sc, fidelity="skidding")
    assert sim.tier == "skidding"
    b = sim.advance(600)
    nb = sc.bearing.balls
    assert b.accel.shape == (600, 2) and b.contact_forces.shape == (600, 2 * nb)
    assert b.cage_speed.shape == (600,)
    for key in ("ball_skid", "cage_skid"):
        assert b.extras[key].shape == (600,)
    for key in ("slip_inner", "slip_outer", "friction_inner", "friction_outer"):
        assert b.extras[key].shape == (600, nb)
    # the skid ratio is the documented function of the cage speed
    wct = sc.bearing.cage_speed(sc.shaft_speed)
    np.testing.assert_allclose(b.extras["cage_skid"], 100 * (wct - b.cage_speed) / wct, rtol=1e-6, atol=1e-9)
    # chunking does not change the samples
    s2 = Simulator(sc, fidelity="skidding")
    parts = [s2.advance(200) for _ in range(3)]
    np.testing.assert_array_equal(np.concatenate([p.accel for p in parts]), b.accel)
    np.testing.assert_array_equal(np.concatenate([p.cage_speed for p in parts]), b.cage_speed)


@pytest.mark.parametrize("solver, kwargs", [("default", {}), ("rk4", {"rk4_step": 5e-6})])
def test_inner_race_defect_chunked_equals_continuous_bit_for_bit(solver, kwargs):
    """An inner-race defect turns with the shaft, so its place depends on the shaft angle, which
    the tier took from each chunk's start (angle + w x chunk length): chunks of 97 samples gave
    contact forces 4e-10 N off the continuous run from the first defect passage on.  With the
    inputs held the angle is counted from where they were set, the same number in both runs."""
    sc = load_scene("er16k_inner_race")
    one = Simulator(sc, fidelity="skidding", seed=3, solver=solver, **kwargs).advance(97 * 8)
    sim = Simulator(sc, fidelity="skidding", seed=3, solver=solver, **kwargs)
    parts = [sim.advance(97) for _ in range(8)]
    np.testing.assert_array_equal(np.concatenate([p.contact_forces for p in parts]), one.contact_forces)
    np.testing.assert_array_equal(np.concatenate([p.accel for p in parts]), one.accel)
    # a speed command still moves the angle as the ramp says: half-way speed over the ramp.  The
    # snapshot is at the next output sample, and the physics runs `ahead` samples later, so the
    # 150-sample ramp starts `ahead` samples after the first snapshot
    ahead, dt = sim.chain.lookahead_samples, 1.0 / sim.sample_rate
    a0 = sim.snapshot().shaft_angle
    w0 = sim.shaft_speed
    sim.advance(150, shaft_speed=2 * w0)
    inside = 150 - ahead                            # ramp samples before the second snapshot
    w_there = w0 + w0 * inside / 150
    assert sim.snapshot().shaft_angle - a0 == pytest.approx(
        w0 * ahead * dt + 0.5 * (w0 + w_there) * inside * dt, rel=1e-12)
    sim.advance(150)
    assert sim.snapshot().shaft_angle - a0 == pytest.approx(
        w0 * ahead * dt + 1.5 * w0 * 0.01 + 2 * w0 * inside * dt, rel=1e-12)


def test_oversample_sets_the_default_solvers_step():
    """``oversample`` = steps of the default per output sample: 1 takes one step per four internal
    samples (the ones between from the structure's exact response), still chunk-invariant, and
    close to the shipped 2; a value the step grid cannot take is a one-line error."""
    sc = make_scene()
    with pytest.raises(UserError, match=r"^oversample = 3: allowed values are 1, 2 or a multiple of 4 up to 64$"):
        Simulator(sc, fidelity="skidding", oversample=3)
    # a switch of tiers at run time needs the same sensor-chain rate in both (4 per sample)
    with pytest.raises(UserError, match=r"^oversample = 8: with fidelity auto allowed values are 1, 2 or 4"):
        Simulator(sc, fidelity="auto", oversample=8)
    eight = Simulator(sc, fidelity="skidding", oversample=8)
    assert eight.oversample == 8 and eight.chain_oversample == 4
    assert Simulator(sc, fidelity="skidding").oversample == 2
    assert Simulator(sc, fidelity="kinematic", oversample=1).oversample == 1
    assert Simulator(sc, fidelity="skidding", solver="rk4", rk4_step=3e-6).oversample is None
    assert sk.DEFAULT_OVERSAMPLE == 2
    whole = Simulator(sc, fidelity="skidding", oversample=1).advance(600).accel
    sim = Simulator(sc, fidelity="skidding", oversample=1)
    parts = [sim.advance(n) for n in (201, 199, 200)]
    np.testing.assert_array_equal(np.concatenate([p.accel for p in parts]), whole)
    shipped = Simulator(sc, fidelity="skidding").advance(600).accel
    assert not np.array_equal(whole, shipped)             # the setting reaches the solver
    assert np.all(np.abs(rms(whole[150:]) / rms(shipped[150:]) - 1) < 0.02)


def test_rk4_at_the_papers_step_reports_divergence_in_one_line():
    sc = make_scene()
    with pytest.raises(UserError, match=r"^rk4_step = 1e-05 s: .*diverged.*solver='default'"):
        Simulator(sc, fidelity="skidding", solver="rk4").advance(300)


@pytest.mark.parametrize("index", [0, 7], ids=["er16k", "b6205_ball_outer"])
def test_the_bench_times_rk4_up_to_its_stability_limit(index):
    """The equal-error comparison with RK4 is fair only if the bench times RK4 at the largest step
    it survives: its largest RK4 step runs 50 ms of a bench scene, one 1 us longer diverges."""
    from bearing_sim_ros.bench import SCENARIOS

    scene = SCENARIOS[index].build()
    largest = max(kw["rk4_step"] for _label, family, kw in sk.BENCH_CONFIGS if family == "skidding rk4")
    batch = Simulator(scene, fidelity="skidding", solver="rk4", rk4_step=largest).advance(750)
    assert np.all(np.isfinite(batch.accel))
    with pytest.raises(UserError, match="diverged"):
        Simulator(scene, fidelity="skidding", solver="rk4", rk4_step=largest + 1e-6).advance(750)


def test_default_keeps_the_cage_phase_of_the_reference():
    """The cage angle of the default against the reference's on the inner-race bench scene, at
    50 and 800 ms.  Two steps of the default had each left the cage behind for good: the first
    step from the set-up state, done whole (0.77 mrad at 50 ms; now sub-stepped,
    ``skidding.START_STEPS``), and a plain step across a ball leaving its pocket face at 676 ms
    (0.43 mrad at 800 ms; now an event, ``skidding._step_event``).  Since the second fix the
    first step here is a pocket event of its own, so ``START_STEPS = 0`` passes this test (the
    same bits on four shipped scenes, a mutation check of 2026-11-28): it guards the pocket event."""
    from bearing_sim_ros.bench import SCENARIOS

    scene = SCENARIOS[1].build()
    angles = {}
    for solver in ("reference", "default"):
        sim = Simulator(scene, fidelity="skidding", solver=solver)
        model = sim._model
        for t in (0.05, 0.8):
            sim.advance(int(round(t * 15000)) - sim.index)
            t_state = model.counters[0] * model.hstep          # the time of the state y (s)
            angles[solver, t] = model.y[10] + model.y[11] * (t - t_state)   # cage angle at t
    for t in (0.05, 0.8):
        assert abs(angles["default", t] - angles["reference", t]) < 0.05e-3, t


def test_solvers_agree_with_the_reference():
    """default and rk4 (at a step it survives) against the converged reference, 200 N, 2000 rpm."""
    sc = make_scene()
    seg = [(0.04, 2000, 200)]
    ref = run(sc, seg, solver="reference")
    for kw in ({"solver": "default"}, {"method": it.RK4(step=2e-6)}):
        r = run(sc, seg, **kw)
        assert np.all(np.abs(rms(r.cat("accel")[150:]) / rms(ref.cat("accel")[150:]) - 1) < 0.01)
        assert abs(r.cat("cage").mean() / ref.cat("cage").mean() - 1) < 1e-3


def test_default_follows_the_reference_where_the_load_hands_over():
    """At 2000 N the load hands over from ball to ball at the edges of a narrow load zone: steps
    in which a contact opens or closes are sub-stepped (redone once with the stiffer end's
    Jacobian, as before 2026-11-23, they left the RMS 0.8 % off over this window; now 0.2 %)."""
    sc = make_scene()
    seg = [(0.06, 2000, 2000)]
    ref = run(sc, seg, solver="reference")
    r = run(sc, seg)
    assert np.all(np.abs(rms(r.cat("accel")[150:]) / rms(ref.cat("accel")[150:]) - 1) < 0.005)


def test_structure_propagators_are_exact_for_a_parabolic_input():
    """x(tau) = Phi x0 + G0 u0 + G1 (u1 - u0) + G2 a for u = u0 + (u1 - u0) r + a (r^2 - r),
    r = s / h, against a fine RK4 integration, at the step's end and inside it."""
    rng = np.random.default_rng(3)
    n, k, h = 6, 3, 2.0e-4
    A = rng.normal(size=(n, n)) * 3e3 - 5e3 * np.eye(n)
    B = rng.normal(size=(n, k)) * 1e2
    x0, u0, u1, a = rng.normal(size=n), rng.normal(size=k), rng.normal(size=k), rng.normal(size=k)

    def u(s):
        r = s / h
        return u0 + (u1 - u0) * r + a * (r * r - r)

    for tau in (h, 0.4 * h):
        phi, g0, g1, g2 = sk.propagators(A, B, h, tau)
        x, m = x0.copy(), 4000
        dt = tau / m
        for i in range(m):
            t = i * dt
            k1 = A @ x + B @ u(t)
            k2 = A @ (x + 0.5 * dt * k1) + B @ u(t + 0.5 * dt)
            k3 = A @ (x + 0.5 * dt * k2) + B @ u(t + 0.5 * dt)
            k4 = A @ (x + dt * k3) + B @ u(t + dt)
            x = x + dt / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
        np.testing.assert_allclose(phi @ x0 + g0 @ u0 + g1 @ (u1 - u0) + g2 @ a, x, rtol=1e-9, atol=1e-12)


def test_undamped_balls_touching_a_race_inside_a_step_do_not_rattle():
    """Without the EHL film (and its squeeze film, which damps a ball's contact as it closes) a
    ball may touch a race and leave it inside one step; a step whose ends both see the contact
    open was not sub-stepped, and at two samples per step the balls rattled at 600 rpm / 2000 N
    (accel RMS over 50 ms blocks up to 7.5 m/s^2 against the reference's 0.05-0.07).  The second
    stage's point is checked too, and the default follows the reference block by block."""
    sc = make_scene(rpm=600, load=2000, lub={"ehl_film": False})
    assert sk.SkiddingModel(sc, FS, 0, sc.shaft_speed, np.array(sc.radial_load)).oversample == 2
    seg = [(0.3, 600, 2000)]
    ref, r = run(sc, seg, solver="reference"), run(sc, seg)
    for k in range(150, 4500, 750):
        assert np.all(np.abs(rms(r.cat("accel")[k:k + 750]) / rms(ref.cat("accel")[k:k + 750]) - 1) < 0.03)


def test_two_samples_per_step_pass_the_resonator_band():
    """At two samples per step a force held linear over each step would lose about 6 % at the
    resonator's 4 kHz ((pi f h)^2 / 3); on the parabola through the last three grid points it
    does not: at 2000 N the RMS stays within 0.3 % of the reference (0.84 % with the ramp)."""
    sc = make_scene()
    seg = [(0.06, 2000, 2000)]
    ref = run(sc, seg, solver="reference")
    r = run(sc, seg, method=it.SplitROS2(per_sample=0.5))
    assert np.all(np.abs(rms(r.cat("accel")[150:]) / rms(ref.cat("accel")[150:]) - 1) < 0.003)


def test_samples_inside_a_sub_stepped_step_are_as_accurate_as_those_on_the_grid():
    """At two internal samples per step, the sample between two grid points comes from the
    structure's exact response; in a step redone in event sub-steps (a ball in the pit, 12
    sub-steps) it is the sub-steps' state at that sample, the 6th.  Against 8 steps per output
    sample, the internal samples between grid points of the default are then as accurate as
    those on the grid (measured: 0.25 % both on this scene), where the state of one sub-step
    later (a sub-step's bookkeeping off by one) made them 10x worse (2.5 %) while the grid
    points stayed as they were."""
    sc = make_scene("er16k_outer_race")
    w, load = sc.shaft_speed, np.array(sc.radial_load)
    acc = {}
    for ov in (2, 8):
        model = sk.SkiddingModel(sc, FS, 0, w, load, oversample=ov)
        model.advance(4 * 750, w, w, load, load)
        acc[ov] = model.advance(4 * 1500, w, w, load, load).accel[:, 1]
    ref = acc[8]
    d = acc[2] - ref
    on_grid = np.linalg.norm(d[0::2]) / np.linalg.norm(ref[0::2])
    between = np.linalg.norm(d[1::2]) / np.linalg.norm(ref[1::2])
    assert on_grid < 0.01 and between < 1.5 * on_grid, (on_grid, between)


def test_default_within_one_percent_on_the_inner_race_bench_scene():
    """The bench's error (the largest of RMS, envelope line heights and mean cage speed, against
    the reference, on the bench's window) of the default on the ER-16K inner-race scene, where the
    defect's impacts set it, stays under 1 %: at two samples per step 1.37 % while a step with
    events took 6 sub-steps, 0.15 % with 6 per internal sample (12 per step); at one sample per
    step 1.29 % while every ball in a pit was a defect event and such steps took 4 sub-steps."""
    from bearing_sim_ros import bench

    scenario = next(s for s in bench.SCENARIOS if s.scene == "er16k_inner_race")
    scene = scenario.build()
    ref = bench.run_config(bench.reference_config(), scene, FS, 0.2, 0.5, 1)
    default = bench.run_config(bench.Config("default", "skidding default", "skidding"), scene, FS, 0.2, 0.5, 1)
    err = bench.errors(default, ref, scene, FS)
    assert err["error"] < 0.01, err


# ---------------------------------------------------------------------------------------------
# physics
def test_static_balance_and_stribeck_load_without_clearance():
    """Zero clearance: the mean pedestal deflection carries load + shaft weight, and the most
    loaded ball takes Stribeck's 4.37 W / Nb (Harris) within 15 %."""
    sc = make_scene(load=200, bearing=load_scene("er16k_skidding").bearing.with_clearance(0.0))
    r = run(sc, [(0.03, 2000, 200)])
    m = r.model
    w_total = 200 + sc.structure.shaft_mass * G
    yp = m.y[3]
    assert abs(-yp * sc.structure.pedestal_stiffness / w_total - 1) < 0.03
    qmax = r.cat("qi").max()
    assert abs(qmax / (4.37 * w_total / sc.bearing.balls) - 1) < 0.15


def test_centrifugal_load_on_unloaded_balls():
    """A ball outside the load zone presses on the outer race with m_b R_m w_c^2 (eq. 31)."""
    sc = make_scene(rpm=6000, load=50)
    r = run(sc, [(0.03, 6000, 50)])
    qo = r.cat("qo")[-1]
    qi = r.cat("qi")[-1]
    b = sc.bearing
    fc = b.ball_mass * 0.5 * b.pitch_diameter * r.cat("cage")[-1] ** 2
    free = qi == 0.0
    assert free.sum() >= 3
    np.testing.assert_allclose(qo[free], fc, rtol=0.05)


def test_a_batchs_outer_contact_forces_exceed_the_inner_by_the_centrifugal_force():
    """In a Simulator's batch of the skidding tier, columns ``outer_jj`` less ``inner_jj`` are each
    ball's centrifugal force m_b R_m w_c^2 (eq. 31; a 0 degree contact angle: the two contacts
    are on one line), on average over 40 ms at 10000 rpm / 10 N (5.7 N; measured within 0.4 %).
    The batch's columns, not the model's series: the two races swapped in the Simulator passed."""
    scene = replace(load_scene("er16k_healthy"), shaft_speed=10000 * RPM, radial_load=(0.0, -10.0))
    sim = Simulator(scene, fidelity="skidding")
    sim.advance(300)
    b = sim.advance(600)
    bearing = sim.bearing
    assert bearing.contact_angle == 0.0 and b.contact_channels[bearing.balls] == "outer_00"
    inner, outer = b.contact_forces[:, :bearing.balls], b.contact_forces[:, bearing.balls:]
    centrifugal = bearing.ball_mass * 0.5 * bearing.pitch_diameter * np.mean(b.cage_speed ** 2)
    np.testing.assert_allclose((outer - inner).mean(axis=0), centrifugal, rtol=0.02)


def test_traction_curve_is_eq_23_on_both_sides_of_its_series_switch():
    """mu(v) = (A + B|v|) exp(-C|v|) - A + (A + D) v / sqrt(v^2 + vc^2), odd in v, and its slope:
    the kernel takes exp(-C|v|) from a Taylor series below C|v| = 1/16 and from libm above; both
    branches against the closed form with numpy's exp, and the slope against a difference."""
    ta, tb, tc, td, vc = -0.1, 0.06, 0.2, 0.1, 0.01          # seed 000's curve, as in the scenes
    v = np.concatenate([np.linspace(-5.0, 5.0, 2001), np.linspace(-0.4, 0.4, 2001)])
    assert np.any(tc * np.abs(v) < 1 / 16) and np.any(tc * np.abs(v) > 1 / 16)
    got = np.array([sk._traction(x, ta, tb, tc, td, vc) for x in v])
    a = np.abs(v)
    mu = np.sign(v) * ((ta + tb * a) * np.exp(-tc * a) - ta) + (ta + td) * v / np.hypot(v, vc)
    np.testing.assert_allclose(got[:, 0], mu, rtol=1e-14, atol=1e-16)
    dv = 1e-7
    up = np.array([sk._traction(x + dv, ta, tb, tc, td, vc)[0] for x in v])
    down = np.array([sk._traction(x - dv, ta, tb, tc, td, vc)[0] for x in v])
    away = np.abs(v) > 10 * dv                    # |v| has a kink at 0 (its jump is regularised)
    np.testing.assert_allclose(got[away, 1], ((up - down) / (2 * dv))[away], rtol=1e-5, atol=1e-5)


def _free_balls(sc):
    """A model of ``sc``, its parameter vector without squeeze films and with a 1 um pocket
    clearance, and a state with shaft and pedestal centred and every ball at the pitch radius in
    the middle of its pocket: with no film (the caller's), every ball flies free in the clearance,
    touching neither race nor pocket."""
    w, load = sc.shaft_speed, np.array(sc.radial_load)
    model = sk.SkiddingModel(sc, FS, 0, w, load)
    p = model.p.copy()
    p[sk.P_SQI] = p[sk.P_SQO] = 0.0
    p[sk.P_CPK] = 1e-6            # a pocket clearance of 1 um: a centred ball touches no face
    y = model.y.copy()
    y[:10] = 0.0
    nb = model.nb
    y[10] = 0.0
    spacing = 2.0 * np.pi / nb
    for j in range(nb):
        b = sk.NS0 + sk.NBV * j
        y[b + sk.B_TH] = j * spacing
        y[b + sk.B_R] = p[sk.P_RM]
    return model, p, y


def _rhs(model, p, y, film, ws):
    nb = model.nb
    f = np.zeros_like(y)
    aux, dg, scr, frc = np.zeros((nb, sk.NAUX)), np.zeros((nb, sk.NDG)), np.zeros((nb, 5)), np.zeros(4)
    sk._rhs(y, f, ws, 0.0, 0.0, 0.0, p, model.dtab, model.wti, model.wto, film, aux, dg, scr, frc)
    return f, dg, frc


def test_a_free_ball_obeys_newton_in_polar_coordinates():
    """A ball touching neither race nor its pocket feels only gravity and the lubricant drag:
    theta'' = (F_v / m - 2 rho' theta' - g cos theta) / rho (drag against the revolution, Coriolis),
    rho'' = rho theta'^2 - g sin theta (centrifugal, gravity), Omega' = 0, and it pushes neither
    shaft nor pedestal (seed 000 eqs 30-31).  Each ball's accelerations against the closed forms,
    with Harris' drag F_v = c_v pi xi d^2 (D_m theta')^1.95 / 32 and moving in and out; and the
    cage, which no ball pushes, slows by its own drag only: omega_c' = -c_c omega_c / J_c."""
    sc = make_scene()
    assert sc.bearing.radial_clearance > 0 and sc.gravity
    model, p, y = _free_balls(sc)
    b_, lub = sc.bearing, sc.lubrication
    nb = model.nb
    c_v = lub.drag_coefficient * np.pi * lub.fluid_density * b_.ball_diameter ** 2 / 32
    film = np.zeros((nb, sk.NFILM))
    rng = np.random.default_rng(5)
    for j in range(nb):
        b = sk.NS0 + sk.NBV * j
        y[b + sk.B_W] = rng.uniform(50.0, 150.0) * (1 if j % 2 else -1)
        y[b + sk.B_V] = rng.uniform(-0.02, 0.02)
        y[b + sk.B_OM] = -5 * y[b + sk.B_W]
        w = abs(y[b + sk.B_W])
        film[j, sk.F_DRAG] = c_v * b_.pitch_diameter ** 1.95 * w ** -0.05     # F_v / w^2
    # the cage, pushed by no ball, slows under its viscous drag alone (eq. 35 with cage_drag)
    p[sk.P_CDRAG] = 2e-6
    y[11] = 90.0
    f, dg, frc = _rhs(model, p, y, film, sc.shaft_speed)
    np.testing.assert_array_equal(dg[:, [sk.D_QI, sk.D_QO, sk.D_FI, sk.D_FO]], 0.0)
    np.testing.assert_array_equal(frc, 0.0)
    assert f[10] == 90.0
    assert f[11] == pytest.approx(-2e-6 * 90.0 / sk.cage_inertia(sc), rel=1e-12)
    m, g = b_.ball_mass, G
    for j in range(nb):
        b = sk.NS0 + sk.NBV * j
        th, r, w, v = y[b + sk.B_TH], y[b + sk.B_R], y[b + sk.B_W], y[b + sk.B_V]
        drag = -np.sign(w) * c_v * (b_.pitch_diameter * abs(w)) ** 1.95
        assert f[b + sk.B_W] == pytest.approx((drag / m - 2 * v * w - g * np.cos(th)) / r, rel=1e-9)
        assert f[b + sk.B_V] == pytest.approx(r * w * w - g * np.sin(th), rel=1e-9)
        assert f[b + sk.B_OM] == 0.0
        assert f[b + sk.B_PSI] == w - y[b + sk.B_OM]


@pytest.mark.parametrize("name", ["er16k_skidding", "er16k_inner_race"])
def test_contact_forces_on_the_races_are_the_reactions_of_those_on_the_balls(name):
    """Newton's third law at every contact (seed 000 eqs 20, 25, 33): the shaft gets -Q_i e_r -
    f_i e_t from each ball, the pedestal +Q_o e_r - f_o e_t, where the ball gets +Q_i e_r + f_i e_t
    at the inner race and -Q_o e_r + f_o e_t at the outer (e_r, e_t: radial and tangential unit
    vectors at the ball's angle); so the races' forces, normal and traction parts, are minus the
    balls' recorded contact forces, summed in Cartesian coordinates.  On a running state with
    loaded and unloaded balls, traction and (inner race) a ball in the pit."""
    sc = make_scene(name)
    w, load = sc.shaft_speed, np.array(sc.radial_load)
    model = sk.SkiddingModel(sc, FS, 0, w, load)
    for _ in range(3):
        model.advance(4 * 150, w, w, load, load)
        nb = model.nb
        f = np.zeros_like(model.y)
        aux, dg, scr, frc = np.zeros((nb, sk.NAUX)), np.zeros((nb, sk.NDG)), np.zeros((nb, 5)), np.zeros(4)
        sk._rhs(model.y, f, w, model.shaft_angle, load[0], load[1], model.p, model.dtab, model.wti,
                model.wto, model.film, aux, dg, scr, frc)
        th = model.y[sk.NS0 + sk.B_TH::sk.NBV]
        er = np.stack([np.cos(th), np.sin(th)], axis=1)
        et = np.stack([-np.sin(th), np.cos(th)], axis=1)
        qi, qo, fi, fo = (dg[:, k][:, None] for k in (sk.D_QI, sk.D_QO, sk.D_FI, sk.D_FO))
        assert qi.max() > 10.0 and np.abs(fi).max() > 1e-3 and np.abs(fo).max() > 1e-3
        on_ball_inner = (qi * er + fi * et).sum(axis=0)
        on_ball_outer = (-qo * er + fo * et).sum(axis=0)
        scale = 1e-12 * qi.sum()
        np.testing.assert_allclose(frc[0:2], -on_ball_inner, rtol=0, atol=scale)
        np.testing.assert_allclose(frc[2:4], -on_ball_outer, rtol=0, atol=scale)


def test_the_shaft_angle_is_the_integral_of_the_speed_ramp():
    """The kernels' inputs over a chunk whose speed ramps linearly from w0 to w1 over T: the shaft
    angle a0 + w0 tau + (w1 - w0) tau^2 / (2 T) inside the ramp, a0 + (w0 + w1) T / 2 + w1 (tau - T)
    after it, a0 + w0 tau before it (the integral of the speed, continuous at both ends), the
    speed and the load on the same ramp.  An inner-race defect and waviness sit at this angle."""
    ramp = np.zeros(sk.NRAMP)
    t0, tt, w0, w1, a0 = 0.25, 0.02, 150.0, 260.0, 1.3
    ramp[sk.R_T0], ramp[sk.R_T], ramp[sk.R_S0], ramp[sk.R_S1], ramp[sk.R_A0] = t0, tt, w0, w1, a0
    ramp[sk.R_L0X], ramp[sk.R_L0Y], ramp[sk.R_L1X], ramp[sk.R_L1Y] = 10.0, -200.0, 30.0, -400.0
    for tau in np.linspace(-0.005, 0.03, 36):
        ws, ang, fx, fy = sk._inputs(ramp, t0 + tau)
        if tau <= 0:
            want_ang, frac = a0 + w0 * tau, 0.0
        elif tau >= tt:
            want_ang, frac = a0 + 0.5 * (w0 + w1) * tt + w1 * (tau - tt), 1.0
        else:
            want_ang, frac = a0 + w0 * tau + (w1 - w0) * tau ** 2 / (2 * tt), tau / tt
        assert ang == pytest.approx(want_ang, rel=1e-12, abs=1e-12), tau
        assert ws == pytest.approx(w0 + (w1 - w0) * frac, rel=1e-12), tau
        assert (fx, fy) == pytest.approx((10 + 20 * frac, -200 - 200 * frac), rel=1e-12), tau
    # numerically: the angle's increments are the speed's trapezoids
    taus = np.linspace(0.0, 0.03, 3001)
    vals = np.array([sk._inputs(ramp, t0 + t) for t in taus])
    np.testing.assert_allclose(np.diff(vals[:, 1]), 0.5 * (vals[1:, 0] + vals[:-1, 0]) * np.diff(taus),
                               rtol=1e-6)


def test_the_drag_factor_is_harris_drag_over_the_speed_squared():
    """The drag the kernel freezes over a step, F_v / theta'^2, is Harris' c_v pi xi d^2 D_m^1.95
    theta'^-0.05 / 32 (seed 000 eq. 30 in SI), at slow and fast revolution and either sense."""
    sc = make_scene()
    p = sk.parameters(sc)
    b, lub = sc.bearing, sc.lubrication
    film = np.zeros((1, sk.NFILM))
    for w in (2.0, 80.0, -80.0, 900.0):
        film[:] = 0.0
        sk._drag_factor(film, 0, p, w)
        f_v = lub.drag_coefficient * np.pi * lub.fluid_density * b.ball_diameter ** 2 / 32 * (b.pitch_diameter * abs(w)) ** 1.95
        assert film[0, sk.F_DRAG] * w * w == pytest.approx(f_v, rel=1e-12), w


def test_the_ball_skid_is_eq_38_averaged_over_every_ball():
    """ball_skid = 100 mean_j (w_bt - w_bj) / w_bt over ALL balls (module docstring, seed 000 eq.
    38), w_bt = omega_s D_m / (2 d) (1 - gamma^2) the catalog's pure-rolling spin, w_bj = theta'_j
    - Omega_j: recomputed from the state at the start of a one-sample call, the row recorded
    there; cage_skid likewise from eq. 37.  The balls skid unequally (loaded and unloaded), so
    a mean over fewer balls, or over a wrong count, shows."""
    sc = make_scene()
    w, load = sc.shaft_speed, np.array(sc.radial_load)
    model = sk.SkiddingModel(sc, FS, 0, w, load)
    nb = model.nb
    model.advance(4 * 300, w, w, load, load)
    wbt = sc.bearing.ball_spin_speed(w)
    wct = sc.bearing.cage_speed(w)
    # 29 internal samples: the last recorded row (sample 28) is the grid point the state ends at
    out = model.advance(29, w, w, load, load)
    assert model.counters[0] * model.hstep == pytest.approx((1200 + 28) * model.hs, rel=1e-12)
    y = model.y
    each = 100 * (wbt - (y[sk.NS0 + sk.B_W::sk.NBV] - y[sk.NS0 + sk.B_OM::sk.NBV])) / wbt
    assert each.shape == (nb,) and np.ptp(each) > 0.1 * abs(each.mean())
    assert out.extras["ball_skid"][-1] == pytest.approx(each.mean(), rel=1e-6)
    assert out.extras["cage_skid"][-1] == pytest.approx(100 * (wct - y[11]) / wct, rel=1e-6)


@pytest.mark.parametrize("profile", ["geometric", "rectangular", "half_sine", "piecewise"])
def test_defect_depth_slopes_along_the_ball_angle(profile):
    """The skidding tier's W takes a race defect's loss slope along the ball angle from
    ``defects.interference_loss_slope`` (analytic, one evaluation): it matches a central
    difference of the loss wherever the profile is smooth (both races, a deep and a shallow pit,
    across the whole pit), and a ball defect adds loss but no slope."""
    from bearing_sim_ros.catalog import get_bearing
    from bearing_sim_ros.physics.defects import defect_table, interference_loss_slope
    from bearing_sim_ros.scene import Defect
    b = get_bearing("ER-16K")
    ri, ro, rb = 0.5 * b.inner_race_diameter, 0.5 * b.outer_race_diameter, 0.5 * b.ball_diameter
    checked = 0
    for kind, radius in (("inner", ri), ("outer", ro)):
        for width, depth in ((0.6e-3, 0.25e-3), (1.2e-3, 5e-6)):      # deep: no bottom; shallow
            tab = defect_table([Defect(kind, width, depth, width, angle=0.3, profile=profile)], b)
            half = 0.5 * width / radius
            shaft = 0.2 if kind == "inner" else 0.0
            centre = 0.3 + shaft
            for th in centre + np.linspace(-0.98 * half, 0.98 * half, 41):
                got = interference_loss_slope(tab, 0, th, shaft, 0.0, ri, ro, rb)
                h = 1e-9
                up = interference_loss_slope(tab, 0, th + h, shaft, 0.0, ri, ro, rb)
                dn = interference_loss_slope(tab, 0, th - h, shaft, 0.0, ri, ro, rb)
                k = 0 if kind == "inner" else 1
                fd = (up[k] - dn[k]) / (2 * h)
                one_sided = ((up[k] - got[k]) / h, (got[k] - dn[k]) / h)
                if abs(one_sided[0] - one_sided[1]) > 1e-3 * max(abs(fd), 1e-6):
                    continue                              # a kink inside the difference: skip
                assert got[2 + k] == pytest.approx(fd, rel=1e-4, abs=1e-9)
                assert got[3 - k] == 0.0 and got[1 - k] == 0.0
                checked += 1
    assert checked > 100
    tab = defect_table([Defect("ball", 2e-3, 0.1e-3, 2e-3, angle=0.0, profile=profile)], b)
    li, lo, dli, dlo = interference_loss_slope(tab, 0, 0.1, 0.0, 0.0, ri, ro, rb)
    assert lo > 0.0 and dli == 0.0 and dlo == 0.0


@pytest.mark.parametrize("name", ["er16k_inner_race", "b6205_inner_outer", "b6205_ball_outer"])
def test_defect_search_matches_every_ball_evaluated(name):
    """``_defect_losses`` evaluates a race defect only for the ball nearest to it and that ball's
    two neighbours.  From a settled state (balls where skidding and the pocket clearance put
    them), turned as a whole by random angles against random shaft angles, every ball's losses
    and slopes equal ``interference_loss_slope`` evaluated for that ball at its own angle; and
    the angles do reach the defects."""
    from bearing_sim_ros.physics.defects import D_ANGLE, D_BALL, D_KIND, KIND_BALL, KIND_INNER, interference_loss_slope

    scene = load_scene(name)
    model = sk.SkiddingModel(scene, FS, 0, scene.shaft_speed, np.array(scene.radial_load))
    w, load = scene.shaft_speed, np.array(scene.radial_load)
    model.advance(3000, w, w, load, load)          # 50 ms: the balls settle in their pockets
    p, dtab, nb = model.p, model.dtab, int(model.p[sk.P_NB])
    rng = np.random.default_rng(5)
    scr = np.zeros((nb, 5))
    met = 0
    for i in range(3000):
        y = model.y.copy()
        turn, shaft = rng.uniform(-40.0, 40.0, 2)
        if i % 2:
            # put a race defect next to a ball (a ball defect against a race) half of the time
            k = rng.integers(dtab.shape[0])
            j = rng.integers(nb)
            th_j = y[sk.NS0 + sk.NBV * j + sk.B_TH]
            if int(dtab[k, D_KIND]) == KIND_BALL:
                y[sk.NS0 + sk.NBV * int(dtab[k, D_BALL]) + sk.B_PSI] = (-dtab[k, D_ANGLE] + rng.uniform(-0.1, 0.1)
                                                                 + rng.integers(2) * np.pi)
            else:
                centre = dtab[k, D_ANGLE] + (shaft if int(dtab[k, D_KIND]) == KIND_INNER else 0.0)
                turn = centre - th_j + rng.uniform(-0.03, 0.03)
        y[10] += turn
        for j in range(nb):
            y[sk.NS0 + sk.NBV * j + sk.B_TH] += turn
        sk._defect_losses(dtab, y, p, shaft, scr)
        for j in range(nb):
            b = sk.NS0 + sk.NBV * j
            want = interference_loss_slope(dtab, j, y[b + sk.B_TH], shaft, y[b + sk.B_PSI], p[sk.P_RI], p[sk.P_RO],
                                           p[sk.P_RB])
            assert tuple(scr[j, [0, 1, 3, 4]]) == pytest.approx(want, rel=1e-9, abs=1e-15), (j, turn, shaft)
            met += want[0] + want[1] > 0.0
    assert met > 300, met


def test_a_ball_free_in_a_deep_pit_is_not_a_defect_event():
    """The split solver sub-steps a step in which a ball is inside a defect under a contact it
    changes, unless that contact stays open at both ends by more than OPEN_GAP_MARGIN times its
    gap's change (the ball crosses the pit in free flight); a closed contact inside a defect at
    the step's start sends the step straight to the sub-steps."""
    a0 = np.zeros((3, sk.NAUX))
    a1 = np.zeros((3, sk.NAUX))
    a0[1, sk.X_LOSSO] = a1[1, sk.X_LOSSO] = 50e-6          # ball 1 over an outer-race pit
    a0[1, sk.X_DO], a1[1, sk.X_DO] = -30e-6, -28e-6         # open by 30 and 28 um
    assert not sk._defect_changes_contact(a0, a1, 3)
    assert sk._step_event(a0, a1, 3, True) == sk.NO_EVENT
    a1[1, sk.X_DO] = -10e-6                                 # closing fast: 20 um in the step
    assert sk._defect_changes_contact(a0, a1, 3)
    assert sk._step_event(a0, a1, 3, True) == sk.DEFECT_EVENT
    assert sk._step_event(a0, a1, 3, False) == sk.NO_EVENT  # no defects in the scene
    a1[1, sk.X_DO] = 2e-6                                   # closed at the end
    assert sk._defect_changes_contact(a0, a1, 3)
    assert not sk._inside_defect(a0, 3) and sk._inside_defect(a1, 3)
    a0[1, sk.X_LOSSO] = a1[1, sk.X_LOSSO] = 0.0             # the pit changes no contact
    a0[2, sk.X_LOSSI], a0[2, sk.X_DI], a1[2, sk.X_DI] = 1e-6, 1e-6, 1e-6
    assert sk._defect_changes_contact(a0, a1, 3)            # inner contact closed in a pit


def test_film_switch():
    """ehl_film: the Hamrock-Dowson film (a few tenths of a micron here) and the squeeze damping;
    without it the film is zero and the balls rattle in the clearance more (more high-frequency
    content reaches the sensor).  Each contact's film is module ``film``'s h = C u^0.68 Q^-0.073
    at the load it carries: within 1 % on the loaded balls (u taken at pure rolling, where the
    cage skids 0.4 %), within 12 % on the others (their spin lags the rolling speed, and where a
    ball barely touches, the recorded load includes the squeeze film's force, which does not
    thin the film)."""
    from bearing_sim_ros.physics.film import (FILM_EXP_Q, FILM_EXP_U, FILM_LOAD_FLOOR,
                                              film_coefficient)

    sc = make_scene()
    on = run(sc, [(0.03, 2000, 200)])
    off = run(make_scene(lub={"ehl_film": False}), [(0.03, 2000, 200)])
    h = on.model.film[:, [sk.F_HI, sk.F_HO]]
    assert 0.1e-6 < h.min() and h.max() < 2e-6
    b = sc.bearing
    u = 0.5 * b.outer_race_diameter * b.cage_speed(2000 * RPM)
    for col, contact, key in ((0, b.inner_contact, "qi"), (1, b.outer_contact, "qo")):
        q = on.cat(key)[-1]
        expected = (film_coefficient(contact, sc.lubrication, b.effective_modulus) * u ** FILM_EXP_U
                    * np.maximum(q, FILM_LOAD_FLOOR) ** FILM_EXP_Q)
        ratio = h[:, col] / expected
        assert np.all(np.abs(ratio - 1) < 0.12), ratio
        assert np.all(np.abs(ratio[q > 10.0] - 1) < 0.01), ratio
        assert np.sum(q > 10.0) >= 2
    assert np.all(off.model.film[:, [sk.F_HI, sk.F_HO]] == 0.0)
    assert rms(off.cat("raw"))[1] > rms(on.cat("raw"))[1]


def test_adopt_state_from_the_kinematic_tier_is_seamless():
    # without the kinematic tier's random slip its balls sit where the skidding tier's pockets are
    sc = make_scene(random_slip=0.0)
    w, load = sc.shaft_speed, np.array(sc.radial_load)
    kin = KinematicModel(sc, FS, 4, 0, w, load)
    kin.advance(1200, w, w, load, load)
    skid = sk.SkiddingModel(sc, FS, 0, w, load)
    skid.adopt_state(kin)
    np.testing.assert_array_equal(skid.x, kin.x)
    assert skid.angles[1] == kin.angles[1]
    a_kin = kin.advance(40, w, w, load, load).accel
    a_sk = skid.advance(40, w, w, load, load).accel
    # same structure, same bearing forces, each ball's film from the kinematic tier's: no jump
    # (measured 0.37 m/s^2; a wrong static state shows |W| / m_p = 84 m/s^2, films from none 21,
    # every ball's film from the kinematic tier's one common film 0.7 unless blended over 20 ms)
    assert np.max(np.abs(a_sk - a_kin)) < 0.5
    # the reverse direction reads the same layout
    assert skid.x.shape == (10,) and skid.angles.shape == (3,)


# ---------------------------------------------------------------------------------------------
# hard cases: finite, bounded, converged
HARD = {
    "heavy 2000 N at 2000 rpm": (dict(load=2000), [(0.06, 2000, 2000)], 2000, 0.02),
    "light 10 N at 10000 rpm": (dict(rpm=10000, load=10), [(0.06, 10000, 10)], 10, 0.02),
    "start from rest and ramp": (dict(rpm=0.0), [(0.08, 2000, 200), (0.02, 2000, 200)], 200, 0.0),
    "speed reversal through zero": (dict(rpm=1000), [(0.08, -1000, 200)], 200, 0.0),
    "load steps up, down, to zero": (dict(), [(0.01, 2000, 2000), (0.02, 2000, 2000), (0.01, 2000, 0),
                                             (0.02, 2000, 0), (0.01, 2000, 200)], 2000, 0.0),
    # converged like the others since each contact's film follows its Hertz load (2026-11-23):
    # before, the unloaded balls chattered at zero deflection with an RMS that depended on the step
    # of every solver (accel_x: RK4 at 32 / 64 steps per internal sample 0.068 / 0.107 m/s^2, the
    # default 0.010 and 0.038 at half its step), and this case was held only within 0.05 m/s^2
    "zero clearance": (dict(clearance=0.0), [(0.05, 2000, 200)], 200, 0.01),
    "negative clearance (preload)": (dict(clearance=-5e-6), [(0.05, 2000, 200)], 200, 0.01),
}


@pytest.mark.parametrize("case", list(HARD))
def test_hard_case(case):
    kw, segments, max_load, skip = HARD[case]
    kw = dict(kw)
    if "clearance" in kw:
        kw["bearing"] = load_scene("er16k_skidding").bearing.with_clearance(kw.pop("clearance"))
    sc = make_scene(**kw)
    r = check_converged(sc, segments, skip=skip)
    check_bounded(r, sc, max_load)


def test_defect_wider_than_the_contact_and_deeper_than_the_clearance():
    sc = make_scene("er16k_outer_race", rpm=2000, load=1000)
    d = sc.defects[0]
    b = sc.bearing
    half_width_rolling = b.outer_contact.b_coeff * 1000 ** (1 / 3)      # rolling-direction semi-axis
    assert d.width > 2 * half_width_rolling and d.depth > b.radial_clearance
    r = check_converged(sc, [(0.06, 2000, 1000)], skip=0.01)
    check_bounded(r, sc, 1000)


def test_composite_defects():
    sc = make_scene("b6205_inner_outer")
    assert {d.kind for d in sc.defects} == {"inner", "outer"}
    load = -sc.radial_load[1]
    r = check_converged(sc, [(0.06, sc.shaft_speed / RPM, load)], skip=0.01)
    check_bounded(r, sc, load)


def test_one_minute_without_drift():
    sc = make_scene()
    r = run(sc, [(60.0, 2000, 200)], chunk=0.5)
    cage = r.cat("cage")
    acc = r.cat("accel")
    n5 = int(5 * FS)
    assert abs(cage[n5:2 * n5].mean() / cage[-n5:].mean() - 1) < 1e-4
    assert np.all(np.abs(rms(acc[n5:2 * n5]) / rms(acc[-n5:]) - 1) < 0.02)
    check_bounded(r, sc, 200)
    # the shaft turned as commanded, and the cage with it
    assert abs(r.model.shaft_angle / (sc.shaft_speed * 60.0) - 1) < 1e-9


# ---------------------------------------------------------------------------------------------
# seed 000's numbers and trends
@pytest.mark.parametrize("name, key", [("er16k_inner_race", "bpfi"), ("er16k_outer_race", "bpfo")])
def test_envelope_line_at_theory(name, key):
    """1600 rpm / 50 N, 1 s through the Simulator with sensor noise: the fault line stands out and
    sits within 1 % of theory (seed 000: BPFI 144.8 Hz, BPFO 95.25 Hz)."""
    line, theory = _envelope_line(name, key)
    assert line.prominence > 4.0
    assert abs(line.found_hz / theory - 1) < 0.01


def _envelope_line(name, key, lub=None):
    """The shipped scene's envelope line ``key`` (1 s after 0.05 s, sensor noise on) and its
    theoretical frequency (Hz); ``lub``: lubrication changes."""
    sc = load_scene(name)
    if lub:
        sc = replace(sc, lubrication=replace(sc.lubrication, **lub))
    sim = Simulator(sc, fidelity="skidding")
    sim.advance(750)
    y = sim.advance(15000).accel[:, -1]
    ff = sc.bearing.fault_frequencies(sc.shaft_hz)
    return fault_lines(y, FS, ff)[key], ff[key]


def _skid(name, rpm, load, settle=0.15, seconds=0.1, lub=None, width_mm=None, solver="default"):
    """Mean (ball, cage) skid ratios (%) over ``seconds`` after ``settle``; the scene's defects
    widened to ``width_mm`` (and as long) if given."""
    sc = make_scene(name, rpm=rpm, load=load, lub=lub)
    if width_mm is not None:
        sc = replace(sc, defects=tuple(replace(d, width=width_mm * 1e-3, length=width_mm * 1e-3)
                                       for d in sc.defects))
    r = run(sc, [(settle, rpm, load), (seconds, rpm, load)], solver=solver, chunk=0.1)
    k = int(settle * FS)
    return r.cat("bskid")[k:].mean(), r.cat("cskid")[k:].mean()


def test_healthy_skid_ratios_are_of_the_papers_order():
    """2000 rpm / 200 N: seed 000 gives ball 2.72 %, cage 1.25 %; the README explains the gap."""
    ball, cage = _skid("er16k_skidding", 2000, 200)
    assert 1.0 < ball < 8.0
    assert 0.3 < cage < 2.5


def test_cage_skid_falls_with_load_and_rises_with_speed():
    """Seed 000 Fig. 17(a, b).  Between 1000 and 2000 N the slip part is below the rolling-radius
    change of the deflected contacts (README "The skidding tier"): there it only has to stay level."""
    by_load = [_skid("er16k_skidding", 2000, w)[1] for w in (50, 200, 1000, 2000)]
    assert by_load[0] > by_load[1] > by_load[2], by_load
    assert by_load[3] < by_load[1] and abs(by_load[3] - by_load[2]) < 0.03, by_load
    by_speed = [_skid("er16k_skidding", rpm, 200)[1] for rpm in (2000, 3000, 4000, 5000)]
    assert all(a < b for a, b in zip(by_speed, by_speed[1:])), by_speed


def _defect_skid(name, width_mm=None, solver="default"):
    """Mean cage skid ratio (%) at 2000 rpm / 200 N over 1 s after 0.3 s (whole cage turns and
    a hundred defect passes: a 0.1 s mean moves by the phase of the last passes), the scene's
    defect widened to ``width_mm`` (and as long)."""
    return _skid(name, 2000, 200, settle=0.3, seconds=1.0, width_mm=width_mm, solver=solver)[1]


def test_a_defect_raises_the_cage_skid():
    """Seed 000 Sec. 4.3: a defect raises the cage skid ratio.  At 1.2 mm (twice the shipped
    scenes' width) the default puts the inner-race defect 0.0008 and the outer-race one 0.0034
    percentage points above healthy (the reference 0.0008 and 0.0028), resolvable against the
    solver's own error; at the shipped 0.6 mm the rise (reference 0.00014 / 0.00006) is as small
    as the default's error on it (README, "Seed 000's numbers, side by side")."""
    healthy = _defect_skid("er16k_skidding")
    for name in ("er16k_inner_race", "er16k_outer_race"):
        assert _defect_skid(name, 1.2) - healthy > 4e-4, name


def _pit(width_mm=None, angle_deg=None, lub=None):
    """Mean cage skid ratio (%) and mean total inner-contact load (N, summed over the balls) at
    2000 rpm / 200 N over 1 s after 0.3 s, with ``er16k_outer_race``'s pit widened to
    ``width_mm`` (and as long) and moved to ``angle_deg`` (0 = +x, -90 = the bottom, shipped);
    healthy if ``width_mm`` is None."""
    sc = make_scene("er16k_skidding" if width_mm is None else "er16k_outer_race", rpm=2000,
                    load=200, lub=lub)
    if width_mm is not None:
        ch = dict(width=width_mm * 1e-3, length=width_mm * 1e-3)
        if angle_deg is not None:
            ch["angle"] = np.radians(angle_deg)
        sc = replace(sc, defects=(replace(sc.defects[0], **ch),))
    r = run(sc, [(0.3, 2000, 200), (1.0, 2000, 200)], chunk=0.1)
    k = int(0.3 * FS)
    return r.cat("cskid")[k:].mean(), r.cat("qi")[k:].sum(axis=1).mean()


def test_a_wide_pit_at_the_bottom_lowers_the_cage_skid_by_spreading_the_load():
    """Why a 2.4 mm outer-race pit lowers the cage skid (README, "Seed 000's numbers, side by
    side").  The load zone at 200 N holds about two balls; while the bottom ball crosses the pit
    its neighbours 40 deg away carry the load, so the contact loads must add up to more for the
    same 200 N (1/cos 40 deg): the total inner load rises with the pit's width (215, 218, 222,
    227 N at 0, 1.2, 2.4, 3.6 mm), the traction the balls can give per unit slip rises with it,
    and the slip that carries the drag falls.  That part scales with the drag: at 2.4 mm the
    defect's change of the cage skid is +0.0008 points with 1 % of the drag and -0.0049 with
    twice the drag (-0.0020 as shipped).  Against it, the pit raises the cage skid by a
    drag-free part (the ball sinking into the pit and the shaft's ringing load the contacts more
    deeply, which slows their rolling), which wins at 1.2 mm, or with the pit 30 deg off the
    bottom, where the load goes to a ball nearer the bottom and the total load does not rise
    (+0.8 N): there the 2.4 mm pit raises the cage skid (+0.0021 points)."""
    skid0, load0 = _pit()
    loads = [load0] + [_pit(w)[1] for w in (1.2, 2.4, 3.6)]
    assert all(b - a > 1.0 for a, b in zip(loads, loads[1:])), loads
    drag = {}
    for rho in (3.0, 600.0):
        lub = {"fluid_density": rho}
        drag[rho] = _pit(2.4, lub=lub)[0] - _pit(lub=lub)[0]
    assert drag[3.0] > 3e-4 and drag[600.0] < -3e-3, drag
    skid_off, load_off = _pit(2.4, angle_deg=-60.0)
    assert abs(load_off - load0) < 2.0 and skid_off - skid0 > 1e-3, (skid_off - skid0, load_off - load0)


def study_seed000():
    """The README's "Seed 000's numbers, side by side": envelope lines at 1600 rpm / 50 N, the
    healthy skid ratios at 2000 rpm / 200 N, the cage skid's trends with load, speed and defect,
    and the same with Harris' effective density at the full oil density (870 kg/m^3)."""
    for name, key in (("er16k_inner_race", "bpfi"), ("er16k_outer_race", "bpfo")):
        line, theory = _envelope_line(name, key)
        print(f"{name} {key}: {line.found_hz:.2f} Hz ({line.found_hz / theory - 1:+.2%}), "
              f"prominence {line.prominence:.0f}", flush=True)
    ball, cage = _skid("er16k_skidding", 2000, 200)
    print(f"skid ratios 2000 rpm / 200 N: ball {ball:.3f} %, cage {cage:.3f} %", flush=True)
    print("cage skid % at 2000 rpm, 50 / 200 / 1000 / 2000 N:",
          " ".join(f"{_skid('er16k_skidding', 2000, w)[1]:.3f}" for w in (50, 200, 1000, 2000)), flush=True)
    print("cage skid % at 200 N, 2000 / 3000 / 4000 / 5000 rpm:",
          " ".join(f"{_skid('er16k_skidding', n, 200)[1]:.3f}" for n in (2000, 3000, 4000, 5000)), flush=True)
    for name in ("er16k_skidding", "er16k_inner_race", "er16k_outer_race"):
        ball, cage = _skid(name, 2000, 200)
        print(f"{name} 2000 rpm / 200 N: cage skid {cage:.5f} %, ball skid {ball:.3f} %", flush=True)
    for solver in ("default", "reference"):
        healthy = _defect_skid("er16k_skidding", solver=solver)
        print(f"cage skid at 2000 rpm / 200 N over 1 s, {solver}: healthy {healthy:.5f} %; defect "
              f"0.3 / 0.6 / 1.2 / 2.4 mm wide, minus healthy (pp):", flush=True)
        for name in ("er16k_inner_race", "er16k_outer_race"):
            rise = [_defect_skid(name, w, solver) - healthy for w in (0.3, 0.6, 1.2, 2.4)]
            print(f"  {name}: " + " ".join(f"{x:+.5f}" for x in rise), flush=True)
    flooded = {"fluid_density": 870.0}
    ball, cage = _skid("er16k_skidding", 2000, 200, lub=flooded)
    line, theory = _envelope_line("er16k_outer_race", "bpfo", lub=flooded)
    print(f"flooded (870 kg/m^3): ball {ball:.2f} %, cage {cage:.2f} %, BPFO at 1600 rpm / 50 N "
          f"{line.found_hz / theory - 1:+.2%}", flush=True)


if __name__ == "__main__":
    import sys

    if sys.argv[1:] != ["seed000"]:
        sys.exit("usage: python test/test_skidding.py seed000")
    study_seed000()


def test_a_seed_changes_only_the_sensor_noise_in_the_skidding_tier():
    """README, "The Python API": the skidding tier takes no random slip, so two seeds give the
    same forces and cage speed to the bit and accelerations apart by the sensor noise only; the
    kinematic tier's random slip moves its forces."""
    runs = {seed: Simulator("er16k_outer_race", fidelity="skidding", seed=seed).advance(600) for seed in (0, 1)}
    assert np.array_equal(runs[0].contact_forces, runs[1].contact_forces)
    assert np.array_equal(runs[0].cage_speed, runs[1].cage_speed)
    noise = 3.4e-5 * np.sqrt(7500.0)           # the scene's noise density over the output band
    apart = np.std(runs[0].accel - runs[1].accel, axis=0)
    assert np.all(apart > 0.5 * noise) and np.all(apart < 2.5 * noise)
    kin = [Simulator("er16k_outer_race", fidelity="kinematic", seed=seed).advance(600) for seed in (0, 1)]
    assert not np.array_equal(kin[0].contact_forces, kin[1].contact_forces)


def test_a_diverging_solver_says_which_when_where_and_what_to_try_in_one_line(diverging_scene):
    """``SolverDiverged`` was ``skidding solver 'default' diverged at t = 0.008333 s`` and, in every
    command, an internal error with a traceback.  Now a UserError (still a RuntimeError) whose one
    line names the solver, the time of signal, the operating point there and what to try: the
    reference solver or the kinematic tier for the default (the within-bounds scene of
    conftest.DIVERGING_PIT), the default for the reference (a structure damped at 1e8 N s/m,
    within bounds, is beyond its explicit steps)."""
    scene = load_scene(str(diverging_scene()))
    with pytest.raises(sk.SolverDiverged) as exc:
        Simulator(scene).advance(1500)
    line = str(exc.value)
    assert isinstance(exc.value, UserError) and isinstance(exc.value, RuntimeError) and "\n" not in line
    assert re.fullmatch(r"solver='default': the skidding tier's default solver diverged at t = 0\.0\d+ s of signal "
                        r"\(2000 rpm, radial load \[0, -200\] N\): the scene is beyond what it integrates; try "
                        r"solver='reference' \(.*\) or fidelity='kinematic'", line), line
    stiff = replace(scene, defects=(), structure=replace(scene.structure, shaft_damping=1e8, pedestal_damping=1e8))
    with pytest.raises(sk.SolverDiverged, match=r"^solver='reference': .* diverged at t = .* try solver='default' "):
        Simulator(stiff, solver="reference").advance(150)


def test_a_divergence_after_a_tier_switch_is_told_at_the_signals_time(diverging_scene):
    """A skidding model made at a tier switch counts its time from there: a divergence 9 ms after
    a switch at 0.1 s was told at t = 0.0088 s.  Now at the signal's time, with the operating
    point on the ramp there (fidelity auto, its tolerance between the two operating points, no
    skid ratios asked for: the scene may start on the kinematic tier)."""
    from bearing_sim_ros.fidelity import kinematic_error_estimate

    base = replace(load_scene(str(diverging_scene())), outputs=("accel",))     # no skid ratios asked for
    lo, hi = (kinematic_error_estimate(base, rpm * RPM, (0.0, -load))[0] for rpm, load in ((2000, 200), (10000, 10)))
    sim = Simulator(replace(base, fidelity_tolerance=float(np.sqrt(lo * hi))))
    sim.advance(1500)
    assert sim.tier == "kinematic"
    with pytest.raises(sk.SolverDiverged) as exc:
        sim.advance(1500, shaft_speed=10000 * RPM, radial_load=(0.0, -10.0))
    assert sim.last_tier_switch == (0.1, "kinematic", "skidding")
    assert 0.1 < exc.value.t < 0.2 and f"at t = {exc.value.t:.4g} s of signal" in str(exc.value)
    rpm = exc.value.shaft_speed / RPM
    assert 2000 < rpm < 10000 and f"({rpm:.6g} rpm, radial load [0, " in str(exc.value)


def test_a_divergence_survives_a_round_trip_through_pickle():
    """A process pool hands a worker's exception back pickled: SolverDiverged and RK4Diverged are
    made again from their fields, with the same line (their args are only the message)."""
    import pickle

    for exc in (sk.SolverDiverged("default", 0.0123, 209.44, (0.0, -200.0)),
                sk.RK4Diverged(2e-5, 1e-4, 209.44, (0.0, -200.0))):
        back = pickle.loads(pickle.dumps(exc))
        assert type(back) is type(exc) and str(back) == str(exc) and back.t == exc.t


def test_a_ball_pit_at_300_rpm_is_found_on_the_skidding_tier():
    """er16k_skidding (200 N) at 300 rpm with a 0.6 mm ball pit, judged where the cage and the
    balls ran (the cage speed, ball_skid): in 1 s segments the pit's cage-rate sidebands (2 Hz
    apart) merge with its 2xBSF line and the +-20 Hz floor rises with them (x1.6, "healthy"); in
    segments of 8 cage turns (envelope.decision_segment: the whole 4 s) the line stands, x18."""
    from test_kinematic import _slow

    from bearing_sim_ros.analysis.envelope import diagnose

    y, fs, ff = _slow("ball", 300.0, fidelity="skidding")
    d = diagnose(y, fs, ff)
    assert d["verdict"] == "ball" and d["scores"]["ball"] > 8.0, d["scores"]


# a 6000-size bearing (README "Limitations", docs/probes/custom_bearings: 7 balls of 4.762 mm on
# 18 mm) at 13 888 rpm under 4662 N (a quarter of its speed limit, 2 C0)
SMALL_BEARING = small_bearing(13888, 4662.0, range=49033)


def test_the_default_measures_its_step_on_a_small_fast_bearing_and_lands_near_its_reference():
    """Where the most loaded ball's contact frequency is high for the default's own step, the
    default measures the step it needs (throwaway runs at 2, 4, 8 steps per sample from its start
    state): on the small bearing it takes 8 and is within 1 % of its reference in RMS (0.1 s settle
    + 0.2 s; at its own 2 it was +24 % off, and warned), without a warning; the same samples as an
    explicit ``oversample=8``, which checks nothing."""
    import warnings

    from bearing_sim_ros.scene import scene_from_dict
    from bearing_sim_ros.simulator import DefaultStepWarning

    sc = scene_from_dict(SMALL_BEARING)
    with warnings.catch_warnings():
        warnings.simplefilter("error", DefaultStepWarning)
        default = Simulator(sc, fidelity="skidding")
        eight = Simulator(sc, fidelity="skidding", oversample=8)
        reference = Simulator(sc, fidelity="skidding", solver="reference")
    assert default.oversample == 8 and eight._model.step_estimates == {}

    def tail_rms(sim):
        return rms(sim.advance(4500).accel[1500:, -1])

    checked = tail_rms(default)
    assert abs(checked / tail_rms(reference) - 1) < 0.01
    assert checked == tail_rms(eight)


def test_the_step_check_capped_warns_in_one_line_with_what_helps():
    """At 55 555 rpm the small bearing's default is 0.9 % off at 16 steps per sample (measured
    -0.87 %), above the check's 0.5 % target: it runs at its cap, 16, and says so in one line
    (``DefaultStepWarning``) with what would do better; under fidelity auto (a tolerance that
    picks the skidding tier) the cap is ``AUTO_OVERSAMPLE_MAX``, 4, and the line says why and what
    lifts it.  An explicit ``oversample`` says nothing."""
    import warnings

    from bearing_sim_ros.scene import scene_from_dict
    from bearing_sim_ros.simulator import DefaultStepWarning

    sc = scene_from_dict(small_bearing(55555, 4662.0, range=49033))
    with pytest.warns(DefaultStepWarning) as caught:
        capped = Simulator(sc, fidelity="skidding")
    (text,) = [str(w.message) for w in caught]
    assert "\n" not in text and "found no step within 0.5% up to 16 steps per sample" in text, text
    assert "oversample 32" in text and capped.oversample == 16
    with pytest.warns(DefaultStepWarning) as caught:
        auto = Simulator(sc, tolerance=1e-4)
    (text,) = [str(w.message) for w in caught]
    assert auto.tier == "skidding" and auto.can_switch_tiers and auto.oversample == 4
    assert "up to 4 steps per sample" in text and "fidelity skidding lets the check go up to 16" in text, text
    with warnings.catch_warnings():
        warnings.simplefilter("error", DefaultStepWarning)
        Simulator(sc, fidelity="skidding", oversample=4)


def test_the_step_check_of_a_pitted_bearing_is_the_bearings_own():
    """The step check's trials run on the bearing without its defects.  With a 2 x 1 mm
    rectangular outer pit under the load of the small bearing at 13 888 rpm / 4662 N they read the
    start's impacts (estimates 48, 200, 2.1 and 15 % at 2-16 steps per sample): the default ran at
    the cap, 16, 8 times its own cost, and warned, where 2 steps per sample are within 0.2 % of
    the reference over 0.2 s.  With a 4 x 2.3 mm pit the trials at 2, 4, 8 and 32 diverged in
    their 30 ms, and the warning said "estimated nan% off" beside numpy's RuntimeWarnings.  Now
    both take the healthy bearing's 8, on the same estimates, and warn of nothing."""
    import warnings

    from bearing_sim_ros.scene import scene_from_dict

    healthy = Simulator(scene_from_dict(small_bearing(13888, 4662.0)), fidelity="skidding")
    assert healthy.oversample == 8
    for width, depth in ((2.0, 1.0), (4.0, 2.3)):
        pit = {"kind": "outer", "width_mm": width, "depth_mm": depth, "clock": 6, "profile": "rectangular"}
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            sim = Simulator(scene_from_dict(small_bearing(13888, 4662.0, [pit])), fidelity="skidding")
        assert sim.oversample == 8 and not sim.step_warning, (width, sim.step_warning)
        assert sim._model.step_estimates == healthy._model.step_estimates, width



def test_a_diverged_step_check_trial_counts_as_off_and_is_named_in_the_warning():
    """The step check's rule where a trial diverges (``skidding.choose_step``,
    ``step_check_warning``), on trial results given as they would come (no measured healthy
    bearing in the input limits diverges in the check's 30 ms since its trials left the scene's
    defects out; with them, a 4 x 2.3 mm pit's did at 2, 4, 8 and 32 steps per sample and the
    warning said "estimated nan% off").  A diverged trial gives no estimate: it and the step
    below it count as off and the next finer step is tried; where none is found the warning
    names the diverged steps, says the run's own step may diverge too where it is among them,
    gives the finest finite estimate if there is one, and never "nan" or "inf"."""
    settled = {m: np.array([3.0, 1.0]) * (1.0 + 0.01 / m ** 2) for m in (2, 4, 8, 16, 32)}

    def trials(diverged):
        return lambda m: None if m in diverged else settled[m]

    found, estimates, diverged = sk.choose_step(trials({2}), 2, 16, [0, 1])
    assert (found, diverged) == (4, [2]) and estimates[2] == np.inf and estimates[4] < sk.STEP_CHECK_TARGET

    found, estimates, diverged = sk.choose_step(trials({2, 4, 8, 16, 32}), 2, 16, [0, 1])
    assert found is None and diverged == [2, 4, 8, 16, 32] and set(estimates) == {2, 4, 8, 16}
    text = sk.step_check_warning(estimates, diverged, 16, 16)
    assert ("(its trials at oversample 2, 4, 8, 16, 32 diverged within 30 ms, so the run may; it runs at 16)"
            in text), text
    assert "estimated" not in text and "nan" not in text and "inf" not in text and "\n" not in text

    # the finest step's estimate finite, a coarse trial diverged: both said, the run's step not among them
    off = {m: np.array([3.0, 1.0]) * (1.0 + 0.2 / m) for m in (2, 4, 8, 16, 32)}
    found, estimates, diverged = sk.choose_step(lambda m: None if m == 2 else off[m], 2, 16, [0, 1])
    assert found is None and diverged == [2]
    text = sk.step_check_warning(estimates, diverged, 16, 16)
    assert re.search(r"\(estimated 0\.8\d% off at oversample 16; its trials at oversample 2 diverged within 30 ms; "
                     r"it runs at 16\)", text), text
    # under fidelity auto the cap is lower, and the line says what lifts it
    text = sk.step_check_warning({2: np.inf, 4: np.inf}, [2, 4, 8], 4, 4)
    assert "up to 4 steps per sample (its trials at oversample 2, 4, 8 diverged within 30 ms, so the run may; " \
           "it runs at 4): fidelity auto takes at most 4" in text, text


def test_the_default_step_warning_is_said_of_the_tier_that_runs_not_of_a_throwaway():
    """Under ``fidelity: auto`` the small bearing runs the kinematic tier; the node's
    ``prepare_switches`` builds a throwaway skidding model (to load its kernels) whose signal
    nobody gets: no warning of its step (the node said it of a tier it never ran).  A switch
    builds the skidding model that runs, which warns as a Simulator on that tier does."""
    import warnings

    from bearing_sim_ros.scene import scene_from_dict
    from bearing_sim_ros.simulator import DefaultStepWarning

    sim = Simulator(scene_from_dict(SMALL_BEARING))
    assert sim.tier == "kinematic" and sim.can_switch_tiers
    with warnings.catch_warnings():
        warnings.simplefilter("error", DefaultStepWarning)
        sim.prepare_switches()
        sim.advance(150)
    assert sim.tier == "kinematic"


def test_shipped_and_bench_scenes_keep_the_default_step_without_a_warning():
    """The shipped and bench scenes' most loaded balls are at 34.8 kHz at most, under the step
    check's screen (35.1 kHz at 15 kHz output): the default keeps its step, pays nothing for the
    check (it does not run: no estimates) and says nothing."""
    import warnings

    from bearing_sim_ros.bench import SCENARIOS
    from bearing_sim_ros.scene import shipped_scenes
    from bearing_sim_ros.simulator import DefaultStepWarning

    scenes = [load_scene(name) for name in shipped_scenes()] + [sc.build() for sc in SCENARIOS]
    with warnings.catch_warnings():
        warnings.simplefilter("error", DefaultStepWarning)
        for sc in scenes:
            sim = Simulator(sc, fidelity="skidding")
            assert sim.oversample == 2 and sim._model.step_estimates == {}, sc.name


def test_a_render_says_the_default_step_warning_in_one_line(tmp_path, bearing_sim_exe):
    """``bearing-sim render`` of the small bearing at 55 555 rpm on the skidding tier (its step
    check capped): the warning is one line of its own on standard error (not Python's file, line
    and source line), and the render goes on; the recording's ``/diagnostics`` (read with
    rosbags) carry the same line as ``step_warning`` (a terminal's line is gone when the recording
    is analysed), which a scene whose step is not in doubt does not have."""
    import subprocess

    import yaml
    from rosbags.highlevel import AnyReader

    def recorded_step_warnings(path):
        with AnyReader([path]) as reader:
            conns = [c for c in reader.connections if c.topic == "/diagnostics"]
            return [{kv.key: kv.value for kv in reader.deserialize(raw, conn.msgtype).status[0].values}
                    .get("step_warning") for conn, _t, raw in reader.messages(connections=conns)]

    scene_file = tmp_path / "small.yaml"
    scene_file.write_text(yaml.safe_dump(small_bearing(55555, 4662.0, range=49033)))
    out = subprocess.run([bearing_sim_exe, "render", str(scene_file), "--duration", "0.01", "--fidelity",
                          "skidding", "--out", str(tmp_path / "small.mcap")],
                         capture_output=True, text=True, timeout=300)
    assert out.returncode == 0, out.stderr
    lines = [line for line in out.stderr.splitlines() if "step" in line or "Warning" in line]
    assert len(lines) == 1 and lines[0].startswith("bearing-sim: warning: skidding tier: the default solver's step check"), \
        out.stderr
    said = lines[0].removeprefix("bearing-sim: warning: ")
    assert recorded_step_warnings(tmp_path / "small.mcap") == [said]
    quiet = tmp_path / "quiet.mcap"
    out = subprocess.run([bearing_sim_exe, "render", "er16k_healthy", "--duration", "0.01", "--fidelity", "skidding",
                          "--out", str(quiet)], capture_output=True, text=True, timeout=300)
    assert out.returncode == 0, out.stderr
    assert recorded_step_warnings(quiet) == [None]
