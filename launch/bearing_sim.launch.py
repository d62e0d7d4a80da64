"""Launch the virtual bearing accelerometer in an apt-installed ROS 2 Jazzy workspace.

    ros2 launch bearing_sim_ros bearing_sim.launch.py
    ros2 launch bearing_sim_ros bearing_sim.launch.py scene:=cwru_6205_or007_6 record:=/tmp/run.mcap
    ros2 launch bearing_sim_ros bearing_sim.launch.py namespace:=rig1 fidelity:=skidding

Every node parameter is a launch argument with the node's default (test/test_readme.py checks
the table against the node's).  (Not run by
the test suite: ``launch`` has no PyPI wheel; the pip setup uses ``bearing-sim node`` instead.)
"""
from launch import LaunchDescription
from launch.actions import DeclareLaunchArgument
from launch.substitutions import LaunchConfiguration
from launch_ros.actions import Node
from launch_ros.parameter_descriptions import ParameterValue

# name, default (as text), type, description
ARGUMENTS = [
    ("scene", "er16k_outer_race", str, "shipped scene name or path of a scene YAML"),
    ("sample_rate", "15000.0", float, "output sample rate, Hz"),
    ("batch_duration", "0.01", float, "seconds per waveform table (x sample_rate = whole samples)"),
    ("real_time", "true", bool, "pace on the steady clock; false = as fast as possible"),
    ("duration", "0.0", float, "seconds of signal, then exit; 0 = forever"),
    ("record", "", str, "MCAP file to record to; empty = no recording"),
    ("record_max_duration", "0.0", float, "split the recording: s per file (run_000.mcap, ...); 0 = one file"),
    ("record_max_size", "0", int, "split the recording: bytes on disk per file; 0 = one file"),
    ("fidelity", "auto", str, "auto | kinematic | skidding"),
    ("seed", "0", int, "seed of random slip and sensor noise"),
    ("oversample", "0", int, "integration steps per output sample; 0 = each tier's own"),
    ("publish_clock", "false", bool, "publish /clock with the simulation time"),
    ("frame_id", "", str, "frame of the waveform tables; empty = the scene's sensor frame"),
    ("state_rate", "50.0", float, "JointState rate, Hz (<= 1 / batch_duration); 0 = off"),
    ("compute_ahead", "0.05", float, "compute batches up to this long before they are due, s"),
    ("input_max_age", "1.0", float, "reject load messages older than this, s; 0 = any age"),
    ("wait_for_subscribers", "0", int, "hold the first batch until this many subscribe to accel; 0 = start at once"),
]


def generate_launch_description():
    args = [DeclareLaunchArgument(name, default_value=default, description=text)
            for name, default, _kind, text in ARGUMENTS]
    args.append(DeclareLaunchArgument("namespace", default_value="", description="namespace of the node"))
    params = {name: ParameterValue(LaunchConfiguration(name), value_type=kind)
              for name, _default, kind, _text in ARGUMENTS}
    node = Node(
        package="bearing_sim_ros",
        executable="bearing_sim_node",
        name="bearing_sim",
        namespace=LaunchConfiguration("namespace"),
        parameters=[params],
        output="screen",
        emulate_tty=True,
        # SIGINT first: the node finishes its batch and closes the recording
        sigterm_timeout="10",
    )
    return LaunchDescription(args + [node])
