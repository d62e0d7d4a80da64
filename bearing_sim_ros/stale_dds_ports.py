"""Fast DDS shared-memory ports that a killed process left half made, cleared before a participant starts.

Fast DDS (the default RMW, ``rmw_fastrtps_cpp``) gives each participant on a machine its ports
in shared memory, files ``/dev/shm/fastrtps_port<N>`` named by the participant's port number,
which a domain id and a participant index fix (``7400 + 250 * domain + ...``).  The creator of
such a file sizes it and then marks it as being made (a state word at its start: 0 sized, 1
being made, 2 made).  A process killed between those two moments (a node stopped with ``kill
-9``, or by a signal whose default action ends it, in its first moments) leaves a file whose word
stays 0, or an empty one; and every later participant that takes the same port opens it and
waits for it to be made, for ever (boost.interprocess' ``managed_open_or_create_impl`` spins
while the word is 0 or 1).  So a node, ``monitor``, ``play`` or ``run`` on that domain hung at
start without a word until someone removed the file by hand (``fastdds shm clean``, which a
wheel install does not have).  The suite met it: a test on domain 69 hung in ``Node()`` on a
file that an earlier run's killed process had left.

``clear_half_made_ports`` removes the port files of one domain that are still unmade after
``MADE_WITHIN_S`` (a port is made within microseconds of being sized; one that is younger is
waited for, once).  A file that is made, or that belongs to another domain, is not touched; a
process already waiting on a removed file stays stuck (it has mapped it), the next one makes a
fresh one.  Other RMWs are left alone."""
from __future__ import annotations

import os
import re
import struct
import time
from pathlib import Path

SHM_DIR = Path("/dev/shm")
# Fast DDS 2.x names them fastrtps_port<N>, 3.x fastdds_port<N>; the lock files beside them
# (<name>_el, _sl) are flocks, which a dead process does not hold
PORT_FILE = re.compile(r"(?:fastrtps|fastdds)_port(\d+)")
# the RTPS well-known ports: PB + DG * domain + offsets; a domain's ports lie in [base, base + DG)
PORT_BASE = 7400
DOMAIN_GAIN = 250
MADE_WITHIN_S = 2.0              # s: older and still unmade, its maker is gone
FAST_DDS_RMWS = ("", "rmw_fastrtps_cpp", "rmw_fastrtps_dynamic_cpp")


# the RTPS port formula's limit (PORT_BASE + DOMAIN_GAIN x 232 + offsets stays below 65536), rcl's too
DOMAIN_MAX = 232


def domain_id_error(env=None) -> str:
    """'' where ``ROS_DOMAIN_ID`` of ``env`` (default os.environ) is unset, empty or a whole number
    0 - DOMAIN_MAX, else the one line that says what is wrong.  rclpy took "abc" for a ROS
    argument it could not parse, 300 failed in Fast DDS with exit status 1 (an internal error)
    and -1 ran on domain 0."""
    env = os.environ if env is None else env
    text = env.get("ROS_DOMAIN_ID", "").strip()
    if not text or (text.isdigit() and int(text) <= DOMAIN_MAX):
        return ""
    return (f"ROS_DOMAIN_ID = {env['ROS_DOMAIN_ID']!r}: expected a whole number 0 - {DOMAIN_MAX} "
            "(0 - 101 keeps clear of Linux's ephemeral ports), the same in every terminal of one setup")


def domain_from_env(env=None) -> int | None:
    """The ROS domain id of ``env`` (default os.environ; unset or empty: 0), or None where
    ``ROS_DOMAIN_ID`` is not a whole number (``domain_id_error`` says what is wrong with it) or
    the RMW is not Fast DDS."""
    env = os.environ if env is None else env
    if env.get("RMW_IMPLEMENTATION", "") not in FAST_DDS_RMWS:
        return None
    text = env.get("ROS_DOMAIN_ID", "").strip() or "0"
    return int(text) if text.isdigit() else None


def _unmade(path: Path) -> bool:
    """Whether the port file ``path`` is not (yet) made: empty, or its state word not 2."""
    try:
        with open(path, "rb") as f:
            head = f.read(4)
    except OSError:
        return False                  # gone, or not ours to read: nothing to do with it
    return len(head) < 4 or struct.unpack("<I", head)[0] in (0, 1)


def _age_s(path: Path) -> float:
    try:
        return time.time() - path.stat().st_mtime
    except OSError:
        return float("inf")


def clear_half_made_ports(domain: int | None, shm_dir: Path = SHM_DIR, made_within_s: float = MADE_WITHIN_S) -> list:
    """Remove the Fast DDS port files of ``domain`` (None: nothing) that are still unmade
    ``made_within_s`` after they were sized (see the module docstring); waits at most that long
    for younger ones.  The paths removed, in order."""
    if domain is None:
        return []
    first, end = PORT_BASE + DOMAIN_GAIN * domain, PORT_BASE + DOMAIN_GAIN * (domain + 1)
    try:
        names = os.listdir(shm_dir)
    except OSError:
        return []
    suspects = []
    for name in sorted(names):
        match = PORT_FILE.fullmatch(name)
        if match and first <= int(match.group(1)) < end and _unmade(shm_dir / name):
            suspects.append(shm_dir / name)
    if not suspects:
        return []
    youngest = min(_age_s(path) for path in suspects)
    if youngest < made_within_s:
        time.sleep(made_within_s - youngest)       # a maker may be between its two moments now
    removed = []
    for path in suspects:
        if _unmade(path) and _age_s(path) >= made_within_s:
            try:
                path.unlink()
            except OSError:
                continue              # another's file (sticky /dev/shm), or gone meanwhile
            removed.append(path)
    return removed


def removed_text(removed: list, domain: int) -> str:
    """One line for the user about the files ``clear_half_made_ports`` removed."""
    names = ", ".join(str(path) for path in removed)
    if len(removed) == 1:
        return (f"removed {names}: a Fast DDS shared-memory port that a killed process left half made "
                f"(every participant on ROS domain {domain} that took it hung at start)")
    return (f"removed {names}: Fast DDS shared-memory ports that killed processes left half made "
            f"(every participant on ROS domain {domain} that took one hung at start)")


def clear_before_start(say, env=None) -> None:
    """Before the first participant of this process (or of processes given ``env``): a
    ``ROS_DOMAIN_ID`` that no participant can take is a UserError (``domain_id_error``); else
    clear its domain's half-made ports (``ROS_DOMAIN_ID``, ``RMW_IMPLEMENTATION`` of the
    environment) and ``say`` what was removed."""
    error = domain_id_error(env)
    if error:
        from .errors import UserError

        raise UserError(error)
    domain = domain_from_env(env)
    removed = clear_half_made_ports(domain)
    if removed:
        say(removed_text(removed, domain))
