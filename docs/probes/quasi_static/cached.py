"""The probes' saved runs (``np.savez`` of accel, cage_speed, cage_skid, ...) read back as the bench's
runs, for ``bench.errors``: one reader for every probe in this folder."""
import numpy as np

from bearing_sim_ros import bench


def cached_run(path):
    """(``bench.Run``, the npz) of a run a probe saved at ``path``; (None, the npz) for a run that
    failed (saved with a non-empty ``failed``)."""
    z = np.load(path)
    if "failed" in z and str(z["failed"]):
        return None, z
    return bench.Run(accel=z["accel"], cage_speed=float(z["cage_speed"]), cage_skid=float(z["cage_skid"]),
                     cpu=1.0, repeats=[]), z
