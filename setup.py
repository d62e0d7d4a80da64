"""Packaging for bearing_sim_ros (ament_python layout; also a plain pip package)."""
import os
from glob import glob

from setuptools import find_packages, setup

PACKAGE = "bearing_sim_ros"


def tree(folder):
    """(share/<pkg>/<dir>, [files]) entries for every folder below ``folder``."""
    entries = []
    for root, _dirs, files in os.walk(folder):
        paths = [os.path.join(root, name) for name in files]
        if paths:
            entries.append((os.path.join("share", PACKAGE, root), paths))
    return entries


setup(
    name=PACKAGE,
    version="0.1.0",
    packages=find_packages(exclude=["test"]),
    data_files=[
        ("share/ament_index/resource_index/packages", ["resource/" + PACKAGE]),
        ("share/" + PACKAGE, ["package.xml"]),
        ("share/" + PACKAGE + "/launch", glob("launch/*.py")),
    ]
    + tree("config"),
    install_requires=["setuptools"],
    zip_safe=True,
    maintainer="bearing_sim_ros team",
    maintainer_email="bearing-sim@example.com",
    description="Virtual bearing accelerometer for ROS 2: skidding ball-bearing model, 15 kHz waveform tables, MCAP.",
    license="Apache-2.0",
    entry_points={
        "console_scripts": [
            "bearing-sim = bearing_sim_ros.entry:main",
            "bearing_sim_node = bearing_sim_ros.entry:node_main",
        ],
    },
)
