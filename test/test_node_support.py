"""Helpers for the cross-process node tests (no tests here): the node as a subprocess and an
rclpy listener/publisher in the test process, each test on its own ROS_DOMAIN_ID (``ros_env``)."""
from __future__ import annotations

import contextlib
import os
import signal
import subprocess
import threading
import time
from pathlib import Path

import numpy as np

NS = 1_000_000_000


# how long a node may take to its first table: on a cold cache it compiles the kinematic tier's
# kernels (about 16 s on the AMD host) and, with fidelity auto, the skidding tier's (about 12 s)
# first; 70-160 s together on a busy 2-core Intel Xeon, which is why `make test` compiles them
# before the tests (Makefile, WARM_KERNELS)
FIRST_TABLE_S = 60.0


# a C call that holds the GIL while it waits, as rclpy's destroy_when_not_in_use does (ctypes.PyDLL
# does not release it), so that no Python thread runs until it returns
HANG_HOLDING_THE_GIL = "ctypes.PyDLL(None).sleep(600)"


def hung_teardown_script(call: str, hang: str = "time.sleep(600)") -> str:
    """A Python script that runs ``call`` (an expression that ends the process with its exit
    status, sys.argv available) with ``Node.destroy_node`` hanging for 600 s in ``hang``
    (``HANG_HOLDING_THE_GIL``: without a Python thread running) and the teardown watchdog's
    timeout (``teardown.TEARDOWN_TIMEOUT``) at 1 s."""
    return "\n".join([
        "import ctypes, sys, time",
        "from rclpy.node import Node",
        "from bearing_sim_ros import teardown",
        "teardown.TEARDOWN_TIMEOUT = 1.0",
        f"Node.destroy_node = lambda self: {hang}      # a teardown that never returns",
        call,
        "",
    ])


def assert_hung_teardown_said(err: str, who: str, status: int) -> None:
    """``err`` (a process's standard error) holds the watchdog's line for ``who``, saying that it
    exits with ``status``, and after it the stacks, which show the hanging call (a lambda)."""
    line = (f"{who}: the middleware's teardown (destroy_node, rclpy shutdown) has not ended after 1 s; the "
            f"command's work is complete (its lines above, a recording closed), so it exits with its status "
            f"{status} without it; where it hung: the stacks below")
    assert line in err.splitlines(), err
    stacks = err.split(line)[1]
    assert "Current thread" in stacks or "Thread 0x" in stacks, err
    assert "<lambda>" in stacks, err


def assert_one_error_line(result, words) -> None:
    """``result`` (a finished ``subprocess.run``) ended with exit status 2 and one ``error:`` line
    holding each of ``words`` on stderr, no traceback; rcl's own log lines (it logs "[ERROR]
    [rcl]: Failed to parse global arguments" before it raises) aside."""
    assert result.returncode == 2, result.stderr
    assert "Traceback" not in result.stderr + result.stdout
    lines = [ln for ln in result.stderr.splitlines() if ln.strip() and "[rcl]" not in ln]
    assert len(lines) == 1 and lines[0].startswith("error: "), result.stderr
    for w in words:
        assert w in lines[0], lines[0]


def with_site(env: dict, folder) -> dict:
    """``env`` with ``folder`` first on PYTHONPATH: its sitecustomize runs in the process."""
    return {**env, "PYTHONPATH": os.pathsep.join(filter(None, [str(folder), env.get("PYTHONPATH")]))}


def signal_at_import(env: dict, folder, module: str, sig) -> dict:
    """``env`` for a process that sends itself ``sig`` as it first imports ``module`` (by that
    name: ``import numpy``, ``from numpy import ...``) and then leaves ``folder / "signal_sent"``:
    a sitecustomize in ``folder`` (put first on PYTHONPATH) wraps ``__import__``.  A signal at a
    known moment of a command's start, where one sent after a delay may come while Python itself
    still starts (45-120 ms on the CI machine), before any code of ours."""
    (folder / "sitecustomize.py").write_text("\n".join([
        "import builtins, os",
        "_import = builtins.__import__",
        "def _signal_at_import(name, *a, **kw):",
        f"    if name == {module!r} and not getattr(_signal_at_import, 'sent', False):",
        "        _signal_at_import.sent = True",
        f"        os.kill(os.getpid(), {int(sig)})",
        f"        open({str(folder / 'signal_sent')!r}, 'w').close()",
        "    return _import(name, *a, **kw)",
        "builtins.__import__ = _signal_at_import",
    ]) + "\n")
    return with_site(env, folder)


# Fast DDS's participant lease, shortened from its 20 s.  A killed process's publishers leave the
# others' graph only when its lease runs out, which a test of that otherwise waits out (38 and 28 s
# of the suite's two slowest tests).  A participant announces its own lease, so every process of
# such a test must take the profile.
SHORT_LEASE_PROFILE = """<?xml version="1.0" encoding="UTF-8" ?>
<profiles xmlns="http://www.eprosima.com/XMLSchemas/fastRTPS_Profiles">
  <participant profile_name="short_lease" is_default_profile="true">
    <rtps>
      <builtin>
        <discovery_config>
          <leaseDuration><sec>{lease}</sec></leaseDuration>
          <leaseAnnouncement><sec>1</sec></leaseAnnouncement>
        </discovery_config>
      </builtin>
    </rtps>
  </participant>
</profiles>
"""


def with_short_lease(env: dict, folder, lease_s: int = 4) -> dict:
    """``env`` (a ``ros_env``) whose processes announce a DDS participant lease of ``lease_s`` s
    (Fast DDS's default profile, written into ``folder``; announced every second) instead of 20 s."""
    profile = Path(folder) / "short_lease.xml"
    profile.write_text(SHORT_LEASE_PROFILE.format(lease=int(lease_s)))
    return {**env, "FASTRTPS_DEFAULT_PROFILES_FILE": str(profile)}


def param_text(value) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, float):
        return repr(value)
    return str(value)


class NodeProcess:
    """``bearing-sim node --ros-args -p k:=v ...`` as a subprocess, output to a file."""

    def __init__(self, exe, env, params: dict, log_path, command=("node",), ros_args=()):
        args = [exe, *command]
        if params is not None:
            args.append("--ros-args")
            for key, value in params.items():
                args += ["-p", f"{key}:={param_text(value)}"]
            args += ros_args                     # remaps: -r __ns:=/rig1, -r /clock:=/rig1/clock
        self.log_path = log_path
        self._log = open(log_path, "w+")  # noqa: SIM115 - closed in close()
        self.proc = subprocess.Popen(args, env=env, stdout=self._log, stderr=subprocess.STDOUT,
                                     start_new_session=True)

    def output(self) -> str:
        self._log.flush()
        with open(self.log_path) as f:
            return f.read()

    def wait_for_output(self, text: str, timeout: float = 30.0) -> None:
        end = time.monotonic() + timeout
        while time.monotonic() < end:
            if text in self.output():
                return
            if self.proc.poll() is not None:
                raise AssertionError(f"node exited ({self.proc.returncode}) before printing {text!r}:\n{self.output()}")
            time.sleep(0.1)
        raise AssertionError(f"no {text!r} after {timeout} s:\n{self.output()}")

    def send(self, sig) -> None:
        self.proc.send_signal(sig)

    def wait(self, timeout: float = 20.0) -> int:
        try:
            return self.proc.wait(timeout)
        except subprocess.TimeoutExpired:
            self.kill()
            raise AssertionError(f"node still running after {timeout} s:\n{self.output()}") from None

    def kill(self) -> None:
        if self.proc.poll() is None:
            os.killpg(self.proc.pid, signal.SIGKILL)
            self.proc.wait(5)

    def close(self) -> None:
        """Stop the node as a user would (SIGINT), SIGKILL only if it hangs: a killed Fast DDS
        participant leaves its shared-memory segments behind in /dev/shm (45 after one suite
        run when every node was killed), and with a few hundred of them we saw processes hang
        at exit (3 in ~110 play runs; none in 40 once they were cleared)."""
        if self.proc.poll() is None:
            self.proc.send_signal(signal.SIGINT)
            try:
                self.proc.wait(10)
            except subprocess.TimeoutExpired:
                pass
        self.kill()
        self._log.close()


class Listener:
    """An rclpy node in the test process: subscribes to accel, state, /diagnostics and /clock
    (what a consumer does), publishes shaft_speed and load, and can set the node's parameters."""

    def __init__(self, name: str = "test_listener"):
        import rclpy
        from diagnostic_msgs.msg import DiagnosticArray
        from geometry_msgs.msg import WrenchStamped
        from rclpy.executors import SingleThreadedExecutor
        from rosgraph_msgs.msg import Clock
        from sensor_msgs.msg import JointState, PointCloud2
        from std_msgs.msg import Float64

        from bearing_sim_ros.messages import waveform_qos

        self.ctx = rclpy.Context()
        rclpy.init(context=self.ctx)           # ROS_DOMAIN_ID from the ros_env fixture
        self.node = rclpy.create_node(name, context=self.ctx)
        self.accel = []          # (receive time monotonic s, stamp ns, channels, (n, c) float32)
        self.state = []          # (stamp ns, names, positions, velocities)
        self.diagnostics = []    # (receive time, level, message, {key: value}, stamp ns)
        self.clock = []          # /clock, ns
        self.node.create_subscription(PointCloud2, "accel", self._on_accel, waveform_qos(0.01))
        self.node.create_subscription(JointState, "state", self._on_state, 50)
        self.node.create_subscription(DiagnosticArray, "/diagnostics", self._on_diag, 10)
        self.node.create_subscription(Clock, "/clock", self._on_clock, 100)
        self.pub_speed = self.node.create_publisher(Float64, "shaft_speed", 10)
        self.pub_load = self.node.create_publisher(WrenchStamped, "load", 10)
        self.executor = SingleThreadedExecutor(context=self.ctx)
        self.executor.add_node(self.node)
        self._thread = threading.Thread(target=self._spin, daemon=True)
        self._thread.start()

    def _spin(self):
        from rclpy.executors import ExternalShutdownException

        try:
            while self.ctx.ok():
                self.executor.spin_once(timeout_sec=0.05)
        except (ExternalShutdownException, Exception):  # noqa: BLE001 - shutting down
            pass

    def _on_accel(self, msg):
        from bearing_sim_ros.waveform import from_pointcloud2

        stamp, channels, data = from_pointcloud2(msg)
        self.accel.append((time.monotonic(), stamp, channels, data.copy()))

    def _on_state(self, msg):
        s = msg.header.stamp
        self.state.append((s.sec * NS + s.nanosec, list(msg.name), list(msg.position), list(msg.velocity)))

    def _on_clock(self, msg):
        self.clock.append(msg.clock.sec * NS + msg.clock.nanosec)

    def _on_diag(self, msg):
        for st in msg.status:
            level = st.level[0] if isinstance(st.level, (bytes, bytearray)) else int(st.level)
            self.diagnostics.append((time.monotonic(), level, st.message, {kv.key: kv.value for kv in st.values},
                                     msg.header.stamp.sec * NS + msg.header.stamp.nanosec))

    def wait_for(self, predicate, timeout: float, what: str):
        end = time.monotonic() + timeout
        while time.monotonic() < end:
            value = predicate()
            if value:
                return value
            time.sleep(0.05)
        raise AssertionError(f"timed out after {timeout} s waiting for {what}")

    def wait_matched(self, timeout: float = 30.0) -> None:
        # the node subscribes once its simulator is built, after a cold compilation (as long as
        # the first table can take)
        self.wait_for(lambda: self.pub_speed.get_subscription_count() > 0
                      and self.pub_load.get_subscription_count() > 0, timeout, "the node's subscriptions")

    def publish_speed(self, value: float) -> None:
        from std_msgs.msg import Float64

        self.pub_speed.publish(Float64(data=float(value)))

    def publish_load(self, fx: float, fy: float, fz: float = 0.0, stamp_ns: int | None = None,
                     frame_id: str = "") -> None:
        from geometry_msgs.msg import WrenchStamped

        msg = WrenchStamped()
        msg.header.frame_id = frame_id
        if stamp_ns is None:
            stamp_ns = self.node.get_clock().now().nanoseconds
        msg.header.stamp.sec, msg.header.stamp.nanosec = divmod(int(stamp_ns), NS)
        msg.wrench.force.x, msg.wrench.force.y, msg.wrench.force.z = float(fx), float(fy), float(fz)
        self.pub_load.publish(msg)

    def set_parameters(self, values: dict, timeout: float = 10.0):
        """[(successful, reason)] for each parameter, set on the ``bearing_sim`` node."""
        from rclpy.parameter import Parameter
        from rclpy.parameter_client import AsyncParameterClient

        client = AsyncParameterClient(self.node, "bearing_sim")
        assert client.wait_for_services(timeout_sec=timeout), "bearing_sim parameter services not found"
        future = client.set_parameters([Parameter(k, value=v) for k, v in values.items()])
        self.wait_for(future.done, timeout, "the set_parameters reply")
        return [(r.successful, r.reason) for r in future.result().results]

    def accel_since(self, stamp_ns: int):
        """Contiguous (stamp, data) of the tables from ``stamp_ns`` on."""
        return [(s, d) for _t, s, _c, d in list(self.accel) if s >= stamp_ns]

    def close(self) -> None:
        self.ctx.try_shutdown()
        self._thread.join(5)
        try:
            self.executor.shutdown(timeout_sec=1)
            self.node.destroy_node()
        except Exception:  # noqa: BLE001
            pass


def stamps_and_widths(tables):
    stamps = np.array([s for s, _d in tables], dtype=np.int64)
    widths = np.array([d.shape[0] for _s, d in tables], dtype=np.int64)
    return stamps, widths


def offered_qos(path) -> dict:
    """{topic: the QoS profile its publisher offered} of an MCAP file, read with ``rosbags``."""
    from pathlib import Path

    from rosbags.highlevel import AnyReader

    with AnyReader([Path(path)]) as reader:
        return {c.topic: c.ext.offered_qos_profiles[0] for c in reader.connections}


def read_recording(path):
    """{topic: [(log_time_ns, msg)]} and the metadata of an MCAP file, read with ``rosbags``
    (an independent reader: what a user's tooling sees)."""
    from pathlib import Path

    from rosbags.highlevel import AnyReader

    out = {}
    with AnyReader([Path(path)]) as reader:
        for conn, log_ns, raw in reader.messages():
            out.setdefault(conn.topic, []).append((log_ns, reader.deserialize(raw, conn.msgtype)))
    from mcap.reader import make_reader

    with open(path, "rb") as f:
        meta = {m.name: dict(m.metadata) for m in make_reader(f).iter_metadata()}
    return out, meta


@contextlib.contextmanager
def rendering_until_stopped(out, seed: int, env):
    """A render of ``seed`` to ``out`` in another process, long enough to be stopped by a signal
    (``stop_render``), from when its ``<out>.<pid>.partial`` file is there (held): its Popen,
    killed at the end of the block if it still runs."""
    import sys

    proc = subprocess.Popen([sys.executable, "-m", "bearing_sim_ros.cli", "render", "er16k_outer_race",
                             "--duration", "3000", "--fidelity", "kinematic", "--seed", str(seed), "--out", str(out)],
                            env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        deadline = time.monotonic() + 60
        while not any(out.parent.glob(f"{out.name}.*.partial")):
            if proc.poll() is not None or time.monotonic() > deadline:
                proc.kill()
                raise AssertionError(f"no partial file: {proc.communicate()}")
            time.sleep(0.05)
        time.sleep(0.5)             # created, then held: a moment apart
        yield proc
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()


def stop_render(proc) -> None:
    """Stop ``proc`` (``rendering_until_stopped``) with Ctrl-C: it ends with status 130, its file
    finalised at --out."""
    proc.send_signal(signal.SIGINT)
    _stdout, stderr = proc.communicate(timeout=60)
    assert proc.returncode == 130 and "finalised" in stderr, stderr


def signal_when(proc, ready, sig, settle_s: float, what: str, timeout_s: float = 60.0):
    """Wait up to ``timeout_s`` for ``ready()`` while ``proc`` runs (it must not end first;
    ``what`` names what did not happen), wait ``settle_s`` more, send ``sig``: what
    ``proc.communicate`` returns.  ``proc`` is killed if anything fails on the way."""
    try:
        deadline = time.monotonic() + timeout_s
        while time.monotonic() < deadline and not ready():
            assert proc.poll() is None, proc.communicate()
            time.sleep(0.05)
        assert ready(), what
        time.sleep(settle_s)
        proc.send_signal(sig)
        try:
            return proc.communicate(timeout=timeout_s)
        except subprocess.TimeoutExpired:
            # where it hung (rarely, in full-suite runs only): with PYTHONFAULTHANDLER (ros_env)
            # SIGABRT prints every thread's stack
            proc.send_signal(signal.SIGABRT)
            stdout, stderr = proc.communicate(timeout=10)
            raise AssertionError(f"no exit {timeout_s:g} s after signal {sig}; stacks on SIGABRT:\n"
                                 f"{stdout}\n{stderr}") from None
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()


def on_a_terminal_that_closes(args, env, ready, settle_s: float, what: str, stderr=None,
                              timeout_s: float = 60.0) -> int:
    """Run ``args`` on a terminal of its own (a pty it leads, as a shell in a terminal window
    starts a command; ``stderr`` a file object, else the terminal too), wait up to ``timeout_s``
    for ``ready()`` while it runs, ``settle_s`` more, then close the terminal as closing the
    window does: the kernel sends SIGHUP, and every later write to it fails (EIO).  Its exit
    status; it is killed if anything fails on the way."""
    import fcntl
    import pty
    import termios

    def own_terminal():
        for sig in (signal.SIGINT, signal.SIGHUP):      # as a shell leaves them (conftest)
            signal.signal(sig, signal.SIG_DFL)
        fcntl.ioctl(0, termios.TIOCSCTTY, 0)            # its controlling terminal: it gets the hangup

    master, slave = pty.openpty()
    proc = subprocess.Popen(args, env=env, stdin=slave, stdout=slave, stderr=stderr or slave,
                            start_new_session=True, preexec_fn=own_terminal)
    os.close(slave)
    # what it writes must be read, or it blocks on a full terminal; not by a read that blocks, which
    # would hold the terminal open after os.close (no hangup)
    reading = threading.Event()
    reading.set()
    reader = threading.Thread(target=_read_while, args=(master, reading), daemon=True)
    reader.start()
    try:
        deadline = time.monotonic() + timeout_s
        while time.monotonic() < deadline and not ready():
            assert proc.poll() is None, f"{what}: exited with {proc.returncode}"
            time.sleep(0.05)
        assert ready(), what
        time.sleep(settle_s)
    finally:
        reading.clear()
        reader.join()
        os.close(master)                # the window closed
    try:
        return proc.wait(timeout_s)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()


def closed_as_it_writes(args, env, line: str, tmp_path, stderr=None, stream: str = "stdout") -> int:
    """``on_a_terminal_that_closes`` at the moment the command writes the first ``line`` (a
    part of it) to ``stream`` (``stdout``, or ``stderr`` where ``stderr`` is None: the terminal
    too): the write fails (EIO) from the hangup on, and Python runs the
    handler of the SIGHUP that comes with it only at the main thread's next step, or, where a
    shell passes the hangup on to its jobs, milliseconds later.  A sitecustomize (in
    ``tmp_path``/site) holds the handler as the line is written, lets the terminal close, writes the
    line once it hung up and the SIGHUP came, then runs the handler.  (Blocking the signal in the
    main thread would not do: the kernel gives it to another thread, and the handler runs at
    once.)  The command's exit status; ``stderr``: a file object, or None."""
    site, at_line = tmp_path / "site", tmp_path / "at_line"
    site.mkdir()
    (site / "sitecustomize.py").write_text("\n".join([
        "import select, signal, sys, time",
        "class _ClosedAsItWrites:",
        "    def __init__(self, stream):",
        "        self._stream, self._done = stream, False",
        "    def write(self, text):",
        f"        if self._done or {line!r} not in text:",
        "            return self._stream.write(text)",
        "        self._done = True",
        "        held = []",
        "        handler = signal.signal(signal.SIGHUP, lambda signum, _frame: held.append(signum))",
        "        try:",
        f"            open({str(at_line)!r}, 'w').close()",
        "            poll = select.poll()",
        "            poll.register(self._stream.fileno(), select.POLLOUT)",
        "            deadline = time.monotonic() + 30",
        "            while not (held and any(ev & select.POLLHUP for _fd, ev in poll.poll(0))) \\",
        "                    and time.monotonic() < deadline:",
        "                time.sleep(0.01)",
        "            written = self._stream.write(text)",
        "            self._stream.flush()",
        "            return written",
        "        finally:",
        "            signal.signal(signal.SIGHUP, handler)",
        "            for signum in held:",
        "                handler(signum, None)",
        "    def __getattr__(self, name):",
        "        return getattr(self._stream, name)",
        f"sys.{stream} = _ClosedAsItWrites(sys.{stream})",
    ]) + "\n")
    env = with_site(env, site)
    return on_a_terminal_that_closes(args, env, at_line.exists, 0.0, f"no {line!r} written", stderr=stderr)


def _read_while(fd: int, reading: threading.Event) -> None:
    import select

    while reading.is_set():
        if select.select([fd], [], [], 0.1)[0]:
            try:
                os.read(fd, 65536)
            except OSError:             # the other side went (EIO)
                return


def assert_diverged_and_recorded(result, recording, advice: str) -> None:
    """``result`` (a finished ``subprocess.run`` of the node or ``run`` on conftest's
    DIVERGING_PIT) ended with exit status 2, no traceback, the divergence logged as an error
    and said in one ``error:`` line (which solver, the time of signal, the operating point and
    ``advice``), and ``recording`` finalised: readable, finite tables up to the divergence,
    its last ``/diagnostics`` an ERROR with the same line."""
    import re

    import numpy as np

    from bearing_sim_ros.waveform import from_pointcloud2

    assert result.returncode == 2, result.stderr
    assert "Traceback" not in result.stderr + result.stdout
    said = [ln for ln in result.stderr.splitlines() if ln.startswith("error: ")]
    assert len(said) == 1, result.stderr
    found = re.fullmatch(r"error: (the skidding tier's default solver diverged at t = (0\.\d+) s of signal \(2000 rpm, "
                         r"radial load \[0, -200\] N\): the scene is beyond what it integrates; try "
                         + re.escape(advice) + r"); recorded to (.*), finalised", said[0])
    assert found and found[3] == str(recording), said[0]
    line, t = found[1], float(found[2])
    assert any("[ERROR]" in ln and ln.endswith(line) for ln in result.stderr.splitlines()), result.stderr
    topics, _meta = read_recording(recording)
    tables = [from_pointcloud2(msg)[2] for _t, msg in topics["/accel"]]
    assert tables and all(np.isfinite(a).all() for a in tables)
    assert 0.3 <= sum(len(a) for a in tables) / 15000.0 < t < 0.4
    # the end status: the run ended by the divergence, the signal published, the line
    last = topics["/diagnostics"][-1][1].status[0]
    values = {kv.key: kv.value for kv in last.values}
    samples = sum(len(a) for a in tables)
    assert last.level == 2 and last.message == (f"run ended: the solver diverged, {samples / 15000.0:.6f} s of "
                                                f"signal ({samples} samples) published; {line}"), last.message
    assert (values["run"], values["end_reason"], values["published_samples"]) == ("ended", "diverged", str(samples))


def render_run_up(folder, scene_name: str, duration: float = 4.0, **options):
    """A kinematic render of ``scene_name`` whose shaft runs up from 1000 to 3000 rpm over
    ``duration`` s (its operating point at 1000 rpm and a ``profile`` knot at the end), to
    ``folder``, with ``render``'s ``options`` (``state_rate``); its path.  Its lines move 89 % in Hz: the order tracking of report, monitor and
    run (test_report, test_monitor, test_run)."""
    import re

    from bearing_sim_ros import load_scene
    from bearing_sim_ros.recording.render import render

    text = load_scene(scene_name).source_text
    text, found = re.subn(r"operating_point: \{shaft_speed_rpm: \d+", "operating_point: {shaft_speed_rpm: 1000", text)
    assert found == 1, f"{scene_name}.yaml's operating point moved: update this test"
    scene = folder / f"{scene_name}_run_up.yaml"
    scene.write_text(text + f"profile:\n  - {{t: {duration:g}, shaft_speed_rpm: 3000}}\n")
    rec = folder / f"{scene_name}_run_up.mcap"
    render(str(scene), duration, rec, fidelity="kinematic", progress=False, **options)
    return rec
