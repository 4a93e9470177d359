#include "src/io/vtk.hpp"

#include <sstream>

namespace knitsim {

std::string to_vtk(const VtkPolyData& d) {
  std::ostringstream os;
  os.precision(10);
  os << "# vtk DataFile Version 3.0\n" << d.title << "\nASCII\nDATASET POLYDATA\n";
  os << "POINTS " << d.points.size() << " double\n";
  for (const Vec3& p : d.points) os << p.x << " " << p.y << " " << p.z << "\n";
  size_t size = 0;
  for (const auto& poly : d.polygons) size += poly.size() + 1;
  os << "POLYGONS " << d.polygons.size() << " " << size << "\n";
  for (const auto& poly : d.polygons) {
    os << poly.size();
    for (int i : poly) os << " " << i;
    os << "\n";
  }
  if (!d.point_ints.empty() || !d.point_vectors.empty())
    os << "POINT_DATA " << d.points.size() << "\n";
  for (const auto& [name, values] : d.point_ints) {
    os << "SCALARS " << name << " int 1\nLOOKUP_TABLE default\n";
    for (int v : values) os << v << "\n";
  }
  for (const auto& [name, values] : d.point_vectors) {
    os << "VECTORS " << name << " double\n";
    for (const Vec3& v : values) os << v.x << " " << v.y << " " << v.z << "\n";
  }
  return os.str();
}

}  // namespace knitsim
