"""bearing_sim_ros: a virtual bearing accelerometer for ROS 2.

    from bearing_sim_ros import load_scene, Simulator
    sim = Simulator(load_scene("er16k_outer_race"), sample_rate=15000.0)
    batch = sim.advance(150)
"""
__version__ = "0.1.0"

from .errors import SceneError, UserError  # noqa: E402
from .scene import load_scene  # noqa: E402
from .simulator import Batch, Simulator  # noqa: E402

__all__ = ["Batch", "SceneError", "Simulator", "UserError", "__version__", "load_scene"]
