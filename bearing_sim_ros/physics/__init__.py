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
    folder = os.path.join(base, digest.hexdigest()[:16])
    if not _can_write_in(folder):
        # an installed package the user cannot write in (site-packages of another user) and no
        # writable cache home (a service account, HOME=/nonexistent): numba then had no place
        # for any cache=True kernel and every command ended at import ("cannot cache function
        # ...: no locator available")
        folder = _private_temp_folder(digest.hexdigest()[:16])
    nb_config.CACHE_DIR = folder


def _can_write_in(folder: str) -> bool:
    """Whether ``folder`` exists or can be made, and a file can be made in it."""
    import tempfile

    try:
        os.makedirs(folder, exist_ok=True)
        fd, probe = tempfile.mkstemp(dir=folder, prefix=".bearing-sim-probe-")
        os.close(fd)
        os.unlink(probe)
    except OSError:
        return False
    return True


def _private_temp_folder(key: str) -> str:
    """``$TMPDIR/bearing_sim_ros-numba-<uid>/<key>``, kept across runs, if that folder is the
    user's own and nobody else can write in it (numba's cache files are pickles: a folder
    another user could fill must not be loaded from); else a new temporary folder."""
    import stat
    import tempfile

    uid = os.getuid() if hasattr(os, "getuid") else None
    top = os.path.join(tempfile.gettempdir(), f"bearing_sim_ros-numba-{uid}")
    try:
        os.makedirs(top, mode=0o700, exist_ok=True)
        info = os.lstat(top)
        if (stat.S_ISDIR(info.st_mode) and (uid is None or info.st_uid == uid)
                and not info.st_mode & 0o022 and _can_write_in(os.path.join(top, key))):
            return os.path.join(top, key)
    except OSError:
        pass
    return tempfile.mkdtemp(prefix="bearing_sim_ros-numba-")


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
