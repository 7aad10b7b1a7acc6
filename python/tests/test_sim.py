"""uavsim.Sim, the named world-control ops: clock, ground truth, events, faults and wind."""

import pytest

import uavsim


@pytest.fixture(scope="module")
def world():
    with uavsim.Server("mbzirc2020", seed=3, cameras=False, lockstep=False) as s:
        s.sim.pause()
        yield s


def test_clock(world):
    sim = world.sim
    t0 = sim.status()["time_s"]
    assert sim.step(steps=5)["time_s"] == pytest.approx(t0 + 5 / 500)
    assert sim.step(duration_s=0.1)["time_s"] == pytest.approx(t0 + 5 / 500 + 0.1)
    with pytest.raises(ValueError):
        sim.step()
    assert sim.set_rate(0)["rate"] == 0
    with pytest.raises(uavsim.InvalidArgumentError):
        sim.set_rate(-3)
    armed = sim.pause_at(time_s=t0 + 10.0)
    assert armed["pause_at_s"]
    assert sim.reset(3) is not None and sim.status()["time_s"] == 0


def test_ground_truth(world):
    sim = world.sim
    vs = sim.vehicles()
    assert [v["name"] for v in vs] == ["uav0", "uav1"]
    assert sim.vehicle("uav1")["index"] == 1 and sim.vehicle(0)["name"] == "uav0"
    with pytest.raises(uavsim.InvalidArgumentError):
        sim.vehicle("uav7")
    balloons = sim.balloons()
    assert len(balloons) == 5 and all(not b["popped"] for b in balloons)
    with pytest.raises(uavsim.UavsimError) as e:
        sim.trucks()
    assert e.value.code == uavsim.Error.UNSUPPORTED


def test_faults_events_and_wind(world):
    sim = world.sim
    sim.reset(3)
    assert sim.subscribe_events()["events"] == []
    sim.gps_glitch("uav0", [1.0, 0.0, 0.0])
    sim.gps_glitch("uav0", [0.0, 0.0, 0.0])
    sim.gps_denied(0, True)
    sim.gps_denied(0, False)
    sim.link_drop("uav1", True)
    sim.link_drop("uav1", False)
    sim.motor_failure("uav0", 1)
    sim.kill_vehicle("uav1", "test")
    with pytest.raises(uavsim.InvalidArgumentError):
        sim.motor_failure("uav0", 99)
    with pytest.raises(uavsim.UavsimError):
        sim.camera_blackout("uav0_front", 1.0)  # no cameras in this server: not available
    sim.step(duration_s=0.1)
    types = [e["type"] for e in sim.events()["events"]]
    assert "motor_failure" in types and "vehicle_killed" in types
    sim.poll(0)
    streamed = [m.json["type"] for m in sim.take_messages() if m.kind == "sim_event"]
    assert "vehicle_killed" in streamed
    w = sim.wind(speed_m_s=4.0, from_deg=90.0)
    assert w["speed_m_s"] == pytest.approx(4.0) and w["from_deg"] == pytest.approx(90.0)
    assert sim.wind()["speed_m_s"] == pytest.approx(4.0)
    with pytest.raises(uavsim.InvalidArgumentError):
        sim.wind(speed_m_s=500.0)
    assert sim.request("status")["vehicles"] == 2
