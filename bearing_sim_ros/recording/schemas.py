"""ROS 2 type information for MCAP recordings: ``ros2msg`` schemas and QoS metadata.

The schema of a channel is the type's ``.msg`` file followed by every type it depends on,
recursively, in the rosbag2 format (rosbag2 ``docs/message_definition_encoding.md``)::

    <main .msg text>
    ================================================================================
    MSG: std_msgs/msg/Header
    <Header.msg text>
    ...

The ``.msg`` files are read from the installed interface packages (``$AMENT_PREFIX_PATH/share/
<pkg>/msg/<Type>.msg``), so a schema always matches the CDR that rclpy produces here.

QoS: ``offered_qos_profiles`` channel metadata is the YAML list rosbag2 (Jazzy, metadata version
9) writes: enum names in lower case, durations as ``{sec, nsec}``.
"""
from __future__ import annotations

import os
import re
import sys
from collections import deque
from functools import lru_cache
from pathlib import Path

from ..errors import UserError

DELIMITER = "=" * 80
PRIMITIVES = frozenset({
    "bool", "byte", "char", "float32", "float64", "int8", "uint8", "int16", "uint16",
    "int32", "uint32", "int64", "uint64", "string", "wstring",
})
_ARRAY = re.compile(r"\[[^\]]*\]$")      # [], [3], [<=3]
_BOUND = re.compile(r"<=\d+$")           # string<=10


def qualified_type(token: str, package: str) -> str:
    """``pkg/msg/Name`` of a non-primitive field type written in a .msg file of ``package``
    (``Name``, ``pkg/Name``, ``pkg/msg/Name``; the bare ``Header`` is std_msgs')."""
    if "/" in token:
        pkg, name = _split_type(token)
    elif token == "Header":
        pkg, name = "std_msgs", "Header"
    else:
        pkg, name = package, token
    return f"{pkg}/msg/{name}"


def _split_type(msg_type: str) -> tuple:
    """'sensor_msgs/msg/PointCloud2' or 'sensor_msgs/PointCloud2' -> ('sensor_msgs', 'PointCloud2')."""
    parts = msg_type.strip().split("/")
    if len(parts) == 3 and parts[1] == "msg":
        return parts[0], parts[2]
    if len(parts) == 2:
        return parts[0], parts[1]
    raise UserError(f"message type = {msg_type!r}: expected 'package/msg/Type'")


def _share_dirs() -> list:
    """Where installed interface packages may live: each AMENT_PREFIX_PATH entry's share/, then
    the Python environment's share/ (pip wheels of ROS 2 install there)."""
    dirs = []
    for prefix in os.environ.get("AMENT_PREFIX_PATH", "").split(os.pathsep):
        if prefix:
            dirs.append(Path(prefix) / "share")
    dirs.append(Path(sys.prefix) / "share")
    return dirs


@lru_cache(maxsize=None)
def msg_text(package: str, name: str) -> str:
    """The text of ``<package>/msg/<name>.msg`` from the installed interfaces."""
    tried = []
    for share in _share_dirs():
        path = share / package / "msg" / f"{name}.msg"
        tried.append(str(path))
        if path.is_file():
            return path.read_text(encoding="utf-8")
    raise UserError(f"message type {package}/msg/{name}: no {name}.msg under AMENT_PREFIX_PATH "
                    f"(looked in {', '.join(tried)}); set AMENT_PREFIX_PATH to the ROS 2 environment")


def field_types(text: str, package: str) -> list:
    """Complex (non-primitive) field types of a .msg text, as 'pkg/msg/Type', in order.

    Constants (``byte OK=0``) have primitive types and are skipped; a bare ``Type`` refers to the
    message's own package; ``Header`` alone is the ROS 1 spelling of std_msgs/Header."""
    out = []
    for line in text.splitlines():
        line = line.split("#", 1)[0].strip()
        if not line:
            continue
        token = line.split()[0]
        token = _BOUND.sub("", _ARRAY.sub("", token))
        if token in PRIMITIVES:
            continue
        out.append(qualified_type(token, package))
    return out


@lru_cache(maxsize=None)
def message_definition(msg_type: str) -> str:
    """The complete ``ros2msg`` definition of ``msg_type`` ('pkg/msg/Type'): the type's own
    text, then each dependency once (breadth-first, as rosbag2 does) after the delimiter."""
    package, name = _split_type(msg_type)
    root = msg_text(package, name)
    parts = [root.rstrip("\n")]
    seen = {f"{package}/msg/{name}"}
    todo = deque(field_types(root, package))
    while todo:
        dep = todo.popleft()
        if dep in seen:
            continue
        seen.add(dep)
        dpkg, dname = _split_type(dep)
        text = msg_text(dpkg, dname)
        parts.append(f"{DELIMITER}\nMSG: {dep}\n{text.rstrip(chr(10))}")
        todo.extend(field_types(text, dpkg))
    return "\n".join(parts) + "\n"


# ---- QoS <-> rosbag2 YAML ------------------------------------------------------------------
def _duration_ns(value) -> int:
    if value is None:
        return 0
    ns = getattr(value, "nanoseconds", None)
    return int(ns) if ns is not None else int(value)


def qos_to_yaml(qos) -> str:
    """``offered_qos_profiles`` text for one rclpy ``QoSProfile`` (or None: no profile, "")."""
    if qos is None:
        return ""

    def dur(key, value):
        ns = _duration_ns(value)
        return f"  {key}:\n    sec: {ns // 1_000_000_000}\n    nsec: {ns % 1_000_000_000}\n"

    return ("- history: " + qos.history.name.lower() + "\n"
            f"  depth: {int(qos.depth)}\n"
            f"  reliability: {qos.reliability.name.lower()}\n"
            f"  durability: {qos.durability.name.lower()}\n"
            + dur("deadline", qos.deadline)
            + dur("lifespan", qos.lifespan)
            + f"  liveliness: {qos.liveliness.name.lower()}\n"
            + dur("liveliness_lease_duration", qos.liveliness_lease_duration)
            + "  avoid_ros_namespace_conventions: "
            + ("true" if qos.avoid_ros_namespace_conventions else "false"))


def qos_from_yaml(text: str):
    """An rclpy ``QoSProfile`` from ``offered_qos_profiles`` text (the first profile), accepting
    rosbag2's v9 enum names and older integer values; None when there is no profile, or none
    that can be read (another tool's text that is not YAML or not rosbag2's): the publisher then
    takes the default, as for a channel without one (a yaml or Python traceback ended play)."""
    import yaml

    if not text or not text.strip():
        return None
    try:
        return _qos_from_items(yaml.safe_load(text))
    except (yaml.YAMLError, ValueError, TypeError, AttributeError, OverflowError):
        return None


def _qos_from_items(items):
    """``qos_from_yaml`` of the parsed text."""
    from rclpy.duration import Duration
    from rclpy.qos import (DurabilityPolicy, HistoryPolicy, LivelinessPolicy, QoSProfile,
                           ReliabilityPolicy)

    if not isinstance(items, list) or not items or not isinstance(items[0], dict):
        return None
    item = items[0]

    def enum(cls, key, default):
        value = item.get(key, default.name)
        try:
            policy = cls(value) if isinstance(value, int) else cls[str(value).upper()]
        except (KeyError, ValueError):
            return default
        # UNKNOWN is what discovery reports when it cannot tell; publish with the default
        return default if policy.name == "UNKNOWN" else policy

    def dur(key):
        value = item.get(key) or {}
        sec, nsec = int(value.get("sec", 0)), int(value.get("nsec", 0))
        # rmw's "infinite" (and Foxy's 2147483647/4294967295) means: no deadline/lifespan
        if sec >= 2147483647:
            return Duration()
        return Duration(seconds=sec, nanoseconds=nsec)

    history = enum(HistoryPolicy, "history", HistoryPolicy.KEEP_LAST)
    depth = int(item.get("depth", 10) or 10)
    return QoSProfile(
        history=history,
        depth=depth,
        reliability=enum(ReliabilityPolicy, "reliability", ReliabilityPolicy.RELIABLE),
        durability=enum(DurabilityPolicy, "durability", DurabilityPolicy.VOLATILE),
        deadline=dur("deadline"),
        lifespan=dur("lifespan"),
        liveliness=enum(LivelinessPolicy, "liveliness", LivelinessPolicy.SYSTEM_DEFAULT),
        liveliness_lease_duration=dur("liveliness_lease_duration"),
        avoid_ros_namespace_conventions=bool(item.get("avoid_ros_namespace_conventions", False)),
    )
