// LAND at any moment of a take-off, and a new take-off at any moment of a LAND, end on the ground
// with no crash (the soak bench's churn does both, pipelined, on every vehicle; a crash there is a
// vehicle lost for the rest of the run). Every 0.25 s of the climb, every 0.5 s of the descent.
#include <gtest/gtest.h>

#include "sim_fixture.hpp"

namespace uavsim::server::sim::testing {
namespace {

std::string crashes(Simulation& sim) {
  std::string s;
  for (const Event& e : sim.events().recent()) {
    if (e.type == EventType::kCrash) s += std::to_string(e.time_s) + " " + e.detail + "; ";
  }
  return s;
}

TEST(LandAfterTakeoff, LandAtAnyMomentOfTheClimbCrashesNothing) {
  for (double d = 0.0; d <= 4.0; d += 0.25) {
    auto sim = make_sim("empty.xml");
    wait_ready(*sim);
    sim->post(0, [&](fc::FlightController& f) {
      f.set_mode(fc::Mode::kGuided);
      f.arm(false);
      f.takeoff(3.0);
    });
    const double t_land = sim->time_s() + d;
    while (sim->time_s() < t_land) sim->step();
    sim->post(0, [&](fc::FlightController& f) { f.land(); });
    const double end = sim->time_s() + 30.0;
    double max_z = 0;
    while (sim->time_s() < end && (sim->fc(0).armed() || sim->time_s() < t_land + 1.0)) {
      sim->step();
      max_z = std::max(max_z, sim->truth(0).position_enu_m.z());
    }
    EXPECT_EQ(crashes(*sim), "") << "LAND " << d << " s after take-off, max z " << max_z;
    EXPECT_FALSE(sim->fc(0).armed()) << d;
  }
}

TEST(LandAfterTakeoff, TakeoffAgainWhileLandingThenLand) {
  for (double d = 0.5; d <= 8.0; d += 0.5) {
    auto sim = make_sim("empty.xml");
    take_off(*sim, 3.0);
    sim->post(0, [&](fc::FlightController& f) { f.land(); });
    const double t2 = sim->time_s() + d;
    while (sim->time_s() < t2) sim->step();
    const double z_at = sim->truth(0).position_enu_m.z();
    sim->post(0, [&](fc::FlightController& f) {
      f.set_mode(fc::Mode::kGuided);
      f.arm(false);
      f.takeoff(3.0);
    });
    for (int k = 0; k < 2; ++k) sim->step();
    sim->post(0, [&](fc::FlightController& f) { f.land(); });
    const double end = sim->time_s() + 30.0;
    while (sim->time_s() < end && sim->fc(0).armed()) sim->step();
    EXPECT_EQ(crashes(*sim), "") << "re-take-off " << d << " s into LAND at z " << z_at;
  }
}

}  // namespace
}  // namespace uavsim::server::sim::testing
