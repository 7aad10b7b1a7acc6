"""The event loop, the sim API connection, JSON and the exceptions of uavsim._core."""

import math
import threading
import time

import numpy as np
import pytest

import uavsim
from uavsim import _core


def test_error_codes_map_to_exception_classes():
    assert issubclass(uavsim.InvalidArgumentError, uavsim.UavsimError)
    assert issubclass(uavsim.InvalidArgumentError, ValueError)
    assert issubclass(uavsim.TimeoutError, TimeoutError)
    assert issubclass(uavsim.ConnectionError, ConnectionError)
    assert issubclass(uavsim.UavsimError, RuntimeError)


def test_host_loop_timers_tasks_and_run():
    loop = uavsim.EventLoop.host()
    assert not loop.is_lockstep and loop.clock_alive
    fired = []
    loop.call_after(0.01, lambda: fired.append("after"))
    every = loop.call_every(0.01, lambda: fired.append("every"))
    cancelled = loop.call_after(0.01, lambda: fired.append("cancelled"))
    assert loop.cancel(cancelled)
    assert not loop.cancel(cancelled)
    loop.run_until(lambda: fired.count("every") >= 3, 10.0, "three periods")
    assert "after" in fired and "cancelled" not in fired
    assert loop.cancel(every)
    # post from another thread, then stop() ends run()
    threading.Thread(target=lambda: loop.post(loop.stop)).start()
    loop.run()
    assert loop.now() > 0.0


def test_a_callbacks_exception_is_raised_by_the_blocking_call_it_ran_in():
    loop = uavsim.EventLoop.host()

    def boom():
        raise KeyError("from a timer")

    loop.call_after(0.0, boom)
    with pytest.raises(KeyError, match="from a timer"):
        loop.run_for(0.05)
    loop.run_for(0.01)  # kept once: the next call is clean
    with pytest.raises(ZeroDivisionError):
        loop.run_until(lambda: 1 / 0, 5.0)


def test_run_until_times_out_with_the_error_code():
    loop = uavsim.EventLoop.host()
    with pytest.raises(uavsim.TimeoutError) as e:
        loop.run_until(lambda: False, 0.02, "never")
    assert e.value.code == uavsim.Error.TIMEOUT
    assert "never" in e.value.message


def test_blocking_calls_release_the_gil():
    # a thread that records the time while the main thread waits inside run_for: with the GIL held
    # there, it could record nothing inside the wait
    loop = uavsim.EventLoop.host()
    stamps, stop = [], threading.Event()
    started = threading.Event()

    def spin():
        started.set()
        while not stop.is_set():
            stamps.append(time.monotonic())

    t = threading.Thread(target=spin)
    t.start()
    started.wait()
    begin = time.monotonic()
    loop.run_for(0.3)
    end = time.monotonic()
    stop.set()
    t.join()
    assert any(begin < s < end for s in stamps)


@pytest.mark.parametrize("call", [
    lambda l: l.run_for(-1.0),
    lambda l: l.run_for(math.nan),
    lambda l: l.run_for(math.inf),
    lambda l: l.call_every(0.0, lambda: None),
    lambda l: l.call_after(-0.5, lambda: None),
    lambda l: l.run_until(lambda: True, -1.0),
])
def test_loop_refuses_out_of_range_numbers(call):
    with pytest.raises(uavsim.InvalidArgumentError) as e:
        call(uavsim.EventLoop.host())
    assert e.value.code == uavsim.Error.INVALID_ARGUMENT


def test_loop_refuses_wrong_types():
    loop = uavsim.EventLoop.host()
    with pytest.raises(TypeError):
        loop.run_for("1")
    with pytest.raises(TypeError):
        loop.call_after(0.1, "not callable")


def test_lockstep_join_to_a_dead_port_and_bad_config():
    with pytest.raises(uavsim.ConnectionError) as e:
        uavsim.EventLoop.lockstep("127.0.0.1", 1, 0.01, 5.0)
    assert e.value.code == uavsim.Error.CONNECTION_REFUSED
    with pytest.raises(uavsim.InvalidArgumentError):
        uavsim.EventLoop.lockstep("127.0.0.1", 70000)
    with pytest.raises(uavsim.InvalidArgumentError):
        uavsim.EventLoop.lockstep("127.0.0.1", 5700, 0.0)
    with pytest.raises(uavsim.ConnectionError):
        uavsim.SimConnection.connect("127.0.0.1", 1, 5.0)


def test_a_closed_loop_refuses_calls():
    loop = uavsim.EventLoop.host()
    loop.close()
    assert loop.closed
    with pytest.raises(uavsim.ConnectionError):
        loop.run_for(0.1)


def test_geodesy_round_trip():
    origin = uavsim.GeodeticOrigin(47.397742, 8.545594, 488.0)
    p = uavsim.geodetic_from_enu(origin, [100.0, -50.0, 10.0])
    assert p.alt_m == pytest.approx(498.0)
    np.testing.assert_allclose(uavsim.enu_from_geodetic(origin, p), [100.0, -50.0, 10.0], atol=1e-6)
    np.testing.assert_allclose(uavsim.ned_from_geodetic(origin, p), [-50.0, 100.0, -10.0], atol=1e-6)
    assert uavsim.wrap_pi(3 * math.pi) == pytest.approx(math.pi)


def test_sim_connection_control_queries_and_json(empty_world):
    c = uavsim.SimConnection.connect("127.0.0.1", empty_world.api_port)
    assert c.connected and c.hello["hello"] == "uavsim"
    assert "vehicles" in c.hello["ops"]
    st = c.status()
    assert st["vehicles"] == 1 and st["seed"] == 1
    # nested JSON both ways, numpy numbers included
    v = c.request({"op": "vehicles", "nested": {"a": [1, 2.5, None, True]}, "n": np.int64(3)})
    assert v["vehicles"][0]["name"] == "uav0"
    assert len(v["vehicles"][0]["position_enu_m"]) == 3
    with pytest.raises(TypeError):
        c.request({"op": "status", "bad": {1, 2}})
    with pytest.raises(TypeError):
        c.request({"op": "status", 3: "int key"})
    with pytest.raises(TypeError):
        c.request("status")
    # the server's refusals carry its code mapped to an Error
    with pytest.raises(uavsim.InvalidArgumentError) as e:
        c.request({"op": "step", "steps": "x"})
    assert "bad_field" in e.value.message
    with pytest.raises(uavsim.UavsimError) as e:
        c.request({"op": "no_such_op"})
    assert e.value.code == uavsim.Error.UNSUPPORTED
    with pytest.raises(uavsim.UavsimError) as e:
        c.truck()  # the empty world has none
    assert e.value.code == uavsim.Error.UNSUPPORTED
    with pytest.raises(uavsim.InvalidArgumentError):
        c.step_for(-1.0)
    with pytest.raises(TypeError):
        c.reset(-1)
    c.close()
    with pytest.raises(uavsim.ConnectionError):
        c.status()


def test_sim_connection_lockstep_events_and_messages():
    with uavsim.Server("empty", seed=2, lockstep=False) as s:
        c = uavsim.SimConnection.connect("127.0.0.1", s.api_port)
        assert c.pause()["paused"]
        c.reset(5)
        assert c.status()["seed"] == 5
        t0 = c.status()["time_s"]
        assert c.step_for(0.5)["time_s"] == pytest.approx(t0 + 0.5, abs=0.01)
        assert c.subscribe_events()["events"] == []
        # lockstep by hand: join, answer ticks through a handler, leave
        ticks = []
        c.on_message("tick", lambda m: ticks.append(m.json["tick"]))
        joined = c.lockstep_join(0.1, 10.0)
        assert joined["period_s"] == pytest.approx(0.1)
        c.resume()
        while len(ticks) < 3:
            c.poll(1000)
            if ticks:
                c.done(ticks[-1])
        c.lockstep_leave()
        c.on_message("tick", None)
        assert ticks == sorted(ticks) and len(set(ticks)) == len(ticks)
        # radio through the API: subscribe vehicle 0, send to itself refused or delivered, never lost silently
        assert "vehicles" in c.radio_subscribe(0)
        with pytest.raises(uavsim.InvalidArgumentError):
            c.radio_send(0, b"x" * 200)
        # a sim event streams as a message (kill the vehicle: vehicle_killed, crash)
        c.request({"op": "kill_vehicle", "vehicle": 0, "reason": "test"})
        kinds = []
        while "vehicle_killed" not in kinds:
            c.poll(1000)
            kinds += [m.json.get("type") for m in c.take_messages() if m.kind == "sim_event"]
        c.close()
    # the server is gone: a new connection is refused
    with pytest.raises(uavsim.ConnectionError):
        uavsim.SimConnection.connect("127.0.0.1", s.api_port, 2.0)
