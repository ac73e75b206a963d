// The reference `tinsmith tin` is measured against: a plain CGAL 5 program
// that does the same job from the same files — read XYZ text points and
// GeoJSON LineString break lines, build the constrained Delaunay
// triangulation of both with the break lines as constraints, write the result
// in binary — written the way a careful CGAL user would write it:
//
// - the text is read whole and parsed with std::from_chars (no iostreams);
//   the GeoJSON with nlohmann::json;
// - CGAL's usual TIN set-up: Constrained_Delaunay_triangulation_2 over
//   Projection_traits_xy_3<Epick>, so z rides along with every point (a
//   crossing of two break lines gets its z from the traits), with
//   Exact_intersections_tag: crossing constraints are placed with exact
//   constructions, as the CDT benchmark's CGAL does (Exact_predicates_tag
//   measured the same here, within 5 %);
// - the points go in as one range (CGAL sorts them spatially), the break-line
//   segments in one insert_constraints call (points and index pairs);
// - the output is the vertices (x, y, z doubles), the finite triangles (three
//   u32 vertex indices) and the constrained edges (two u32), written with
//   large fwrite calls and fsync'd, like tinsmith's atomic write.
//
//   cgal_tin POINTS.xyz LINES.geojson OUT.bin
//
// Prints "read S triangulate S write S vertices V triangles T constrained C"
// on stdout. One thread (CGAL's 2D triangulations are sequential).
#include <CGAL/Constrained_Delaunay_triangulation_2.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Projection_traits_xy_3.h>
#include <CGAL/Triangulation_vertex_base_with_info_2.h>
#include <unistd.h>

#include <charconv>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iterator>
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

namespace {

using Epick = CGAL::Exact_predicates_inexact_constructions_kernel;
using Gt = CGAL::Projection_traits_xy_3<Epick>;
using Vb = CGAL::Triangulation_vertex_base_with_info_2<std::uint32_t, Gt>;
using Fb = CGAL::Constrained_triangulation_face_base_2<Gt>;
using Tds = CGAL::Triangulation_data_structure_2<Vb, Fb>;
using Cdt = CGAL::Constrained_Delaunay_triangulation_2<Gt, Tds, CGAL::Exact_intersections_tag>;
using Point = Gt::Point_2;  // a Point_3

double seconds(std::chrono::steady_clock::time_point since) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - since).count();
}

std::string slurp(const char* path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    std::fprintf(stderr, "cgal_tin: cannot open %s\n", path);
    std::exit(3);
  }
  return {std::istreambuf_iterator<char>(in), {}};
}

std::vector<Point> readXyz(const char* path) {
  const std::string text = slurp(path);
  std::vector<Point> points;
  const char* p = text.data();
  const char* end = p + text.size();
  auto skipBlanks = [&] {
    while (p < end && (*p == ' ' || *p == '\t' || *p == ',' || *p == '\r' || *p == '\n')) ++p;
  };
  double v[3];
  for (;;) {
    for (double& x : v) {
      skipBlanks();
      if (p >= end) return points;
      const auto r = std::from_chars(p, end, x);
      if (r.ec != std::errc()) {
        std::fprintf(stderr, "cgal_tin: %s: not a number at byte %td\n", path, p - text.data());
        std::exit(3);
      }
      p = r.ptr;
    }
    points.emplace_back(v[0], v[1], v[2]);
  }
}

void readLines(const char* path, std::vector<Point>& vertices,
               std::vector<std::pair<std::size_t, std::size_t>>& segments) {
  const auto json = nlohmann::json::parse(slurp(path));
  for (const auto& feature : json.at("features")) {
    const auto& coordinates = feature.at("geometry").at("coordinates");
    const std::size_t first = vertices.size();
    for (const auto& c : coordinates)
      vertices.emplace_back(c.at(0).get<double>(), c.at(1).get<double>(), c.at(2).get<double>());
    for (std::size_t i = first + 1; i < vertices.size(); ++i) segments.emplace_back(i - 1, i);
  }
}

template <class T>
void put(std::FILE* f, const std::vector<T>& items) {
  if (!items.empty() && std::fwrite(items.data(), sizeof(T), items.size(), f) != items.size()) {
    std::perror("cgal_tin: write");
    std::exit(5);
  }
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 4) {
    std::fprintf(stderr, "usage: cgal_tin POINTS.xyz LINES.geojson OUT.bin\n");
    return 2;
  }
  auto start = std::chrono::steady_clock::now();
  const std::vector<Point> points = readXyz(argv[1]);
  std::vector<Point> lineVertices;
  std::vector<std::pair<std::size_t, std::size_t>> segments;
  readLines(argv[2], lineVertices, segments);
  const double readSeconds = seconds(start);

  start = std::chrono::steady_clock::now();
  Cdt cdt;
  cdt.insert(points.begin(), points.end());
  cdt.insert_constraints(lineVertices.begin(), lineVertices.end(), segments.begin(), segments.end());
  const double triangulateSeconds = seconds(start);

  start = std::chrono::steady_clock::now();
  struct Xyz {
    double x, y, z;
  };
  std::vector<Xyz> xyz;
  xyz.reserve(cdt.number_of_vertices());
  std::uint32_t index = 0;
  for (auto v = cdt.finite_vertices_begin(); v != cdt.finite_vertices_end(); ++v) {
    v->info() = index++;
    xyz.push_back({v->point().x(), v->point().y(), v->point().z()});
  }
  std::vector<std::uint32_t> triangles, constrained;
  triangles.reserve(3 * cdt.number_of_faces());
  for (auto f = cdt.finite_faces_begin(); f != cdt.finite_faces_end(); ++f)
    for (int i = 0; i < 3; ++i) triangles.push_back(f->vertex(i)->info());
  for (auto e = cdt.finite_edges_begin(); e != cdt.finite_edges_end(); ++e) {
    if (!cdt.is_constrained(*e)) continue;
    constrained.push_back(e->first->vertex(Cdt::cw(e->second))->info());
    constrained.push_back(e->first->vertex(Cdt::ccw(e->second))->info());
  }
  std::FILE* out = std::fopen(argv[3], "wb");
  if (!out) {
    std::perror(argv[3]);
    return 5;
  }
  const std::uint64_t counts[3] = {xyz.size(), triangles.size() / 3, constrained.size() / 2};
  if (std::fwrite(counts, sizeof counts, 1, out) != 1) return 5;
  put(out, xyz);
  put(out, triangles);
  put(out, constrained);
  if (std::fflush(out) != 0 || ::fsync(fileno(out)) != 0 || std::fclose(out) != 0) {
    std::perror(argv[3]);
    return 5;
  }
  const double writeSeconds = seconds(start);
  std::printf("read %.3f triangulate %.3f write %.3f vertices %llu triangles %llu constrained %llu\n",
              readSeconds, triangulateSeconds, writeSeconds,
              static_cast<unsigned long long>(counts[0]), static_cast<unsigned long long>(counts[1]),
              static_cast<unsigned long long>(counts[2]));
  return 0;
}
