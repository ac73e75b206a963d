// Fuzz target: bytes → a PSLG. Coordinates come from a small integer lattice
// (so collinear, cocircular, duplicate and overlapping input is common), scaled
// and offset to UTM-sized values, some nudged by a few ulps.
// tests/fuzz/seeds keeps inputs that once failed (named for what they showed);
// tools/test.sh runs them before the fuzzing proper. CDT_FUZZ_VERBOSE=1
// prints a run's operations.
#include <fuzzer/FuzzedDataProvider.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <vector>

#include "core/base/error.hpp"
#include "core/cdt/cdt.hpp"

namespace {

tinsmith::Point3 point(FuzzedDataProvider& in, double scale, double offset) {
  double x = offset + scale * in.ConsumeIntegralInRange<int>(-20, 20);
  double y = offset + scale * in.ConsumeIntegralInRange<int>(-20, 20);
  const int nudge = in.ConsumeIntegralInRange<int>(-2, 2);
  if (nudge != 0 && in.ConsumeBool()) x = std::nextafter(x, nudge > 0 ? INFINITY : -INFINITY);
  if (nudge == 2) y = std::nextafter(y, INFINITY);
  return {x, y, static_cast<double>(in.ConsumeIntegralInRange<int>(0, 100))};
}

}  // namespace

int runOne(const std::uint8_t* data, std::size_t size);

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  try {
    return runOne(data, size);
  } catch (const tinsmith::Error& e) {
    // Rejected input is fine; a broken invariant is a bug.
    if (e.kind() == tinsmith::ErrorKind::Internal) {
      std::fprintf(stderr, "internal error: %s\n", e.what());
      std::abort();
    }
    return 0;
  }
}

int runOne(const std::uint8_t* data, std::size_t size) {
  FuzzedDataProvider in(data, size);
  const double scale = in.PickValueInArray({1.0, 0.001, 0.1, 1000.0});
  const double offset = in.PickValueInArray({0.0, 7000000.0, 500000.25});
  tinsmith::CdtOptions options;
  options.snapTolerance = in.PickValueInArray({0.0, 0.0, 0.0005 * scale, 1.5 * scale});
  // Small thresholds send the first bulk through the two-half build.
  options.splitMinPoints = in.PickValueInArray<std::size_t>({0, 6, 24, 50000});
  tinsmith::Cdt cdt(options);
  std::vector<tinsmith::FeatureId> features;
  for (int k = 0; k < 6; ++k) {
    features.push_back(cdt.addFeature(static_cast<tinsmith::FeatureKind>(k), "fuzz"));
  }
  const auto boundary = cdt.addFeature(tinsmith::FeatureKind::Boundary, "boundary");
  const auto hole = cdt.addFeature(tinsmith::FeatureKind::Hole, "hole");
  bool any = false;
  int rounds = 0;
  while (in.remaining_bytes() > 0 && rounds++ < 64) {
    const int op = in.ConsumeIntegralInRange<int>(0, 9);
    const int n = in.ConsumeIntegralInRange<int>(1, 12);
    std::vector<tinsmith::Point3> pts;
    for (int i = 0; i < n; ++i) pts.push_back(point(in, scale, offset));
    int feature = op;
    if (op <= 4) {
      cdt.insertPoints(pts, features[op]);
    } else if (op <= 7) {
      feature = in.ConsumeIntegralInRange<int>(0, 5);
      cdt.insertConstraint(pts, features[feature], op == 7);
    } else if (op == 8) {
      cdt.addBoundary(pts, boundary);
    } else {
      cdt.addHole(pts, hole);
    }
    any = true;
    if (std::getenv("CDT_FUZZ_VERBOSE")) {
      std::fprintf(stderr, "op %d feature %d snap %.17g split %zu:", op, feature,
                   options.snapTolerance, options.splitMinPoints);
      for (const auto& p : pts) std::fprintf(stderr, " (%.17g, %.17g, %g)", p.x, p.y, p.z);
      std::fprintf(stderr, "\n");
    }
    if (in.ConsumeIntegralInRange<int>(0, 7) == 0) {
      if (std::getenv("CDT_FUZZ_VERBOSE")) std::fprintf(stderr, "finalize\n");
      try {
        cdt.finalize();
      } catch (const tinsmith::Error& e) {
        if (e.kind() == tinsmith::ErrorKind::Internal) {
          std::fprintf(stderr, "internal error: %s\n", e.what());
          std::abort();
        }
        return 0;
      }
    }
  }
  if (!any) return 0;
  try {
    cdt.finalize();
  } catch (const tinsmith::Error& e) {
    if (e.kind() == tinsmith::ErrorKind::Internal) {
      std::fprintf(stderr, "internal error: %s\n", e.what());
      std::abort();
    }
    return 0;
  }
  if (std::getenv("CDT_FUZZ_VERBOSE")) {
    for (const auto& x : cdt.report().intersections) {
      if (x.forced)
        std::fprintf(stderr, "forced crossing moved %.17g (scale %g)\n", x.moved, scale);
    }
  }
  const tinsmith::ValidationReport r = cdt.validate();
  if (!r.ok) {
    std::fprintf(stderr, "%s\n", r.summary().c_str());
    std::abort();
  }
  return 0;
}
