// Scale benchmark of the multilevel fitter: n points from Franke's function
// (uniform on [0, 1]², z scaled to metres-like values) or from an XYZ text file,
// error tolerance as a percentage of the z range; prints time, peak memory
// (ru_maxrss), bytes per point and final vertices, and per-level statistics.
//
//   fit_scale_bench franke N [--tolerance PCT] [--threads T] [--lambda K] [--max-level L]
//   fit_scale_bench xyz FILE [--tolerance PCT | --max-error M] ...
#include <sys/resource.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include "core/base/error.hpp"
#include "core/fit/multilevel_fit.hpp"

using namespace tinsmith;
using namespace tinsmith::fit;

namespace {

double peakMegabytes() {
  rusage ru{};
  getrusage(RUSAGE_SELF, &ru);
  return static_cast<double>(ru.ru_maxrss) / 1024.0;
}

std::vector<Point3> frankeUniform(std::size_t n, std::uint64_t seed) {
  std::vector<Point3> pts;
  pts.reserve(n);
  std::uint64_t s = seed;
  auto next = [&] {
    std::uint64_t z = (s += 0x9e3779b97f4a7c15ULL);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
    return static_cast<double>((z ^ (z >> 31)) >> 11) * 0x1.0p-53;
  };
  for (std::size_t i = 0; i < n; ++i) {
    const double x = next(), y = next();
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
    for (int i = 3; i + 1 < argc; i += 2) {
      const std::string a = argv[i];
      const double v = std::atof(argv[i + 1]);
      if (a == "--tolerance") opt.criteria.errorPercent = v;
      else if (a == "--max-error") opt.criteria.errorPercent.reset(), opt.criteria.errorAbsolute = v;
      else if (a == "--threads") opt.threads = static_cast<int>(v);
      else if (a == "--lambda") opt.lambdaFactor = v;
      else if (a == "--max-level") opt.maxLevel = static_cast<int>(v);
      else if (a == "--count") opt.criteria.countAbove = static_cast<std::size_t>(v);
      else if (a == "--solver") opt.solver = std::strcmp(argv[i + 1], "cg") == 0 ? SolverKind::ConjugateGradient : SolverKind::GaussSeidel;
    }
    const auto t0 = std::chrono::steady_clock::now();
    const std::vector<Point3> pts = std::strcmp(argv[1], "franke") == 0
                                        ? frankeUniform(static_cast<std::size_t>(std::atoll(argv[2])), 42)
                                        : readXyz(argv[2]);
    const auto t1 = std::chrono::steady_clock::now();
    const double baseMb = peakMegabytes();
    opt.progress = [](const std::string& line) { std::printf("  %s\n", line.c_str()); };
    const MultilevelFit fit = fitMultilevel(pts, opt);
    const auto t2 = std::chrono::steady_clock::now();
    const double secs = std::chrono::duration<double>(t2 - t1).count();
    const double mb = peakMegabytes();
    const auto& last = fit.levels().back();
    std::printf("points %zu  load %.2f s  fit %.2f s  peak RSS %.1f MB (%.1f MB after loading; %.1f bytes/point over the loaded points)  "
                "final level %d  vertices %zu  triangles %zu  max error %.4g  rms %.4g\n",
                pts.size(), std::chrono::duration<double>(t1 - t0).count(), secs, mb, baseMb,
                (mb - baseMb) * 1024.0 * 1024.0 / static_cast<double>(pts.size()), last.level, last.vertices,
                last.triangles, last.maxError, last.rmsError);
  } catch (const Error& e) {
    std::fprintf(stderr, "ERROR: %s\n", e.what());
    return 1;
  }
  return 0;
}
