#!/usr/bin/env python3
"""A mission's wall time against its floor's, in one sitting (docs/results/performance.md):

  mission  the launcher's run (`mbzirc2017-run`, `mbzirc2020-run`, `coverage-run`), headless
  floor    the same launcher with `--floor S`: the same server and world for the mission's own sim time S,
           its vehicles hovering and the cameras the mission's programs subscribe to rendered, with no
           program and no client: what the mission cannot be faster than

For each case the mission runs first (its summary gives the sim time the floor then runs for), then the two
alternate --runs times, so that both see the same machine. Printed: each run's wall time, the ratios
mission / floor, and the mission's speed (sim seconds per wall second). The machine should be otherwise idle.

    bench/mission_floor.py [--build build] [--runs 2] [--cases mbzirc2017,mbzirc2020,coverage25]
                           [--seed 1] [--json FILE]

Cases: mbzirc2017, mbzirc2017-field, mbzirc2020, mbzirc2020-field (`--realism ideal|field`), coverage25 (25 quads
over 600 x 600 m), coverage5 (5 quads over 150 x 100 m, a minute of wall time).
"""

import argparse
import json
import os
import resource
import subprocess
import sys
import tempfile
import time

# launcher (relative to the build tree) and its arguments beyond --seed, per case
CASES = {
    "mbzirc2017": ("missions/mbzirc2017/mbzirc2017-run", ["--realism", "ideal"]),
    "mbzirc2017-field": ("missions/mbzirc2017/mbzirc2017-run", ["--realism", "field"]),
    "mbzirc2020": ("missions/mbzirc2020/mbzirc2020-run", ["--realism", "ideal"]),
    "mbzirc2020-field": ("missions/mbzirc2020/mbzirc2020-run", ["--realism", "field"]),
    "coverage25": ("missions/coverage/coverage-run", ["--agents", "25", "--area", "600x600", "--budget", "1000"]),
    "coverage5": ("missions/coverage/coverage-run", ["--agents", "5", "--area", "150x100"]),
}


def timed(argv):
    """Runs argv to its end: (exit code, wall seconds, CPU seconds of it and its children)."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    start = time.monotonic()
    code = subprocess.run(argv, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL).returncode
    wall = time.monotonic() - start
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return code, wall, cpu


def one_run(launcher, args, summary_path, floor_s=None):
    argv = [launcher, *args, "--no-record", "--no-run-dir", "--quiet", "--json", summary_path]
    if floor_s is not None:
        argv += ["--floor", f"{floor_s:.3f}"]
    code, wall, cpu = timed(argv)
    try:
        with open(summary_path) as f:
            summary = json.load(f)
    except (OSError, ValueError) as e:
        sys.exit(f"mission_floor: {' '.join(argv)}: no summary ({e}), exit code {code}")
    return {"exit_code": code, "wall_s": wall, "cpu_s": cpu, "sim_s": summary.get("sim_time_s", -1.0),
            "success": bool(summary.get("success", False))}


def bench_case(name, build, seed, runs, workdir):
    rel, extra = CASES[name]
    launcher = os.path.join(build, rel)
    if not os.access(launcher, os.X_OK):
        sys.exit(f"mission_floor: {launcher} is not built (cmake --build {build})")
    args = ["--seed", str(seed), *extra]
    summary = os.path.join(workdir, name + ".json")
    missions, floors = [], []
    for i in range(runs):
        m = one_run(launcher, args, summary)
        if m["sim_s"] <= 0:
            sys.exit(f"mission_floor: {name}: the mission ran no sim time (exit code {m['exit_code']})")
        missions.append(m)
        # the floor spans the first mission's sim time, every time (the runs are deterministic)
        f = one_run(launcher, args, summary, floor_s=missions[0]["sim_s"])
        if not f["success"]:
            sys.exit(f"mission_floor: {name}: the floor failed (exit code {f['exit_code']})")
        floors.append(f)
        print(f"  {name} {i + 1}/{runs}: mission {m['wall_s']:.2f} s ({'SUCCESS' if m['success'] else 'FAILURE'}),"
              f" floor {f['wall_s']:.2f} s", flush=True)
    ratios = [m["wall_s"] / f["wall_s"] for m, f in zip(missions, floors)]
    return {"case": name, "sim_s": missions[0]["sim_s"], "missions": missions, "floors": floors,
            "ratios": ratios, "speed_x": [m["sim_s"] / m["wall_s"] for m in missions]}


def span(values, fmt):
    lo, hi = min(values), max(values)
    return fmt.format(lo) if fmt.format(lo) == fmt.format(hi) else fmt.format(lo) + "-" + fmt.format(hi)


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--build", default=os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "build"))
    p.add_argument("--runs", type=int, default=2)
    p.add_argument("--cases", default="mbzirc2017,mbzirc2020,coverage25")
    p.add_argument("--seed", type=int, default=1)
    p.add_argument("--json", help="write the results as JSON")
    o = p.parse_args()
    cases = [c for c in o.cases.split(",") if c]
    unknown = [c for c in cases if c not in CASES]
    if unknown or not cases or not 1 <= o.runs <= 100:
        p.error(f"cases are {', '.join(CASES)}; runs 1-100")
    print(f"load average {os.getloadavg()[0]:.2f}, {time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())}",
          flush=True)
    with tempfile.TemporaryDirectory(prefix="mission_floor-") as workdir:
        results = [bench_case(c, o.build, o.seed, o.runs, workdir) for c in cases]
    print("\n| case | sim time | mission wall | floor wall | mission / floor | mission speed |")
    print("|---|---|---|---|---|---|")
    for r in results:
        print(f"| {r['case']} | {r['sim_s']:.1f} s | {span([m['wall_s'] for m in r['missions']], '{:.2f}')} s"
              f" | {span([f['wall_s'] for f in r['floors']], '{:.2f}')} s | {span(r['ratios'], '{:.2f}')}x"
              f" | {span(r['speed_x'], '{:.1f}')}x real time |")
    if o.json:
        with open(o.json, "w") as f:
            json.dump(results, f, indent=1)
    return 0 if all(m["success"] for r in results for m in r["missions"]) else 1


if __name__ == "__main__":
    sys.exit(main())
