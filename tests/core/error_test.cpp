#include "core/base/error.hpp"

#include <gtest/gtest.h>

namespace tinsmith {
namespace {

TEST(Error, MessageNamesFileLayerFeatureLineAndHint) {
  const Error e = inputError("attribute 'elev' is not numeric ('n/a')",
                             SourceLocation{"contours.gpkg", "contours", 17, std::nullopt},
                             "give every contour a numeric elevation");
  EXPECT_EQ(e.kind(), ErrorKind::Input);
  EXPECT_STREQ(e.what(),
               "contours.gpkg, layer 'contours', feature 17: attribute 'elev' is not numeric "
               "('n/a') — give every contour a numeric elevation");
  EXPECT_EQ(e.problem(), "attribute 'elev' is not numeric ('n/a')");
  EXPECT_EQ(e.where().layer, "contours");
  EXPECT_EQ(e.hint(), "give every contour a numeric elevation");
}

TEST(Error, LocationShowsOnlyTheFieldsThatAreSet) {
  EXPECT_EQ((SourceLocation{"pts.csv", "", std::nullopt, 12}.str()), "pts.csv, line 12");
  EXPECT_EQ((SourceLocation{"", "", 4, std::nullopt}.str()), "feature 4");
  EXPECT_TRUE(SourceLocation{}.empty());
  EXPECT_FALSE((SourceLocation{"", "", std::nullopt, 1}.empty()));
}

TEST(Error, MessageWithoutLocationIsJustTheProblem) {
  const Error e = geometryError("fewer than 3 non-collinear points");
  EXPECT_STREQ(e.what(), "fewer than 3 non-collinear points");
  EXPECT_EQ(e.kind(), ErrorKind::Geometry);
}

TEST(Error, IsARuntimeErrorSoGenericHandlersCatchIt) {
  try {
    throw ioError("cannot rename 'out.tin.part' to 'out.tin'", SourceLocation{"out.tin"});
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("out.tin.part"), std::string::npos);
    return;
  }
  FAIL() << "tinsmith::Error must derive from std::runtime_error";
}

TEST(Error, EveryKindHasAName) {
  for (ErrorKind kind : {ErrorKind::Usage, ErrorKind::Input, ErrorKind::Geometry, ErrorKind::Io,
                         ErrorKind::NotImplemented, ErrorKind::Internal}) {
    EXPECT_FALSE(toString(kind).empty());
    EXPECT_NE(toString(kind), "error");
  }
  EXPECT_EQ(notImplemented("tinsmith tile").kind(), ErrorKind::NotImplemented);
  EXPECT_NE(std::string(internalError("twin mismatch").what()).find("bug"), std::string::npos);
}

}  // namespace
}  // namespace tinsmith
