#!/usr/bin/env python3
"""Fly a 10 m square at 5 m in the empty world, then land: uavsim.Server starts the simulator, the vehicle
flies through the C++ client library (MAVLink, GUIDED setpoints), and the sim API's ground truth checks
where it went.

    python3 python/examples/fly_square.py [--side 10] [--alt 5] [--seed 1]
"""

import argparse

import uavsim


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--side", type=float, default=10.0, help="side of the square (m)")
    p.add_argument("--alt", type=float, default=5.0, help="altitude (m above home)")
    p.add_argument("--seed", type=int, default=1)
    p.add_argument("--world", default="empty")
    args = p.parse_args()

    with uavsim.Server(args.world, seed=args.seed, cameras=False) as sim:
        uav = sim.vehicle("uav0")  # connected, and ready to fly
        uav.set_mode(uavsim.FlightMode.GUIDED)
        uav.arm()
        uav.takeoff(args.alt)
        home = uav.telemetry.position_enu_m.copy()
        print(f"t={sim.now():6.2f} s  took off to {uav.telemetry.relative_alt_m:.1f} m")
        s = args.side
        for corner in ([s, 0], [s, s], [0, s], [0, 0]):
            target = [home[0] + corner[0], home[1] + corner[1], args.alt]
            uav.goto_local_enu(target)
            uav.wait_position_enu(target, 0.5, 60.0)
            truth = sim.sim.vehicle("uav0")["position_enu_m"]
            print(f"t={sim.now():6.2f} s  at corner {corner}: ground truth "
                  f"({truth[0]:.2f}, {truth[1]:.2f}, {truth[2]:.2f}) m")
        uav.land(wait=True)
        print(f"t={sim.now():6.2f} s  landed, battery {uav.telemetry.battery_voltage_v:.2f} V")


if __name__ == "__main__":
    main()
