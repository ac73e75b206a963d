// Scale benchmark of the multilevel fitter: n points from Franke's function
// (uniform on [0, 1]², z scaled to metres-like values) or from an XYZ text file,
// error tolerance as a percentage of the z range; prints time, peak memory
// (ru_maxrss), CPU seconds of the fit (user + system, all threads), bytes per point and final vertices, and per-level statistics.
//
//   fit_scale_bench franke N [--tolerance PCT] [--threads T] [--lambda K] [--max-level L]
//   fit_scale_bench xyz FILE [--tolerance PCT | --max-error M] [--count N] [--check REF.xyz] ...
// --check evaluates the fitted surface at every point of REF.xyz (e.g. all
// cells of a DEM) and prints max error and RMSE against them.
#include <sys/resource.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include "core/base/error.hpp"
#include "core/fit/multilevel_fit.hpp"
#include "core/base/split_mix.hpp"
#include "core/surface/franke_function.hpp"

using namespace tinsmith;
using namespace tinsmith::fit;

namespace {

double cpuSeconds() {
  rusage ru{};
  getrusage(RUSAGE_SELF, &ru);
  return static_cast<double>(ru.ru_utime.tv_sec + ru.ru_stime.tv_sec) +
         1e-6 * static_cast<double>(ru.ru_utime.tv_usec + ru.ru_stime.tv_usec);
}

double peakMegabytes() {
  rusage ru{};
  getrusage(RUSAGE_SELF, &ru);
  return static_cast<double>(ru.ru_maxrss) / 1024.0;
}

std::vector<Point3> frankeUniform(std::size_t n, std::uint64_t seed) {
  std::vector<Point3> pts;
  pts.reserve(n);
  SplitMix64 random(seed);
  for (std::size_t i = 0; i < n; ++i) {
    const double x = random.uniform(), y = random.uniform();
    pts.push_back({x * 10000.0, y * 10000.0, 1000.0 * frankeFunction(x, y)});
  }
  return pts;
}

std::vector<Point3> readXyz(const char* path) {
  std::FILE* f = std::fopen(path, "r");
  if (!f) throw inputError(std::string("cannot open ") + path);
  std::vector<Point3> pts;
  double x, y, z;
  while (std::fscanf(f, "%lf%*[ ,\t]%lf%*[ ,\t]%lf", &x, &y, &z) == 3) pts.push_back({x, y, z});
  std::fclose(f);
  return pts;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 3) {
    std::fprintf(stderr, "usage: %s franke N | xyz FILE [--tolerance PCT] [--max-error M] [--threads T] [--lambda K] [--max-level L] [--solver gs|cg]\n", argv[0]);
    return 2;
  }
  try {
    MultilevelOptions opt;
    opt.criteria.errorPercent = 0.1;
    const char* check = nullptr;
    for (int i = 3; i + 1 < argc; i += 2) {
      const std::string a = argv[i];
      const double v = std::atof(argv[i + 1]);
      if (a == "--tolerance") opt.criteria.errorPercent = v;
      else if (a == "--max-error") opt.criteria.errorPercent.reset(), opt.criteria.errorAbsolute = v;
      else if (a == "--threads") opt.threads = static_cast<int>(v);
      else if (a == "--lambda") opt.lambdaFactor = v;
      else if (a == "--max-level") opt.maxLevel = static_cast<int>(v);
      else if (a == "--count") opt.criteria.countAbove = static_cast<std::size_t>(v);
      else if (a == "--count-only") opt.criteria.errorPercent.reset(), opt.criteria.countAbove = static_cast<std::size_t>(v);
      else if (a == "--check") check = argv[i + 1];
      else if (a == "--smoothing") opt.smoothing = std::strcmp(argv[i + 1], "membrane") == 0 ? Smoothing::Membrane : Smoothing::ThinPlate;
      else if (a == "--solver") opt.solver = std::strcmp(argv[i + 1], "cg") == 0 ? SolverKind::ConjugateGradient : SolverKind::GaussSeidel;
    }
    const auto t0 = std::chrono::steady_clock::now();
    const std::vector<Point3> pts = std::strcmp(argv[1], "franke") == 0
                                        ? frankeUniform(static_cast<std::size_t>(std::atoll(argv[2])), 42)
                                        : readXyz(argv[2]);
    const auto t1 = std::chrono::steady_clock::now();
    const double baseMb = peakMegabytes();
    const double cpu0 = cpuSeconds();
    opt.progress = [](const std::string& line) { std::printf("  %s\n", line.c_str()); };
    const MultilevelFit fit = fitMultilevel(pts, opt);
    const auto t2 = std::chrono::steady_clock::now();
    const double secs = std::chrono::duration<double>(t2 - t1).count();
    const double cpu = cpuSeconds() - cpu0;
    const double mb = peakMegabytes();
    const auto& last = fit.levels().back();
    std::printf("points %zu  load %.2f s  fit %.2f s (cpu %.2f s)  peak RSS %.1f MB (%.1f MB after loading; %.1f bytes/point over the loaded points)  "
                "final level %d  vertices %zu  triangles %zu  max error %.4g  rms %.4g\n",
                pts.size(), std::chrono::duration<double>(t1 - t0).count(), secs, cpu, mb, baseMb,
                (mb - baseMb) * 1024.0 * 1024.0 / static_cast<double>(pts.size()), last.level, last.vertices,
                last.triangles, last.maxError, last.rmsError);
    if (check) {
      const std::vector<Point3> ref = readXyz(check);
      double mx = 0.0, ss = 0.0;
      std::size_t outside = 0;
      for (const auto& p : ref) {
        const Point2 o = fit.mesh().origin();
        const double sz = fit.mesh().size();
        if (p.x < o.x || p.y < o.y || p.x > o.x + sz || p.y > o.y + sz) {
          ++outside;
          continue;
        }
        const double e = std::abs(fit.evaluate(p.xy()) - p.z);
        mx = std::max(mx, e);
        ss += e * e;
      }
      std::printf("check against %s: %zu points (%zu outside the domain), max error %.4g, RMSE %.4g\n", check,
                  ref.size(), outside, mx, std::sqrt(ss / static_cast<double>(ref.size() - outside)));
    }
  } catch (const Error& e) {
    std::fprintf(stderr, "ERROR: %s\n", e.what());
    return 1;
  }
  return 0;
}
