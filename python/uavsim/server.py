"""Starting a simulator from Python: ``Server`` runs ``uavsim-server`` for a world on ephemeral ports, hands
out connected vehicles (and cameras, radios, switches) on one event loop, and always stops it.

    with uavsim.Server("empty", seed=3) as sim:
        uav = sim.vehicle("uav0")          # connected and ready to fly
        ...

The server runs as fast as the lockstep allows (``rate=0``) with the program's event loop on its lockstep
clock by default, so a run is the same every time for a seed. It is started in a process group of its
own and stopped (SIGTERM, then SIGKILL of the group) on leaving the ``with`` block — exception or not —,
on ``stop()``, when the object is collected, and at interpreter exit.
"""

import atexit
import collections
import os
import re
import selectors
import shutil
import signal
import subprocess
import sys
import threading
import time
import weakref

from . import _core
from .sim import Sim

_MAVLINK_RE = re.compile(r"uavsim-server: (\S+): MAVLink on tcp:[0-9.]+:(\d+)")
_API_RE = re.compile(r"sim API on tcp:[0-9.]+:(\d+)")
_STOP_TIMEOUT_S = 5.0
_SETTLE_S = 0.1  # sim seconds the clock runs between closing the MAVLink links and a reset


def find_server(path=None):
    """The uavsim-server to run: path, else $UAVSIM_SERVER, else the build tree this package was built in,
    else uavsim-server on PATH or beside the interpreter (an installed prefix). FileNotFoundError if none."""
    if path is not None:
        if os.path.isfile(path) and os.access(path, os.X_OK):
            return os.fspath(path)
        raise FileNotFoundError(f"uavsim-server: no program at {path}")
    candidates = [os.environ.get("UAVSIM_SERVER")]
    try:
        from . import _build_paths  # generated in the build tree only

        candidates.append(_build_paths.SERVER)
    except ImportError:
        pass
    candidates.append(shutil.which("uavsim-server"))
    candidates += [os.path.join(d, "uavsim-server") for d in (os.path.join(sys.prefix, "bin"), "/usr/local/bin", "/usr/bin")]
    for c in candidates:
        if c and os.path.isfile(c) and os.access(c, os.X_OK):
            return c
    raise FileNotFoundError(
        "uavsim-server not found: pass server=PATH, set UAVSIM_SERVER, or put it on PATH (cmake --install)")


def _terminate(proc):
    """Stops the server's process group: SIGTERM, SIGKILL after a grace period; reaps it."""
    if proc.poll() is not None:
        return
    try:
        os.killpg(proc.pid, signal.SIGTERM)
    except ProcessLookupError:
        pass
    try:
        proc.wait(_STOP_TIMEOUT_S)
    except subprocess.TimeoutExpired:
        try:
            os.killpg(proc.pid, signal.SIGKILL)
        except ProcessLookupError:
            pass
        proc.wait()


def _drain(stream, output, echo):
    """Reads the server's output to its end, keeping the last lines."""
    for raw in stream:
        line = raw.decode(errors="replace").rstrip("\n")
        output.append(line)
        if echo:
            print(f"[server] {line}", file=sys.stderr)


# servers still running, stopped at interpreter exit whatever holds them
_running = weakref.WeakSet()


@atexit.register
def _stop_all():
    for s in list(_running):
        s.stop()


class Server:
    """A uavsim-server for one world, with a program's event loop and vehicles on it.

    world: a shipped world's name ("empty", "mbzirc2020", ...) or an MJCF file.
    seed: the seed of every random generator (and of ``reset()``).
    realism: None (the world's), "ideal" or "field".
    rate: 0 as fast as possible (the default), 1 real time.
    lockstep: the loop runs on the simulator's lockstep clock (ticks of period_s sim seconds; the server
      waits for the program at each tick); False: the host clock, the simulation runs on its own.
    cameras: a dict {camera: "width=64,height=48,fps=10"} of --camera overrides; False: no renderer.
    extra_args: more uavsim-server options.
    lockstep_timeout_s: wall seconds the server waits for the program at a tick before it drops it from
      the lockstep (the program stops between ticks while it does anything but run the loop).
    """

    def __init__(self, world="empty", *, seed=1, realism=None, rate=0.0, lockstep=True, period_s=0.01,
                 cameras=None, extra_args=(), server=None, start_timeout_s=60.0, lockstep_timeout_s=600.0,
                 echo=False):
        if not isinstance(world, (str, os.PathLike)):
            raise TypeError("world must be a name or a path")
        if not (isinstance(seed, int) and 0 <= seed < 2**64):
            raise ValueError("seed must be an int in [0, 2^64)")
        if realism not in (None, "ideal", "field"):
            raise ValueError("realism must be None, 'ideal' or 'field'")
        if not (rate == 0 or 0.001 <= rate <= 1e6):
            raise ValueError("rate must be 0 (as fast as possible) or in [0.001, 1e6]")
        if not 0 < period_s <= 60:
            raise ValueError("period_s must be in (0, 60]")
        self.world = os.fspath(world)
        self.seed = seed
        self.realism = realism
        self.rate = float(rate)
        self.lockstep = bool(lockstep)
        self.period_s = float(period_s)
        self.cameras = cameras
        self.extra_args = [str(a) for a in extra_args]
        self.server_path = server
        self.start_timeout_s = float(start_timeout_s)
        self.lockstep_timeout_s = float(lockstep_timeout_s)
        self.echo = echo
        self.api_port = 0
        self.mavlink_ports = {}  # vehicle name -> TCP port, in the server's order (index = position)
        self.sim = None
        self.loop = None
        self._proc = None
        self._finalizer = None
        self._output = collections.deque(maxlen=200)
        self._reader = None
        self._vehicles = {}
        self._devices = []

    # lifetime
    def __enter__(self):
        self.start()
        return self

    def __exit__(self, *exc):
        self.stop()
        return False

    def start(self):
        """Starts the server, connects to its API, and (lockstep) starts the clock from t = 0 for the seed."""
        if self._proc is not None:
            raise RuntimeError("the server is already started")
        args = [find_server(self.server_path), self.world, "--rate", repr(self.rate), "--seed", str(self.seed),
                "--mavlink-port", "0", "--api-port", "0", "--lockstep-timeout",
                repr(self.lockstep_timeout_s)]
        if self.realism:
            args += ["--realism", self.realism]
        if self.cameras is False:
            args.append("--no-cameras")
        elif self.cameras:
            for cam, spec in self.cameras.items():
                args += ["--camera", f"{cam}:{spec}"]
        args += self.extra_args
        self._proc = subprocess.Popen(args, stdin=subprocess.DEVNULL, stdout=subprocess.PIPE,
                                      stderr=subprocess.STDOUT, start_new_session=True)
        self._finalizer = weakref.finalize(self, _terminate, self._proc)
        _running.add(self)
        try:
            self._read_banner()
            self.sim = Sim.connect("127.0.0.1", self.api_port, max(1.0, self.start_timeout_s))
            self._start_clock(self.seed)
        except BaseException:
            self.stop()
            raise
        return self

    def stop(self):
        """Drops the loop and what was handed out on it, then stops the server and reaps it. Idempotent;
        the server is stopped whatever else fails."""
        try:
            self._drop_clients()
            if self.sim is not None:
                self.sim.close()
        finally:
            self.sim = None
            self.loop = None
            if self._finalizer is not None:
                self._finalizer()  # _terminate, once
        if self._reader is not None:
            self._reader.join(_STOP_TIMEOUT_S)
            self._reader = None
        _running.discard(self)

    @property
    def pid(self):
        return None if self._proc is None else self._proc.pid

    @property
    def running(self):
        return self._proc is not None and self._proc.poll() is None

    def output(self):
        """The server's last lines of output."""
        return list(self._output)

    def reset(self, seed=None):
        """Back to t = 0 (with this seed, else the last one): the vehicles, cameras, radios and switches
        handed out are dropped, and a new loop joins the clock (call vehicle() again)."""
        if seed is not None:
            self.seed = seed
        self._drop_clients(settle=True)
        self._start_clock(self.seed)

    # what a program gets
    @property
    def vehicle_names(self):
        return list(self.mavlink_ports)

    def vehicle(self, vehicle=0, *, wait_ready=True, timeout_s=60.0, **config):
        """A Vehicle connected to this vehicle (index or name) on the server's loop; with wait_ready,
        once it is ready to fly. The same object for the same vehicle until reset()."""
        name = self._vehicle_name(vehicle)
        if name in self._vehicles:
            return self._vehicles[name]
        v = _core.Vehicle(self.loop, sim_vehicle=name, **config)
        try:
            v.connect(f"tcp:127.0.0.1:{self.mavlink_ports[name]}", timeout_s)
            if wait_ready:
                v.wait_ready(timeout_s)
        except BaseException:
            v.close()
            raise
        self._vehicles[name] = v
        return v

    def camera(self, name, **options):
        """A Camera subscription on the server's loop (options as Camera.subscribe)."""
        if not self.lockstep:
            options.setdefault("api_address", f"127.0.0.1:{self.api_port}")
        c = _core.Camera.subscribe(self.loop, name, **options)
        self._devices.append(c)
        return c

    def radio(self, vehicle=0, timeout_s=10.0):
        """The radio of a vehicle (index or name); needs lockstep."""
        c = _core.Radio.open(self.loop, self.vehicle_names.index(self._vehicle_name(vehicle)), timeout_s)
        self._devices.append(c)
        return c

    def switches(self, vehicle=0, on_change=None, timeout_s=10.0):
        """The landing-pad switches of a vehicle (index or name); needs lockstep."""
        c = _core.Switches.subscribe(self.loop, self._vehicle_name(vehicle), on_change, timeout_s)
        self._devices.append(c)
        return c

    def run_for(self, duration_s):
        """Runs the loop (vehicles, timers, callbacks) for duration_s of its clock."""
        self.loop.run_for(duration_s)

    def now(self):
        return self.loop.now()

    # internals
    def _vehicle_name(self, vehicle):
        names = self.vehicle_names
        if isinstance(vehicle, bool) or not isinstance(vehicle, (int, str)):
            raise TypeError("vehicle must be an index or a name")
        if isinstance(vehicle, int):
            if not 0 <= vehicle < len(names):
                raise _core.InvalidArgumentError(f"no vehicle {vehicle} (the world has {len(names)})")
            return names[vehicle]
        if vehicle not in self.mavlink_ports:
            raise _core.InvalidArgumentError(f"no vehicle {vehicle!r} (the world has {names})")
        return vehicle

    def _read_banner(self):
        """Reads the server's output up to the API's port (the MAVLink ports come before it)."""
        fd = self._proc.stdout.fileno()
        sel = selectors.DefaultSelector()
        sel.register(fd, selectors.EVENT_READ)
        deadline = time.monotonic() + self.start_timeout_s
        pending = b""
        try:
            while self.api_port == 0:
                left = deadline - time.monotonic()
                if left <= 0:
                    raise TimeoutError(f"uavsim-server printed no sim API port in {self.start_timeout_s} s: "
                                       + " | ".join(self._output))
                if not sel.select(min(left, 0.5)):
                    continue
                chunk = os.read(fd, 65536)  # what is there, without waiting for more
                if not chunk:  # end of file: the server exited
                    self._proc.wait()
                    raise RuntimeError(f"uavsim-server exited ({self._proc.returncode}) before it served the API: "
                                       + " | ".join(self._output))
                pending += chunk
                *lines, pending = pending.split(b"\n")
                for raw in lines:
                    self._line(raw.decode(errors="replace"))
        finally:
            sel.close()
        # the rest of the output is read on a thread of its own, so the server never blocks on a full pipe
        if pending:
            self._line(pending.decode(errors="replace"))
        # (a function of its own, not a method: the thread must not keep this object from being collected)
        self._reader = threading.Thread(target=_drain, args=(self._proc.stdout, self._output, self.echo),
                                        name="uavsim-server output", daemon=True)
        self._reader.start()

    def _line(self, line):
        self._output.append(line)
        if self.echo:
            print(f"[server] {line}", file=sys.stderr)
        m = _MAVLINK_RE.search(line)
        if m:
            self.mavlink_ports[m.group(1)] = int(m.group(2))
        m = _API_RE.search(line)
        if m:
            self.api_port = int(m.group(1))

    def _start_clock(self, seed):
        """Lockstep: hold the clock, back to t = 0 with the seed, join, then let it go — every run of a seed
        starts the same. Host clock: reset and let the simulation run."""
        self.sim.pause()
        self.sim.reset(seed)
        if self.lockstep:
            self.loop = _core.EventLoop.lockstep("127.0.0.1", self.api_port, self.period_s)
        else:
            self.loop = _core.EventLoop.host()
        self.sim.resume()

    def _drop_clients(self, settle=False):
        # the devices and vehicles before their loop, which leaves the lockstep as it closes (objects a
        # program still holds raise ConnectionError from then on)
        for d in self._devices:
            d.close()
        self._devices.clear()
        for v in self._vehicles.values():
            v.close()
        had_vehicles = bool(self._vehicles)
        self._vehicles.clear()
        if settle and had_vehicles and self.loop is not None and self.loop.clock_alive:
            # settle: let the clock run while the server takes in the closed MAVLink links, before a
            # reset. A link event still queued for a vehicle when the world resets is dropped with the
            # reset, and the server's endpoint then serves that vehicle's links no more.
            self.loop.run_for(_SETTLE_S)
        if self.loop is not None:
            self.loop.close()
            self.loop = None
