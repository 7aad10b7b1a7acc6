// --api-token-file: with a token, a connection is served only once it has sent it (an auth op or a token
// field); gcs_link_open is held to the client's own address unless allowed.
#include <gtest/gtest.h>

#include "api_fixture.hpp"

namespace uavsim::server::api::testing {
namespace {

TEST(ApiAuth, NothingIsServedBeforeTheToken) {
  ApiConfig config;
  config.token = "s3cret";
  TestServer server("empty.xml", config);
  TestClient c(server.port());
  EXPECT_EQ(c.hello().value("auth_required", false), true);
  EXPECT_EQ(error_code(c.request({{"op", "status"}, {"id", 1}})), "unauthorized");
  EXPECT_EQ(error_code(c.request({{"op", "auth"}, {"token", "guess"}})), "unauthorized");
  EXPECT_EQ(error_code(c.request({{"op", "auth"}, {"token", "s3cre"}})), "unauthorized");
  const Json ok = c.request({{"op", "auth"}, {"token", "s3cret"}});
  ASSERT_EQ(ok.value("ok", false), true) << ok.dump();
  EXPECT_EQ(ok["result"].value("authenticated", false), true);
  EXPECT_EQ(c.request({{"op", "status"}}).value("ok", false), true);
  // another connection: a token field on its first request serves it
  TestClient d(server.port());
  EXPECT_EQ(d.request({{"op", "status"}, {"token", "s3cret"}}).value("ok", false), true);
  EXPECT_EQ(d.request({{"op", "status"}}).value("ok", false), true);
}

TEST(ApiAuth, WithoutATokenEverythingIsServed) {
  TestServer server("empty.xml");
  TestClient c(server.port());
  EXPECT_FALSE(c.hello().contains("auth_required"));
  EXPECT_EQ(c.request({{"op", "status"}}).value("ok", false), true);
  EXPECT_EQ(c.request({{"op", "auth"}, {"token", "x"}})["result"].value("authenticated", true), false);
}

}  // namespace
}  // namespace uavsim::server::api::testing
