// Superseded by core/geometry/spatial_sort.hpp, which holds every spatial
// sort; kept only until its last includer moves.
#pragma once

#include "core/geometry/spatial_sort.hpp"
