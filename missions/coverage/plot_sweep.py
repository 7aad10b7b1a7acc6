#!/usr/bin/env python3
"""Plots of a coverage sweep (missions/coverage/sweep.sh plot OUT_DIR [PNG_DIR]).

fig4_7.png: mission time (take-off to last landing, the thesis's measure) and the time to coverage
(the leader's query that found the rectangle covered) against the number of agents, and the energy
per agent, from the failure-free runs; the thesis's 25-agent figures of table 4.2 (0-10 failed
agents) beside them. fig4_9.png: the share of time in each state of fig. 4.6 but Non-Leader (the
rest; Going Home, Landed and Failed left out, as in the thesis). One area per figure: the first (largest) one found.
"""
import glob
import json
import os
import statistics
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

STATES = ["Taking Off", "Querying", "Deploying", "Running", "Waiting", "Non-Leader"]
THESIS_25 = {"time_s": (719, 63), "energy_mah": (479, 44)}  # table 4.2, 0-10 failed agents


def main():
    if len(sys.argv) < 2:
        print(__doc__)
        return 2
    out = sys.argv[1]
    png_dir = sys.argv[2] if len(sys.argv) > 2 else out
    runs = [json.load(open(p)) for p in sorted(glob.glob(os.path.join(out, "*.json")))]
    runs = [j for j in runs if j["failure_prob"] == 0 and j["success"]]
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

    os.makedirs(png_dir, exist_ok=True)
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
