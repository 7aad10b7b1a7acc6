#!/usr/bin/python3
"""plot_run.py on a generated run directory: two quads take off and fly a square, one pops a balloon."""
import json
import math
import os
import subprocess
import sys
import tempfile

MIN_PNG_BYTES = 10_000  # a blank 800 x 600 figure is a few kB; plotted lines make it larger


def main():
    plot = sys.argv[1]
    try:
        import matplotlib  # noqa: F401
    except ImportError:
        print("SKIP: matplotlib is missing (scripts/install_deps.sh installs python3-matplotlib)")
        return 77
    with tempfile.TemporaryDirectory() as run:
        # ground truth at 10 Hz for 60 s
        for k, name in enumerate(["uav0", "uav1"]):
            with open(os.path.join(run, f"truth_{name}.csv"), "w") as f:
                f.write("t_s,x_m,y_m,z_m,vx_m_s,vy_m_s,vz_m_s,roll_deg,pitch_deg,yaw_deg,battery_v,"
                        "battery_used_mah,mode,armed,crashed,on_ground\n")
                for i in range(600):
                    t = i / 10.0
                    a = 2 * math.pi * t / 60.0
                    x, y = 20 * math.cos(a) + 10 * k, 20 * math.sin(a)
                    z = min(10.0, t)
                    f.write(f"{t:.1f},{x:.2f},{y:.2f},{z:.2f},{-2 * math.sin(a):.2f},{2 * math.cos(a):.2f},0,"
                            f"0,0,0,{16.8 - t / 100:.3f},{t * 10:.1f},GUIDED,1,0,{int(t < 1)}\n")
        with open(os.path.join(run, "events.jsonl"), "w") as f:
            f.write(json.dumps({"t": 1.0, "vehicle": 0, "name": "uav0", "event": "takeoff", "detail": ""}) + "\n")
            f.write(json.dumps({"t": 30.0, "vehicle": 0, "name": "uav0", "event": "balloon_popped",
                                "detail": "b1"}) + "\n")
        with open(os.path.join(run, "summary.json"), "w") as f:
            json.dump({"mission": "mbzirc2020", "seed": 1,
                       "balloons": [{"name": "b1", "position_enu_m": [-20, 0, 3], "popped": True}]}, f)
        r = subprocess.run([sys.executable, plot, run], capture_output=True, text=True)
        if r.returncode != 0:
            print(r.stdout, r.stderr)
            return 1
        ok = True
        for png in ["trajectories.png", "altitude_speed.png", "battery.png"]:
            path = os.path.join(run, png)
            size = os.path.getsize(path) if os.path.exists(path) else 0
            print(f"{png}: {size} bytes")
            if size < MIN_PNG_BYTES:
                ok = False
        # a directory without ground truth is refused
        with tempfile.TemporaryDirectory() as empty:
            if subprocess.run([sys.executable, plot, empty], capture_output=True).returncode != 1:
                ok = False
        return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
