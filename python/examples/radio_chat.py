#!/usr/bin/env python3
"""Two vehicles talking over the air-to-air radio (802.15.4 frames, simulated with range and losses):
uav0 and uav1 of the MBZIRC 2020 arena take off, and each second uav0 sends its position; uav1 answers
with its own and the distance it computes between them. Everything runs on the lockstep clock, so every
run of a seed prints the same lines.

    python3 python/examples/radio_chat.py [--seconds 10] [--seed 1]
"""

import argparse
import struct

import numpy as np

import uavsim

POSITION = struct.Struct("<3f")  # a frame: ENU metres as three little-endian floats


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--seconds", type=float, default=10.0)
    p.add_argument("--seed", type=int, default=1)
    args = p.parse_args()

    with uavsim.Server("mbzirc2020", seed=args.seed, cameras=False) as sim:
        uavs = [sim.vehicle(n) for n in ("uav0", "uav1")]
        radios = [sim.radio(0), sim.radio(1)]
        for i, uav in enumerate(uavs):
            uav.set_mode(uavsim.FlightMode.GUIDED)
            uav.arm()
            uav.takeoff(3.0 + 2.0 * i)
        o0 = uavs[0].telemetry.origin
        origin = [uavsim.enu_from_geodetic(o0, uavsim.Geodetic(u.telemetry.origin.lat_deg, u.telemetry.origin.lon_deg,
                                                               u.telemetry.origin.alt_m)) for u in uavs]

        def where(i):  # a vehicle's position in the world frame (each EKF origin is where it started)
            return uavs[i].telemetry.position_enu_m + origin[i] - origin[0]

        def tick():
            radios[0].send(POSITION.pack(*where(0)), to=1)
            for f in radios[1].take_received():
                theirs = np.array(POSITION.unpack(f.data))
                d = np.linalg.norm(theirs - where(1))
                radios[1].send(f"uav1 heard uav0 at t={f.time_s:.2f} s, {d:.1f} m away".encode())
            for f in radios[0].take_received():
                print(f"uav0 got from uav{f.sender}: {f.data.decode()}")

        sim.loop.call_every(1.0, tick)
        sim.run_for(args.seconds)
        print(f"radio counters: uav0 sent {radios[0].counters.sent}, uav1 received {radios[1].counters.received}")


if __name__ == "__main__":
    main()
