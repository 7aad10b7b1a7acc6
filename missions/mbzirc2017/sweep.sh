#!/usr/bin/env bash
# Seed sweep of the MBZIRC 2017 landing (not a ctest: 20 seeds take about a minute, two at a time), a thin
# wrapper of uavsim-sweep (tools/sweep, docs/sweeps.md) that keeps this sweep's table:
#   missions/mbzirc2017/sweep.sh jobs OUT_DIR [FIRST_SEED] [COUNT] [REALISM] [SPACE] > jobs.txt   # one run per line
#     (REALISM: field|ideal, given to every run as --realism; default the world's. SPACE: fixed, the default,
#     or sampled: each seed draws its start on the eight, its speed (5-20 km/h) and two camera blackouts;
#     MBZIRC2017_ARGS=--phase slow puts a sampled sweep in the 5 km/h phase)
#   parallel -j2 < jobs.txt               # or any job runner; or: uavsim-sweep resume OUT_DIR [--runner slurm ...]
#   missions/mbzirc2017/sweep.sh table OUT_DIR                                  # the table, beside the seed's result
# Fixed: each seed runs at 15 km/h from t = 0. Each run goes into OUT_DIR/runs/ID (its run directory, log and exit code).
# MBZIRC2017_RUN overrides the launcher (default: build/missions/mbzirc2017/mbzirc2017-run); MBZIRC2017_ARGS
# adds options to every run.
set -euo pipefail
source "$(dirname "$0")/../common/sweep_lib.sh"
sweep_start 2,13 "${MBZIRC2017_RUN:-$root/build/missions/mbzirc2017/mbzirc2017-run}" "$@"
case "$cmd" in
  jobs)
    sweep_seeds "${3:-1}" "${4:-20}"
    space=${6:-fixed}
    [[ "$space" == fixed || "$space" == sampled ]] || { echo "SPACE: fixed or sampled" >&2; exit 2; }
    args=(--mission mbzirc2017 --seeds "$first-$((first + count - 1))" --budget 300 --arg=--quiet)
    [[ -z "${5:-}" ]] || args+=(--grid "realism=$5")
    if [[ "$space" == sampled ]]; then
      for a in --start-phase random --truck-speed-kmh random --random-blackouts 2; do args+=("--arg=$a"); done
    fi
    for a in ${MBZIRC2017_ARGS:-}; do args+=("--arg=$a"); done
    sweep_jobs "${args[@]}"
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

def med(v):
    v = sorted(v)
    if not v:
        return None
    return v[len(v)//2] if len(v) % 2 else 0.5 * (v[len(v)//2 - 1] + v[len(v)//2])

def f(v, fmt="%.2f"):
    return "-" if v is None else fmt % v

def part(j):  # where on the eight: the touchdown's part, else where the approach began
    return j.get("eight_part_at_touchdown") or j.get("eight_part_at_approach") or "none"

def cab_contact(j):
    return any("truck/cab" in c for c in j["crashes"])

def truck_contact(j):  # any part of the truck but the deck from above (the launcher's count)
    return j.get("truck_contacts", 0) > 0 or cab_contact(j)

print("| seed | speed [km/h] | start [s] | part of the eight | landed on the deck | take-off to touchdown [s] | relative speed [m/s] | from the marker centre [m] | cab clearance min [m] | skids to deck edge min [m] | climb-aways | crash | wall [s] |")
print("|---|---|---|---|---|---|---|---|---|---|---|---|---|")
for s in sorted(rows):
    j = rows[s]
    landed = "yes" if j["success"] else ("landed, fell off" if j["landed"] else "no")
    t = "%.1f" % j["mission_time_s"] if j["mission_time_s"] >= 0 else "-"
    v = "%.2f" % j["relative_speed_m_s"] if j["landed"] else "-"
    d = "%.2f" % j["marker_distance_m"] if j["landed"] else "-"
    crash = "; ".join(j["crashes"]) if j["crashes"] else "no"
    print("| %d | %.1f | %.1f | %s | %s | %s | %s | %s | %s | %s | %s | %s | %.0f |" % (
        s, j.get("truck_speed_kmh", 15.0), j.get("start_time_s", 0.0), part(j), landed, t, v, d,
        f(j.get("min_cab_clearance_m")), f(j.get("min_deck_edge_margin_m")), j.get("climb_aways", "-"),
        crash, j["wall_time_s"]))

def summary(label, js):
    ok = [j for j in js if j["success"]]
    ts = [j["mission_time_s"] for j in ok]
    cab = [j["min_cab_clearance_m"] for j in js if j.get("min_cab_clearance_m") is not None]
    edge = [j["min_deck_edge_margin_m"] for j in ok if j.get("min_deck_edge_margin_m") is not None]
    return "| %s | %d | %d (%.0f %%) | %d | %d | %d | %s | %s | %s |" % (
        label, len(js), len(ok), 100.0 * len(ok) / len(js) if js else 0.0,
        sum(1 for j in js if truck_contact(j)), sum(1 for j in js if cab_contact(j)),
        sum(1 for j in js if j["crashes"]),
        f(med(ts), "%.1f"), f(min(cab) if cab else None), f(min(edge) if edge else None))

print()
print("| runs | n | landed and stayed | truck contacts | cab contacts | crashes | median take-off to touchdown [s] | cab clearance min [m] | skids to deck edge min [m] |")
print("|---|---|---|---|---|---|---|---|---|")
allj = list(rows.values())
print(summary("all", allj))
for lo, hi in [(5, 8.75), (8.75, 12.5), (12.5, 16.25), (16.25, 20.01)]:
    js = [j for j in allj if lo <= j.get("truck_speed_kmh", 15.0) < hi]
    if js:
        print(summary("%.2f-%.2f km/h" % (lo, min(hi, 20)), js))
for p in ["straight", "curve", "crossing", "none"]:
    js = [j for j in allj if part(j) == p]
    if js:
        print(summary("on the " + p if p != "none" else "no approach", js))
cab = sorted(j["min_cab_clearance_m"] for j in allj if j.get("min_cab_clearance_m") is not None)
if cab:
    q = lambda x: cab[min(len(cab) - 1, int(x * len(cab)))]
    print()
    print("cab clearance over %d runs: min %.2f, 5 %% %.2f, median %.2f m" % (len(cab), cab[0], q(0.05), q(0.5)))
ok = [j for j in allj if j["success"]]
ts = sorted(j["mission_time_s"] for j in ok)
print()
if ts:
    print("%d/%d landed on the deck (%.0f %%); take-off to touchdown min %.1f, median %.1f, max %.1f s; %d crash(es), %d truck contact(s), %d with the cab"
          % (len(ok), len(rows), 100.0 * len(ok) / len(rows), ts[0], med(ts), ts[-1],
             sum(1 for j in allj if j["crashes"]), sum(1 for j in allj if truck_contact(j)),
             sum(1 for j in allj if cab_contact(j))))
else:
    print("no landing in %d runs; %d crash(es)" % (len(rows), sum(1 for j in allj if j["crashes"])))
print("the thesis's competition run (section 7.1): one landing, 140 s")
PY
    ;;
  *) sweep_usage ;;
esac
