#!/usr/bin/env python3
"""Python against C++ on the same server, in one run (docs/results/python.md):

  ticks   lockstep ticks per second with one vehicle connected and a telemetry callback
  camera  camera frames per second delivered (numpy arrays in Python, cv::Mat in C++): colour, then depth and
          segmentation (the same camera given modalities=rgb+depth+segmentation, subscribed to the two planes)
  env     HoverEnv steps per second (Python only)

The C++ side is bench/client_rate_bench (the same measurement with client_cpp); the two alternate on one
server, each run from t = 0 with the same seed, and the medians of --repeat runs give the ratio.

    PYTHONPATH=build/python /usr/bin/python3 bench/python_bench.py [--build build] [--repeat 3]
"""

import argparse
import json
import os
import statistics
import subprocess
import sys
import time

import uavsim


def python_run(server, mode, seconds, period_s, camera, seed, modalities=("rgb",)):
    """The Python twin of client_rate_bench: the same steps through the bindings."""
    sim = uavsim.Sim.connect(port=server.api_port)
    sim.pause()
    sim.reset(seed)
    loop = uavsim.EventLoop.lockstep("127.0.0.1", server.api_port, period_s)
    sim.resume()
    counts = {"telemetry": 0, "frames": 0}
    held = None
    if mode == "ticks":
        held = uavsim.Vehicle(loop, sim_vehicle="uav0")
        held.connect(f"tcp:127.0.0.1:{server.mavlink_ports['uav0']}")

        def on_telemetry(t):
            counts["telemetry"] += 1

        held.on_telemetry(on_telemetry)
    else:
        def on_frame(f):
            counts["frames"] += 1 if (f.image if f.image is not None else f.depth_m).size else 0

        held = uavsim.Camera.subscribe(loop, camera, modalities=list(modalities), on_frame=on_frame, queue=0)
    t0 = loop.now()
    w0 = time.perf_counter()
    loop.run_for(seconds)
    wall_s = time.perf_counter() - w0
    sim_s = loop.now() - t0
    held.close()
    loop.close()
    sim.close()
    return {"mode": mode, "sim_s": sim_s, "wall_s": wall_s, "ticks": sim_s / period_s, **counts}


def cpp_run(exe, server, mode, seconds, period_s, camera, seed, modalities=("rgb",)):
    out = subprocess.run([exe, "--api", str(server.api_port), "--mavlink", str(server.mavlink_ports["uav0"]),
                          "--mode", mode, "--seconds", str(seconds), "--period", str(period_s),
                          "--camera", camera, "--modalities", "+".join(modalities), "--seed", str(seed)],
                         check=True, capture_output=True, text=True, timeout=600)
    return json.loads(out.stdout.strip().splitlines()[-1])


def rate(r, mode):
    return (r["ticks"] if mode == "ticks" else r["frames"]) / r["wall_s"]


def compare(exe, world, mode, seconds, period_s, camera, cameras, repeat, modalities=("rgb",)):
    """Alternating runs (C++ first in even pairs, Python first in odd ones), so that both sides see the same
    machine load; the figure is the median of the ratios of each pair's rates."""
    py, cpp = [], []
    with uavsim.Server(world, lockstep=False, cameras=cameras) as server:
        for i in range(repeat):
            runs = [("cpp", lambda: cpp_run(exe, server, mode, seconds, period_s, camera, 1, modalities)),
                    ("py", lambda: python_run(server, mode, seconds, period_s, camera, 1, modalities))]
            for side, fn in (runs if i % 2 == 0 else runs[::-1]):
                (cpp if side == "cpp" else py).append(rate(fn(), mode))
    ratios = [p / c for p, c in zip(py, cpp)]
    return statistics.median(ratios), statistics.median(py), statistics.median(cpp), ratios


def env_rate(steps):
    env = uavsim.HoverEnv(max_episode_s=3600.0)
    env.reset(seed=1)
    w0 = time.perf_counter()
    for _ in range(steps):
        env.step([0.3, 0.0, 0.0])
    wall_s = time.perf_counter() - w0
    sim_s = steps * env.action_period_s
    env.close()
    return steps / wall_s, sim_s / wall_s


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--build", default="build", help="the build directory (bench/client_rate_bench)")
    p.add_argument("--repeat", type=int, default=3)
    p.add_argument("--tick-seconds", type=float, default=20.0, help="sim seconds per ticks run")
    p.add_argument("--period", type=float, default=0.01, help="lockstep period (s)")
    p.add_argument("--camera-seconds", type=float, default=10.0, help="sim seconds per camera run")
    p.add_argument("--camera-size", default="320x240")
    p.add_argument("--camera-fps", type=float, default=30.0)
    p.add_argument("--env-steps", type=int, default=300)
    p.add_argument("--only", default="ticks,camera,planes,env",
                   help="the measurements to run, comma-separated: ticks, camera, planes, env")
    args = p.parse_args()
    exe = os.path.join(args.build, "bench", "client_rate_bench")
    if not os.access(exe, os.X_OK):
        sys.exit(f"python_bench: {exe} not found (build it: cmake --build {args.build} --target client_rate_bench)")
    w, h = args.camera_size.split("x")
    cameras = {"overview": f"width={w},height={h},fps={args.camera_fps:g}"}
    rgbd = {"overview": cameras["overview"] + ",modalities=rgb+depth+segmentation"}

    only = set(args.only.split(","))
    if not only <= {"ticks", "camera", "planes", "env"}:
        sys.exit(f"python_bench: --only takes ticks, camera, planes, env, not {args.only}")
    if "ticks" in only:
        ratio, py, cpp, ratios = compare(exe, "empty", "ticks", args.tick_seconds, args.period, "overview", False,
                                         args.repeat)
        print(f"lockstep ticks/s, one vehicle + telemetry callback (period {args.period} s): Python/C++ "
              f"{ratio:.2f} (median of {len(ratios)} pairs: {[round(r, 2) for r in ratios]}); medians Python "
              f"{py:.0f}, C++ {cpp:.0f}")
    if "camera" in only:
        ratio, py, cpp, ratios = compare(exe, "empty", "camera", args.camera_seconds, args.period, "overview",
                                         cameras, args.repeat)
        print(f"camera frames/s delivered ({args.camera_size} BGR at {args.camera_fps:g} fps sim): Python/C++ "
              f"{ratio:.2f} (median of {len(ratios)} pairs: {[round(r, 2) for r in ratios]}); medians Python "
              f"{py:.1f}, C++ {cpp:.1f}")
    if "planes" in only:
        ratio, py, cpp, ratios = compare(exe, "empty", "camera", args.camera_seconds, args.period, "overview",
                                         rgbd, args.repeat, ("depth", "segmentation"))
        print(f"depth + segmentation frames/s delivered ({args.camera_size} at {args.camera_fps:g} fps sim, "
              f"float32 and 2 x uint16 numpy / cv::Mat): Python/C++ {ratio:.2f} (median of {len(ratios)} pairs: "
              f"{[round(r, 2) for r in ratios]}); medians Python {py:.1f}, C++ {cpp:.1f}")
    if "env" in only:
        steps_s, speed = env_rate(args.env_steps)
        print(f"HoverEnv: {steps_s:.1f} steps/s ({speed:.1f}x real time at 0.1 s per step)")

if __name__ == "__main__":
    main()
