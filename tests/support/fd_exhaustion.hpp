// Running out of file descriptors on purpose, for tests of what a listener does then.
#pragma once

#include <dirent.h>
#include <fcntl.h>
#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdlib>
#include <vector>

namespace uavsim::testing {

// While alive, the process has no free file descriptor: the soft RLIMIT_NOFILE is lowered to just above
// the highest open descriptor and every free number below it is taken. The destructor gives them back and
// restores the limit. Affects every thread of the process; descriptors opened before it stay usable.
class FdExhaustion {
 public:
  FdExhaustion() {
    getrlimit(RLIMIT_NOFILE, &saved_);
    const int source = open("/dev/null", O_RDONLY | O_CLOEXEC);
    // the highest open descriptor, from /proc/self/fd (its own descriptor is a hole filled below)
    int highest = source;
    if (DIR* dir = opendir("/proc/self/fd")) {
      while (const dirent* e = readdir(dir)) highest = std::max(highest, std::atoi(e->d_name));
      closedir(dir);
    }
    rlimit low = saved_;
    low.rlim_cur = static_cast<rlim_t>(highest) + 1;
    setrlimit(RLIMIT_NOFILE, &low);
    // fill the holes below the limit (bounded: at most one descriptor per number)
    for (int k = 0; k <= highest; ++k) {
      const int fd = fcntl(source, F_DUPFD_CLOEXEC, 0);
      if (fd < 0) break;
      held_.push_back(fd);
    }
    held_.push_back(source);
  }
  ~FdExhaustion() {
    for (int fd : held_) close(fd);
    setrlimit(RLIMIT_NOFILE, &saved_);
  }
  FdExhaustion(const FdExhaustion&) = delete;
  FdExhaustion& operator=(const FdExhaustion&) = delete;

  // True if opening a descriptor now fails with EMFILE.
  bool exhausted() const {
    const int fd = open("/dev/null", O_RDONLY | O_CLOEXEC);
    if (fd >= 0) {
      close(fd);
      return false;
    }
    return errno == EMFILE;
  }

 private:
  rlimit saved_{};
  std::vector<int> held_;
};

}  // namespace uavsim::testing
