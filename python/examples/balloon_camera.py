#!/usr/bin/env python3
"""A camera frame into OpenCV: in the MBZIRC 2020 arena, uav0 takes off, turns on the spot, and looks for
the green balloons in its forward camera with the idea of uavsim's balloon detector (vision/): an HSV
window around green, a morphological clean-up, then round, filled blobs. Each detection's bearing comes
from the frame's intrinsics, and the first annotated frame with a balloon is written to a PNG.

    python3 python/examples/balloon_camera.py [--out balloon.png] [--seed 1]
"""

import argparse
import math

import cv2
import numpy as np

import uavsim

# HSV window (OpenCV scales: hue 0..180): green is 60; shading keeps hue and saturation, so value_min is low
HUE_MIN, HUE_MAX, SATURATION_MIN, VALUE_MIN = 38, 85, 70, 25
MIN_RADIUS_PX, MIN_FILL = 3.0, 0.6


def detect_balloons(bgr):
    """Green, round, filled blobs: [(u, v, radius_px)]."""
    hsv = cv2.cvtColor(bgr, cv2.COLOR_BGR2HSV)
    mask = cv2.inRange(hsv, (HUE_MIN, SATURATION_MIN, VALUE_MIN), (HUE_MAX, 255, 255))
    kernel = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (3, 3))
    mask = cv2.morphologyEx(mask, cv2.MORPH_OPEN, kernel)
    mask = cv2.morphologyEx(mask, cv2.MORPH_CLOSE, kernel)
    contours, _ = cv2.findContours(mask, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_NONE)
    found = []
    for c in contours:
        (u, v), r = cv2.minEnclosingCircle(c)
        if r < MIN_RADIUS_PX:
            continue
        if cv2.contourArea(c) / (math.pi * r * r) < MIN_FILL:  # crescents, stripes, bushes
            continue
        found.append((u, v, r))
    return found


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--out", default="balloon.png", help="the annotated frame (PNG)")
    p.add_argument("--seed", type=int, default=1)
    args = p.parse_args()

    with uavsim.Server("mbzirc2020", seed=args.seed, cameras={"uav0_front": "width=320,height=180,fps=5"}) as sim:
        uav = sim.vehicle("uav0")
        uav.set_mode(uavsim.FlightMode.GUIDED)
        uav.arm()
        uav.takeoff(3.0)
        camera = sim.camera("uav0_front", queue=0)
        for step in range(12):  # a full turn in 30 degree steps
            sim.run_for(2.0)
            frame = camera.latest
            found = detect_balloons(frame.image)  # frame.image: a numpy view of the C++ frame, BGR
            k = frame.intrinsics
            print(f"t={frame.stamp_s:6.2f} s  heading {uav.telemetry.heading_deg:5.1f} deg: {len(found)} balloon(s)")
            if found:
                annotated = frame.image.copy()
                for u, v, r in found:
                    bearing = math.degrees(math.atan2(u - k.cx, k.fx))  # right of the optical axis
                    print(f"    at pixel ({u:.0f}, {v:.0f}), radius {r:.1f} px, {bearing:+.1f} deg off the axis")
                    cv2.circle(annotated, (int(round(u)), int(round(v))), int(round(r)) + 2, (0, 0, 255), 1)
                cv2.imwrite(args.out, annotated)
                print(f"wrote {args.out}")
                break
            uav.set_yaw(30.0, 30.0, relative=True)
        else:
            print("no balloon seen in a full turn")
        uav.land(wait=True)


if __name__ == "__main__":
    main()
