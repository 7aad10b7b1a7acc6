#!/usr/bin/env bash
# Sweeps of the coverage flock in the simulator (not a ctest: minutes per run), the thesis's section
# 4.3 experiments: fig. 4.7 (mission time and energy against the number of agents, no failures) and
# tables 4.2/4.3 (failure probability against failed agents, mission time, energy and the extra
# distance flown to recover). A thin wrapper of uavsim-sweep (tools/sweep, docs/sweeps.md) that keeps
# this sweep's tables and plots. Three steps, so that any job runner can do the middle:
#   missions/coverage/sweep.sh jobs OUT_DIR [AREA] [SEEDS] > jobs.txt   # one coverage-run per line
#   parallel -j2 < jobs.txt      # or any job runner; or: uavsim-sweep resume OUT_DIR [--runner slurm ...]
#   missions/coverage/sweep.sh table OUT_DIR                           # the tables, beside the thesis's
#   missions/coverage/sweep.sh plot OUT_DIR [PNG_DIR]                  # fig. 4.7, 4.8 and 4.9 (matplotlib)
# AREA defaults to 600x600 (the thesis's), SEEDS to 3. Environment (space-separated lists):
#   SWEEP_AGENTS       flock sizes flown without failures (default "5 10 15 20 25")
#   SWEEP_FAIL_AGENTS  flock size of the failure runs (default 25; empty: no failure runs)
#   SWEEP_PROBS        failure probabilities (default table 4.3's, 0.0005 .. 0.009)
#   SWEEP_ARGS         more coverage-run options on every line, e.g. "--gcs --budget 2500" (the
#                      table keeps runs with a ground station apart: "600x600 gcs"; default budget 5000)
# Each run goes into OUT_DIR/runs/ID (its run directory with ground truth at 1 Hz, log, exit code).
# Extra distance: the distance flown by the flock beyond the failure-free run of the same seed and
# size (so SWEEP_AGENTS must hold SWEEP_FAIL_AGENTS), all agents' and the survivors' only; and the
# distance flown to recover (coverage-run's recovery_distance_m: the agents' flight photographing
# ground that only a failed agent had held) over the run's own distance, the thesis's measure; and
# the ground lost at the failures (share of the rectangle, all and per failed agent), its floor.
# COVERAGE_RUN overrides the launcher (default: build/missions/coverage/coverage-run).
set -euo pipefail
source "$(dirname "$0")/../common/sweep_lib.sh"
sweep_start 2,24 "${COVERAGE_RUN:-$root/build/missions/coverage/coverage-run}" "$@"
case "$cmd" in
  jobs)
    area=${3:-600x600}
    seeds=${4:-3}
    agents=${SWEEP_AGENTS-5 10 15 20 25}
    fail_agents=${SWEEP_FAIL_AGENTS-25}
    probs=${SWEEP_PROBS-0.0005 0.0007 0.0009 0.001 0.003 0.005 0.007 0.009}
    [[ "$area" =~ ^[0-9.]+x[0-9.]+$ && "$seeds" =~ ^[1-9][0-9]*$ ]] || sweep_usage
    for n in $agents $fail_agents; do [[ "$n" =~ ^[0-9]+$ ]] || sweep_usage; done
    for p in $probs; do [[ "$p" =~ ^0?\.[0-9]+$ ]] || sweep_usage; done
    # SWEEP_ARGS: its --budget is the sweep's; the rest goes to every run as it is
    budget=5000
    rest=()
    set -- ${SWEEP_ARGS-}
    while (($#)); do
      if [[ "$1" == --budget && $# -gt 1 ]]; then budget=$2; shift 2; continue; fi
      rest+=("$1")
      shift
    done
    extra=$(sweep_toml_args "${rest[@]}")
    [[ "$budget" =~ ^[0-9.]+$ ]] || sweep_usage
    list() { local out="" x; for x in "$@"; do out+="${out:+, }$x"; done; echo "[$out]"; }
    mkdir -p "$out"
    {
      echo "name = \"coverage $area, seeds 1-$seeds\""
      part() {
        printf '[[sweep]]\nmission = "coverage"\nseeds = "1-%s"\nbudget_s = %s\nargs = ["--quiet", "--truth-hz", "1"%s]\ngrid = { area = "%s", %s }\n' \
          "$seeds" "$budget" "$extra" "$area" "$1"
      }
      # the failure-free flocks, then the failure runs (one flock size, every probability)
      [[ -z "${agents// /}" ]] || part "agents = $(list $agents)"
      [[ -z "$fail_agents" ]] || part "agents = $fail_agents, failure_prob = $(list $probs)"
    } > "$out/sweep.toml"
    sweep_jobs "$out/sweep.toml"
    ;;
  table)
    python3 - "$out" "$root" <<'PY'
import glob, json, os, statistics, sys
out = sys.argv[1]
sys.path.insert(0, os.path.join(sys.argv[2], "missions", "coverage"))
from plot_sweep import overcoverage
# uavsim-sweep's run directories (and the JSON files of sweeps made before it)
runs = [json.load(open(p)) for p in sorted(glob.glob(os.path.join(out, "runs", "*", "summary.json")) +
                                          glob.glob(os.path.join(out, "*.json")))
        if os.path.basename(p) != "sweep.json"]  # not uavsim-sweep's plan
# the thesis's table 4.3: failure probability -> (failed agents, extra distance), both in %
THESIS_43 = {0.0005: (2.50, 0.0000), 0.0007: (3.75, 0.1493), 0.0009: (5.00, 0.2095),
             0.001: (3.75, 0.1924), 0.003: (12.16, 0.5015), 0.005: (10.94, 0.7475),
             0.007: (38.33, 0.6517), 0.009: (28.57, 1.3916)}
def mean_sd(xs):
    if not xs: return "-", "-"
    return "%.0f" % statistics.mean(xs), ("%.0f" % statistics.stdev(xs)) if len(xs) > 1 else "-"
ok = lambda j: j["success"]
area = lambda j: "%gx%g" % tuple(j["area_m"]) + (" gcs" if j.get("gcs") else "")
print("fig. 4.7: no failures (thesis: mission time and energy fall up to 25 agents, then flatten;")
print("its table 4.2 gives 719 +- 63 s and 479 +- 44 mAh for 25 agents over 600 x 600 m, 0-10 failed)")
print("| area | agents | runs ok | mission time [s] | sd | coverage complete [s] | energy per agent [mAh] | sd | speed [x real time] |")
print("|---|---|---|---|---|---|---|---|---|")
for a, n in sorted({(area(j), j["agents"]) for j in runs if j["failure_prob"] == 0}):
    rs = [j for j in runs if area(j) == a and j["agents"] == n and j["failure_prob"] == 0]
    good = [j for j in rs if ok(j)]
    t = mean_sd([j["mission_time_s"] for j in good])
    c = mean_sd([j["coverage_complete_s"] for j in good if j.get("coverage_complete_s", -1) >= 0])
    e = mean_sd([j["energy_mah_mean"] for j in good])
    speed = statistics.mean(j["sim_time_s"] / j["wall_time_s"] for j in rs) if rs else 0
    print("| %s | %d | %d/%d | %s | %s | %s | %s | %s | %.1f |" % (a, n, len(good), len(rs), *t, c[0], *e, speed))
print()
print("tables 4.2/4.3: with failures (extra distance against the seed's p = 0 run of the same size)")
print("| area | agents | failure p | runs ok | failed agents (thesis) | coverage held (mean) | mission time [s] | energy [mAh] | extra distance: all agents | survivors | distance flown to recover (thesis) | lost at the failures: all | per failed agent |")
print("|---|---|---|---|---|---|---|---|---|---|---|---|---|")
base = {(area(j), j["seed"], j["agents"]): j for j in runs if j["failure_prob"] == 0}
for a, n, p in sorted({(area(j), j["agents"], j["failure_prob"]) for j in runs if j["failure_prob"] > 0}):
    rs = [j for j in runs if area(j) == a and j["agents"] == n and j["failure_prob"] == p]
    good = [j for j in rs if ok(j)]
    failed = statistics.mean(j["failed"] / j["agents"] for j in rs)
    cov = statistics.mean(j["coverage"] for j in rs)
    extra = [j["distance_m_total"] / base[(a, j["seed"], n)]["distance_m_total"] - 1
             for j in rs if (a, j["seed"], n) in base]
    # the survivors' distance beyond what the same agents flew without failures (a dead agent's
    # unflown distance does not offset what the others fly again), over the failure-free total
    def survivors_extra(j, b):
        bd = {x["agent"]: x["distance_m"] for x in b["per_agent"]}
        more = sum(x["distance_m"] - bd[x["agent"]] for x in j["per_agent"] if not x["failed"])
        return more / b["distance_m_total"]
    extra_s = [survivors_extra(j, base[(a, j["seed"], n)]) for j in rs if (a, j["seed"], n) in base]
    # the share of the run's flight spent photographing lost ground (runs before the measure: none)
    recover = [j["recovery_distance_m"] / j["distance_m_total"] for j in rs
               if "recovery_distance_m" in j and j["distance_m_total"] > 0]
    # the ground that died with the failed agents (share of the rectangle): the recovery's floor
    lost = [j["lost_at_failures_fraction"] for j in rs if "lost_at_failures_fraction" in j]
    lost_each = [j["lost_at_failures_fraction"] / j["failed"] for j in rs
                 if "lost_at_failures_fraction" in j and j["failed"] > 0]
    t = mean_sd([j["mission_time_s"] for j in good])
    e = mean_sd([j["energy_mah_mean"] for j in good])
    th = THESIS_43.get(p)
    pct = lambda xs: ("%+.2f %%" % (100 * statistics.mean(xs))) if xs else "-"
    share = ("%.4f %%" % (100 * statistics.mean(recover))) if recover else "-"
    of_area = lambda xs: ("%.2f %%" % (100 * statistics.mean(xs))) if xs else "-"
    print("| %s | %d | %g | %d/%d | %.2f %% (%s) | %.2f %% | %s (sd %s) | %s (sd %s) | %s | %s | %s (%s) | %s | %s |" % (
        a, n, p, len(good), len(rs), 100 * failed, ("%.2f %%" % th[0]) if th else "-", 100 * cov, *t, *e,
        pct(extra), pct(extra_s), share, ("%.4f %%" % th[1]) if th else "-", of_area(lost), of_area(lost_each)))
print()
print("table 4.2: the runs with failures (p > 0) grouped by failed agents, as the thesis's (25 agents over")
print("600 x 600 m: 0-10 failed 719 +- 63 s, 479 +- 44 mAh; 10-30 failed 1360 +- 418 s, 913 +- 282 mAh);")
print("mission time and energy of the runs that held 100 % with every survivor landed")
print("| area | agents | failed agents | runs | runs ok | mission time [s] | sd | energy per agent [mAh] | sd |")
print("|---|---|---|---|---|---|---|---|---|")
for a, n in sorted({(area(j), j["agents"]) for j in runs if j["failure_prob"] > 0}):
    for lo, hi in ((0, 10), (11, 30)):
        rs = [j for j in runs if (area(j), j["agents"]) == (a, n) and j["failure_prob"] > 0
              and lo <= j["failed"] <= hi]
        if not rs:
            continue
        good = [j for j in rs if ok(j)]
        print("| %s | %d | %d-%d | %d | %d | %s | %s | %s | %s |" % (
            a, n, lo, hi, len(rs), len(good), *mean_sd([j["mission_time_s"] for j in good]),
            *mean_sd([j["energy_mah_mean"] for j in good])))
print()
print("fig. 4.8: overcoverage, the share of the rectangle the pictures of k agents cover (every agent's")
print("last APD, the dead ones' included; the thesis plots its distribution and calls it negligible)")
print("(neighbours' footprints overlap by design: D_R1 is 25 % under Y_sensor, and passes by the 20 % margin,")
print("so the failure-free flock already covers much twice; the last column is what failures add to it)")
print("| area | agents | failure p | runs | not covered | 1 agent | 2 agents | 3 agents | 4+ agents | covered again: sum of (k-1) x share | beyond the failure-free runs |")
print("|---|---|---|---|---|---|---|---|---|---|---|")
again = lambda m: sum((k - 1) * m[k] for k in range(2, 5))
dist = {}
for key in sorted({(area(j), j["agents"], j["failure_prob"]) for j in runs if "apd_reports" in j}):
    ds = [overcoverage(j) for j in runs if (area(j), j["agents"], j["failure_prob"]) == key]
    dist[key] = (len(ds), [statistics.mean(d[k] for d in ds) for k in range(5)])
for (a, n, p), (count, m) in dist.items():
    b = dist.get((a, n, 0.0))
    extra = ("%+.2f %%" % (100 * (again(m) - again(b[1])))) if b and p > 0 else "-"
    print("| %s | %d | %g | %d | %s | %.2f %% | %s |" % (a, n, p, count, " | ".join("%.2f %%" % (100 * v) for v in m), 100 * again(m), extra))
PY
    ;;
  plot)
    # Debian's python3-matplotlib belongs to Debian's python3 (another python3 may come first in PATH)
    py=/usr/bin/python3
    [[ -x "$py" ]] || py=python3
    "$py" "$root/missions/coverage/plot_sweep.py" "$out" "${3:-$out}"
    ;;
  *) sweep_usage ;;
esac
