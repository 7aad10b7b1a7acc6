#!/usr/bin/python3
"""Plots a launcher's run directory (mbzirc2020-run, mbzirc2017-run, coverage-run --run-dir DIR).

usage: plot_run.py RUN_DIR [--coverage-map FILE.png]

Reads RUN_DIR/truth_VEHICLE.csv (the launcher's ground truth), RUN_DIR/truck_NAME.csv (the truck, if
any), RUN_DIR/events.jsonl (the server's events) and RUN_DIR/summary.json (which mission: the balloons,
the coverage rectangle), and writes into RUN_DIR:
  trajectories.png  the vehicles' tracks over the world map (balloons / the truck's eight / the rectangle)
  altitude_speed.png  altitude and speed over sim time, events marked
  battery.png       battery voltage and charge used over sim time, events marked
  coverage_map.png  (coverage-run) the rectangle as the agents' APD reports left it: covered once, by two or
                    more agents, lost with a dead agent, lost then covered again, delivered to the ground
                    station only, not covered; and the tracks (--coverage-map: write it to FILE.png instead)
Exit status 0; 1 when the directory holds no ground truth; 3 when matplotlib is missing.
"""
import csv
import glob
import json
import math
import os
import sys

MARKED_EVENTS = {"takeoff", "touchdown", "crash", "balloon_popped", "landed_on_target",
                 "vehicle_killed", "motor_failure", "state_fault", "failsafe"}


def read_csv(path):
    with open(path, newline="") as f:
        rows = list(csv.DictReader(f))
    cols = {}
    for r in rows:
        for k, v in r.items():
            try:
                cols.setdefault(k, []).append(float(v))
            except (TypeError, ValueError):
                cols.setdefault(k, []).append(v)
    return cols


def read_events(run_dir):
    path = os.path.join(run_dir, "events.jsonl")
    events = []
    if os.path.exists(path):
        with open(path) as f:
            for line in f:
                line = line.strip()
                if not line:
                    continue
                try:
                    events.append(json.loads(line))
                except ValueError:
                    pass
    return events


def event_kind(e):
    return e.get("event") or e.get("type") or ""


STATION = 255  # the ground station's APD reports (coverage-gcs)


def parse_apd(report, stripes):
    """An `APD <agent> <t> <stripe>:<a>-<b>,...;...` line (centimetres) -> {stripe: [(a_m, b_m)]}."""
    parts = report.split(" ", 3)
    out = {}
    if len(parts) < 4 or parts[3] == "-":
        return out
    for item in parts[3].split(";"):
        s, _, ivs = item.partition(":")
        s = int(s)
        if 0 <= s < stripes:
            out[s] = [(int(a) / 100.0, int(b) / 100.0) for a, b in (iv.split("-") for iv in ivs.split(","))]
    return out


def coverage_map(plt, summary, truth, title, path):
    """The coverage map of a coverage-run summary (its apd_reports) with the tracks over it."""
    import numpy as np
    w, h = summary["area_m"]
    ox, oy = summary.get("area_origin_m", [0.0, 0.0])
    stripes = int(summary["stripes"])
    cell_m = 0.1
    ny = max(1, int(round(h / cell_m)))

    def mask(apd):
        m = np.zeros((ny, stripes), dtype=bool)
        for s, ivs in apd.items():
            for a, b in ivs:
                m[int(math.ceil(a / cell_m)):int(math.floor(b / cell_m)), s] = True
        return m

    count = np.zeros((ny, stripes), dtype=int)  # agents whose pictures cover a cell, the dead included
    dead = np.zeros((ny, stripes), dtype=bool)
    alive = np.zeros((ny, stripes), dtype=bool)
    station = np.zeros((ny, stripes), dtype=bool)
    for r in summary.get("apd_reports", []):
        m = mask(parse_apd(r["report"], stripes))
        if r["agent"] == STATION:
            station |= m
        else:
            count += m
            if r["failed"]:
                dead |= m
            else:
                alive |= m
    classes = [("not covered", "white"), ("covered", "#b7e4b0"), ("covered by 2+ agents", "#4caf50"),
               ("lost with a dead agent", "#e53935"), ("lost, then covered again", "#ff9800"),
               ("delivered to the station only", "#42a5f5")]
    img = np.zeros((ny, stripes), dtype=int)
    img[count == 1] = 1
    img[count >= 2] = 2
    img[dead] = 3
    img[dead & alive] = 4
    img[station & ~alive] = 5
    from matplotlib.colors import ListedColormap
    from matplotlib.patches import Patch
    fig, ax = plt.subplots(figsize=(8, 7))
    ax.imshow(img, origin="lower", extent=(ox, ox + w, oy, oy + h), aspect="equal", interpolation="nearest",
              cmap=ListedColormap([c for _, c in classes]), vmin=0, vmax=len(classes) - 1)
    for name, c in truth.items():
        ax.plot(c["x_m"], c["y_m"], lw=0.5, color="0.2", alpha=0.6)
    ax.add_patch(plt.Rectangle((ox, oy), w, h, fill=False, ls="--", color="green"))
    used = sorted(set(np.unique(img).tolist()))
    ax.legend(handles=[Patch(facecolor=classes[k][1], edgecolor="0.5", label=classes[k][0]) for k in used]
              + [plt.Line2D([], [], color="0.2", lw=0.8, label="tracks")], fontsize=8, loc="upper right")
    ax.set_xlabel("east [m]")
    ax.set_ylabel("north [m]")
    ax.set_title(f"{title}: coverage map, {100.0 * summary.get('coverage', 0.0):.2f} % held")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main(argv):
    map_path = None
    if len(argv) == 4 and argv[2] == "--coverage-map":
        map_path = argv[3]
    elif len(argv) != 2:
        print(__doc__.strip().splitlines()[2], file=sys.stderr)
        return 2
    run_dir = argv[1]
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        print("plot_run.py: matplotlib is missing (scripts/install_deps.sh installs python3-matplotlib)",
              file=sys.stderr)
        return 3

    truth = {}
    for path in sorted(glob.glob(os.path.join(run_dir, "truth_*.csv"))):
        name = os.path.basename(path)[len("truth_"):-len(".csv")]
        cols = read_csv(path)
        if cols.get("t_s"):
            truth[name] = cols
    if not truth:
        print(f"plot_run.py: no truth_*.csv in {run_dir}", file=sys.stderr)
        return 1
    trucks = {os.path.basename(p)[len("truck_"):-len(".csv")]: read_csv(p)
              for p in sorted(glob.glob(os.path.join(run_dir, "truck_*.csv")))}
    summary = {}
    if os.path.exists(os.path.join(run_dir, "summary.json")):
        with open(os.path.join(run_dir, "summary.json")) as f:
            summary = json.load(f)
    mission = summary.get("mission", "")
    events = [e for e in read_events(run_dir) if event_kind(e) in MARKED_EVENTS]
    title = f"{mission or 'run'} seed {summary.get('seed', '?')}" if summary else os.path.basename(run_dir)

    # 1. trajectories over the world map
    fig, ax = plt.subplots(figsize=(7, 6))
    for name, c in trucks.items():
        ax.plot(c["x_m"], c["y_m"], color="0.6", lw=1.0, label=f"{name} (truck)")
    if mission == "coverage" and "area_m" in summary:
        ox, oy = summary.get("area_origin_m", [0.0, 0.0])
        w, h = summary["area_m"]
        ax.add_patch(plt.Rectangle((ox, oy), w, h, fill=False, ls="--", color="green", label="area"))
    for b in summary.get("balloons", []):
        p = b.get("position_enu_m", [0, 0, 0])
        ax.plot(p[0], p[1], "o", ms=9, mfc="none" if b.get("popped") else "limegreen", mec="green")
        ax.annotate(b.get("name", ""), (p[0], p[1]), textcoords="offset points", xytext=(6, 4), fontsize=8)
    for name, c in truth.items():
        line, = ax.plot(c["x_m"], c["y_m"], lw=1.2, label=name)
        ax.plot(c["x_m"][0], c["y_m"][0], "^", color=line.get_color())
        ax.plot(c["x_m"][-1], c["y_m"][-1], "s", color=line.get_color())
    for e in events:
        name = e.get("name") or e.get("vehicle_name")
        if name in truth and event_kind(e) in ("crash", "balloon_popped", "landed_on_target"):
            c = truth[name]
            i = min(range(len(c["t_s"])), key=lambda k: abs(c["t_s"][k] - e.get("t", e.get("time", 0.0))))
            ax.plot(c["x_m"][i], c["y_m"][i], "x" if event_kind(e) == "crash" else "*", color="red", ms=9)
    ax.set_xlabel("east [m]")
    ax.set_ylabel("north [m]")
    ax.set_aspect("equal", adjustable="datalim")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8, loc="best")
    ax.set_title(f"{title}: trajectories (^ start, s end, * event, x crash)")
    fig.tight_layout()
    fig.savefig(os.path.join(run_dir, "trajectories.png"), dpi=100)
    plt.close(fig)

    def mark_events(axes):
        for e in events:
            t = e.get("t", e.get("time"))
            if t is None:
                continue
            for a in axes:
                a.axvline(t, color="red" if event_kind(e) == "crash" else "0.5", lw=0.7, ls=":")
            axes[0].annotate(event_kind(e), (t, 1.0), xycoords=("data", "axes fraction"), rotation=90,
                             fontsize=6, va="top", ha="right", color="0.3")

    # 2. altitude and speed
    fig, (a1, a2) = plt.subplots(2, 1, sharex=True, figsize=(8, 6))
    for name, c in truth.items():
        a1.plot(c["t_s"], c["z_m"], lw=1, label=name)
        speed = [math.sqrt(x * x + y * y + z * z) for x, y, z in zip(c["vx_m_s"], c["vy_m_s"], c["vz_m_s"])]
        a2.plot(c["t_s"], speed, lw=1, label=name)
    a1.set_ylabel("altitude [m]")
    a2.set_ylabel("speed [m/s]")
    a2.set_xlabel("sim time [s]")
    for a in (a1, a2):
        a.grid(True, alpha=0.3)
    a1.legend(fontsize=8)
    mark_events([a1, a2])
    a1.set_title(f"{title}: altitude and speed")
    fig.tight_layout()
    fig.savefig(os.path.join(run_dir, "altitude_speed.png"), dpi=100)
    plt.close(fig)

    # 3. battery
    fig, (b1, b2) = plt.subplots(2, 1, sharex=True, figsize=(8, 5))
    for name, c in truth.items():
        b1.plot(c["t_s"], c["battery_v"], lw=1, label=name)
        b2.plot(c["t_s"], c["battery_used_mah"], lw=1, label=name)
    b1.set_ylabel("battery [V]")
    b2.set_ylabel("used [mAh]")
    b2.set_xlabel("sim time [s]")
    for a in (b1, b2):
        a.grid(True, alpha=0.3)
    b1.legend(fontsize=8)
    mark_events([b1, b2])
    b1.set_title(f"{title}: battery")
    fig.tight_layout()
    fig.savefig(os.path.join(run_dir, "battery.png"), dpi=100)
    plt.close(fig)
    wrote = "trajectories.png, altitude_speed.png, battery.png"

    # 4. the coverage map
    if mission == "coverage" and "apd_reports" in summary and "stripes" in summary:
        path = map_path or os.path.join(run_dir, "coverage_map.png")
        coverage_map(plt, summary, truth, title, path)
        wrote += ", " + path
    print(f"plot_run.py: wrote {wrote} in {run_dir}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
