#!/usr/bin/env bash
# The README's main job: build, then run the MBZIRC 2020 balloon mission (seed 7.2) on
# models/worlds/mbzirc2020.xml: uavsim-server (recording a video), the ground station and two UAV programs
# under lockstep at full speed, printing progress and a summary with a RESULT line (exit 0 on 5/5 balloons
# and no crash). Extra arguments go to mbzirc2020-run (--seed N, --kill uav1, --no-record, --help).
# The earlier scripted flight is still there: build/server/uavsim-server models/worlds/empty.xml --demo
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
"$root/scripts/build.sh"
exec "$root/build/missions/mbzirc2020/mbzirc2020-run" --record "$root/build/mbzirc2020.mp4" "$@"
