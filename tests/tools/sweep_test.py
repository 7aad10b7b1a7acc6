#!/usr/bin/python3
"""uavsim-sweep's plan, status, resume and collect (label unit): the plan's run ids, refusals of bad
sweeps before anything is written or submitted, and the local runner (GNU parallel) on a stand-in
launcher, a few lines of shell that write a summary the way the launchers do, so these tests take
seconds. The real launchers under the local and SLURM runners: sweep_cluster_test.py (label cluster).

usage: sweep_test.py PATH/TO/uavsim-sweep
"""

import json
import os
import shutil
import subprocess
import sys
import tempfile
import unittest

SWEEP = None

# stands in for mbzirc2017-run: a summary into --run-dir from the seed (odd seeds succeed and exit 0,
# even ones fall short and exit 1); seed 13 is a harness failure (exit 4, no summary)
FAKE_LAUNCHER = r"""#!/bin/bash
seed=; dir=; speed=15
while [ $# -gt 0 ]; do
  case "$1" in --seed) seed=$2; shift;; --run-dir) dir=$2; shift;; --truck-speed-kmh) speed=$2; shift;; esac
  shift
done
echo "stand-in launcher: seed $seed"
if [ "$seed" = 13 ]; then echo "made to fail: the server did not start" >&2; exit 4; fi
ok=false; [ $((seed % 2)) = 1 ] && ok=true
printf '{"mission": "mbzirc2017", "seed": %s, "truck_speed_kmh": %s, "success": %s, "mission_time_s": %s.25, "wall_time_s": 0.1}\n' \
  "$seed" "$speed" "$ok" "$((100 + seed))" > "$dir/summary.json"
$ok && exit 0 || exit 1
"""


def sweep(*args, cwd=None):
    """(exit status, stdout, stderr) of uavsim-sweep ARGS."""
    r = subprocess.run([sys.executable, SWEEP] + [str(a) for a in args], capture_output=True, text=True,
                       cwd=cwd)
    return r.returncode, r.stdout, r.stderr


class Plan(unittest.TestCase):
    def setUp(self):
        self.dir = tempfile.mkdtemp(prefix="sweep_test_")

    def tearDown(self):
        shutil.rmtree(self.dir)

    def write(self, name, text):
        path = os.path.join(self.dir, name)
        with open(path, "w") as f:
            f.write(text)
        return path

    def plan(self, *args):
        rc, out, err = sweep("plan", "--json", *args)
        self.assertEqual(rc, 0, err)
        return json.loads(out)["runs"]

    def test_the_same_plan_gives_the_same_run_ids(self):
        a = self.write("a.toml", 'mission = "mbzirc2017"\nseeds = "1-3"\nbudget_s = 60\n'
                                 '[grid]\ntruck_speed_kmh = [10, 15]\nrealism = ["field"]\n')
        # the same sweep spelt otherwise: keys in another order, 10.0 for 10, the seeds as a list
        b = self.write("b.toml", 'budget_s = 60.0\nseeds = [1, 2, 3]\nmission = "mbzirc2017"\n'
                                 '[grid]\nrealism = "field"\ntruck_speed_kmh = [10.0, 15]\n')
        ra, rb = self.plan(a), self.plan(b)
        self.assertEqual(len(ra), 6)
        self.assertEqual([r["id"] for r in ra], [r["id"] for r in rb])
        self.assertEqual(len({r["id"] for r in ra}), 6)
        # flags give the same plan as the file
        rf = self.plan("--mission", "mbzirc2017", "--seeds", "1-3", "--budget", "60",
                       "--grid", "truck_speed_kmh=10,15", "--grid", "realism=field")
        self.assertEqual([r["id"] for r in ra], [r["id"] for r in rf])
        # another budget is another run
        rc = self.plan("--mission", "mbzirc2017", "--seeds", "1-3", "--budget", "61",
                       "--grid", "truck_speed_kmh=10,15", "--grid", "realism=field")
        self.assertFalse({r["id"] for r in ra} & {r["id"] for r in rc})
        # every run's options: its seed, the budget and its grid point
        first = ra[0]
        self.assertEqual(first["argv"][:4], ["--seed", "1", "--budget", "60.0"])
        self.assertIn("--truck-speed-kmh", first["argv"])
        self.assertIn("--no-record", first["argv"])

    def assert_refused(self, args, words, results=None):
        rc, out, err = sweep(*args)
        self.assertEqual(rc, 2, out + err)
        for w in words:
            self.assertIn(w, err)
        if results is not None:
            self.assertFalse(os.path.exists(results), "a refused plan wrote " + results)

    def test_an_unknown_mission_is_refused_before_anything_is_written(self):
        results = os.path.join(self.dir, "results")
        self.assert_refused(["run", "--mission", "mbzirc2019", results, "--runner", "slurm"],
                            ["unknown mission 'mbzirc2019'", "coverage, mbzirc2017, mbzirc2020"], results)
        f = self.write("s.toml", '[[sweep]]\nmission = "coverage"\n[[sweep]]\nmission = "balloons"\n')
        self.assert_refused(["run", f, results], ["sweep 2", "unknown mission 'balloons'"], results)
        # a runner that cannot run is refused as early
        self.assert_refused(["run", "--mission", "coverage", results, "--runner", "ssh"],
                            ["needs --sshloginfile"], results)
        self.assert_refused(["run", "--mission", "coverage", results, "-j", "0"], ["--jobs 0"], results)

    def test_a_bad_grid_is_refused_with_the_reason(self):
        results = os.path.join(self.dir, "results")
        cases = [
            ('mission = "coverage"\n[grid]\nspeed = [1]\n', ["coverage has no parameter 'speed'", "agents"]),
            ('mission = "coverage"\n[grid]\nagents = [5, 65]\n', ["agents = 65", "out of range [1, 64]"]),
            ('mission = "coverage"\n[grid]\nagents = [2.5]\n', ["agents = 2.5", "an integer"]),
            ('mission = "coverage"\n[grid]\nagents = []\n', ["agents: no values"]),
            ('mission = "coverage"\n[grid]\narea = ["150 by 100"]\n', ["WxH"]),
            ('mission = "coverage"\n[grid]\nfailure_prob = [0.1, 0.1]\n', ["listed twice"]),
            ('mission = "mbzirc2017"\n[grid]\nrealism = ["foggy"]\n', ["one of field, ideal"]),
            ('mission = "mbzirc2017"\n[grid]\ntruck_speed_kmh = ["fast"]\n', ["a number"]),
            ('mission = "mbzirc2020"\n[grid]\nkill = ["uav2"]\n', ["uav0, uav1"]),
            ('mission = "mbzirc2017"\nseeds = "5-1"\n', ["FIRST-LAST"]),
            ('mission = "mbzirc2017"\nseeds = [-1]\n', ["seed -1"]),
            ('mission = "mbzirc2017"\nbudget_s = 0\n', ["budget_s 0"]),
            ('mission = "mbzirc2017"\nargs = ["--seed", "3"]\n', ["--seed is set by the sweep"]),
            ('mission = "mbzirc2017"\nseed = 3\n', ["unknown key 'seed'"]),
            ('mission = "mbzirc2017"\nseeds = [1\n', ["s.toml"]),
        ]
        for text, words in cases:
            with self.subTest(sweep=text):
                self.assert_refused(["run", self.write("s.toml", text), results], words, results)


class Runs(unittest.TestCase):
    """The local runner on the stand-in launcher."""

    def setUp(self):
        if shutil.which("parallel") is None:
            raise unittest.SkipTest("GNU parallel is not installed (scripts/install_deps.sh)")
        self.dir = tempfile.mkdtemp(prefix="sweep_test_")
        self.launchers = os.path.join(self.dir, "bin")
        os.makedirs(self.launchers)
        fake = os.path.join(self.launchers, "mbzirc2017-run")
        with open(fake, "w") as f:
            f.write(FAKE_LAUNCHER)
        os.chmod(fake, 0o755)
        self.results = os.path.join(self.dir, "results")

    def tearDown(self):
        shutil.rmtree(self.dir)

    def run_sweep(self, seeds):
        rc, out, err = sweep("run", "--mission", "mbzirc2017", "--seeds", seeds, "--grid",
                             "truck_speed_kmh=10,15", self.results, "--launcher-dir", self.launchers, "-j", "2")
        self.assertEqual(rc, 0, out + err)
        with open(os.path.join(self.results, "sweep.json")) as f:
            return json.load(f)["runs"]

    def started(self, run):
        with open(os.path.join(self.results, "runs", run["id"], "started")) as f:
            return f.read()

    def test_resume_after_a_run_dir_is_deleted_reruns_only_that_run(self):
        runs = self.run_sweep("1-3")
        self.assertEqual(len(runs), 6)
        before = {r["id"]: self.started(r) for r in runs}
        rc, out, _ = sweep("status", self.results)
        self.assertEqual(rc, 0, out)
        self.assertIn("6/6: done 6, running 0, failed 0, left 0", out)
        gone = runs[4]
        shutil.rmtree(os.path.join(self.results, "runs", gone["id"]))
        rc, out, _ = sweep("status", self.results)
        self.assertIn("done 5, running 0, failed 0, left 1", out)
        rc, out, err = sweep("resume", self.results)
        self.assertEqual(rc, 0, out + err)
        self.assertIn("1 run(s)", out)
        for r in runs:
            if r["id"] == gone["id"]:
                self.assertNotEqual(self.started(r), before[r["id"]])
            else:
                self.assertEqual(self.started(r), before[r["id"]], r["id"] + " ran again")
        rc, out, err = sweep("resume", self.results)
        self.assertIn("nothing to run", out)

    def test_a_failed_run_is_reported_with_its_log_and_resume_reruns_only_it(self):
        runs = self.run_sweep("12-13")
        failed = [r for r in runs if r["seed"] == 13]
        rc, out, _ = sweep("status", self.results)
        self.assertEqual(rc, 1, out)
        self.assertIn("done 2, running 0, failed 2, left 0", out)
        for r in failed:
            self.assertIn("failed: %s (exit 4) log: %s" % (r["id"], os.path.join(
                self.results, "runs", r["id"], "launcher.log")), out)
        self.assertIn("made to fail: the server did not start", out)
        before = {r["id"]: self.started(r) for r in runs}
        rc, out, err = sweep("resume", self.results)
        self.assertIn("2 run(s)", out)
        for r in runs:
            self.assertEqual(self.started(r) != before[r["id"]], r["seed"] == 13, r["id"])

    def test_collect_makes_one_row_per_run_and_the_same_table_every_time(self):
        runs = self.run_sweep("1-2")
        rc, out, err = sweep("collect", self.results, "--no-plots")
        self.assertEqual(rc, 0, out + err)
        with open(os.path.join(self.results, "collect", "sweep.csv")) as f:
            rows = f.read().splitlines()
        self.assertEqual(len(rows), 1 + len(runs))
        self.assertTrue(rows[0].startswith("run,mission,seed,truck_speed_kmh,budget_s,state,exit,success"))
        with open(os.path.join(self.results, "collect", "sweep.md")) as f:
            md = f.read()
        # seed 1 succeeded (101.25 s), seed 2 fell short: one success in each group of two
        self.assertIn("| mbzirc2017 | 10 | 2 | 2 | 1 | 101.2 | - |", md)
        # the wall time is not in the table: it differs from run to run and runner to runner
        self.assertNotIn("wall", md)
        # the same plan into the same directory is the same sweep: nothing runs again
        rc, out, err = sweep("run", "--mission", "mbzirc2017", "--seeds", "1-2", "--grid",
                             "truck_speed_kmh=10,15", self.results, "--launcher-dir", self.launchers)
        self.assertIn("nothing to run", out)
        # another plan is refused there
        rc, out, err = sweep("run", "--mission", "mbzirc2017", "--seeds", "1-3", self.results,
                             "--launcher-dir", self.launchers)
        self.assertEqual(rc, 2)
        self.assertIn("holds another sweep", err)


if __name__ == "__main__":
    SWEEP = os.path.abspath(sys.argv.pop(1))
    unittest.main(verbosity=2)
