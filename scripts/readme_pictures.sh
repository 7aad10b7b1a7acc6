#!/usr/bin/env bash
# Makes the README's mission pictures (docs/images/) from real runs of the built launchers, so that they
# show what a user's run shows today:
#   mbzirc2020_follow.jpg   mbzirc2020-run --seed 1: the follow camera with the overlay and the onboard
#                           views, just after the last pop
#   mbzirc2017_follow.jpg   mbzirc2017-run --seed 1: the follow camera, 1 s after the touchdown
#   mbzirc2017_vision.png   the same run's UAV video log: its last sighting of the marker before it
#   coverage_trajectories.png  coverage-run (5 agents, 150 x 100 m, seed 1): plot_run.py's tracks
# usage: scripts/readme_pictures.sh [OUT_DIR]   (default docs/images; after scripts/build.sh; about 10-15 min
#        on 2 cores)
# env UAVSIM_BUILD_DIR: another build directory
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
build="${UAVSIM_BUILD_DIR:-$root/build}"
out="${1:-$root/docs/images}"
mkdir -p "$out"
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT

json() { python3 -c 'import json, sys; print(json.load(open(sys.argv[1]))[sys.argv[2]])' "$1" "$2"; }
# one frame of a video at a time of sim time (the recorder's frames are at k / fps of sim time from 0)
still() { ffmpeg -loglevel error -y -ss "$2" -i "$1" -frames:v 1 -vf scale=640:-2 -q:v 5 "$3"; }

echo "readme_pictures: MBZIRC 2020, seed 1 (recorded)"
"$build/missions/mbzirc2020/mbzirc2020-run" --seed 1 --run-dir "$tmp/2020" --json "$tmp/2020.json" >"$tmp/2020.log"
still "$tmp/2020/video.mp4" "$(python3 -c "print($(json "$tmp/2020.json" last_pop_time_s) + 0.5)")" \
  "$out/mbzirc2020_follow.jpg"

echo "readme_pictures: MBZIRC 2017, seed 1 (recorded)"
"$build/missions/mbzirc2017/mbzirc2017-run" --seed 1 --run-dir "$tmp/2017" --json "$tmp/2017.json" >"$tmp/2017.log"
touchdown=$(json "$tmp/2017.json" touchdown_time_s)
still "$tmp/2017/video.mp4" "$(python3 -c "print($touchdown + 1.0)")" "$out/mbzirc2017_follow.jpg"
# the video log's last frame with the marker taken by the filter before the touchdown
"$build/vision/uavsim-videolog-export" "$tmp/2017/uav0_vision.vlog" --png "$tmp/vlog" >/dev/null
index=$("$build/vision/uavsim-videolog-export" "$tmp/2017/uav0_vision.vlog" --info |
  python3 -c "
import re, sys
last = 0
for line in sys.stdin:
    m = re.match(r'\s*(\d+)\s+t=([0-9.]+) s.*accepted', line)
    if m and float(m.group(2)) < $touchdown:
        last = int(m.group(1))
print(last)")
cp "$(printf '%s/frame_%06d.png' "$tmp/vlog" "$index")" "$out/mbzirc2017_vision.png"

echo "readme_pictures: coverage, 5 agents over 150 x 100 m, seed 1 (plotted)"
"$build/missions/coverage/coverage-run" --agents 5 --area 150x100 --seed 1 --no-record --run-dir "$tmp/coverage" \
  >"$tmp/coverage.log"
"$root/scripts/plot_run.py" "$tmp/coverage" >/dev/null
cp "$tmp/coverage/trajectories.png" "$out/coverage_trajectories.png"
ls -la "$out"
