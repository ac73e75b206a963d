// Helpers shared by the CDT tests: validation assertions, random inputs,
// OBJ/XYZ/GeoJSON export for the independent checker.
#pragma once

#include <gtest/gtest.h>

#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>
#include <vector>

#include "core/cdt/cdt.hpp"
#include "core/mesh/validate.hpp"

namespace tinsmith::testing {

#if defined(__SANITIZE_ADDRESS__)
inline constexpr bool kSanitized = true;
#else
inline constexpr bool kSanitized = false;
#endif

inline ::testing::AssertionResult isValid(const Cdt& cdt) {
  const ValidationReport r = cdt.validate();
  if (r.ok) return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure() << r.summary();
}

inline ::testing::AssertionResult isValid(const Mesh& mesh) {
  const ValidationReport r = validate(mesh);
  if (r.ok) return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure() << r.summary();
}

inline std::vector<Point3> randomPoints(std::size_t n, std::uint32_t seed, double lo = 0,
                                        double hi = 1000) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> d(lo, hi);
  std::vector<Point3> pts(n);
  for (auto& p : pts) {
    p.x = d(rng);
    p.y = d(rng);
    p.z = d(rng) * 0.01;
  }
  return pts;
}

inline std::filesystem::path scratchDir(const std::string& name) {
  const char* env = std::getenv("TINSMITH_TEST_TMP");
  std::filesystem::path dir = env ? env : std::filesystem::temp_directory_path();
  dir /= "core_" + name;
  std::filesystem::create_directories(dir);
  return dir;
}

/// Writes mesh.obj, points.xyz (every input point) and lines.geojson (the
/// constraint polylines), all with %.17g.
inline void exportCase(const std::filesystem::path& dir, const Mesh& mesh,
                       const std::vector<Point3>& points,
                       const std::vector<std::vector<Point3>>& lines) {
  {
    FILE* f = std::fopen((dir / "mesh.obj").c_str(), "w");
    for (const Point3& p : mesh.points()) std::fprintf(f, "v %.17g %.17g %.17g\n", p.x, p.y, p.z);
    for (std::uint32_t t = 0; t < mesh.triangleCount(); ++t) {
      const auto v = mesh.vertices(TriangleId(t));
      std::fprintf(f, "f %u %u %u\n", v[0].value + 1, v[1].value + 1, v[2].value + 1);
    }
    std::fclose(f);
  }
  {
    FILE* f = std::fopen((dir / "points.xyz").c_str(), "w");
    for (const Point3& p : points) std::fprintf(f, "%.17g %.17g %.17g\n", p.x, p.y, p.z);
    std::fclose(f);
  }
  {
    FILE* f = std::fopen((dir / "lines.geojson").c_str(), "w");
    std::fprintf(f, "{\"type\":\"FeatureCollection\",\"features\":[");
    for (std::size_t i = 0; i < lines.size(); ++i) {
      std::fprintf(f, "%s{\"type\":\"Feature\",\"properties\":{},\"geometry\":{\"type\":"
                   "\"LineString\",\"coordinates\":[",
                   i ? "," : "");
      for (std::size_t k = 0; k < lines[i].size(); ++k) {
        std::fprintf(f, "%s[%.17g,%.17g,%.17g]", k ? "," : "", lines[i][k].x, lines[i][k].y,
                     lines[i][k].z);
      }
      std::fprintf(f, "]}}");
    }
    std::fprintf(f, "]}\n");
    std::fclose(f);
  }
}

/// A constrained edge R–L with a vertex one ulp from L (a sliver beside the
/// edge) and a break line A–B crossing it near R, in a frame of four points:
/// the input of CdtConstraintRegression.CrossingBesideASliverStaysOnBothLines
/// and CdtReview.RerouteNestingIsBoundedByAnInternalError.
namespace crossing_beside_a_sliver {
inline const Point3 R{6999980.9999999991, 7000017.0000000000, 10.0};
inline const Point3 L{6999980.0000000000, 6999980.0000000000, 20.0};
inline const Point3 apex{6999980.0000000000, 6999980.0000000009, 0.0};  // one ulp above L
inline const Point3 A{6999981.7548746532, 7000013.3426183844, 30.0};
inline const Point3 B{6999980.0000000000, 7000015.0000000009, 40.0};
/// L, apex, R, then the frame.
inline std::vector<Point3> points() {
  return {L,
          apex,
          R,
          {6999990.0, 6999990.0, 0.0},
          {6999970.0, 6999990.0, 0.0},
          {6999990.0, 7000020.0, 0.0},
          {6999970.0, 7000020.0, 0.0}};
}
}  // namespace crossing_beside_a_sliver

}  // namespace tinsmith::testing
