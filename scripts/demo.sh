#!/usr/bin/env bash
# The README's main job: build, then run the MBZIRC 2020 balloon mission (seed 7.2) on
# models/worlds/mbzirc2020.xml: uavsim-server (recording a video), the ground station and two UAV programs
# under lockstep at full speed, printing progress and a summary with a RESULT line (exit 0 on 5/5 balloons
# and no crash). The run directory (video.mp4, summary.json, events, tlogs, ground truth) is
# runs/mbzirc2020-seedN-TIME under the repository; the summary's "video:" and "run directory:" lines say
# where. Extra arguments go to mbzirc2020-run (--seed N, --kill uav1, --no-record, --run-dir DIR, --help).
# The earlier scripted flight is still there: build/server/uavsim-server models/worlds/empty.xml --demo
# Builds only the programs the demo runs (the server, the launcher, the ground station and UAV programs);
# ./scripts/test.sh builds the rest (tests, benches) and installs what only the tests use.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
UAVSIM_BUILD_TARGETS="mbzirc2020-run mbzirc2020-uav mbzirc2020-gcs uavsim-server" "$root/scripts/build.sh"
cd "$root"
exec "$root/build/missions/mbzirc2020/mbzirc2020-run" "$@"
