#include "src/io/vtk.hpp"

#include "src/base/text.hpp"

namespace knitsim {

std::string to_vtk(const VtkPolyData& d) {
  // The numbers as a stream at precision 10 wrote them (%.10g), through std::to_chars.
  std::string os;
  os.reserve(64 * d.points.size() * (1 + d.point_vectors.size()) + 32 * d.polygons.size() + 256);
  const auto line = [&os](const std::string& head, long long a, const char* tail) {
    os += head;
    append_integer(os, a);
    os += tail;
  };
  const auto xyz = [&os](const Vec3& p) {
    append_general(os, p.x, 10);
    os += ' ';
    append_general(os, p.y, 10);
    os += ' ';
    append_general(os, p.z, 10);
    os += '\n';
  };
  os += "# vtk DataFile Version 3.0\n" + d.title + "\nASCII\nDATASET POLYDATA\n";
  line("POINTS ", static_cast<long long>(d.points.size()), " double\n");
  for (const Vec3& p : d.points) xyz(p);
  size_t size = 0;
  for (const auto& poly : d.polygons) size += poly.size() + 1;
  line("POLYGONS ", static_cast<long long>(d.polygons.size()), " ");
  line("", static_cast<long long>(size), "\n");
  for (const auto& poly : d.polygons) {
    append_integer(os, static_cast<long long>(poly.size()));
    for (int i : poly) line(" ", i, "");
    os += '\n';
  }
  if (!d.point_ints.empty() || !d.point_vectors.empty())
    line("POINT_DATA ", static_cast<long long>(d.points.size()), "\n");
  for (const auto& [name, values] : d.point_ints) {
    os += "SCALARS " + name + " int 1\nLOOKUP_TABLE default\n";
    for (int v : values) line("", v, "\n");
  }
  for (const auto& [name, values] : d.point_vectors) {
    os += "VECTORS " + name + " double\n";
    for (const Vec3& v : values) xyz(v);
  }
  return os;
}

}  // namespace knitsim
