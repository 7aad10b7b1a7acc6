// What a whole MBZIRC 2020 run with both UAVs must show, from the launcher's summary
// (mission_run_test.cpp, mission_ns3_test.cpp): all five balloons popped within the budget, no
// collision, no crash.
#pragma once

#include <gtest/gtest.h>

#include <nlohmann/json.hpp>
#include <string>

namespace uavsim::tests {

inline void expect_all_five_popped(const nlohmann::json& r, const std::string& out,
                                   double budget_s) {
  EXPECT_EQ(r["total"].get<int>(), 5) << out;
  EXPECT_EQ(r["popped"].get<int>(), 5) << out;
  EXPECT_FALSE(r["collision"].get<bool>()) << out;
  EXPECT_TRUE(r["crashes"].empty()) << out;
  EXPECT_GT(r["mission_time_s"].get<double>(), 0.0) << out;
  EXPECT_LT(r["mission_time_s"].get<double>(), budget_s) << out;
  EXPECT_TRUE(r["success"].get<bool>()) << out;
}

}  // namespace uavsim::tests
