// RecordFile and replace_file_atomically: what a process killed with SIGKILL leaves behind. The
// writers run in a forked child that kills itself at a point the test chooses, so every case is
// deterministic; a full disk is in tests/missions/common (it needs a mount).
#include "uavsim/common/record_file.hpp"

#include <gtest/gtest.h>
#include <signal.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <fstream>
#include <iterator>
#include <sstream>
#include <string>
#include <vector>

namespace uavsim::common {
namespace {

std::string read_all(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

// runs body in a child process that then kills itself with SIGKILL; true when it died that way
template <class Body>
bool run_then_sigkill(Body body) {
  const pid_t pid = fork();
  if (pid == 0) {
    body();
    raise(SIGKILL);
    _exit(0);  // not reached
  }
  int status = 0;
  waitpid(pid, &status, 0);
  return WIFSIGNALED(status) && WTERMSIG(status) == SIGKILL;
}

TEST(RecordFile, AProcessKilledAfterItsLastRecordLeavesEveryRecordWhole) {
  // 300 short lines (an event log's size: far below any stdio buffer, which would have kept them
  // all in memory and lost them with the process)
  constexpr int kLines = 300;
  const std::string path = ::testing::TempDir() + "record_file_kill.jsonl";
  ASSERT_TRUE(run_then_sigkill([&] {
    RecordFile f;
    if (!f.open(path, nullptr)) _exit(1);
    for (int i = 0; i < kLines; ++i) f.write("{\"n\":" + std::to_string(i) + "}\n");
  }));
  const std::string text = read_all(path);
  ASSERT_FALSE(text.empty());
  EXPECT_EQ(text.back(), '\n');
  std::istringstream in(text);
  int n = 0;
  for (std::string line; std::getline(in, line); ++n) {
    ASSERT_EQ(line, "{\"n\":" + std::to_string(n) + "}") << "line " << n;
  }
  EXPECT_EQ(n, kLines);
}

// A full disk mid-record: a child process whose file size limit (RLIMIT_FSIZE, SIGXFSZ ignored so
// a write past it fails with EFBIG as on a full disk) lets the third 40-byte record in only in
// part. The file keeps the two whole records, the failure names the file, later writes are refused.
TEST(RecordFile, ADiskFullMidRecordLeavesTheWholeRecordsBeforeIt) {
  constexpr int kRecordBytes = 40;
  const std::string path = ::testing::TempDir() + "record_file_full.csv";
  const std::string record = std::string(kRecordBytes - 1, 'r') + "\n";
  const pid_t pid = fork();
  ASSERT_GE(pid, 0);
  if (pid == 0) {
    signal(SIGXFSZ, SIG_IGN);
    const rlimit limit{100, 100};  // two records and half of the third
    if (setrlimit(RLIMIT_FSIZE, &limit) != 0) _exit(1);
    RecordFile f;
    if (!f.open(path, nullptr)) _exit(2);
    if (!f.write(record) || !f.write(record)) _exit(3);
    if (f.write(record)) _exit(4);  // past the limit
    if (f.error().find(path + ": File too large") == std::string::npos) _exit(5);
    if (f.write("x\n")) _exit(6);  // refused from now on
    _exit(0);
  }
  int status = 0;
  waitpid(pid, &status, 0);
  ASSERT_TRUE(WIFEXITED(status)) << status;
  EXPECT_EQ(WEXITSTATUS(status), 0) << "the child's check that failed";
  EXPECT_EQ(read_all(path), record + record);
}

TEST(RecordFile, WritesFailWithTheReasonWhenNotOpen) {
  RecordFile f;
  EXPECT_FALSE(f.write("x\n"));
  std::string why;
  EXPECT_FALSE(f.open("/proc/self/nonexistent/dir/file", &why));
  EXPECT_NE(why.find("cannot write /proc/self/nonexistent/dir/file"), std::string::npos) << why;
}

TEST(ReplaceFileAtomically, AKillAtAnyMomentLeavesTheOldOrANewFileWhole) {
  // each version is 256 KiB of one letter: a torn or mixed file would hold two letters or be short
  constexpr std::size_t kBytes = 256 * 1024;
  const std::string path = ::testing::TempDir() + "atomic_summary.json";
  ASSERT_TRUE(replace_file_atomically(path, std::string(kBytes, 'a'), nullptr));
  // the child is killed by the test while it rewrites the file over and over: whenever that is,
  // the file is one whole version
  int ready[2];
  ASSERT_EQ(pipe(ready), 0);
  const pid_t pid = fork();
  if (pid == 0) {
    close(ready[0]);
    for (int k = 0;; ++k) {
      if (!replace_file_atomically(path, std::string(kBytes, static_cast<char>('b' + k % 20)),
                                   nullptr))
        _exit(1);
      if (k == 0) (void)!write(ready[1], "r", 1);  // one rewrite done: the kill may come
    }
  }
  close(ready[1]);
  char c = 0;
  ASSERT_EQ(read(ready[0], &c, 1), 1);
  close(ready[0]);
  kill(pid, SIGKILL);
  int status = 0;
  waitpid(pid, &status, 0);
  ASSERT_TRUE(WIFSIGNALED(status));
  const std::string text = read_all(path);
  ASSERT_EQ(text.size(), kBytes);
  EXPECT_EQ(text.find_first_not_of(text[0]), std::string::npos);
  EXPECT_NE(text[0], 'a');  // the child's first rewrite had landed before the kill
  std::remove((path + ".tmp-" + std::to_string(pid)).c_str());  // the temporary a kill may leave
}

TEST(ReplaceFileAtomically, ADirectoryThatIsAFileIsAnErrorWithTheReason) {
  const std::string file = ::testing::TempDir() + "atomic_not_a_dir";
  std::ofstream(file) << "x";
  std::string why;
  EXPECT_FALSE(replace_file_atomically(file + "/summary.json", "{}", &why));
  EXPECT_NE(why.find("Not a directory"), std::string::npos) << why;
}

}  // namespace
}  // namespace uavsim::common
