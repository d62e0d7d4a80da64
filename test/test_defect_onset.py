"""Defects that appear and grow mid-run (a scene's ``onset_s`` and ``growth_s``): the schedule, the
signal before and after the onset in both tiers, chunking, tier switches and the trend a detector
sees (README, "Faults that appear and grow")."""
from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from bearing_sim_ros import Simulator, load_scene
from bearing_sim_ros.errors import UserError
from bearing_sim_ros.analysis.envelope import diagnose
from bearing_sim_ros.physics.defects import (D_INDEX, D_KIND, KIND_BALL, KIND_OUTER, DefectSchedule,
                                             active_defect_table, wander_reach)
from bearing_sim_ros.scene import Defect

FS = 15000.0


def _with_defects(scene, **changes):
    """``scene`` with each of its defects changed by ``changes`` (onset=..., growth=...)."""
    return dataclasses.replace(scene, defects=tuple(dataclasses.replace(d, **changes) for d in scene.defects))


def test_schedule_sizes_change_only_where_next_change_says():
    """Onset at 0.5 s, growth over 0.1 s at 15 kHz: absent up to sample 7499, 0.1 of the size at
    7500, a tenth more every 150 samples (10 ms), full from 8850; a defect without onset is at
    full size throughout.  Walking every sample, the sizes change exactly at the samples that
    ``next_change`` names and nowhere else."""
    growing = Defect("outer", 1e-4, 1e-4, 1e-4, onset=0.5, growth=0.1)
    fixed = Defect("inner", 1e-4, 1e-4, 1e-4)
    sch = DefectSchedule((growing, fixed), FS)
    assert not sch.static and DefectSchedule((fixed,), FS).static
    assert sch.sizes(7499) == (0.0, 1.0)
    assert sch.sizes(7500) == (pytest.approx(0.1), 1.0)
    assert sch.sizes(7649)[0] == pytest.approx(0.1) and sch.sizes(7650)[0] == pytest.approx(0.2)
    assert sch.sizes(8849)[0] == pytest.approx(0.9) and sch.sizes(8850) == (1.0, 1.0)
    assert sch.next_change(8850) is None
    changes, index = [], 0
    while (nxt := sch.next_change(index)) is not None:
        assert nxt > index
        changes.append(nxt)
        index = nxt
    assert changes == [7500 + 150 * k for k in range(10)]
    sizes = [sch.sizes(i)[0] for i in range(7000, 9500)]
    moved = [7000 + i for i in range(1, len(sizes)) if sizes[i] != sizes[i - 1]]
    assert moved == changes
    # an onset between two samples takes the first sample at or after it
    assert DefectSchedule((dataclasses.replace(fixed, onset=1.00001 / FS),), FS).sizes(1) == (0.0,)
    assert DefectSchedule((dataclasses.replace(fixed, onset=1.00001 / FS),), FS).sizes(2) == (1.0,)


def test_a_scene_key_out_of_range_is_one_line(tmp_path):
    from bearing_sim_ros.errors import SceneError

    text = (load_scene("cwru_6205_or007_6").source_text
            .replace("clock: 6, profile: geometric}", "clock: 6, profile: geometric, onset_s: -1}"))
    path = tmp_path / "bad.yaml"
    path.write_text(text)
    with pytest.raises(SceneError, match=r"^scene bad.yaml: defects\[0\]\.onset_s = -1: allowed range is \[0, 1e\+06\]$"):
        load_scene(path)
    path.write_text(text.replace("onset_s: -1", "growth_s: yes"))
    with pytest.raises(SceneError, match=r"^scene bad.yaml: defects\[0\]\.growth_s = True: expected a number"):
        load_scene(path)
    path.write_text(text.replace("onset_s: -1", "onset_s: 2.5, growth_s: 4"))
    d = load_scene(path).defects[0]
    assert (d.onset, d.growth) == (2.5, 4.0)


def test_shipped_growing_scene_is_the_outer_race_scene_with_an_onset():
    grown = load_scene("cwru_6205_or007_6_growing")
    plain = load_scene("cwru_6205_or007_6")
    assert _with_defects(grown, onset=0.0, growth=0.0).defects == plain.defects
    assert (grown.defects[0].onset, grown.defects[0].growth) == (5.0, 20.0)
    for f in dataclasses.fields(plain):
        if f.name not in ("name", "description", "defects", "source_text", "source_path"):
            assert getattr(grown, f.name) == getattr(plain, f.name), f.name


@pytest.mark.parametrize("tier", ["kinematic", "skidding"])
def test_before_the_onset_the_signal_is_the_healthy_scenes(tier):
    """ER-16K outer race with onset at 0.3 s against the same scene without defects: the same
    samples, bit for bit, up to the sensor chain's lookahead before the onset (the linear-phase
    anti-aliasing FIR reaches that far ahead), different from the onset on; the contact forces,
    which no filter delays, are the same up to the onset itself."""
    scene = load_scene("er16k_outer_race")
    late = _with_defects(scene, onset=0.3)
    healthy = dataclasses.replace(scene, defects=())
    a, b = Simulator(late, fidelity=tier), Simulator(healthy, fidelity=tier)
    onset = int(0.3 * FS)
    ba, bb = a.advance(onset + 1500), b.advance(onset + 1500)
    ahead = a.chain.lookahead_samples
    assert ahead == 19                   # the FIR's reach: 76 chain samples at 4 per output sample
    differs = np.nonzero(np.any(ba.accel != bb.accel, axis=1))[0]
    # README: the last 18 samples (the kinematic tier's chain sample at the onset instant ends
    # the step before the pit: the first with it is a quarter sample later), 19 in the skidding tier
    assert onset - differs[0] == {"kinematic": ahead - 1, "skidding": ahead}[tier]
    assert np.array_equal(ba.contact_forces[:onset], bb.contact_forces[:onset])
    assert not np.array_equal(ba.contact_forces[onset:onset + 150], bb.contact_forces[onset:onset + 150])
    assert a.defect_sizes == (1.0,) and b.defect_sizes == ()
    # after the onset the pit is there: the ball passing it loses its outer-race load
    full = Simulator(scene, fidelity=tier).advance(onset + 1500)
    assert ba.accel[onset:, 1].std() == pytest.approx(full.accel[onset:, 1].std(), rel=0.1)
    assert ba.accel[onset:, 1].std() > 3 * bb.accel[onset:, 1].std()


@pytest.mark.parametrize("tier", ["kinematic", "skidding"])
def test_chunking_does_not_change_a_sample_across_onset_and_growth(tier):
    """Onset and growth steps that fall inside batches of 97 samples give the same samples as
    one advance (every output: accel, contact forces, cage speed, the skidding tier's extras)."""
    scene = _with_defects(load_scene("er16k_inner_race"), onset=0.02, growth=0.05)
    n = 97 * 12
    one = Simulator(scene, fidelity=tier, seed=3).advance(n)
    sim = Simulator(scene, fidelity=tier, seed=3)
    parts = [sim.advance(97) for _ in range(12)]
    assert sim.defect_sizes == (1.0,)
    assert np.array_equal(one.accel, np.concatenate([p.accel for p in parts]))
    assert np.array_equal(one.contact_forces, np.concatenate([p.contact_forces for p in parts]))
    assert np.array_equal(one.cage_speed, np.concatenate([p.cage_speed for p in parts]))
    for key, val in one.extras.items():
        assert np.array_equal(val, np.concatenate([p.extras[key] for p in parts])), key
    assert (tier == "skidding") == bool(one.extras)


def test_a_growing_outer_race_pit_raises_the_rms_and_is_called_outer_from_40_percent():
    """The shipped ``cwru_6205_or007_6_growing`` in 1 s windows: healthy (verdict and RMS) before
    the onset at 5 s, still healthy while the pit is under 30 % of its size, outer at 50 % and
    above; from 30 % on the RMS rises from window to window as the pit grows, to the full-size
    scene's level
    (README, "Faults that appear and grow")."""
    scene = load_scene("cwru_6205_or007_6_growing")
    sim = Simulator(scene, seed=1)
    fr = scene.bearing.fault_frequencies(scene.shaft_hz)
    rows = []
    for _ in range(27):
        x = sim.advance(int(FS)).accel[:, 1]
        rows.append((sim.defect_sizes[0], float(x.std()), diagnose(x, FS, fr)["verdict"]))
    sizes, rms, verdicts = zip(*rows)
    assert sizes[4] == 0.0 and sizes[5] == pytest.approx(0.05, abs=1e-3) and sizes[24] == 1.0
    assert all(v == "healthy" for s, v in zip(sizes, verdicts) if s <= 0.3), rows
    assert all(v == "outer" for s, v in zip(sizes, verdicts) if s >= 0.5), rows
    called = next(i for i, v in enumerate(verdicts) if v == "outer")
    assert 11 <= called <= 13           # the window that ends at 12-14 s: "13 s into the run"
    healthy = Simulator(load_scene("cwru_6205_normal"), seed=1).advance(int(5 * FS)).accel[:, 1].std()
    assert rms[0:5] == pytest.approx([healthy] * 5, rel=0.1)
    assert all(b > a for a, b in zip(rms[10:24], rms[11:25])), rms          # 30 % to full size
    full = Simulator(load_scene("cwru_6205_or007_6"), seed=1)
    full.advance(int(FS))
    assert rms[26] == pytest.approx(full.advance(int(FS)).accel[:, 1].std(), rel=0.15)


def test_a_tier_switch_keeps_the_defects_as_they_are():
    """fidelity auto switches to the skidding tier at 10000 rpm / 10 N: the new tier takes the
    defects present at the switch (none before the onset, the pit after it), and its signal
    shows the pit as the kinematic tier's did."""
    scene = _with_defects(load_scene("er16k_outer_race"), onset=0.05)
    sim = Simulator(scene)
    assert sim.tier == "kinematic"
    sim.advance(150)
    sim.advance(150, shaft_speed=10000 * 2 * np.pi / 60, radial_load=(0.0, -10.0))
    assert sim.tier == "skidding" and sim._model.dtab.shape[0] == 0
    sim.advance(600)
    assert sim.defect_sizes == (1.0,) and sim._model.dtab.shape[0] == 1
    sim.advance(1500, shaft_speed=1600 * 2 * np.pi / 60, radial_load=(0.0, -50.0))
    assert sim.tier == "kinematic" and sim._model.defect_sizes == (1.0,)
    assert sim._model.dtab.shape[0] == 1


def test_a_table_without_the_absent_defects_keeps_each_ones_draws():
    """The wandering ball defect's latitude draws are a stream per scene defect: with the first
    defect absent, the ball defect's row keeps its index (``D_INDEX``), so it is met at the same
    spin angles as when every defect is there."""
    b = load_scene("cwru_6205_b007").bearing
    defects = (Defect("outer", 1e-4, 1e-4, 1e-4), Defect("ball", 1e-4, 1e-4, 1e-4, wander_turns=3.0))
    both = active_defect_table(defects, None, b, seed=7)
    only_ball = active_defect_table(defects, (0.0, 1.0), b, seed=7)
    assert only_ball.shape[0] == 1 and only_ball[0, D_KIND] == KIND_BALL and only_ball[0, D_INDEX] == 1
    assert both[0, D_KIND] == KIND_OUTER
    spins = np.linspace(0.0, 200.0, 2001)
    reach_both = [wander_reach(both, 1, s) for s in spins]
    assert [wander_reach(only_ball, 0, s) for s in spins] == reach_both
    assert 0.0 in reach_both and 1.0 in reach_both           # the draws matter to the test
    half = active_defect_table(defects, (1.0, 0.5), b, seed=7)
    assert half[1, 1] == pytest.approx(0.5 * both[1, 1])     # D_HALF: half the width


def test_a_wandering_ball_defect_is_met_for_the_share_of_time_its_geometry_gives():
    """The CWRU ball scene's pit (length L = 0.1778 mm on a ball of radius r = 3.97 mm) is met
    while sin(latitude) lies within (a + L / 2) / r, a the contact ellipse's transverse semi-axis
    (Hamrock-Brewe, from the catalog's coefficient, at the most loaded ball's static load), and
    fully within L less.  With sin(latitude) a linear interpolation of independent uniform draws
    on [-1, 1], the share of spin angle in each band follows from that distribution alone: here
    from numpy's own generator, not the kernel's hash.  The README's figures (a = 0.36 mm at
    19 N; met 16 %, fully 9 %) are these."""
    from bearing_sim_ros.physics.defects import D_WANDER

    scene = load_scene("cwru_6205_b007")
    model = Simulator(scene, fidelity="kinematic")._model
    b, d = scene.bearing, scene.defects[0]
    a = max(b.inner_contact.a_coeff, b.outer_contact.a_coeff) * model.ellipse_ball_load ** (1.0 / 3.0)
    reach = (a + 0.5 * d.length) / (0.5 * b.ball_diameter)
    full = reach - min(d.length, a) / (0.5 * b.ball_diameter)
    assert a == pytest.approx(0.36e-3, abs=0.005e-3) and model.ellipse_ball_load == pytest.approx(19.0, abs=1.0)
    rng = np.random.default_rng(1)
    f = rng.random(1_000_000)
    lat = (1.0 - f) * rng.uniform(-1.0, 1.0, f.size) + f * rng.uniform(-1.0, 1.0, f.size)
    expected_met, expected_full = np.mean(np.abs(lat) < reach), np.mean(np.abs(lat) < full)
    # 20 000 draws of the kernel's, ten spin angles between two draws
    turns = model.dtab[0, D_WANDER]
    spins = np.linspace(0.0, 2.0 * np.pi * turns * 20000, 200001)
    applied = np.array([wander_reach(model.dtab, 0, s) for s in spins])
    assert np.mean(applied > 0.0) == pytest.approx(expected_met, abs=0.01)
    assert np.mean(applied >= 1.0) == pytest.approx(expected_full, abs=0.01)
    assert round(expected_met, 2) == 0.16 and round(expected_full, 2) == 0.09
    # and the faded band between: the loss falls linearly from full to none over it
    mid = (applied > 0.0) & (applied < 1.0)
    assert np.mean(mid) == pytest.approx(expected_met - expected_full, abs=0.01)


def test_recorded_diagnostics_say_when_the_fault_is_there(tmp_path):
    """``bearing-sim render`` of the CWRU outer race with its pit appearing at 1.5 s and growing
    over 1 s: the recorded ``/diagnostics`` (read with rosbags) give ``faults_present`` none at
    1 s, outer from 2 s, and ``defect_sizes`` 0, then the size at each second (0.5 at 2 s, full
    at 3 s), as the node's do, and at the end of the signal (3.5 s)."""
    from rosbags.highlevel import AnyReader

    from bearing_sim_ros.recording.render import render

    text = (load_scene("cwru_6205_or007_6").source_text
            .replace("clock: 6, profile: geometric}", "clock: 6, profile: geometric, onset_s: 1.5, growth_s: 1.0}"))
    scene = tmp_path / "onset.yaml"
    scene.write_text(text)
    out = tmp_path / "onset.mcap"
    render(str(scene), 3.5, out, progress=False)
    seen = {}
    with AnyReader([out]) as reader:
        conns = [c for c in reader.connections if c.topic == "/diagnostics"]
        for conn, t, raw in reader.messages(connections=conns):
            msg = reader.deserialize(raw, conn.msgtype)
            values = {kv.key: kv.value for kv in msg.status[0].values}
            seen[round(msg.header.stamp.sec + msg.header.stamp.nanosec * 1e-9, 3)] = (
                values["faults_present"], values["defect_sizes"])
    assert seen == {1.0: ("none", "0"), 2.0: ("outer", "0.5"), 3.0: ("outer", "1"), 3.5: ("outer", "1")}


def test_both_tiers_draw_a_wandering_ball_defects_latitudes_from_the_runs_seed():
    """The skidding tier drew them from seed 0 whatever the run's seed, so a switch of tiers
    changed where the pit was met; now both tables carry the run's seed."""
    from bearing_sim_ros.physics.defects import D_WSEED

    scene = load_scene("cwru_6205_b007")
    for tier in ("kinematic", "skidding"):
        sim = Simulator(scene, fidelity=tier, seed=11)
        assert sim._model.dtab[0, D_WSEED] == 11, tier
        sim._model.set_defect_sizes((0.5,))
        assert sim._model.dtab[0, D_WSEED] == 11, tier


def test_a_wandering_ball_defect_keeps_its_contact_ellipse_across_tier_switches():
    """The contact ellipse that a wandering pit must lie within to be met is sized by the most
    loaded ball's static load.  Both tiers find about the same load on the CWRU ball scene (the
    skidding tier took a nominal 100 N, five times as much, before), and a tier switch hands the
    old tier's on whatever the load is then, so the pit is met as often after it as before."""
    from bearing_sim_ros.physics.defects import D_WREACH

    scene = load_scene("cwru_6205_b007")
    own = {tier: Simulator(scene, fidelity=tier)._model for tier in ("kinematic", "skidding")}
    assert own["skidding"].ellipse_ball_load == pytest.approx(own["kinematic"].ellipse_ball_load, rel=0.02)
    assert 15.0 < own["kinematic"].ellipse_ball_load < 25.0       # 0 N radial load: the shaft's weight
    # the scene's 5 % tolerance keeps the kinematic tier up to 20000 rpm: ask for 0.2 %
    sim = Simulator(dataclasses.replace(scene, fidelity_tolerance=0.002))
    assert sim.tier == "kinematic"
    first = (sim._model.ellipse_ball_load, sim._model.dtab[0, D_WREACH])
    sim.advance(150)
    sim.advance(150, shaft_speed=10000 * 2 * np.pi / 60, radial_load=(0.0, -10.0))
    assert sim.tier == "skidding"
    assert (sim._model.ellipse_ball_load, sim._model.dtab[0, D_WREACH]) == first
    sim.advance(150, shaft_speed=1797 * 2 * np.pi / 60, radial_load=(0.0, -2000.0))
    assert sim.tier == "kinematic"
    assert (sim._model.ellipse_ball_load, sim._model.dtab[0, D_WREACH]) == first


def test_the_diagnostics_truth_is_that_of_the_sample_asked_for():
    """The live node computes up to 50 ms ahead of what it has published; its ``faults_present``,
    ``defect_sizes`` and ``fault_onsets_s`` are those of the last published sample, which
    ``defect_values`` gives for a sample before the latest computed one.  The onset is the first
    sample's time with the defect: the scene's ``onset_s`` rounded up to the sample grid."""
    from bearing_sim_ros.recording.render import defect_values

    sim = Simulator(_with_defects(load_scene("er16k_outer_race"), onset=0.1), sample_rate=FS)
    sim.advance(int(0.12 * FS))
    assert defect_values(sim) == {"faults_present": "outer", "defect_sizes": "1", "fault_onsets_s": "outer=0.100000"}
    assert defect_values(sim, int(0.1 * FS) - 1) == {"faults_present": "none", "defect_sizes": "0",
                                                     "fault_onsets_s": "none"}
    assert defect_values(sim, int(0.1 * FS))["faults_present"] == "outer"
    assert defect_values(sim, -1)["faults_present"] == "none"
    off_grid = Simulator(_with_defects(load_scene("er16k_outer_race"), onset=0.10001), sample_rate=FS)
    assert off_grid.defect_onsets_s == (1501 / FS,)
    assert defect_values(off_grid, 1501)["fault_onsets_s"] == "outer=0.100067"
    assert defect_values(off_grid, 1500)["fault_onsets_s"] == "none"


@pytest.mark.parametrize("tier", ["kinematic", "skidding"])
def test_a_speed_ramp_across_growth_steps_turns_the_shaft_by_its_integral(tier):
    """One advance whose speed ramps w0 -> 1.5 w0 while the defect appears and grows inside it
    runs the tier in segments, one per size step, each continuing the call's ramp from where the
    last ended: the shaft turns by the integral of the ramp, as it does without a defect, and the
    batch's speed series is the same ramp.  The snapshots are at the next output sample, and the
    physics (and with it the ramp) runs the chain's lookahead ahead of it."""
    scene = _with_defects(load_scene("er16k_inner_race"), onset=0.02, growth=0.05)
    sim = Simulator(scene, fidelity=tier)
    sim.advance(150)
    a0, w0 = sim.snapshot().shaft_angle, sim.shaft_speed
    n = 1500                   # 0.1 s: the onset at 0.02 s and the ten growth steps inside it
    b = sim.advance(n, shaft_speed=1.5 * w0)
    assert sim.defect_sizes == (1.0,)
    ahead = sim.chain.lookahead_samples
    w_at_stamp = w0 * (1 + 0.5 * (n - ahead) / n)
    turned = w0 * ahead / FS + 0.5 * (w0 + w_at_stamp) * (n - ahead) / FS
    assert sim.snapshot().shaft_angle - a0 == pytest.approx(turned, rel=1e-9)
    np.testing.assert_allclose(b.shaft_speed[ahead:], w0 * (1 + 0.5 * np.arange(n - ahead) / n), rtol=1e-12)


@pytest.mark.parametrize("sample", [None, "3", 1.5, True, np.array([3])])
def test_defect_sizes_at_names_a_sample_that_is_not_a_whole_number(sample):
    """``defect_sizes_at("3")`` and ``(1.5)`` answered for sample 3 and 1, ``(True)`` for sample 1
    and ``(None)`` ended in a TypeError from int(); a numpy integer is a sample like any other."""
    sim = Simulator(_with_defects(load_scene("er16k_outer_race"), onset=0.01), fidelity="kinematic")
    with pytest.raises(UserError) as exc:
        sim.defect_sizes_at(sample)
    assert str(exc.value) == f"sample = {sample!r}: expected a whole number (an output sample index)"
    assert sim.defect_sizes_at(np.int64(149)) == (0.0,) and sim.defect_sizes_at(150) == (1.0,)


def test_a_pits_largest_drop_is_the_sag_of_its_half_width_on_either_race():
    """The ball sinks into a pit from both edges at once, so its largest drop is the sagitta of
    half the pit's width on the contact's radius rho = 1 / (1/r +- 1/R_race) (convex inner race
    "+", concave outer "-"): for the ER-16K's 0.6 mm pits 14.3 um on the inner race and 9.4 um on
    the outer one (``physics.defects``), far less than their 0.25 mm depth."""
    from bearing_sim_ros.catalog import get_bearing
    from bearing_sim_ros.physics.defects import D_HMAX_I, D_HMAX_O, defect_table

    b = get_bearing("ER-16K")
    row = defect_table([Defect("inner", 0.6e-3, 0.25e-3, 0.6e-3)], b)[0]
    assert row[D_HMAX_I] == pytest.approx(14.3e-6, abs=0.05e-6) and row[D_HMAX_O] == pytest.approx(9.4e-6, abs=0.05e-6)


def test_a_growing_pit_scales_its_width_length_and_depth_together():
    """A spall grows from a small shallow pit: at half its size it is half as wide, half as long
    and half as deep (``scaled_defect``), in the table the tiers read too."""
    from bearing_sim_ros.physics.defects import D_DEPTH, D_HALF, scaled_defect

    b = load_scene("er16k_outer_race").bearing
    pit = Defect("outer", 0.6e-3, 0.02e-3, 0.8e-3)
    half = scaled_defect(pit, 0.5)
    assert (half.width, half.length, half.depth) == pytest.approx((0.3e-3, 0.4e-3, 0.01e-3), rel=1e-12)
    assert scaled_defect(pit, 1.0) == pit
    full, grown = active_defect_table([pit], None, b), active_defect_table([pit], (0.5,), b)
    assert grown[0, D_DEPTH] == pytest.approx(0.5 * full[0, D_DEPTH]) and grown[0, D_HALF] == pytest.approx(0.5 * full[0, D_HALF])


def test_a_wandering_ball_defect_is_met_within_the_wider_of_its_two_contact_ellipses():
    """A ball defect meets both races: it is met while it lies within the wider contact ellipse's
    transverse semi-axis a (+ half its length) of the rolling track, a = a_coeff Q^(1/3) at the
    nominal 100 N.  Grooves of 0.51 (inner) and 0.54 (outer) conformity make the two ellipses
    differ (the closer inner groove's is the wider here)."""
    from bearing_sim_ros.catalog import bearing_from_mapping
    from bearing_sim_ros.physics.defects import D_WREACH, NOMINAL_BALL_LOAD, defect_table

    b = bearing_from_mapping("custom", {"balls": 9, "ball_diameter_mm": 7.94, "pitch_diameter_mm": 38.5,
                                        "inner_groove_conformity": 0.51, "outer_groove_conformity": 0.54})
    a_inner, a_outer = (c.a_coeff * NOMINAL_BALL_LOAD ** (1 / 3) for c in (b.inner_contact, b.outer_contact))
    assert a_inner > 1.2 * a_outer
    length = 0.2e-3
    row = defect_table([Defect("ball", 0.2e-3, 0.1e-3, length, wander_turns=3.0)], b)[0]
    assert row[D_WREACH] == pytest.approx((a_inner + 0.5 * length) / (0.5 * b.ball_diameter), rel=1e-12)
