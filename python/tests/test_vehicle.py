"""Vehicle against a live server on the lockstep clock: every bound call, telemetry and its callbacks,
missions, parameters, and the exceptions for bad input."""

import math

import numpy as np
import pytest

import uavsim
from uavsim import FlightMode

ALT_M = 3.0
TOL_M = 0.5  # the library's own take-off tolerance


@pytest.fixture(scope="module")
def uav(empty_world):
    v = empty_world.vehicle("uav0")
    yield v


def test_connected_and_ready_with_telemetry(empty_world, uav):
    assert uav.connected and uav.ready
    t = uav.telemetry
    assert isinstance(t, uavsim.Telemetry)
    assert t.heartbeat_seen and t.home_set and t.origin_set and t.ekf_ok and t.gps_fix_type >= 3
    assert t.position_enu_m.shape == (3,) and t.position_enu_m.dtype == np.float64
    assert not t.armed and t.landed == uavsim.LandedState.ON_GROUND
    assert t.battery_voltage_v > 0
    assert empty_world.loop.is_lockstep and empty_world.now() > 0


def test_telemetry_callbacks_run_on_the_loop_with_the_gil(empty_world, uav):
    seen = []
    uav.on_telemetry(lambda t: seen.append(t.vehicle_time_s))
    empty_world.run_for(1.0)
    uav.on_telemetry(None)
    n = len(seen)
    empty_world.run_for(0.2)
    assert n >= 10 and len(seen) == n  # 10 Hz streams at least; none after removal
    assert seen == sorted(seen)


def test_a_callbacks_exception_comes_out_of_the_blocking_call(empty_world, uav):
    calls = []

    def bad(t):
        calls.append(t)
        if len(calls) == 1:
            raise RuntimeError("telemetry handler failed")

    uav.on_telemetry(bad)
    with pytest.raises(RuntimeError, match="telemetry handler failed"):
        empty_world.run_for(0.5)
    uav.on_telemetry(None)
    assert len(calls) > 1  # the loop went on after the exception


def test_parameters(uav):
    old = uav.get_param("WPNAV_SPEED")
    assert uav.set_param("WPNAV_SPEED", old + 100.0) == pytest.approx(old + 100.0)
    assert uav.get_param("WPNAV_SPEED") == pytest.approx(old + 100.0)
    uav.set_param("WPNAV_SPEED", old)
    with pytest.raises(uavsim.TimeoutError) as e:
        uav.get_param("NO_SUCH_PARAM", 0.5)
    assert "NO_SUCH_PARAM" in e.value.message
    with pytest.raises(uavsim.InvalidArgumentError):
        uav.get_param("A_NAME_LONGER_THAN_16")
    with pytest.raises(uavsim.InvalidArgumentError):
        uav.set_param("WPNAV_SPEED", math.nan)


def test_bad_input_raises_before_anything_is_sent(empty_world, uav):
    with pytest.raises(TypeError):
        uav.goto_local_enu([1.0, 2.0])  # not 3 numbers
    with pytest.raises(TypeError):
        uav.set_mode("GUIDED")
    with pytest.raises(uavsim.InvalidArgumentError):
        uav.set_velocity_enu([math.nan, 0, 0])
    with pytest.raises(uavsim.InvalidArgumentError):
        uav.set_velocity_enu([200.0, 0, 0])
    with pytest.raises(uavsim.InvalidArgumentError):
        uav.takeoff(-1.0)
    with pytest.raises(uavsim.InvalidArgumentError):
        uav.goto_local_enu([0, 0, 1], math.inf)
    with pytest.raises(uavsim.InvalidArgumentError):
        uav.upload_mission([])
    with pytest.raises(uavsim.InvalidArgumentError):
        uav.wait_ready(-1.0)
    with pytest.raises(TypeError):
        uav.command_long(400, [0.0] * 6)  # 7 params
    with pytest.raises(uavsim.InvalidArgumentError):
        uavsim.Vehicle(empty_world.loop, gcs_sysid=300)
    with pytest.raises(uavsim.InvalidArgumentError):
        uavsim.Vehicle(empty_world.loop, telemetry_rate_hz=0.0)
    with pytest.raises(uavsim.InvalidArgumentError):
        uavsim.Vehicle(empty_world.loop).connect("no-address")
    # a refusal carries the vehicle's answer: velocity outside GUIDED is not ready
    with pytest.raises(uavsim.UavsimError) as e:
        uav.set_velocity_enu([1.0, 0, 0])
    assert e.value.code == uavsim.Error.NOT_READY


def test_flight_modes_take_off_goto_velocity_yaw_and_land(empty_world, uav):
    sim = empty_world.sim
    uav.set_mode(FlightMode.GUIDED)
    assert uav.telemetry.mode == FlightMode.GUIDED and uavsim.mode_name(FlightMode.GUIDED) == "GUIDED"
    uav.arm()
    assert uav.telemetry.armed
    uav.takeoff(ALT_M)
    assert uav.telemetry.relative_alt_m == pytest.approx(ALT_M, abs=TOL_M)
    truth = sim.vehicle("uav0")
    assert truth["position_enu_m"][2] == pytest.approx(ALT_M, abs=TOL_M)

    # local and geodetic setpoints
    uav.goto_local_enu([4.0, 0.0, ALT_M])
    uav.wait_position_enu([4.0, 0.0, ALT_M], TOL_M, 30.0)
    assert sim.vehicle(0)["position_enu_m"][0] == pytest.approx(4.0, abs=TOL_M)
    uav.goto_local_ned([0.0, 0.0, -ALT_M], 0.0)
    uav.wait_position_enu([0.0, 0.0, ALT_M], TOL_M, 30.0)
    origin = uav.telemetry.origin
    uav.goto_geodetic(uavsim.geodetic_from_enu(origin, [0.0, 4.0, ALT_M]))
    uav.wait_position_enu([0.0, 4.0, ALT_M], TOL_M, 30.0)

    # velocity: 1 m/s east for 2 s, then hold
    x0 = uav.telemetry.position_enu_m[0]
    uav.set_velocity_enu([1.0, 0.0, 0.0])
    empty_world.run_for(2.0)
    assert uav.telemetry.velocity_enu_m_s[0] == pytest.approx(1.0, abs=0.3)
    uav.set_velocity_enu_yaw([0.0, 0.0, 0.0], 0.0)
    empty_world.run_for(0.5)
    uav.stop()
    empty_world.run_for(2.0)
    assert uav.telemetry.position_enu_m[0] - x0 > 1.0
    assert np.linalg.norm(uav.telemetry.velocity_enu_m_s) < 0.3

    # yaw to north-east (45 deg clockwise from north)
    uav.set_yaw(45.0, 90.0)
    empty_world.run_for(3.0)
    assert uav.telemetry.heading_deg == pytest.approx(45.0, abs=5.0)

    # the gimbal command is answered (the empty world's quad has no gimbal: refused or accepted, never silent)
    try:
        uav.point_gimbal(-30.0, 0.0)
    except uavsim.UavsimError as e:
        assert e.code in (uavsim.Error.UNSUPPORTED, uavsim.Error.DENIED, uavsim.Error.FAILED)

    # any COMMAND_LONG: MAV_CMD_DO_CHANGE_SPEED (178) to 3 m/s
    uav.command_long(178, [1.0, 3.0, -1.0, 0.0, 0.0, 0.0, 0.0])

    uav.land(wait=True, timeout_s=60.0)
    assert not uav.telemetry.armed
    assert sim.vehicle(0)["on_ground"]


def test_async_commands_report_through_done(empty_world, uav):
    outcomes = []
    uav.set_mode_async(FlightMode.GUIDED, outcomes.append)
    empty_world.loop.run_until(lambda: len(outcomes) == 1, 10.0)
    assert outcomes == [None]
    uav.arm_async(outcomes.append)
    empty_world.loop.run_until(lambda: len(outcomes) == 2, 10.0)
    assert outcomes[1] is None and uav.telemetry.armed
    uav.takeoff_async(2.0, outcomes.append)
    empty_world.loop.run_until(lambda: len(outcomes) == 3, 10.0)
    assert outcomes[2] is None
    uav.wait_position_enu(uav.telemetry.position_enu_m * [1, 1, 0] + [0, 0, 2.0], TOL_M, 30.0)
    uav.land_async(outcomes.append)
    empty_world.loop.run_until(lambda: len(outcomes) == 4, 10.0)
    assert outcomes[3] is None
    empty_world.loop.run_until(lambda: not uav.telemetry.armed, 60.0, "landed and disarmed")
    # a refused command is answered with the vehicle's MAV_RESULT: take-off while disarmed
    done = []
    uav.command_long_async(22, [0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 5.0], done.append)
    empty_world.loop.run_until(lambda: len(done) == 1, 10.0)
    assert isinstance(done[0], uavsim.UavsimError) and done[0].mav_result > 0


def test_mission_upload_and_start_then_return_to_launch(empty_world, uav):
    origin = uav.telemetry.origin
    wp = uavsim.geodetic_from_enu(origin, [5.0, 5.0, 0.0])
    items = [uavsim.MissionItem.takeoff(3.0), uavsim.MissionItem.waypoint(wp.lat_deg, wp.lon_deg, 3.0),
             uavsim.MissionItem.rtl()]
    assert items[0].command == 22 and items[1].command == 16 and items[2].command == 20
    uav.upload_mission(items)
    uav.set_mode(FlightMode.GUIDED)
    start = np.array(empty_world.sim.vehicle(0)["position_enu_m"][:2])
    uav.arm()  # home is where it arms
    uav.start_mission()
    empty_world.loop.run_until(lambda: uav.telemetry.mission_last_reached >= 2, 60.0, "the waypoint reached")
    assert np.array(empty_world.sim.vehicle(0)["position_enu_m"][:2]) == pytest.approx([5.0, 5.0], abs=1.0)
    uav.set_mode(FlightMode.GUIDED)
    uav.return_to_launch()
    assert uav.telemetry.mode == FlightMode.RTL
    empty_world.loop.run_until(lambda: not uav.telemetry.armed, 120.0, "home and disarmed")
    assert np.linalg.norm(np.array(empty_world.sim.vehicle(0)["position_enu_m"][:2]) - start) < 1.0


def test_status_texts(uav):
    texts = uav.status_texts
    assert isinstance(texts, list) and all(isinstance(t, str) for t in texts)


def test_a_dead_server_raises_connection_errors():
    with uavsim.Server("empty", seed=4) as s:
        v = s.vehicle(0, wait_ready=False)
        loop = s.loop
    # the server is stopped and the server's objects closed
    with pytest.raises(uavsim.ConnectionError):
        v.arm()
    with pytest.raises(uavsim.ConnectionError):
        loop.run_for(0.1)
    # a vehicle on a loop of its own, the server gone: the link is lost, not hung
    with uavsim.Server("empty", seed=4, lockstep=False) as s:
        loop = uavsim.EventLoop.host()
        v = uavsim.Vehicle(loop)
        v.connect(f"tcp:127.0.0.1:{s.mavlink_ports['uav0']}")
    with pytest.raises(uavsim.ConnectionError):
        v.arm()
    with pytest.raises(uavsim.ConnectionError):
        uavsim.Vehicle(loop).connect(f"tcp:127.0.0.1:{s.mavlink_ports['uav0']}", 2.0)
