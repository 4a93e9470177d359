// Legacy VTK (ASCII, DATASET POLYDATA), opened by ParaView and VisIt.
#pragma once

#include <string>
#include <utility>
#include <vector>

#include "src/core/vec3.hpp"

namespace knitsim {

struct VtkPolyData {
  std::string title;  // one line
  std::vector<Vec3> points;
  std::vector<std::vector<int>> polygons;  // point indices, any number >= 3 per polygon
  std::vector<std::pair<std::string, std::vector<int>>> point_ints;      // SCALARS int
  std::vector<std::pair<std::string, std::vector<Vec3>>> point_vectors;  // VECTORS double
};
std::string to_vtk(const VtkPolyData& data);

}  // namespace knitsim
