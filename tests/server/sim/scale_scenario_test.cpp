// The scale world (models/worlds/grid1000.xml): 1000 lean quads start parked on the ground; 100 of
// them take off and hover while the rest stay parked. Half a minute of wall time: labelled
// scenario.
#include <gtest/gtest.h>

#include "grid_flight.hpp"

namespace uavsim::server::sim {
namespace {

TEST(Scale, AThousandQuadsStartOnTheGroundAndAHundredOfThemTakeOff) {
  testing::fly_some_of_a_grid(std::string(UAVSIM_MODELS_DIR) + "/worlds/grid1000.xml", 1000, 100);
}

}  // namespace
}  // namespace uavsim::server::sim
