#!/usr/bin/env bash
# Seed sweep of the balloon mission (not a ctest: minutes per seed), a thin wrapper of uavsim-sweep
# (tools/sweep, docs/sweeps.md) that keeps this sweep's table:
#   missions/mbzirc2020/sweep.sh jobs OUT_DIR [FIRST_SEED] [COUNT] [REALISM] > jobs.txt   # one run per line
#     (REALISM: field|ideal, given to every run as --realism; default the world's)
#   parallel -j2 < jobs.txt               # or any job runner; or: uavsim-sweep resume OUT_DIR [--runner slurm ...]
#   missions/mbzirc2020/sweep.sh table OUT_DIR                                  # the table, beside seed table 7.1
# Each seed runs twice: both UAVs, and uav1 killed right after take-off (Competition Day 2), each into
# OUT_DIR/runs/ID (its run directory, log and exit code). MBZIRC2020_RUN overrides the launcher (default:
# build/missions/mbzirc2020/mbzirc2020-run); MBZIRC2020_ARGS adds options to every run (e.g. --wind 6,270).
set -euo pipefail
source "$(dirname "$0")/../common/sweep_lib.sh"
sweep_start 2,11 "${MBZIRC2020_RUN:-$root/build/missions/mbzirc2020/mbzirc2020-run}" "$@"
case "$cmd" in
  jobs)
    sweep_seeds "${3:-1}" "${4:-10}"
    [[ -z "${5:-}" || "$5" =~ ^(field|ideal)$ ]] || sweep_usage
    seeds="[$(seq -s, "$first" $((first + count - 1)))]"
    realism=${5:+realism = \"$5\"}
    extra=$(sweep_toml_args ${MBZIRC2020_ARGS:-})
    mkdir -p "$out"
    # two sweeps in one: both UAVs, and uav1 killed after its take-off
    {
      echo "name = \"mbzirc2020 seeds $first-$((first + count - 1))\""
      for kill in "" 'kill = "uav1"'; do
        grid="$kill${kill:+${realism:+, }}$realism"
        printf '[[sweep]]\nmission = "mbzirc2020"\nseeds = %s\nbudget_s = 400\nargs = ["--quiet"%s]\ngrid = { %s }\n' \
          "$seeds" "$extra" "$grid"
      done
    } > "$out/sweep.toml"
    sweep_jobs "$out/sweep.toml"
    ;;
  table)
    python3 - "$out" <<'PY'
import glob, json, os, sys
out = sys.argv[1]
def load(kind):
    # uavsim-sweep's run directories (uav1 killed: "one"), and the JSON files of sweeps made before it
    rows = {}
    for p in glob.glob(os.path.join(out, "runs", "*", "summary.json")):
        j = json.load(open(p))
        if ("one" if j["killed"] else "two") == kind:
            rows[j["seed"]] = j
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
  *) sweep_usage ;;
esac
