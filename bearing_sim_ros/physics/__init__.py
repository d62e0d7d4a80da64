"""The physics core: bearing models (tiers) and the accelerometer chain.  No ROS imports here.

Every tier is a class with the interface of :class:`TierModel`: it advances the bearing by a
number of internal steps while speed and load move linearly from one value to another, and
returns what happened at the internal rate as a :class:`TierOutput`.  The simulator turns that
into output samples (anti-aliasing, decimation, sensor).
"""
from __future__ import annotations

import hashlib
import os
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np


def _isolate_numba_cache() -> None:
    """Give the compiled kernels a cache folder keyed by the physics sources.

    numba's ``cache=True`` checks only the source file of the function it caches, not the
    modules it calls (e.g. a kernel in kinematic.py inlining defects.py): after an edit or an
    upgrade it could load a stale kernel.  A folder per hash of every physics source makes any
    change recompile once, and keeps start-up fast afterwards.
    """
    import numba.core.config as nb_config

    here = Path(__file__).resolve().parent
    digest = hashlib.sha256()
    for src in sorted(here.rglob("*.py")):
        digest.update(src.name.encode())
        digest.update(src.read_bytes())
    base = nb_config.CACHE_DIR or os.path.join(
        os.environ.get("XDG_CACHE_HOME", os.path.expanduser("~/.cache")), "bearing_sim_ros", "numba")
    nb_config.CACHE_DIR = os.path.join(base, digest.hexdigest()[:16])


_isolate_numba_cache()


@dataclass
class TierOutput:
    """What a tier produced over ``n`` internal steps (arrays at the internal rate).

    accel: (n, 2) acceleration of the sensor mount, x horizontal and y vertical (m/s^2), at the
    start of each internal sample interval; inner_force, outer_force: (n, Nb) contact force of each ball on the inner
    and the outer race (N); cage_speed: (n,) rad/s; extras: further per-step series of a tier
    (e.g. "ball_skid", "cage_skid" ratios for the skidding tier).
    """

    accel: np.ndarray
    inner_force: np.ndarray
    outer_force: np.ndarray
    cage_speed: np.ndarray
    extras: dict = field(default_factory=dict)


@dataclass
class KinematicSnapshot:
    """Angles (rad) and speeds (rad/s) of the rotating parts for the ``state`` topic."""

    shaft_angle: float
    shaft_speed: float
    cage_angle: float
    cage_speed: float
    ball_angles: np.ndarray      # revolution angle of each ball about the bearing axis
    ball_speeds: np.ndarray


class TierModel:
    """Interface of a bearing model tier (documentation; tiers duck-type it).

    Attributes: ``name`` ("kinematic" or "skidding"), ``internal_rate`` (Hz, an integer multiple
    of the output rate chosen by the simulator).  A tier's "output rate" is the simulator's
    ``physics_rate``: the output rate, or a whole multiple of it below 15 kHz, decimated by the
    simulator (every k-th row of the per-sample series; the chain filters the acceleration).
    """

    name = "abstract"

    def advance(self, n_steps: int, speed0: float, speed1: float,
                load0: np.ndarray, load1: np.ndarray) -> TierOutput:  # pragma: no cover
        """Advance by ``n_steps`` internal steps; shaft speed (rad/s) and load (N, (2,)) move
        linearly from the first to the second value over the span."""
        raise NotImplementedError

    def snapshot(self) -> KinematicSnapshot:  # pragma: no cover
        raise NotImplementedError
