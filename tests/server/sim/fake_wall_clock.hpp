// A wall clock for tests: it only moves when the code under test sleeps on it or the test advances
// it.
#pragma once

#include "sim/runner.hpp"

namespace uavsim::server::sim::testing {

class FakeWallClock : public WallClock {
 public:
  double now_s() override { return now_s_; }
  void sleep_until_s(double t_s) override {
    if (t_s > now_s_) now_s_ = t_s;
  }
  void advance(double dt_s) { now_s_ += dt_s; }

 private:
  double now_s_ = 100.0;
};

}  // namespace uavsim::server::sim::testing
