"""Where the shipped configuration lives: the source tree, or share/ of an installed package."""
from __future__ import annotations

import os
import sys
from pathlib import Path

PACKAGE = "bearing_sim_ros"


def config_dir() -> Path:
    """The ``config/`` folder: beside the package in a source checkout (pip -e, tests), else the
    ament share directory of an installed package (colcon, pip wheel)."""
    here = Path(__file__).resolve().parent.parent / "config"
    if (here / "bearings.yaml").is_file():
        return here
    candidates = [Path(sys.prefix) / "share" / PACKAGE / "config"]
    for prefix in os.environ.get("AMENT_PREFIX_PATH", "").split(os.pathsep):
        if prefix:
            candidates.append(Path(prefix) / "share" / PACKAGE / "config")
    for cand in candidates:
        if (cand / "bearings.yaml").is_file():
            return cand
    raise FileNotFoundError(f"cannot find the {PACKAGE} config folder (looked in {here})")


def scenes_dir() -> Path:
    return config_dir() / "scenes"
