# Sourced by the missions' sweep.sh (mbzirc2017, mbzirc2020, coverage): the start they share and
# their call of uavsim-sweep (tools/sweep, docs/sweeps.md). Each script keeps its own command line,
# job grid and table.

# sweep_start USAGE_LINES LAUNCHER "$@": sets root (the source tree), run (the mission launcher,
# LAUNCHER), cmd and out (the first two arguments); no command or no OUT_DIR is a usage error.
# USAGE_LINES: the lines of the script's header comment that are its usage (sed -n's range).
sweep_start() {
  sweep_usage_lines=$1
  run=$2
  cmd=${3:-}
  out=${4:-}
  [[ -n "$cmd" && -n "$out" ]] || sweep_usage
}

# The script's usage on stdout, then exit 2.
sweep_usage() {
  sed -n "${sweep_usage_lines}p" "$0"
  exit 2
}

# sweep_seeds FIRST COUNT: sets first and count; a usage error unless FIRST is a whole number and
# COUNT a positive one.
sweep_seeds() {
  first=$1
  count=$2
  [[ "$first" =~ ^[0-9]+$ && "$count" =~ ^[1-9][0-9]*$ ]] || sweep_usage
}

# sweep_toml_args WORD...: the words as TOML strings, each after ", " (quotes and backslashes
# dropped), for a sweep file's args list.
sweep_toml_args() {
  local s="" a
  for a in "$@"; do s+=", \"${a//[\"\\]/}\""; done
  printf '%s' "$s"
}

# sweep_jobs ARG...: uavsim-sweep's job list for the plan ARG... (a sweep file, or --mission and
# its options) into OUT_DIR, each job running the launcher's directory's programs.
sweep_jobs() {
  /usr/bin/python3 "$root/tools/sweep/uavsim-sweep" jobs "$@" --launcher-dir "$(dirname "$run")" "$out"
}

root=$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)
