#include "server/http/error_status.hpp"

#include <gtest/gtest.h>

namespace tinsmith::server {
namespace {

TEST(ErrorStatus, InputAndUsageAreClientErrors) {
  EXPECT_EQ(httpStatusFor(ErrorKind::Input), 400);
  EXPECT_EQ(httpStatusFor(ErrorKind::Usage), 400);
  EXPECT_EQ(httpStatusFor(ErrorKind::NotImplemented), 501);
  EXPECT_EQ(httpStatusFor(ErrorKind::Internal), 500);
  EXPECT_EQ(httpStatusFor(ErrorKind::Io), 500);
}

TEST(ErrorStatus, BodyIsJsonWithStatusKindAndMessage) {
  EXPECT_EQ(errorBodyJson(400, ErrorKind::Input, "x=\"abc\" is not a number"),
            R"({"error":{"kind":"input error","message":"x=\"abc\" is not a number","status":400}})");
}

}  // namespace
}  // namespace tinsmith::server
