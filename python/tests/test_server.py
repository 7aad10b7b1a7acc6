"""The launcher: a server on ephemeral ports for a world, vehicles handed out, always stopped."""

import os

import pytest

import uavsim
from conftest import THREE_QUADS, server_alive


def test_world_by_name_and_by_file_with_options():
    with uavsim.Server("empty", seed=7, realism="field", cameras=False) as s:
        assert s.running and s.vehicle_names == ["uav0"] and s.api_port > 0
        st = s.sim.status()
        assert st["seed"] == 7 and st["realism"] == "field" and st["rate"] == 0
        assert os.path.isfile(uavsim.find_server())
    with uavsim.Server(THREE_QUADS, cameras=False) as s:
        assert s.vehicle_names == ["uav0", "uav1", "uav2"]
        a, b = s.vehicle("uav0"), s.vehicle(2)
        assert a is s.vehicle(0) and a is not b
        assert b.telemetry.sysid != a.telemetry.sysid
        with pytest.raises(uavsim.InvalidArgumentError):
            s.vehicle(3)
        with pytest.raises(uavsim.InvalidArgumentError):
            s.vehicle("uav9")
        with pytest.raises(TypeError):
            s.vehicle(1.5)


def test_the_server_stops_on_an_exception_and_its_objects_close():
    with pytest.raises(ZeroDivisionError):
        with uavsim.Server("empty", cameras=False) as s:
            pid = s.pid
            v = s.vehicle(0, wait_ready=False)
            assert server_alive(pid)
            1 / 0
    assert not server_alive(pid) and not s.running
    with pytest.raises(uavsim.ConnectionError):
        v.telemetry


def test_a_failed_start_leaves_no_server():
    with pytest.raises(RuntimeError, match="exited"):
        uavsim.Server("no_such_world").start()
    s = uavsim.Server("empty", cameras=False, extra_args=["--physics-hz", "-5"])
    with pytest.raises(RuntimeError):
        s.start()
    assert s.pid is not None and not server_alive(s.pid)


def test_stop_is_idempotent_and_collecting_stops_the_server():
    s = uavsim.Server("empty", cameras=False).start()
    pid = s.pid
    s.stop()
    s.stop()
    assert not server_alive(pid)
    s = uavsim.Server("empty", cameras=False).start()
    pid = s.pid
    del s
    assert not server_alive(pid)


def test_bad_options_are_refused_before_starting():
    for kwargs in ({"seed": -1}, {"realism": "wild"}, {"rate": -1}, {"period_s": 0}):
        with pytest.raises(ValueError):
            uavsim.Server("empty", **kwargs)
    with pytest.raises(TypeError):
        uavsim.Server(42)
    with pytest.raises(FileNotFoundError):
        uavsim.Server("empty", server="/nonexistent/uavsim-server").start()


def test_reset_restarts_the_clock_with_a_new_loop():
    with uavsim.Server("empty", seed=3, cameras=False) as s:
        v = s.vehicle(0)
        s.run_for(1.0)
        old_loop = s.loop
        s.reset(9)
        assert old_loop.closed and s.sim.status()["seed"] == 9
        with pytest.raises(uavsim.ConnectionError):
            v.arm()
        assert s.now() < 1.0
        assert s.vehicle(0).ready
