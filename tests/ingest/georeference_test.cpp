// ProjGeoReference's heights: geoid "egm96" adds the EGM96 undulation read
// independently from PROJ's grid file (GDAL, bilinear, here), a compound CRS
// converts when its grid is installed, and fails naming the grid when not.
#include <gdal_priv.h>
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <filesystem>

#include "core/base/error.hpp"
#include "ingest/base/gdal_runtime.hpp"
#include "ingest/tiles/proj_georeference.hpp"

namespace tinsmith::ingest {
namespace {

constexpr const char* kEgm96Grid = "/usr/share/proj/egm96_15.gtx";
// Red Butte Canyon, NAD83 / UTM 12N.
constexpr Point3 kRedButte{434000.0, 4516000.0, 1700.0};

encode::Geodetic geodetic(const ProjGeoReference& geo, const Point3& p) {
  encode::Geodetic g;
  geo.toGeodetic({&p, 1}, {&g, 1});
  return g;
}

/// The EGM96 undulation at (lon, lat) in degrees, bilinear between the
/// grid's nodes (the .gtx is a lon/lat raster of node values; GDAL reports
/// the cells centred on the nodes).
double undulationFromGrid(double lon, double lat) {
  ensureGdalReady();
  std::unique_ptr<GDALDataset> grid(static_cast<GDALDataset*>(GDALOpen(kEgm96Grid, GA_ReadOnly)));
  if (!grid) throw std::runtime_error(std::string("cannot open ") + kEgm96Grid);
  std::array<double, 6> t{};
  grid->GetGeoTransform(t.data());
  const double col = (lon - t[0]) / t[1] - 0.5;  // node coordinates
  const double row = (lat - t[3]) / t[5] - 0.5;
  const int c0 = static_cast<int>(std::floor(col)), r0 = static_cast<int>(std::floor(row));
  std::array<float, 4> v{};  // (r0, c0), (r0, c0 + 1), (r0 + 1, c0), (r0 + 1, c0 + 1)
  if (grid->GetRasterBand(1)->RasterIO(GF_Read, c0, r0, 2, 2, v.data(), 2, 2, GDT_Float32, 0, 0) !=
      CE_None)
    throw std::runtime_error("cannot read the EGM96 grid");
  const double fc = col - c0, fr = row - r0;
  return (1 - fr) * ((1 - fc) * v[0] + fc * v[1]) + fr * ((1 - fc) * v[2] + fc * v[3]);
}

TEST(Heights, Egm96AddsTheUndulationOfProjsGrid) {
  ASSERT_TRUE(std::filesystem::exists(kEgm96Grid)) << "install Debian's proj-data";
  const encode::Geodetic ellipsoidal = geodetic(ProjGeoReference("EPSG:26912", ""), kRedButte);
  const encode::Geodetic egm96 = geodetic(ProjGeoReference("EPSG:26912", "egm96"), kRedButte);
  // Without a geoid z is taken as ellipsoidal, as it is.
  EXPECT_NEAR(ellipsoidal.height, kRedButte.z, 1e-6);
  // The geoid moves heights only.
  EXPECT_NEAR(egm96.lon, ellipsoidal.lon, 1e-9);
  EXPECT_NEAR(egm96.lat, ellipsoidal.lat, 1e-9);
  EXPECT_NEAR(ellipsoidal.lon, -111.7823, 1e-3);
  EXPECT_NEAR(ellipsoidal.lat, 40.7923, 1e-3);

  const double added = egm96.height - kRedButte.z;
  const double fromGrid = undulationFromGrid(ellipsoidal.lon, ellipsoidal.lat);
  EXPECT_GT(fromGrid, -17.5);  // the grid is what we think it is: N ≈ −16.5 m here
  EXPECT_LT(fromGrid, -15.5);
  // h = H + N; bilinear here and in PROJ, so they agree to rounding.
  EXPECT_NEAR(added, fromGrid, 1e-3) << "PROJ added " << added << " m, the grid says " << fromGrid;
}

TEST(Heights, CompoundCrsWhoseGridIsInstalledConverts) {
  // EGM96 height (EPSG:5773) as the CRS's own vertical datum: the same
  // conversion as geoid "egm96" on the horizontal CRS.
  const encode::Geodetic compound = geodetic(ProjGeoReference("EPSG:26912+5773", ""), kRedButte);
  const encode::Geodetic egm96 = geodetic(ProjGeoReference("EPSG:26912", "egm96"), kRedButte);
  EXPECT_NEAR(compound.height, egm96.height, 1e-3);
  EXPECT_NEAR(compound.height - kRedButte.z, undulationFromGrid(compound.lon, compound.lat), 1e-3);
  EXPECT_NEAR(compound.lon, egm96.lon, 1e-9);
  EXPECT_NEAR(compound.lat, egm96.lat, 1e-9);
}

TEST(Heights, CompoundCrsWhoseGridIsMissingFailsNamingIt) {
  // NAD83 / UTM 12N + NAVD88 height: PROJ needs a NOAA geoid grid, which
  // Debian's proj-data does not ship (PROJ alone would leave z unconverted).
  try {
    ProjGeoReference("EPSG:26912+5703", "");
    FAIL() << "accepted; is a NAVD88 geoid grid installed in /usr/share/proj? Then this test "
              "needs a datum whose grid is not";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::Input);
    const std::string problem = e.problem();
    const auto grid = problem.find("us_noaa_");
    ASSERT_NE(grid, std::string::npos) << e.what();
    const std::string name = problem.substr(grid, problem.find(".tif", grid) + 4 - grid);
    EXPECT_FALSE(std::filesystem::exists("/usr/share/proj/" + name)) << name;
    EXPECT_NE(problem.find("North American Vertical Datum 1988"), std::string::npos) << e.what();
    EXPECT_NE(problem.find("not installed"), std::string::npos) << e.what();
    EXPECT_NE(e.hint().find("https://cdn.proj.org/" + name), std::string::npos) << e.what();
    EXPECT_NE(e.hint().find("EPSG:26912 alone with geoid = \"egm96\""), std::string::npos)
        << e.what();
  }
}

TEST(Heights, AGeoidOnACompoundCrsIsAUsageError) {
  try {
    ProjGeoReference("EPSG:26912+5773", "egm96");
    FAIL() << "accepted";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::Usage);
    EXPECT_NE(e.hint().find("EPSG:26912"), std::string::npos) << e.what();
  }
  try {
    ProjGeoReference("EPSG:26912", "egm2008");
    FAIL() << "accepted";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::Usage);
    EXPECT_NE(e.problem().find("egm2008"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace tinsmith::ingest
