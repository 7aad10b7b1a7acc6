// The wind op (docs/protocol.md "Wind"): query, set at run time, a gust on demand, bad values
// refused.
#include <gtest/gtest.h>

#include <cmath>

#include "api_fixture.hpp"

namespace uavsim::server::api::testing {
namespace {

constexpr double kWindTol_m_s = 1e-9;
constexpr double kGustTol_m_s = 0.01;

TEST(WindOp, QuerySetAndGust) {
  TestServer server("mbzirc2020.xml", paused());
  TestClient c(server.port());
  // the ideal world: calm
  Json r = c.request({{"op", "wind"}});
  ASSERT_TRUE(r["ok"]) << r;
  EXPECT_EQ(r["result"]["speed_m_s"], 0.0);
  EXPECT_EQ(r["result"]["realism"], "ideal");
  EXPECT_EQ(c.request({{"op", "status"}})["result"]["realism"], "ideal");
  // 6 m/s from the north: the air moves towards -y
  r = c.request({{"op", "wind"}, {"speed_m_s", 6.0}, {"from_deg", 0.0}});
  ASSERT_TRUE(r["ok"]) << r;
  EXPECT_NEAR(r["result"]["velocity_enu_m_s"][1].get<double>(), -6.0, kWindTol_m_s);
  // a 4 m/s gust for 2 s: at its peak after 1 s
  ASSERT_TRUE(c.request({{"op", "wind"}, {"gust_m_s", 4.0}, {"gust_duration_s", 2.0}})["ok"]);
  ASSERT_TRUE(c.request({{"op", "step"}, {"duration_s", 1.0}})["ok"]);
  r = c.request({{"op", "wind"}});
  EXPECT_NEAR(r["result"]["gust_m_s"].get<double>(), 4.0, kGustTol_m_s);
  EXPECT_NEAR(r["result"]["velocity_enu_m_s"][1].get<double>(), -10.0, kGustTol_m_s);
}

TEST(WindOp, RefusesValuesOutOfRange) {
  TestServer server("mbzirc2020.xml", paused());
  TestClient c(server.port());
  EXPECT_EQ(error_code(c.request({{"op", "wind"}, {"speed_m_s", -1.0}})), "bad_field");
  EXPECT_EQ(error_code(c.request({{"op", "wind"}, {"speed_m_s", 1e9}})), "bad_field");
  EXPECT_EQ(error_code(c.request({{"op", "wind"}, {"from_deg", 1000.0}})), "bad_field");
  EXPECT_EQ(error_code(c.request({{"op", "wind"}, {"gust_m_s", 5.0}, {"gust_duration_s", 0.0}})),
            "bad_field");
  EXPECT_EQ(error_code(c.request({{"op", "wind"}, {"speed_m_s", "fast"}})), "bad_field");
  // nothing half-applied
  EXPECT_EQ(c.request({{"op", "wind"}})["result"]["speed_m_s"], 0.0);
}

}  // namespace
}  // namespace uavsim::server::api::testing
