// A table of text cells, printable three ways: aligned text for terminals, CSV, Markdown.
#pragma once

#include <string>
#include <vector>

namespace knitsim {

// A table of text cells, printable three ways. Every row has columns.size() cells.
struct Table {
  std::vector<std::string> columns;
  std::vector<std::vector<std::string>> rows;

  std::string text() const;      // columns aligned with two spaces, for terminals
  std::string csv() const;       // RFC 4180: cells holding , " or a newline are quoted
  std::string markdown() const;  // GitHub pipe table
};

}  // namespace knitsim
