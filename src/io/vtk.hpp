// Legacy VTK (ASCII, DATASET POLYDATA), opened by ParaView and VisIt: the one VTK writer of every
// command (drape.vtk: a grid of quads; knit's centerlines.vtk: one polyline per course).
#pragma once

#include <string>
#include <utility>
#include <vector>

#include "src/core/vec3.hpp"

namespace knitsim {

struct VtkPolyData {
  enum class Cells { Polygons, Lines };
  std::string title;  // one line
  std::vector<Vec3> points;
  Cells kind = Cells::Polygons;        // POLYGONS (>= 3 points each) or LINES (polylines)
  std::vector<std::vector<int>> cells;  // point indices of each cell; the section is always written
  std::vector<std::pair<std::string, std::vector<int>>> point_ints;      // SCALARS int
  std::vector<std::pair<std::string, std::vector<Vec3>>> point_vectors;  // VECTORS double
  std::vector<std::pair<std::string, std::vector<int>>> cell_ints;       // SCALARS int, per cell
  // Significant digits of the coordinates (%.<digits>g); 0: the shortest text that reads back as
  // the same double.
  int digits = 10;
};
std::string to_vtk(const VtkPolyData& data);

}  // namespace knitsim
