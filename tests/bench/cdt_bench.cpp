// CDT benchmark: tinsmith::Cdt against CGAL's Constrained_Delaunay_triangulation_2
// (Epick, Exact_intersections_tag) on identical inputs. Each (case, library)
// runs in its own child process; the parent reports the wall time of the
// triangulation (input generation excluded; for tinsmith also with the compact
// output Mesh built, which CGAL has no counterpart of) and the child's peak RSS
// (ru_maxrss, input included — the same input for both; tinsmith's includes
// the output Mesh).
//
// tinsmith runs with 1 and with 2 threads (CdtOptions::threads), CGAL on one;
// the three alternate within each repetition so that load changes on a shared
// machine hit all alike.
//
//   cdt_bench                 all cases, 3 repetitions, best time reported
//   cdt_bench --reps 5        more repetitions
//   cdt_bench --case uniform  one case (uniform, grid, crossing, contours, scaling)
//   cdt_bench --split-min N   CdtOptions::splitMinPoints (0: no two-half build)
//   cdt_bench --smoke         10k points, every case once, checks validity (ctest)
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include "core/base/allocator.hpp"
#include "core/cdt/cdt.hpp"

#ifdef TINSMITH_BENCH_CGAL
#include <CGAL/Constrained_Delaunay_triangulation_2.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#endif

namespace {

using tinsmith::Point3;

struct Input {
  std::vector<Point3> points;
  std::vector<std::vector<Point3>> lines;  // constraint polylines
};

Input uniform(std::size_t n, std::uint64_t seed) {
  Input in;
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> d(0, 10000);
  in.points.resize(n);
  for (auto& p : in.points) p = {d(rng), d(rng), d(rng) * 0.01};
  return in;
}

Input perturbedGrid(std::size_t n) {
  Input in;
  const auto side = static_cast<std::size_t>(std::sqrt(double(n)));
  std::mt19937_64 rng(2);
  std::uniform_real_distribution<double> d(-0.1, 0.1);
  in.points.reserve(side * side);
  for (std::size_t j = 0; j < side; ++j) {
    for (std::size_t i = 0; i < side; ++i) {
      in.points.push_back({500000.0 + 10.0 * i + d(rng), 7000000.0 + 10.0 * j + d(rng), 0});
    }
  }
  return in;
}

Input crossing(std::size_t n, std::size_t segments) {
  Input in = uniform(n, 3);
  std::mt19937_64 rng(4);
  std::uniform_real_distribution<double> d(0, 10000), len(-500, 500);
  for (std::size_t i = 0; i < segments; ++i) {
    const double x = d(rng), y = d(rng);
    in.lines.push_back({{x, y, 1}, {std::clamp(x + len(rng), 0.0, 10000.0),
                                    std::clamp(y + len(rng), 0.0, 10000.0), 2}});
  }
  return in;
}

/// Closed contour-like rings around a hill: radius R_k + wobble, never crossing.
Input contours(std::size_t vertices) {
  Input in;
  const std::size_t rings = 200, per = vertices / rings;
  for (std::size_t k = 0; k < rings; ++k) {
    std::vector<Point3> ring;
    const double r = 100.0 + 20.0 * k;
    for (std::size_t i = 0; i < per; ++i) {
      const double a = 2 * std::numbers::pi * i / per;
      const double rr = r + 6.0 * std::sin(7 * a + 0.1 * k) + 3.0 * std::cos(13 * a);
      ring.push_back({rr * std::cos(a), rr * std::sin(a), 1000.0 - k});
    }
    ring.push_back(ring.front());
    in.lines.push_back(std::move(ring));
  }
  return in;
}

double now() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

/// Builds with tinsmith; returns seconds, or −1 if the result fails validation.
/// `withMesh` gets the time including the compact output Mesh (mesh()).
std::size_t gSplitMin = tinsmith::CdtOptions{}.splitMinPoints;

double runTinsmith(const Input& in, unsigned threads, bool check, double& withMesh) {
  const double t0 = now();
  tinsmith::CdtOptions options;
  options.threads = threads;
  options.splitMinPoints = gSplitMin;
  tinsmith::Cdt cdt(options);
  const auto f = cdt.addFeature(tinsmith::FeatureKind::Contour, "bench");
  cdt.insertPoints(in.points);
  for (const auto& l : in.lines) cdt.insertConstraint(l, f);
  cdt.finalize();
  const double t = now() - t0;
  if (cdt.mesh().triangleCount() == 0) return -1;
  withMesh = now() - t0;
  if (check) {
    const auto r = cdt.validate();
    if (!r.ok) {
      std::fprintf(stderr, "%s\n", r.summary().c_str());
      return -1;
    }
  }
  return t;
}

#ifdef TINSMITH_BENCH_CGAL
using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using Tds = CGAL::Triangulation_data_structure_2<CGAL::Triangulation_vertex_base_2<K>,
                                                 CGAL::Constrained_triangulation_face_base_2<K>>;
using CgalCdt = CGAL::Constrained_Delaunay_triangulation_2<K, Tds, CGAL::Exact_intersections_tag>;

double runCgal(const Input& in, bool check) {
  std::vector<K::Point_2> pts;
  pts.reserve(in.points.size());
  for (const auto& p : in.points) pts.emplace_back(p.x, p.y);
  std::vector<std::pair<K::Point_2, K::Point_2>> segs;
  for (const auto& l : in.lines) {
    for (std::size_t i = 0; i + 1 < l.size(); ++i) {
      segs.emplace_back(K::Point_2(l[i].x, l[i].y), K::Point_2(l[i + 1].x, l[i + 1].y));
    }
  }
  const double t0 = now();
  CgalCdt cdt;
  cdt.insert(pts.begin(), pts.end());
  if (!segs.empty()) cdt.insert_constraints(segs.begin(), segs.end());
  const double t = now() - t0;
  if (check && !cdt.is_valid()) return -1;
  return t;
}
#endif

struct Result {
  double seconds = -1;
  double withMesh = -1;  // tinsmith: finalize() + mesh()
  double peakMb = 0;
};

enum class Run { Tinsmith1, Tinsmith2, Cgal };

/// Runs one (case, library) in a child process.
Result measure(const std::string& kind, std::size_t n, Run run, bool check) {
  int fds[2];
  if (pipe(fds) != 0) return {};
  const pid_t pid = fork();
  if (pid == 0) {
    close(fds[0]);
    Input in;
    if (kind == "uniform" || kind == "scaling") in = uniform(n, 1);
    if (kind == "grid") in = perturbedGrid(n);
    if (kind == "crossing") in = crossing(n, n / 100);
    if (kind == "contours") in = contours(n);
    double t[2] = {-2, -1};
#ifdef TINSMITH_BENCH_CGAL
    if (run == Run::Cgal) t[0] = runCgal(in, check);
#endif
    if (run != Run::Cgal) t[0] = runTinsmith(in, run == Run::Tinsmith1 ? 1 : 2, check, t[1]);
    if (write(fds[1], t, sizeof t) != sizeof t) _exit(2);
    _exit(0);
  }
  close(fds[1]);
  Result r;
  double t[2];
  if (read(fds[0], t, sizeof t) != sizeof t) {
    t[0] = -1;
    t[1] = -1;
  }
  r.seconds = t[0];
  r.withMesh = t[1];
  close(fds[0]);
  int status = 0;
  struct rusage ru {};
  wait4(pid, &status, 0, &ru);
  r.peakMb = ru.ru_maxrss / 1024.0;
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0) r.seconds = -1;
  return r;
}

}  // namespace

int main(int argc, char** argv) {
  tinsmith::returnLargeBlocksToSystem();  // as the tinsmith binary does; CGAL runs with it too
  int reps = 3;
  bool smoke = false;
  std::string only;
  for (int i = 1; i < argc; ++i) {
    if (!std::strcmp(argv[i], "--smoke")) smoke = true;
    if (!std::strcmp(argv[i], "--reps") && i + 1 < argc) reps = std::atoi(argv[++i]);
    if (!std::strcmp(argv[i], "--case") && i + 1 < argc) only = argv[++i];
    if (!std::strcmp(argv[i], "--split-min") && i + 1 < argc) {
      gSplitMin = static_cast<std::size_t>(std::atoll(argv[++i]));
    }
  }
  struct Case {
    std::string kind;
    std::size_t n;
    std::string label;
  };
  std::vector<Case> cases;
  if (smoke) {
    reps = 1;
    gSplitMin = std::min<std::size_t>(gSplitMin, 2000);  // check the two-half build too
    cases = {{"uniform", 10000, "10k uniform"},
             {"grid", 10000, "10k perturbed grid"},
             {"crossing", 10000, "10k + 100 crossing segments"},
             {"contours", 20000, "20k contour vertices"}};
  } else {
    cases = {{"uniform", 1000000, "1M uniform points"},
             {"grid", 1000000, "1M perturbed grid"},
             {"crossing", 1000000, "1M points + 10k crossing segments"},
             {"contours", 200000, "200k contour vertices, all constrained"},
             {"scaling", 100000, "scaling: 100k uniform"},
             {"scaling", 250000, "scaling: 250k uniform"},
             {"scaling", 500000, "scaling: 500k uniform"},
             {"scaling", 2000000, "scaling: 2M uniform"},
             {"scaling", 4000000, "scaling: 4M uniform"}};
  }
#ifdef TINSMITH_BENCH_CGAL
  const bool haveCgal = true;
#else
  const bool haveCgal = false;
#endif
  std::printf("tinsmith with 1 and 2 threads (splitMinPoints %zu), CGAL on 1; best of %d\n\n",
              gSplitMin, reps);
  std::printf("| case | tinsmith 1T s | tinsmith 2T s | CGAL s | ratio 1T | ratio 2T | "
              "ratio incl. mesh() 1T / 2T | peak MB 1T / 2T | CGAL peak MB |\n");
  std::printf("|---|---|---|---|---|---|---|---|---|\n");
  const std::vector<Run> runs =
      haveCgal ? std::vector<Run>{Run::Tinsmith1, Run::Tinsmith2, Run::Cgal}
               : std::vector<Run>{Run::Tinsmith1, Run::Tinsmith2};
  const char* names[] = {"tinsmith 1T", "tinsmith 2T", "CGAL"};
  int failures = 0;
  for (const Case& c : cases) {
    if (!only.empty() && c.kind != only) continue;
    Result best[3];
    for (int r = 0; r < reps; ++r) {
      for (const Run run : runs) {
        const auto k = static_cast<std::size_t>(run);
        const Result x = measure(c.kind, c.n, run, smoke);
        if (x.seconds < 0) {
          ++failures;
          std::fprintf(stderr, "%s: %s failed\n", c.label.c_str(), names[k]);
          continue;
        }
        if (best[k].seconds < 0 || x.seconds < best[k].seconds) {
          best[k].seconds = x.seconds;
          best[k].withMesh = x.withMesh;
        }
        best[k].peakMb = std::max(best[k].peakMb, x.peakMb);
      }
    }
    const Result &one = best[0], &two = best[1], &cgal = best[2];
    if (haveCgal) {
      std::printf("| %s | %.3f | %.3f | %.3f | %.2f | %.2f | %.2f / %.2f | %.0f / %.0f | %.0f |\n",
                  c.label.c_str(), one.seconds, two.seconds, cgal.seconds,
                  one.seconds / cgal.seconds, two.seconds / cgal.seconds,
                  one.withMesh / cgal.seconds, two.withMesh / cgal.seconds, one.peakMb,
                  two.peakMb, cgal.peakMb);
    } else {
      std::printf("| %s | %.3f | %.3f | – | – | – | – | %.0f / %.0f | – |\n", c.label.c_str(),
                  one.seconds, two.seconds, one.peakMb, two.peakMb);
    }
    std::fflush(stdout);
  }
  return failures == 0 ? 0 : 1;
}
