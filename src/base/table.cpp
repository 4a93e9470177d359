#include "src/base/table.hpp"

#include <algorithm>
#include <sstream>

namespace knitsim {

std::string Table::text() const {
  std::vector<size_t> width(columns.size());
  for (size_t c = 0; c < columns.size(); ++c) width[c] = columns[c].size();
  for (const auto& row : rows)
    for (size_t c = 0; c < row.size() && c < width.size(); ++c)
      width[c] = std::max(width[c], row[c].size());
  std::ostringstream os;
  auto line = [&](const std::vector<std::string>& cells) {
    std::string s;
    for (size_t c = 0; c < cells.size(); ++c) {
      s += cells[c];
      if (c + 1 < cells.size()) s += std::string(width[c] - cells[c].size() + 2, ' ');
    }
    os << s << "\n";
  };
  line(columns);
  for (const auto& row : rows) line(row);
  return os.str();
}

std::string Table::csv() const {
  auto cell = [](const std::string& s) {
    if (s.find_first_of(",\"\n") == std::string::npos) return s;
    std::string q = "\"";
    for (char ch : s) q += ch == '"' ? std::string("\"\"") : std::string(1, ch);
    return q + "\"";
  };
  std::ostringstream os;
  auto line = [&](const std::vector<std::string>& cells) {
    for (size_t c = 0; c < cells.size(); ++c) os << (c ? "," : "") << cell(cells[c]);
    os << "\n";
  };
  line(columns);
  for (const auto& row : rows) line(row);
  return os.str();
}

std::string Table::markdown() const {
  std::ostringstream os;
  auto line = [&](const std::vector<std::string>& cells) {
    os << "|";
    for (const std::string& c : cells) os << " " << c << " |";
    os << "\n";
  };
  line(columns);
  os << "|";
  for (size_t c = 0; c < columns.size(); ++c) os << "---|";
  os << "\n";
  for (const auto& row : rows) line(row);
  return os.str();
}

}  // namespace knitsim
