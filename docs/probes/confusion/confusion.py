"""Confusion table probe: render scene variants (recording.render.render, what `bearing-sim
render` runs), judge each as `bearing-sim report` does (its channel, its line frequencies)."""
import json, math, os, re, sys, time
from pathlib import Path
import numpy as np
from bearing_sim_ros.recording.render import render
from bearing_sim_ros.recording.reader import open_recording
from bearing_sim_ros.analysis import report as R
from bearing_sim_ros.analysis.envelope import diagnose

REPO = Path(__file__).resolve().parents[3]
OUT = Path(os.environ.get("CONFUSION_DIR", "/tmp/confusion"))
OUT.mkdir(parents=True, exist_ok=True)
BASES = {  # (geometry, state) -> shipped scene, its defects text
    ("er16k", "healthy"): ("er16k_healthy", "[]"),
    ("er16k", "outer"): ("er16k_healthy", "[{kind: outer, width_mm: 0.6, depth_mm: 0.25, length_mm: 0.6, clock: 6, profile: geometric}]"),
    ("er16k", "inner"): ("er16k_healthy", "[{kind: inner, width_mm: 0.6, depth_mm: 0.25, length_mm: 0.6, clock: 6, profile: geometric}]"),
    ("er16k", "ball"): ("er16k_healthy", "[{kind: ball, width_mm: 0.6, depth_mm: 0.25, angle_deg: 0}]"),
    ("6205", "healthy"): ("cwru_6205_normal", "[]"),
    ("6205", "outer"): ("cwru_6205_normal", "[{kind: outer, width_mm: 0.1778, depth_mm: 0.2794, length_mm: 0.1778, clock: 6, profile: geometric}]"),
    ("6205", "inner"): ("cwru_6205_normal", "[{kind: inner, width_mm: 0.1778, depth_mm: 0.2794, length_mm: 0.1778, clock: 6, profile: geometric}]"),
    ("6205", "ball"): ("cwru_6205_normal", "[{kind: ball, width_mm: 0.1778, depth_mm: 0.2794, angle_deg: 0}]"),
}

def variant(geom, state, rpm, load, tier):
    name, defects = BASES[(geom, state)]
    text = (REPO / "config/scenes" / f"{name}.yaml").read_text()
    text, n1 = re.subn(r"operating_point: \{[^}]*\}", f"operating_point: {{shaft_speed_rpm: {rpm}, radial_load: [0.0, {-load:.1f}]}}", text)
    text, n2 = re.subn(r"^defects: \[\]", f"defects: {defects}", text, flags=re.M)
    assert n1 == 1 and n2 == 1
    tag = f"{geom}_{state}_{rpm}_{load}_{tier}"
    p = OUT / f"{tag}.yaml"
    p.write_text(text)
    return tag, p

def analyse(path):
    rec = open_recording(path)
    try:
        d = R._Data(rec, None)
        scene, _ = R._scene_from_metadata(dict(rec.metadata))
        ch = R.envelope_channel(d.channels)
        x = d.accel[:, d.channels.index(ch)]
        speed = float(np.mean(d.cmd_speed))
        rolling = scene.bearing.fault_frequencies(speed / (2 * math.pi))
        freqs = R.line_frequencies(rolling, d.signal_frequencies)
        v = diagnose(x, d.sample_rate, freqs)
        return {"verdict": v["verdict"], "freqs": freqs, "shaft_hz": speed / (2 * math.pi),
                "lines": {k: [l.expected_hz, l.found_hz, l.height, l.prominence] for k, l in v["lines"].items()}}
    finally:
        rec.close()

if __name__ == "__main__":
    # python confusion.py er16k,6205 healthy,outer,inner,ball 300,600,1000,1800,3000,6000 50,1000 \
    #     kinematic,skidding before.json     (recordings kept in $CONFUSION_DIR, /tmp/confusion)
    geoms, states, rpms, loads, tiers = (a.split(",") for a in sys.argv[1:6])
    res_file = Path(sys.argv[6])
    results = json.loads(res_file.read_text()) if res_file.exists() else {}
    for geom in geoms:
        for tier in tiers:
            for load in loads:
                for rpm in rpms:
                    for state in states:
                        tag, p = variant(geom, state, int(rpm), float(load), tier)
                        mcap = OUT / f"{tag}.mcap"
                        t0 = time.time()
                        if not mcap.exists():
                            render(str(p), 4.0, mcap, fidelity=tier, progress=False)
                        r = analyse(mcap)
                        results[tag] = r
                        res_file.write_text(json.dumps(results, indent=0))
                        L = r["lines"]
                        print(f"{tag:32s} {r['verdict']:8s} O {L['bpfo'][3]:8.1f} I {L['bpfi'][3]:6.1f} B {L['2bsf'][3]:6.1f} ({time.time()-t0:.1f}s)", flush=True)
