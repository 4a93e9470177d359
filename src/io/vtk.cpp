#include "src/io/vtk.hpp"

#include "src/base/text.hpp"

namespace knitsim {

std::string to_vtk(const VtkPolyData& d) {
  // %.<digits>g as a stream at that precision wrote them, through std::to_chars.
  std::string os;
  os.reserve(64 * d.points.size() * (1 + d.point_vectors.size()) + 32 * d.cells.size() + 256);
  const auto line = [&os](const std::string& head, long long a, const char* tail) {
    os += head;
    append_integer(os, a);
    os += tail;
  };
  const auto number = [&os, &d](double v) {
    if (d.digits > 0)
      append_general(os, v, d.digits);
    else
      append_number(os, v);
  };
  const auto xyz = [&os, &number](const Vec3& p) {
    number(p.x);
    os += ' ';
    number(p.y);
    os += ' ';
    number(p.z);
    os += '\n';
  };
  os += "# vtk DataFile Version 3.0\n" + d.title + "\nASCII\nDATASET POLYDATA\n";
  line("POINTS ", static_cast<long long>(d.points.size()), " double\n");
  for (const Vec3& p : d.points) xyz(p);
  size_t size = 0;
  for (const auto& cell : d.cells) size += cell.size() + 1;
  line(d.kind == VtkPolyData::Cells::Lines ? "LINES " : "POLYGONS ",
       static_cast<long long>(d.cells.size()), " ");
  line("", static_cast<long long>(size), "\n");
  for (const auto& cell : d.cells) {
    append_integer(os, static_cast<long long>(cell.size()));
    for (int i : cell) line(" ", i, "");
    os += '\n';
  }
  const auto ints = [&os, &line](const std::string& name, const std::vector<int>& values) {
    os += "SCALARS " + name + " int 1\nLOOKUP_TABLE default\n";
    for (int v : values) line("", v, "\n");
  };
  if (!d.point_ints.empty() || !d.point_vectors.empty())
    line("POINT_DATA ", static_cast<long long>(d.points.size()), "\n");
  for (const auto& [name, values] : d.point_ints) ints(name, values);
  for (const auto& [name, values] : d.point_vectors) {
    os += "VECTORS " + name + " double\n";
    for (const Vec3& v : values) xyz(v);
  }
  if (!d.cell_ints.empty()) line("CELL_DATA ", static_cast<long long>(d.cells.size()), "\n");
  for (const auto& [name, values] : d.cell_ints) ints(name, values);
  return os;
}

}  // namespace knitsim
