"""Radio (air-to-air frames between vehicles) and landing-pad switches, on the lockstep clock."""

import pytest

import uavsim
from conftest import THREE_QUADS


def test_two_vehicles_talk_over_the_radio():
    with uavsim.Server(THREE_QUADS, seed=1, cameras=False) as s:
        r0, r1, r2 = s.radio(0), s.radio("uav1"), s.radio(2)
        assert (r0.vehicle, r1.vehicle) == (0, 1)
        r0.send(b"hello uav1", 1)
        r1.send(bytearray(b"hello all"))
        s.run_for(0.5)
        got1 = r1.take_received()
        assert [(f.sender, f.data, f.broadcast) for f in got1] == [(0, b"hello uav1", False)]
        got0 = r0.take_received()
        assert [(f.sender, f.data, f.broadcast) for f in got0] == [(1, b"hello all", True)]
        assert [f.data for f in r2.take_received()] == [b"hello all"]
        assert got1[0].time_s > 0 and r0.counters.sent == 1 and r1.counters.received == 1
        with pytest.raises(uavsim.InvalidArgumentError):
            r0.send(b"")
        # the simple backend's channel: 802.15.4's whole PSDU
        assert r0.max_frame_bytes == uavsim._core.RADIO_MAX_FRAME_BYTES == 127
        r0.send(b"x" * r0.max_frame_bytes)
        with pytest.raises(uavsim.InvalidArgumentError):
            r0.send(b"x" * (r0.max_frame_bytes + 1))
        with pytest.raises(TypeError):
            r0.send("a str is not bytes")
        with pytest.raises(uavsim.InvalidArgumentError):
            s.radio(3)  # the world has vehicles 0-2
        with pytest.raises(uavsim.UavsimError) as e:
            uavsim.Radio.open(s.loop, 7)  # the simulator's refusal
        assert e.value.code == uavsim.Error.DENIED and "unknown_vehicle" in e.value.message
        r2.close()
        with pytest.raises(uavsim.ConnectionError):
            r2.send(b"closed")


def test_radio_needs_lockstep():
    with uavsim.Server(THREE_QUADS, seed=1, cameras=False, lockstep=False) as s:
        with pytest.raises(uavsim.UavsimError) as e:
            s.radio(0)
        assert e.value.code == uavsim.Error.UNSUPPORTED


def test_landing_pad_switches_on_the_ground():
    with uavsim.Server("hexa", seed=1, cameras=False) as s:
        changes = []
        sw = s.switches("uav0", changes.append)
        s.loop.run_until(lambda: len(sw.state.closed) > 0, 10.0, "a switch reading")
        st = sw.state
        assert len(st.closed) == 4 and st.any() and all(st.closed)
        assert changes and changes[-1].closed == st.closed
        with pytest.raises(uavsim.UavsimError) as e:
            s.switches("no_such_vehicle")
