#!/usr/bin/env bash
# Seed sweep of the MBZIRC 2017 landing (not a ctest: 20 seeds take about a minute, two at a time), a thin
# wrapper of uavsim-sweep (tools/sweep, docs/sweeps.md) that keeps this sweep's table:
#   missions/mbzirc2017/sweep.sh jobs OUT_DIR [FIRST_SEED] [COUNT] [REALISM] > jobs.txt   # one run per line
#     (REALISM: field|ideal, given to every run as --realism; default the world's)
#   parallel -j2 < jobs.txt               # or any job runner; or: uavsim-sweep resume OUT_DIR [--runner slurm ...]
#   missions/mbzirc2017/sweep.sh table OUT_DIR                                  # the table, beside the seed's result
# Each seed runs at 15 km/h from t = 0, each into OUT_DIR/runs/ID (its run directory, log and exit code).
# MBZIRC2017_RUN overrides the launcher (default: build/missions/mbzirc2017/mbzirc2017-run); MBZIRC2017_ARGS
# adds options to every run.
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
run=${MBZIRC2017_RUN:-$root/build/missions/mbzirc2017/mbzirc2017-run}
cmd=${1:-}
out=${2:-}
[[ -n "$cmd" && -n "$out" ]] || { sed -n 2,11p "$0"; exit 2; }
case "$cmd" in
  jobs)
    first=${3:-1}
    count=${4:-20}
    [[ "$first" =~ ^[0-9]+$ && "$count" =~ ^[1-9][0-9]*$ ]] || { sed -n 2,11p "$0"; exit 2; }
    args=(--mission mbzirc2017 --seeds "$first-$((first + count - 1))" --budget 300 --arg=--quiet)
    [[ -z "${5:-}" ]] || args+=(--grid "realism=$5")
    for a in ${MBZIRC2017_ARGS:-}; do args+=("--arg=$a"); done
    /usr/bin/python3 "$root/tools/sweep/uavsim-sweep" jobs "${args[@]}" --launcher-dir "$(dirname "$run")" "$out"
    ;;
  table)
    python3 - "$out" <<'PY'
import glob, json, os, sys
out = sys.argv[1]
rows = {}
# uavsim-sweep's run directories (and the JSON files of sweeps made before it)
for p in glob.glob(os.path.join(out, "runs", "*", "summary.json")) + glob.glob(os.path.join(out, "seed*.json")):
    j = json.load(open(p))
    rows[j["seed"]] = j
print("| seed | landed on the deck | take-off to touchdown [s] | relative speed [m/s] | from the marker centre [m] | crash | wall [s] |")
print("|---|---|---|---|---|---|---|")
for s in sorted(rows):
    j = rows[s]
    landed = "yes" if j["success"] else ("landed, fell off" if j["landed"] else "no")
    t = "%.1f" % j["mission_time_s"] if j["mission_time_s"] >= 0 else "-"
    v = "%.2f" % j["relative_speed_m_s"] if j["landed"] else "-"
    d = "%.2f" % j["marker_distance_m"] if j["landed"] else "-"
    print("| %d | %s | %s | %s | %s | %s | %.0f |" % (s, landed, t, v, d, "yes" if j["crashes"] else "no", j["wall_time_s"]))
ok = [j for j in rows.values() if j["success"]]
ts = sorted(j["mission_time_s"] for j in ok)
crashed = sum(1 for j in rows.values() if j["crashes"])
print()
if ts:
    med = ts[len(ts)//2] if len(ts) % 2 else 0.5 * (ts[len(ts)//2 - 1] + ts[len(ts)//2])
    print("%d/%d landed on the deck (%.0f %%); take-off to touchdown min %.1f, median %.1f, max %.1f s; %d crash(es)"
          % (len(ok), len(rows), 100.0 * len(ok) / len(rows), ts[0], med, ts[-1], crashed))
else:
    print("no landing in %d runs; %d crash(es)" % (len(rows), crashed))
print("the thesis's competition run (section 7.1): one landing, 140 s")
PY
    ;;
  *) sed -n 2,11p "$0"; exit 2 ;;
esac
