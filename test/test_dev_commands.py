"""The developer commands that README.md shows beside ``bearing-sim`` (``python -m
bearing_sim_ros.nodes.node_bench``, ``python -m bearing_sim_ros.analysis.validate_fit``,
``python -m bearing_sim_ros.physics.skidding``) take a mistake as ``bearing-sim`` does: one line
on stderr that names the option, the value and what is allowed, exit status 2, no traceback,
before any work (no node started, no simulation run)."""
from __future__ import annotations

import subprocess
import sys

import pytest

CASES = [
    # (module, arguments, what the one line must say)
    ("bearing_sim_ros.analysis.validate_fit", ["--seconds", "-1"],
     "argument --seconds: '-1' must be a finite number > 0"),
    ("bearing_sim_ros.analysis.validate_fit", ["--maxfev", "0"],
     "argument --maxfev: '0' must be a finite number > 0"),
    # its default --cwru is relative to the repository's root: run from elsewhere, one line
    ("bearing_sim_ros.analysis.validate_fit", ["--maxfev", "1"],
     "--cwru '../shared/validation/cwru': no such folder; give a folder of CWRU .mat files"),
    # --scene nope too: where the duration is not refused the old code skipped both tiers
    # (no node started) and printed a table, exit status 0
    ("bearing_sim_ros.nodes.node_bench", ["--duration", "-5", "--scene", "nope"],
     "argument --duration: '-5' must be a finite number > 0"),
    ("bearing_sim_ros.nodes.node_bench", ["--scene", "er16k_outer_rce", "--duration", "1"],
     "scene = 'er16k_outer_rce': unknown scene; shipped scenes are"),
    ("bearing_sim_ros.physics.skidding", ["abc"],
     "argument seconds: 'abc' is not a number"),
    ("bearing_sim_ros.physics.skidding", ["-1"],
     "argument seconds: -1 s: allowed range is [0.01, 60] s"),
]


@pytest.mark.parametrize("module,args,said", CASES, ids=[f"{m.rsplit('.', 1)[1]} {' '.join(a)}" for m, a, _ in CASES])
def test_a_mistake_is_one_line_and_exit_status_2(tmp_path, module, args, said):
    # tmp_path as the working folder: no ../shared/validation/cwru beside it
    r = subprocess.run([sys.executable, "-m", module, *args], cwd=tmp_path,
                       capture_output=True, text=True, timeout=120)
    assert r.returncode == 2, r.stdout + r.stderr
    assert r.stdout == "", r.stdout
    assert r.stderr.count("\n") == 1 and r.stderr.startswith("error: ") and said in r.stderr, r.stderr
