// Chaos: Ctrl-C (SIGINT) or a scheduler's SIGTERM reaching a running mission launcher
// (mbzirc2017-run, mbzirc2020-run, coverage-run). The signal is sent once the run's ground truth
// has passed a few seconds of sim time (read back from the run directory, no sleeps). The
// launcher must then end the run in order: exit code 130, no process of the run left, the event log
// readable, and a complete summary that says it was interrupted and names the signal as its cause.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "../support/run_process.hpp"

namespace {

using Json = nlohmann::json;
namespace fs = std::filesystem;
using uavsim::tests::events_of;
using uavsim::tests::expect_no_orphan;
using uavsim::tests::last_truth_time_s;
using uavsim::tests::Proc;
using uavsim::tests::read_whole_file;
using uavsim::tests::RunProcess;

constexpr double kSignalAt_s = 2.0;  // sim seconds of ground truth before the signal
constexpr int kExitInterrupted = 130;

std::string run_dir(const std::string& name) {
  const std::string dir =
      ::testing::TempDir() + "interrupt-" + name + "-" + std::to_string(getpid());
  fs::remove_all(dir);
  return dir;
}

// runs args (the launcher and its options, "--run-dir DIR" added), sends sig once truth_uav0.csv
// has passed kSignalAt_s and checks the run ended in order
void expect_interrupt_stops_the_run_in_order(const std::string& name, std::vector<std::string> args,
                                             int sig, const std::string& sig_name) {
  const std::string dir = run_dir(name);
  args.insert(args.end(), {"--run-dir", dir});
  RunProcess run(args);
  ASSERT_TRUE(run.until([&] { return last_truth_time_s(dir + "/truth_uav0.csv") >= kSignalAt_s; }))
      << run.output();
  const std::vector<Proc> snapshot = run.tree();
  ASSERT_GE(snapshot.size(), 2u) << run.output();  // the server and at least one program
  ASSERT_EQ(kill(run.pid(), sig), 0);
  ASSERT_TRUE(run.until_exit()) << run.output();

  EXPECT_TRUE(WIFEXITED(run.status()) && WEXITSTATUS(run.status()) == kExitInterrupted)
      << "status " << run.status() << "\n"
      << run.output();
  EXPECT_NE(run.output().find("interrupted by " + sig_name), std::string::npos) << run.output();
  const size_t result = run.output().find("RESULT: FAILURE");
  ASSERT_NE(result, std::string::npos) << run.output();
  EXPECT_NE(run.output().find("(interrupted)", result), std::string::npos) << run.output();
  expect_no_orphan(snapshot, dir);

  // the server closed its event log: every line whole
  EXPECT_TRUE(fs::exists(dir + "/events.jsonl"));
  events_of(dir);

  const Json s = Json::parse(read_whole_file(dir + "/summary.json"), nullptr, false);
  ASSERT_TRUE(s.is_object()) << read_whole_file(dir + "/summary.json");
  EXPECT_TRUE(s.value("complete", false)) << s.dump();
  EXPECT_TRUE(s.value("interrupted", false)) << s.dump();
  EXPECT_FALSE(s.value("success", true)) << s.dump();
  EXPECT_NE(s.value("cause", Json()).dump().find("the launcher was interrupted by " + sig_name),
            std::string::npos)
      << s.dump();
  EXPECT_GE(s.value("sim_time_s", -1.0), kSignalAt_s) << s.dump();
  ASSERT_TRUE(s.contains("programs")) << s.dump();
  for (const Json& p : s["programs"]) {
    EXPECT_FALSE(p.contains("running")) << p.dump();
    EXPECT_TRUE(p.value("stopped_by_launcher", false)) << p.dump();
  }
  if (!::testing::Test::HasFailure()) fs::remove_all(dir);
}

TEST(Interrupt, Mbzirc2017RunStopsInOrderOnSigint) {
  expect_interrupt_stops_the_run_in_order(
      "mbzirc2017", {MBZIRC2017_RUN, "--seed", "1", "--no-record", "--wall-limit", "280"}, SIGINT,
      "SIGINT");
}

// a scheduler's stop (SLURM's, a timeout's) is SIGTERM
TEST(Interrupt, Mbzirc2020RunStopsInOrderOnSigterm) {
  expect_interrupt_stops_the_run_in_order(
      "mbzirc2020", {MBZIRC2020_RUN, "--seed", "1", "--no-record", "--wall-limit", "280"}, SIGTERM,
      "SIGTERM");
}

TEST(Interrupt, CoverageRunStopsInOrderOnSigint) {
  expect_interrupt_stops_the_run_in_order("coverage",
                                          {COVERAGE_RUN, "--agents", "3", "--area", "60x40",
                                           "--seed", "29", "--no-record", "--wall-limit", "280"},
                                          SIGINT, "SIGINT");
}

}  // namespace
