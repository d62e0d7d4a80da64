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


def output_folder(text, option: str = "--out") -> Path:
    """The folder ``text`` (the value of ``option``) for a command's files, created if missing;
    a one-line UserError naming the option when it is empty, a file or cannot be created."""
    from .errors import UserError

    where = f"{option} = {str(text)!r}"
    if not str(text).strip():
        raise UserError(f"{where}: expected the path of a folder")
    out = Path(text)
    if out.exists() and not out.is_dir():
        raise UserError(f"{where}: exists and is not a folder; give a folder")
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise UserError(f"{where}: cannot create the folder ({exc.strerror})") from None
    return out


def output_file(text, option: str = "--out") -> Path:
    """The path ``text`` (the value of ``option``) of an .mcap file to write; a one-line
    UserError naming the option when it is empty or a folder (``open`` said
    "IsADirectoryError: '.'" for an empty one).  Whether it can be written is the writer's to say."""
    from .errors import UserError

    where = f"{option} = {str(text)!r}"
    if not str(text).strip():
        raise UserError(f"{where}: expected the path of an .mcap file")
    out = Path(text)
    if out.is_dir():
        raise UserError(f"{where}: is a folder; expected the path of an .mcap file")
    return out
