"""World control over the simulator's sim API: a thin layer over ``_core.SimConnection`` that names
the operations of docs/protocol.md (ground truth, events, faults, wind, clock).

Every method sends one request and returns its reply's ``result`` as a dict; a refusal raises
``UavsimError`` (``InvalidArgumentError`` for a field out of range, ``UavsimError`` with code
``UNSUPPORTED`` for something the world does not have). Ground truth is for scoring, tests and
rewards; a mission decides with what a real drone has.
"""

from . import _core


class Sim:
    """A connection to a running server's sim API (``Sim.connect(host, port)``)."""

    def __init__(self, connection):
        self.connection = connection

    @classmethod
    def connect(cls, host="127.0.0.1", port=5700, timeout_s=10.0):
        return cls(_core.SimConnection.connect(host, port, timeout_s))

    def request(self, op, timeout_s=30.0, **fields):
        """Any op: ``request("vehicles")``, ``request("gimbal", gimbal="uav0_gimbal", mode="down")``."""
        return self.connection.request(dict(fields, op=op), timeout_s)

    def close(self):
        self.connection.close()

    # the clock
    def status(self):
        return self.connection.status()

    def pause(self):
        return self.connection.pause()

    def resume(self):
        return self.connection.resume()

    def step(self, steps=None, duration_s=None, timeout_s=60.0):
        """Pauses and advances by control steps or sim seconds; returns once done."""
        if (steps is None) == (duration_s is None):
            raise ValueError("step: give steps or duration_s")
        if steps is not None:
            return self.request("step", timeout_s=timeout_s, steps=int(steps))
        return self.request("step", timeout_s=timeout_s, duration_s=float(duration_s))

    def reset(self, seed):
        """Back to t = 0 with this seed (world, flight controllers, objects, events)."""
        return self.connection.reset(seed)

    def set_rate(self, rate):
        """1 = real time, 0 = as fast as possible."""
        return self.request("set_rate", rate=float(rate))

    def pause_at(self, time_s=None, lockstep_empty=None):
        fields = {}
        if time_s is not None:
            fields["time_s"] = float(time_s)
        if lockstep_empty is not None:
            fields["lockstep_empty"] = bool(lockstep_empty)
        return self.request("pause_at", **fields)

    # ground truth
    def vehicles(self):
        """Every vehicle's true state: a list of dicts (position_enu_m, velocity_enu_m_s, q_enu_body, ...)."""
        return self.request("vehicles")["vehicles"]

    def vehicle(self, vehicle=0):
        """One vehicle's true state, by index or name."""
        for v in self.vehicles():
            if vehicle in (v["index"], v["name"]):
                return v
        raise _core.InvalidArgumentError(f"no vehicle {vehicle!r}")

    def balloons(self):
        return self.request("balloons")["balloons"]

    def trucks(self):
        return self.connection.truck()["trucks"]

    # events
    def events(self, from_seq=0):
        """The events recorded since from_seq (one-off query)."""
        return self.request("events", from_seq=int(from_seq))

    def subscribe_events(self):
        """The backlog now; later events stream as ``sim_event`` messages (take_messages / on_message)."""
        return self.connection.subscribe_events()

    def take_messages(self):
        return self.connection.take_messages()

    def poll(self, timeout_ms=0):
        self.connection.poll(timeout_ms)

    # faults
    def kill_vehicle(self, vehicle, reason="killed from Python"):
        return self.request("kill_vehicle", vehicle=vehicle, reason=reason)

    def motor_failure(self, vehicle, rotor, failed=True):
        return self.request("motor_failure", vehicle=vehicle, rotor=int(rotor), failed=bool(failed))

    def gps_glitch(self, vehicle, offset_enu_m):
        return self.request("gps_glitch", vehicle=vehicle, offset_enu_m=[float(x) for x in offset_enu_m])

    def gps_denied(self, vehicle, denied=True):
        return self.request("gps_denied", vehicle=vehicle, denied=bool(denied))

    def camera_blackout(self, camera, duration_s):
        return self.request("camera_blackout", camera=camera, duration_s=float(duration_s))

    def link_drop(self, vehicle, down=True):
        return self.request("link_drop", vehicle=vehicle, down=bool(down))

    # wind
    def wind(self, **fields):
        """Sets (any of speed_m_s, from_deg, turbulence_sd_m_s, gust_m_s, gust_duration_s) or, with none,
        reads the wind."""
        return self.request("wind", **fields)
