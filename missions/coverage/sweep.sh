#!/usr/bin/env bash
# Sweeps of the coverage flock in the simulator (not a ctest: minutes per run), the thesis's section
# 4.3 experiments: fig. 4.7 (mission time and energy against the number of agents, no failures) and
# tables 4.2/4.3 (failure probability against failed agents, mission time, energy and the extra
# distance flown to recover). Two steps, so that any job runner can do the middle:
#   missions/coverage/sweep.sh jobs OUT_DIR [AREA] [SEEDS] > jobs.txt   # one coverage-run per line
#   parallel -j2 < jobs.txt                                            # GNU parallel (or: bash jobs.txt)
#   missions/coverage/sweep.sh table OUT_DIR                           # the tables
# AREA defaults to 600x600 (the thesis's), SEEDS to 3. Agents: 5 10 15 20 25 without failures;
# failure probabilities 0.0005 .. 0.009 (table 4.3) with 25 agents. Extra distance: the distance
# flown by the flock beyond the failure-free run of the same seed and size.
# COVERAGE_RUN overrides the launcher (default: build/missions/coverage/coverage-run).
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
run=${COVERAGE_RUN:-$root/build/missions/coverage/coverage-run}
cmd=${1:-}
out=${2:-}
[[ -n "$cmd" && -n "$out" ]] || { sed -n 2,13p "$0"; exit 2; }
case "$cmd" in
  jobs)
    area=${3:-600x600}
    seeds=${4:-3}
    [[ "$area" =~ ^[0-9.]+x[0-9.]+$ && "$seeds" =~ ^[0-9]+$ ]] || { sed -n 2,13p "$0"; exit 2; }
    mkdir -p "$out"
    for ((s = 1; s <= seeds; s++)); do
      for n in 5 10 15 20 25; do
        echo "$run --no-run-dir --no-record --agents $n --area $area --seed $s --quiet --budget 5000 --json $out/n${n}_p0_seed$s.json > $out/n${n}_p0_seed$s.log 2>&1"
      done
      for p in 0.0005 0.0007 0.0009 0.001 0.003 0.005 0.007 0.009; do
        echo "$run --no-run-dir --no-record --agents 25 --area $area --seed $s --failure-prob $p --quiet --budget 5000 --json $out/n25_p${p}_seed$s.json > $out/n25_p${p}_seed$s.log 2>&1"
      done
    done
    ;;
  table)
    python3 - "$out" <<'PY'
import glob, json, os, statistics, sys
out = sys.argv[1]
runs = [json.load(open(p)) for p in sorted(glob.glob(os.path.join(out, "*.json")))]
def mean_sd(xs):
    if not xs: return "-", "-"
    return "%.0f" % statistics.mean(xs), ("%.0f" % statistics.stdev(xs)) if len(xs) > 1 else "-"
ok = lambda j: j["success"]
print("fig. 4.7: no failures")
print("| agents | runs ok | mission time [s] mean | sd | energy per agent [mAh] mean | sd | speed [x real time] |")
print("|---|---|---|---|---|---|---|")
for n in sorted({j["agents"] for j in runs if j["failure_prob"] == 0}):
    rs = [j for j in runs if j["agents"] == n and j["failure_prob"] == 0]
    good = [j for j in rs if ok(j)]
    t = mean_sd([j["mission_time_s"] for j in good])
    e = mean_sd([j["energy_mah_mean"] for j in good])
    speed = statistics.mean(j["sim_time_s"] / j["wall_time_s"] for j in rs) if rs else 0
    print("| %d | %d/%d | %s | %s | %s | %s | %.1f |" % (n, len(good), len(rs), *t, *e, speed))
print()
print("tables 4.2/4.3: 25 agents with failures (extra distance against the seed's p = 0 run)")
print("| failure p | runs ok | failed agents | coverage held (mean) | mission time [s] | energy [mAh] | extra distance |")
print("|---|---|---|---|---|---|---|")
base = {(j["seed"], j["agents"]): j for j in runs if j["failure_prob"] == 0}
for p in sorted({j["failure_prob"] for j in runs if j["failure_prob"] > 0}):
    rs = [j for j in runs if j["failure_prob"] == p and j["agents"] == 25]
    good = [j for j in rs if ok(j)]
    failed = statistics.mean(j["failed"] / j["agents"] for j in rs) if rs else 0
    cov = statistics.mean(j["coverage"] for j in rs) if rs else 0
    extra = [j["distance_m_total"] / base[(j["seed"], 25)]["distance_m_total"] - 1
             for j in rs if (j["seed"], 25) in base]
    t = mean_sd([j["mission_time_s"] for j in good])
    e = mean_sd([j["energy_mah_mean"] for j in good])
    print("| %g | %d/%d | %.2f %% | %.2f %% | %s (sd %s) | %s (sd %s) | %s |" % (
        p, len(good), len(rs), 100 * failed, 100 * cov, *t, *e,
        ("%.2f %%" % (100 * statistics.mean(extra))) if extra else "-"))
PY
    ;;
  *) sed -n 2,13p "$0"; exit 2 ;;
esac
