"""package.xml, setup.py and setup.cfg against the code and the README (static, about a second):
what an apt-installed ROS 2 workspace (rosdep, colcon, ``ros2 run``, ``ros2 launch``) and a
non-editable ``pip install`` rely on, which ``make test``'s editable install does not exercise."""
import ast
import os
import re
import runpy
import sys
import xml.etree.ElementTree as ET
from configparser import ConfigParser
from pathlib import Path
from unittest import mock

import bearing_sim_ros

REPO = Path(__file__).resolve().parent.parent
PACKAGE = "bearing_sim_ros"

# import name -> its rosdep key in package.xml
ROSDEP_KEYS = {"numpy": "python3-numpy", "yaml": "python3-yaml", "scipy": "python3-scipy",
               "matplotlib": "python3-matplotlib"}
# imported, but without a rosdep key on Ubuntu 24.04 (an unresolvable key stops `rosdep install`
# for the whole workspace): installed by the README's pip line instead
# (zstandard, whose ZstdError the reader catches, comes with mcap: a requirement of it)
PIP_ONLY = {"numba": "numba", "mcap": "mcap", "threadpoolctl": "threadpoolctl", "zstandard": "mcap"}


def _package_xml():
    return ET.parse(REPO / "package.xml").getroot()


def _setup_kwargs() -> dict:
    """The keyword arguments setup.py gives ``setup()``, run from the repository."""
    import setuptools

    cwd = os.getcwd()
    with mock.patch.object(setuptools, "setup") as setup:
        os.chdir(REPO)              # setup.py globs launch/ and walks config/ from where it runs
        try:
            runpy.run_path(str(REPO / "setup.py"))
        finally:
            os.chdir(cwd)
    return setup.call_args.kwargs


def _imports(files) -> set:
    """Top-level names of the absolute imports in ``files``."""
    names = set()
    for path in files:
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.Import):
                names.update(alias.name.split(".")[0] for alias in node.names)
            elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
                names.add(node.module.split(".")[0])
    return names - set(sys.stdlib_module_names) - {PACKAGE}


def test_versions_agree():
    assert _package_xml().findtext("version") == _setup_kwargs()["version"] == bearing_sim_ros.__version__


def test_package_xml_is_format_3_with_name_license_and_maintainer():
    root = _package_xml()
    assert root.get("format") == "3"
    assert root.findtext("name") == _setup_kwargs()["name"] == PACKAGE
    assert root.findtext("license") == _setup_kwargs()["license"]
    assert root.find("maintainer").get("email") == _setup_kwargs()["maintainer_email"]
    assert root.findtext("export/build_type") == "ament_python"


def test_every_runtime_import_is_a_declared_dependency_or_in_the_readmes_pip_line():
    """A module the installed package imports that neither rosdep nor the README's workspace
    instructions install fails at run time in a colcon workspace, not in the pip venv."""
    declared = {e.text for e in _package_xml().findall("exec_depend")}
    imported = _imports((REPO / PACKAGE).rglob("*.py")) | _imports((REPO / "launch").glob("*.py"))
    section = (REPO / "README.md").read_text().split("## In an apt-installed ROS 2 Jazzy workspace", 1)[1]
    pip_line = re.search(r"^pip install (.*)$", section, re.M).group(1).split()
    for name in sorted(imported):
        if name in PIP_ONLY:
            assert PIP_ONLY[name] in pip_line, f"{name}: not in the README's pip line"
            assert PIP_ONLY[name] not in declared
        else:
            assert ROSDEP_KEYS.get(name, name) in declared, f"{name}: no exec_depend in package.xml"


def test_setup_cfg_puts_the_executables_where_ros2_run_looks():
    cfg = ConfigParser()
    cfg.read(REPO / "setup.cfg")
    assert cfg["develop"]["script_dir"] == cfg["install"]["install_scripts"] == f"$base/lib/{PACKAGE}"
    # ... which `setup.py install` also follows: pyproject.toml's build system keeps a plain
    # `pip install .` (a pip before 23.1 without `wheel`) from it, so that bin/ gets the commands
    assert re.search(r'^build-backend = "setuptools.build_meta"$', (REPO / "pyproject.toml").read_text(), re.M)


def test_the_entry_points_named_in_the_readme_and_the_launch_file_exist():
    scripts = {entry.split("=")[0].strip() for entry in _setup_kwargs()["entry_points"]["console_scripts"]}
    assert {"bearing-sim", "bearing_sim_node"} <= scripts
    launch = (REPO / "launch" / "bearing_sim.launch.py").read_text()
    assert set(re.findall(r'executable="([^"]+)"', launch)) <= scripts
    assert set(re.findall(r"ros2 run bearing_sim_ros ([\w-]+)", (REPO / "README.md").read_text())) <= scripts


def test_data_files_install_the_ament_marker_package_xml_launch_and_every_config_file():
    """Where an installed package (colcon, a wheel) finds them: share/ament_index/... for
    ``ros2 run``, share/bearing_sim_ros/{package.xml,launch/,config/} (paths.config_dir)."""
    installed = {str(Path(folder) / Path(f).name) for folder, files in _setup_kwargs()["data_files"] for f in files}
    expected = {f"share/ament_index/resource_index/packages/{PACKAGE}", f"share/{PACKAGE}/package.xml"}
    assert (REPO / "resource" / PACKAGE).is_file()
    for folder in ("launch", "config"):
        expected |= {f"share/{PACKAGE}/{p.relative_to(REPO)}" for p in (REPO / folder).rglob("*")
                     if p.is_file() and "__pycache__" not in p.parts}
    assert expected <= installed


def test_an_install_outside_sys_prefix_finds_its_own_config(tmp_path):
    """``pip install --user`` puts the data files in ~/.local/share, not under sys.prefix
    (/usr), and AMENT_PREFIX_PATH (apt ROS sourced) does not name ~/.local: every command ended
    with "cannot find the bearing_sim_ros config folder".  The package now looks in the share/
    of the prefix it is installed in first."""
    import shutil
    import subprocess

    prefix = tmp_path / "user"
    site = prefix / "lib" / f"python{sys.version_info[0]}.{sys.version_info[1]}" / "site-packages"
    ignore = shutil.ignore_patterns("__pycache__", "*.nbi", "*.nbc")
    shutil.copytree(REPO / PACKAGE, site / PACKAGE, ignore=ignore)
    shutil.copytree(REPO / "config", prefix / "share" / PACKAGE / "config", ignore=ignore)
    env = {k: v for k, v in os.environ.items() if k != "AMENT_PREFIX_PATH"}
    env.update(PYTHONPATH=str(site), PYTHONDONTWRITEBYTECODE="1")
    code = "from bearing_sim_ros.paths import config_dir; print(config_dir())"
    run = subprocess.run([sys.executable, "-c", code], env=env, cwd=tmp_path, capture_output=True, text=True)
    assert run.returncode == 0, run.stderr
    assert run.stdout.strip() == str(prefix / "share" / PACKAGE / "config")
