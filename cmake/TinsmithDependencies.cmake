# Every dependency comes from a Debian bookworm package; tools/setup.sh installs
# them all. A missing one stops the configure step with the package to install.
include(FindPackageHandleStandardArgs)
find_package(PkgConfig REQUIRED)

# tinsmith_require(<what> <apt package> <found-variable>)
function(tinsmith_require what package found)
  if(NOT ${found})
    message(FATAL_ERROR
      "${what} not found. Install it with: apt-get install ${package} "
      "(or run tools/setup.sh, which installs every dependency).")
  endif()
endfunction()

find_package(Threads REQUIRED)

find_package(Eigen3 3.4 QUIET NO_MODULE)
tinsmith_require("Eigen 3.4" libeigen3-dev Eigen3_FOUND)

# Debian ships GeographicLib's find module outside CMake's default module path.
list(APPEND CMAKE_MODULE_PATH /usr/share/cmake/geographiclib)
find_package(GeographicLib QUIET)
tinsmith_require("GeographicLib" libgeographiclib-dev GeographicLib_FOUND)
if(NOT TARGET GeographicLib::GeographicLib)
  add_library(GeographicLib::GeographicLib INTERFACE IMPORTED)
  target_include_directories(GeographicLib::GeographicLib INTERFACE ${GeographicLib_INCLUDE_DIRS})
  target_link_libraries(GeographicLib::GeographicLib INTERFACE ${GeographicLib_LIBRARIES})
endif()

find_package(draco QUIET)
tinsmith_require("Draco" libdraco-dev draco_FOUND)
if(NOT EXISTS /usr/include/draco/draco_features.h)
  message(FATAL_ERROR "Draco headers missing: apt-get install libdraco-dev")
endif()
file(READ /usr/include/draco/draco_features.h _draco_features)
if(NOT _draco_features MATCHES "DRACO_TRANSCODER_SUPPORTED")
  message(FATAL_ERROR "Draco was built without glTF transcoder support; tinsmith needs Debian's libdraco-dev")
endif()

find_package(TinyGLTF QUIET)
tinsmith_require("tinygltf" libtinygltf-dev TinyGLTF_FOUND)

find_package(nlohmann_json 3 QUIET)
tinsmith_require("nlohmann-json" nlohmann-json3-dev nlohmann_json_FOUND)

find_package(OpenEXR 3 QUIET)
tinsmith_require("OpenEXR 3" libopenexr-dev OpenEXR_FOUND)

find_package(GDAL 3.6 QUIET CONFIG)
if(NOT GDAL_FOUND)
  find_package(GDAL 3.6 QUIET)
endif()
tinsmith_require("GDAL 3.6" libgdal-dev GDAL_FOUND)

# PROJ itself (GDAL's dependency) for what OGR does not expose: which grids a
# height transformation needs and whether they are installed.
pkg_check_modules(PROJ QUIET IMPORTED_TARGET proj)
tinsmith_require("PROJ" "libproj-dev proj-data" PROJ_FOUND)

find_package(SQLite3 QUIET)
tinsmith_require("SQLite 3" libsqlite3-dev SQLite3_FOUND)

find_package(tomlplusplus 3 QUIET)
tinsmith_require("toml++" libtomlplusplus-dev tomlplusplus_FOUND)

find_package(CLI11 2 QUIET)
tinsmith_require("CLI11" libcli11-dev CLI11_FOUND)

# The server's HTTP layer: Boost.Beast over Asio, header-only (chosen by
# measurement, docs/server-http-layer.md). Debian's default Boost: 1.81's -dev
# package conflicts with the 1.74 one GDAL's and CGAL's -dev packages need.
find_package(Boost 1.74 QUIET)
tinsmith_require("Boost 1.74 (Beast, Asio)" libboost-dev Boost_FOUND)
find_package(ZLIB QUIET)
tinsmith_require("zlib" zlib1g-dev ZLIB_FOUND)
pkg_check_modules(BROTLIENC QUIET IMPORTED_TARGET libbrotlienc)
tinsmith_require("brotli (encoder)" libbrotli-dev BROTLIENC_FOUND)

if(TINSMITH_TESTS)
  find_package(GTest QUIET)
  tinsmith_require("GoogleTest" "libgtest-dev libgmock-dev" GTest_FOUND)
endif()
if(TINSMITH_BENCHMARKS)
  find_package(benchmark QUIET)
  tinsmith_require("Google Benchmark" libbenchmark-dev benchmark_FOUND)
  # CGAL is the reference the CDT benchmark measures against; optional.
  find_package(CGAL 5 QUIET)
  if(CGAL_FOUND)
    message(STATUS "CGAL ${CGAL_VERSION} found: CDT benchmarks compare against it")
  else()
    message(STATUS "CGAL not found (apt-get install libcgal-dev): CDT benchmarks run without the reference")
  endif()
endif()
