#!/usr/bin/env python3
"""Plots of a coverage sweep (missions/coverage/sweep.sh plot OUT_DIR [PNG_DIR]).

fig4_7.png: mission time (take-off to last landing, the thesis's measure) and the time to coverage
(the leader's query that found the rectangle covered) against the number of agents, and the energy
per agent, from the failure-free runs; the thesis's 25-agent figures of table 4.2 (0-10 failed
agents) beside them. fig4_9.png: the share of time in each state of fig. 4.6 but Non-Leader (the
rest; Going Home, Landed and Failed left out, as in the thesis). One area per figure: the first (largest) one found.
fig4_8.png: the overcoverage distribution (overcoverage() below) against the failure probability,
from the runs with failures of that area and the failure-free ones.

Imported by sweep.sh's table step for overcoverage(); matplotlib is loaded only to plot.
"""
import glob
import json
import os
import statistics
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "scripts"))
from plot_run import STATION, parse_apd  # noqa: E402

STATES = ["Taking Off", "Querying", "Deploying", "Running", "Waiting", "Non-Leader"]
THESIS_25 = {"time_s": (719, 63), "energy_mah": (479, 44)}  # table 4.2, 0-10 failed agents


def overcoverage(summary, max_k=4):
    """Fig. 4.8's overcoverage distribution of one coverage-run summary: the share of the rectangle
    that the pictures of exactly k agents cover, k = 0 .. max_k (the last: max_k or more), from every
    agent's last APD report, the dead agents' included (what a failure makes the flock photograph
    again is overcoverage). An agent's own APD is a union, so its own repeated pictures count once:
    this is repeated coverage between agents. Stripes weigh the same (as the scoring's fraction)."""
    stripes = summary["stripes"]
    width = summary["area_m"][1]
    apds = [parse_apd(r["report"], stripes) for r in summary.get("apd_reports", [])
            if r.get("agent") != STATION]
    share = [0.0] * (max_k + 1)
    for st in range(stripes):
        # sweep over the interval ends: coverage depth between consecutive ends
        edges = []
        for apd in apds:
            for a, b in apd.get(st, []):
                a, b = max(0.0, a), min(width, b)
                if b > a:
                    edges += [(a, 1), (b, -1)]
        edges.sort()
        depth, y = 0, 0.0
        for pos, step in edges:
            share[min(depth, max_k)] += (pos - y) / (width * stripes)
            depth, y = depth + step, pos
        share[0] += (width - y) / (width * stripes)
    return share


def plot_overcoverage(plt, runs, png_dir):
    """fig4_8.png: mean share covered by 1, 2, 3, 4+ agents per failure probability."""
    area = max({tuple(j["area_m"]) for j in runs}, key=lambda a: a[0] * a[1])
    runs = [j for j in runs if tuple(j["area_m"]) == area and "apd_reports" in j and "stripes" in j]
    if not runs:
        return None
    n = max(j["agents"] for j in runs if j["failure_prob"] > 0) if any(
        j["failure_prob"] > 0 for j in runs) else max(j["agents"] for j in runs)
    runs = [j for j in runs if j["agents"] == n]
    probs = sorted({j["failure_prob"] for j in runs})
    dist = {p: [overcoverage(j) for j in runs if j["failure_prob"] == p] for p in probs}
    fig, ax = plt.subplots(figsize=(6, 3.2), dpi=80)
    bottom = [0.0] * len(probs)
    for k, label in ((2, "2 agents"), (3, "3 agents"), (4, "4 or more")):
        share = [100.0 * statistics.mean(d[k] for d in dist[p]) for p in probs]
        ax.bar([("%g" % p) for p in probs], share, bottom=bottom, label=label)
        bottom = [b + v for b, v in zip(bottom, share)]
    ax.set_xlabel("failure probability (per agent, every 10 s)")
    ax.set_ylabel("share of the rectangle [%]")
    ax.legend(fontsize=7, title="covered by", title_fontsize=7)
    ax.set_title("fig. 4.8: overcoverage, %d agents over %g x %g m (%d runs)" % (n, area[0], area[1], len(runs)),
                 fontsize=9)
    fig.tight_layout()
    path = os.path.join(png_dir, "fig4_8.png")
    fig.savefig(path)
    return path


def main():
    if len(sys.argv) < 2:
        print(__doc__)
        return 2
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    out = sys.argv[1]
    png_dir = sys.argv[2] if len(sys.argv) > 2 else out
    # uavsim-sweep's run directories (and the JSON files of sweeps made before it)
    all_runs = [json.load(open(p)) for p in sorted(glob.glob(os.path.join(out, "runs", "*", "summary.json")) +
                                                   glob.glob(os.path.join(out, "*.json")))
            if os.path.basename(p) != "sweep.json"]  # not uavsim-sweep's plan
    os.makedirs(png_dir, exist_ok=True)
    fig48 = plot_overcoverage(plt, all_runs, png_dir)
    if fig48:
        print("wrote " + fig48)
    runs = [j for j in all_runs if j["failure_prob"] == 0 and j["success"]]
    if not runs:
        print("no successful failure-free runs in " + out)
        return 1
    area = max({tuple(j["area_m"]) for j in runs}, key=lambda a: a[0] * a[1])
    runs = [j for j in runs if tuple(j["area_m"]) == area]
    sizes = sorted({j["agents"] for j in runs})

    def series(key):
        m, s = [], []
        for n in sizes:
            xs = [j[key] for j in runs if j["agents"] == n and j.get(key, -1) >= 0]
            m.append(statistics.mean(xs) if xs else float("nan"))
            s.append(statistics.stdev(xs) if len(xs) > 1 else 0.0)
        return m, s

    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(8, 3.2), dpi=80)
    t, ts = series("mission_time_s")
    c, cs = series("coverage_complete_s")
    e, es = series("energy_mah_mean")
    ax1.errorbar(sizes, t, yerr=ts, marker="o", label="mission (take-off to landing)")
    ax1.errorbar(sizes, c, yerr=cs, marker="s", label="coverage complete")
    ax1.errorbar([25], [THESIS_25["time_s"][0]], yerr=[THESIS_25["time_s"][1]], marker="*",
                 color="k", ms=10, ls="", label="thesis, table 4.2")
    ax1.set_xlabel("agents")
    ax1.set_ylabel("time [s]")
    ax1.legend(fontsize=7)
    ax1.grid(alpha=0.3)
    ax2.errorbar(sizes, e, yerr=es, marker="o", label="this simulator (1.5 kg quad)")
    ax2.errorbar([25], [THESIS_25["energy_mah"][0]], yerr=[THESIS_25["energy_mah"][1]], marker="*",
                 color="k", ms=10, ls="", label="thesis, table 4.2")
    ax2.set_xlabel("agents")
    ax2.set_ylabel("energy per agent [mAh]")
    ax2.set_ylim(bottom=0)
    ax2.legend(fontsize=7)
    ax2.grid(alpha=0.3)
    fig.suptitle("fig. 4.7: %g x %g m, no failures (%d runs)" % (area[0], area[1], len(runs)),
                 fontsize=9)
    fig.tight_layout()
    fig.savefig(os.path.join(png_dir, "fig4_7.png"))

    fig, ax = plt.subplots(figsize=(5, 3.2), dpi=80)
    bottom = [0.0] * len(sizes)
    for st in STATES[:-1]:  # Non-Leader is the rest, up to 100 %
        share = []
        for i, n in enumerate(sizes):
            tot = {k: 0.0 for k in STATES}
            for j in runs:
                if j["agents"] == n:
                    for k in STATES:
                        tot[k] += j["time_in_state_s"].get(k, 0.0)
            s = sum(tot.values())
            share.append(100.0 * tot[st] / s if s > 0 else 0.0)
        ax.bar([str(n) for n in sizes], share, bottom=bottom, label=st)
        bottom = [b + v for b, v in zip(bottom, share)]
    ax.set_xlabel("agents")
    ax.set_ylabel("share of time [%] (the rest: Non-Leader)")
    ax.legend(fontsize=6, loc="upper right")
    ax.set_title("fig. 4.9: time in each state (%g x %g m)" % area, fontsize=9)
    fig.tight_layout()
    fig.savefig(os.path.join(png_dir, "fig4_9.png"))
    print("wrote " + ", ".join(os.path.join(png_dir, f) for f in ("fig4_7.png", "fig4_9.png")))
    return 0


if __name__ == "__main__":
    sys.exit(main())
