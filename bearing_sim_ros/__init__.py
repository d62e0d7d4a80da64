"""bearing_sim_ros: a virtual bearing accelerometer for ROS 2.

    from bearing_sim_ros import load_scene, Simulator
    sim = Simulator(load_scene("er16k_outer_race"), sample_rate=15000.0)
    batch = sim.advance(150)
"""
__version__ = "0.1.0"

__all__ = ["Batch", "SceneError", "Simulator", "UserError", "__version__", "load_scene"]

# where each name of the API lives: imported when first used, so that importing the package (the
# commands' first line imports bearing_sim_ros.cli) does not load numpy and numba, half a second
# in which Ctrl-C and SIGTERM could not yet be handled (teardown.CommandSignals)
_API = {"Batch": "simulator", "SceneError": "errors", "Simulator": "simulator", "UserError": "errors",
        "load_scene": "scene"}


def __getattr__(name):
    if name not in _API:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    from importlib import import_module

    value = getattr(import_module(f"{__name__}.{_API[name]}"), name)
    globals()[name] = value
    return value


def __dir__():
    return sorted(set(globals()) | set(__all__))
