#!/usr/bin/python3
"""What each uavsim-sweep runner adds per run (docs/results/sweeps.md), on daemons of its own (the cluster
test's: munged, slurmctld and slurmd on loopback, an sshd on 127.0.0.1), as root.

  sweep_bench.py UAVSIM_SWEEP overhead N      N runs of a stand-in launcher that returns at once: the job
                                              lines by hand (bash -c, one after the other), then each
                                              runner one run at a time (-j 1, %1); seconds per run each
  sweep_bench.py UAVSIM_SWEEP sweep N K       an MBZIRC 2017 sweep of N seeds (the build's launcher), K at
                                              a time, on SLURM then on the local runner: wall time, runs
                                              an hour, and whether the two tables are the same

Every figure comes from one invocation: compare them as ratios, the machine is shared.
"""

import os
import shutil
import subprocess
import sys
import tempfile
import time

sys.path.insert(0, os.path.join(os.path.dirname(os.path.realpath(__file__)), "..", "..", "tests", "tools"))
import sweep_cluster_test as ct  # noqa: E402  (the daemons, started as the cluster test starts them)

INSTANT = """#!/bin/bash
while [ $# -gt 0 ]; do case "$1" in --seed) seed=$2; shift;; --run-dir) dir=$2; shift;; esac; shift; done
printf '{"mission": "mbzirc2017", "seed": %s, "success": true, "mission_time_s": 1.0}\\n' "$seed" > "$dir/summary.json"
"""


def timed(f):
    t0 = time.monotonic()
    f()
    return time.monotonic() - t0


def sweep(*args, env=None):
    r = subprocess.run([sys.executable, ct.SWEEP] + [str(a) for a in args], capture_output=True, text=True, env=env)
    if r.returncode != 0:
        print(r.stdout + r.stderr)
    return r


def main():
    ct.SWEEP = os.path.abspath(sys.argv[1])
    what = sys.argv[2]
    ct.MODE = "slurm"
    t = ct.SweepOnDaemons("test_the_sweep_gives_the_local_runners_table_and_the_summaries_made_by_hand")
    t.setUp()
    try:
        env = t.start_slurm()
        logins = t.start_sshd()
        work = tempfile.mkdtemp(prefix="sweep_bench_", dir=t.tmp)
        if what == "overhead":
            n = int(sys.argv[3])
            bin_dir = os.path.join(work, "bin")
            os.makedirs(bin_dir)
            with open(os.path.join(bin_dir, "mbzirc2017-run"), "w") as f:
                f.write(INSTANT)
            os.chmod(os.path.join(bin_dir, "mbzirc2017-run"), 0o755)
            plan = ["--mission", "mbzirc2017", "--seeds", "1-%d" % n, "--launcher-dir", bin_dir]
            d = os.path.join(work, "by_hand")
            sweep("jobs", d, *plan)
            with open(os.path.join(d, "jobs.txt")) as f:
                lines = f.read().splitlines()
            rows = [("job lines by hand (bash -c, one after the other)",
                     timed(lambda: [subprocess.run(["bash", "-c", l], check=False) for l in lines]))]
            rows.append(("local (GNU parallel -j 1)", timed(lambda: sweep(
                "run", os.path.join(work, "local"), *plan, "-j", "1"))))
            rows.append(("ssh (GNU parallel --sshloginfile, one login, -j 1)", timed(lambda: sweep(
                "run", os.path.join(work, "ssh"), *plan, "--runner", "ssh", "--sshloginfile", logins, "-j", "1"))))
            rows.append(("slurm (one array, %1, sbatch --wait)", timed(lambda: sweep(
                "run", os.path.join(work, "slurm"), *plan, "--runner", "slurm", "--throttle", "1", "--wait", env=env))))
            print("%d runs of a launcher that returns at once" % n)
            print("| runner | wall [s] | per run [s] | overhead per run over by hand [s] |")
            print("|---|---|---|---|")
            base = rows[0][1] / n
            for name, s in rows:
                print("| %s | %.2f | %.3f | %.3f |" % (name, s, s / n, s / n - base))
        else:
            n, k = int(sys.argv[3]), int(sys.argv[4])
            plan = ["--mission", "mbzirc2017", "--seeds", "1-%d" % n, "--arg=--quiet"]
            rows = []
            for runner, extra in (("slurm", ["--throttle", str(k), "--wait"]), ("local", ["-j", str(k)])):
                d = os.path.join(work, runner)
                s = timed(lambda: sweep("run", d, *plan, "--runner", runner, *extra, env=env))
                st = sweep("status", d, env=env).stdout.splitlines()[0]
                sweep("collect", d, "--no-plots", env=env)
                rows.append((runner, s, st))
            same = all(open(os.path.join(work, "slurm", "collect", f)).read() ==
                       open(os.path.join(work, "local", "collect", f)).read() for f in ("sweep.csv", "sweep.md"))
            print("MBZIRC 2017, %d seeds, %d at a time" % (n, k))
            print("| runner | wall [s] | runs/hour | status |")
            print("|---|---|---|---|")
            for runner, s, st in rows:
                print("| %s | %.0f | %.0f | %s |" % (runner, s, 3600.0 * n / s, st))
            print("tables (sweep.csv, sweep.md) the same: %s" % ("yes" if same else "NO"))
            if not same:
                # The daemons' scratch directory goes with them: keep both tables to find which cell differs.
                kept = tempfile.mkdtemp(prefix="sweep_bench_differ_")
                for runner in ("slurm", "local"):
                    shutil.copytree(os.path.join(work, runner, "collect"), os.path.join(kept, runner))
                print("both tables kept in %s" % kept)
            with open(os.path.join(work, "slurm", "collect", "sweep.md")) as f:
                print(f.read())
    finally:
        t.doCleanups()


if __name__ == "__main__":
    main()
