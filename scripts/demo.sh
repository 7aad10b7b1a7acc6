#!/usr/bin/env bash
# The README's main job: build, start the server on the default world and fly the demo flight
# (take-off, three waypoints, landing), printing progress and a RESULT line.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
"$root/scripts/build.sh"
exec "$root/build/server/uavsim-server" "$root/models/worlds/empty.xml" --demo --rate "${UAVSIM_RATE:-0}" "$@"
