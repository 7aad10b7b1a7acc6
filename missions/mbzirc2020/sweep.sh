#!/usr/bin/env bash
# Seed sweep of the balloon mission (not a ctest: minutes per seed). Two steps, so that any job runner can
# do the middle:
#   missions/mbzirc2020/sweep.sh jobs OUT_DIR [FIRST_SEED] [COUNT] [REALISM] > jobs.txt   # one mbzirc2020-run per line
#     (REALISM: field|ideal, given to every run as --realism; default the world's)
#   parallel -j2 < jobs.txt                                                     # GNU parallel (or: bash jobs.txt)
#   missions/mbzirc2020/sweep.sh table OUT_DIR                                  # the table, beside seed table 7.1
# Each seed runs twice: both UAVs, and uav1 killed right after take-off (Competition Day 2).
# MBZIRC2020_RUN overrides the launcher (default: build/missions/mbzirc2020/mbzirc2020-run); MBZIRC2020_ARGS
# adds options to every run (e.g. --wind 6,270).
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
run=${MBZIRC2020_RUN:-$root/build/missions/mbzirc2020/mbzirc2020-run}
cmd=${1:-}
out=${2:-}
[[ -n "$cmd" && -n "$out" ]] || { sed -n 2,9p "$0"; exit 2; }
case "$cmd" in
  jobs)
    first=${3:-1}
    realism=${5:+--realism $5}
    count=${4:-10}
    mkdir -p "$out"
    for ((s = first; s < first + count; s++)); do
      echo "$run --no-run-dir --no-record --seed $s --budget 400 --quiet $realism ${MBZIRC2020_ARGS:-} --json $out/two_seed$s.json > $out/two_seed$s.log 2>&1"
      echo "$run --no-run-dir --no-record --seed $s --budget 400 --quiet $realism ${MBZIRC2020_ARGS:-} --kill uav1 --json $out/one_seed$s.json > $out/one_seed$s.log 2>&1"
    done
    ;;
  table)
    python3 - "$out" <<'PY'
import glob, json, os, sys
out = sys.argv[1]
def load(kind):
    rows = {}
    for p in glob.glob(os.path.join(out, kind + "_seed*.json")):
        j = json.load(open(p))
        rows[j["seed"]] = j
    return rows
two, one = load("two"), load("one")
print("| seed | two UAVs: popped | time [s] | wall [s] | one UAV (uav1 killed): popped | time [s] | wall [s] |")
print("|---|---|---|---|---|---|---|")
def cell(j):
    if j is None: return "-", "-", "-"
    t = "%.1f" % j["mission_time_s"] if j["mission_time_s"] >= 0 else "n/a"
    bad = "" if j["success"] else " (FAIL%s)" % (": crash" if j["crashes"] else "")
    return "%d/%d%s" % (j["popped"], j["total"], bad), t, "%.0f" % j["wall_time_s"]
for s in sorted(set(two) | set(one)):
    a, b = cell(two.get(s)), cell(one.get(s))
    print("| %d | %s | %s | %s | %s | %s | %s |" % (s, *a, *b))
def stats(rows):
    ok = [j for j in rows.values() if j["success"]]
    ts = sorted(j["mission_time_s"] for j in ok)
    if not ts: return "no success"
    med = ts[len(ts)//2] if len(ts) % 2 else 0.5 * (ts[len(ts)//2 - 1] + ts[len(ts)//2])
    crashed = sum(1 for j in rows.values() if j["crashes"])
    return "%d/%d runs 5/5 with no crash (%.0f %%); time min %.1f, median %.1f, max %.1f s; %d run(s) with a crash" % (
        len(ok), len(rows), 100.0 * len(ok) / len(rows), ts[0], med, ts[-1], crashed)
print()
print("two UAVs: " + stats(two) + "   (seed table 7.1: 126 s and 162 s, 5/5)")
print("one UAV:  " + stats(one) + "   (seed table 7.1: 262 s and 306 s, 5/5)")
PY
    ;;
  *) sed -n 2,9p "$0"; exit 2 ;;
esac
