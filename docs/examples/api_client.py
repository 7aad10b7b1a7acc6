#!/usr/bin/env python3
"""A uavsim sim-API client using only the Python standard library (docs/protocol.md).

    python3 docs/examples/api_client.py --port 5700            # status, step, vehicles, events
    python3 docs/examples/api_client.py --port 5700 --check    # the same, asserting the answers (ctest)
    python3 docs/examples/api_client.py --token-file FILE      # a server run with --api-token-file FILE

It leaves the server as it found it: the vehicle it kills is brought back by a reset with the seed the
server had (sim time restarts at 0), and the clock runs again if it was running.

The protocol is newline-delimited JSON over one TCP connection: the server says hello, every request
{"op": ..., "id": ...} gets exactly one reply {"id": ..., "ok": true, "result": ...} or
{"id": ..., "ok": false, "error": {"code": ..., "message": ...}}, and asynchronous messages (events,
lockstep ticks) carry an "event" field instead of "ok".
"""

import argparse
import itertools
import json
import socket
import sys


class ApiError(Exception):
    def __init__(self, code, message):
        super().__init__(f"{code}: {message}")
        self.code = code


class SimApi:
    """One connection to the sim API. Not thread-safe."""

    def __init__(self, host="127.0.0.1", port=5700, timeout_s=10.0, token=None):
        self._sock = socket.create_connection((host, port), timeout=timeout_s)
        self._file = self._sock.makefile("rwb")
        self._ids = itertools.count(1)
        self.pending_events = []  # asynchronous messages read while waiting for a reply
        self.hello = self._read()
        if self.hello.get("protocol") != 1:
            raise RuntimeError(f"unsupported protocol {self.hello.get('protocol')}")
        if self.hello.get("auth_required"):
            if token is None:
                raise RuntimeError("the server needs a token (--token-file)")
            self.request("auth", token=token)

    def close(self):
        self._file.close()
        self._sock.close()

    def _read(self):
        line = self._file.readline()
        if not line:
            raise ConnectionError("the server closed the connection")
        return json.loads(line)

    def request(self, op, **fields):
        """Sends one request and returns its result; raises ApiError for an error reply."""
        request_id = next(self._ids)
        self._file.write((json.dumps({"op": op, "id": request_id, **fields}) + "\n").encode())
        self._file.flush()
        while True:
            message = self._read()
            if "ok" not in message:
                self.pending_events.append(message)
                continue
            if message.get("id") != request_id:
                continue
            if not message["ok"]:
                raise ApiError(message["error"]["code"], message["error"]["message"])
            return message["result"]

    def next_event(self):
        """The next asynchronous message (a sim event, a tick, ...)."""
        if self.pending_events:
            return self.pending_events.pop(0)
        return self._read()


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--host", default="127.0.0.1")
    parser.add_argument("--port", type=int, default=5700)
    parser.add_argument("--check", action="store_true", help="assert the answers (the ctest)")
    parser.add_argument("--token-file", help="the server's --api-token-file")
    args = parser.parse_args()

    token = None
    if args.token_file:
        with open(args.token_file, encoding="utf-8") as f:
            token = f.readline().strip()
    api = SimApi(args.host, args.port, token=token)
    status = api.request("status")
    print(f"protocol {status['protocol']}: t = {status['time_s']:.3f} s, {status['vehicles']} vehicle(s)")

    # hold the clock, then advance exactly 100 control steps
    api.request("pause")
    t0 = api.request("status")["time_s"]
    t1 = api.request("step", steps=100)["time_s"]
    print(f"stepped 100 control steps: {t0:.3f} s -> {t1:.3f} s")

    for v in api.request("vehicles")["vehicles"]:
        x, y, z = v["position_enu_m"]
        print(f"  {v['name']} ({v['frame']}): ({x:.2f}, {y:.2f}, {z:.2f}) m, {v['mode']}, "
              f"armed={v['armed']}, crashed={v['crashed']}")

    # follow the event stream; a fault makes some events
    api.request("subscribe_events")
    api.request("kill_vehicle", vehicle=0, reason="api_client.py demo")
    api.request("step", steps=1)
    event = api.next_event()
    while event.get("event") != "sim_event":
        event = api.next_event()
    print(f"event #{event['seq']} at {event['time']:.3f} s: {event['type']} {event['vehicle_name']} "
          f"({event['detail']})")

    try:
        api.request("kill_vehicle", vehicle=999)
        unknown_vehicle_error = None
    except ApiError as e:
        unknown_vehicle_error = e.code

    # leave the server as found: the killed vehicle back (a reset with the same seed), the clock running
    api.request("reset", seed=status["seed"])
    if not status["paused"]:
        api.request("resume")
    after = api.request("status")
    revived = api.request("vehicles")["vehicles"][0]
    print(f"restored: seed {after['seed']}, paused={after['paused']}, {revived['name']} crashed={revived['crashed']}")
    api.close()

    if args.check:
        assert abs((t1 - t0) - 100 * 1.0 / status["control_hz"]) < 1e-6, (t0, t1)
        assert event["type"] == "vehicle_killed" and event["vehicle"] == 0, event
        assert unknown_vehicle_error == "unknown_vehicle", unknown_vehicle_error
        assert after["paused"] == status["paused"] and after["seed"] == status["seed"], (status, after)
        assert not revived["crashed"], revived
        print("check passed")
    return 0


if __name__ == "__main__":
    sys.exit(main())
