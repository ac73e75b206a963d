// OBJ and PLY (ASCII) export of a TIN, for other tools to check and diff.
// Coordinates are printed as printf's "%.17g" does, so every double
// round-trips exactly; x, y in the TIN's CRS, z in metres. Triangles keep the
// TIN's counter-clockwise order. Output is deterministic and written
// atomically (ingest/base/atomic_file.hpp): a failure leaves no file.
#pragma once

#include <filesystem>
#include <string>

#include "core/tin/tin_data.hpp"

namespace tinsmith::ingest {

/// Wavefront OBJ: "v x y z" per vertex, "f a b c" (1-based) per triangle, a
/// comment header naming the CRS and the counts. Throws ioError.
void writeObj(const std::filesystem::path& path, const TinData& tin);
/// PLY 1.0 ASCII: element vertex (double x, y, z), element face (uchar count,
/// uint indices); "comment crs …". Throws ioError.
void writePly(const std::filesystem::path& path, const TinData& tin);

/// The exact text the writers produce.
std::string objText(const TinData& tin);
std::string plyText(const TinData& tin);

/// Appends `value` formatted as "%.17g" (shortest exact round trip is not
/// required; 17 significant digits always round-trip a double).
void appendG17(std::string& out, double value);

}  // namespace tinsmith::ingest
