#include "render/gl_context.hpp"

#include <gtest/gtest.h>

#include <stdexcept>
#include <string>

namespace uavsim::server::render {
namespace {

TEST(GlContext, DefaultBackendIsOsmesa) {
  auto gl = make_gl_context("");
  EXPECT_EQ(gl->name(), "osmesa");
  EXPECT_TRUE(gl->make_current());
  EXPECT_TRUE(gl->make_current());  // already current: still fine
  gl->release();
}

TEST(GlContext, UnknownBackendNamesItselfAndTheKnownOnes) {
  try {
    make_gl_context("vulkan");
    FAIL() << "expected std::invalid_argument";
  } catch (const std::invalid_argument& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("'vulkan'"), std::string::npos) << what;
    EXPECT_NE(what.find("osmesa"), std::string::npos) << what;
  }
}

}  // namespace
}  // namespace uavsim::server::render
