#include "src/sparse.hpp"

#include <algorithm>
#include <stdexcept>

namespace knitsim {

int CscPattern::find(int row, int col) const {
  if (col < 0 || col >= cols) return -1;
  auto first = rowind.begin() + colptr[col];
  auto last = rowind.begin() + colptr[col + 1];
  auto it = std::lower_bound(first, last, row);
  return (it != last && *it == row) ? static_cast<int>(it - rowind.begin()) : -1;
}

CscPattern make_csc_pattern(int rows, int cols, std::vector<std::pair<int, int>> entries,
                            bool with_diagonal) {
  if (with_diagonal) {
    if (rows != cols) throw std::logic_error("make_csc_pattern: diagonal needs a square matrix");
    for (int i = 0; i < rows; ++i) entries.emplace_back(i, i);
  }
  for (const auto& [r, c] : entries)
    if (r < 0 || r >= rows || c < 0 || c >= cols)
      throw std::logic_error("make_csc_pattern: entry outside the matrix");
  // Sort by (col, row) and merge duplicates.
  std::sort(entries.begin(), entries.end(), [](const auto& a, const auto& b) {
    return a.second != b.second ? a.second < b.second : a.first < b.first;
  });
  entries.erase(std::unique(entries.begin(), entries.end()), entries.end());

  CscPattern p;
  p.rows = rows;
  p.cols = cols;
  p.colptr.assign(cols + 1, 0);
  p.rowind.reserve(entries.size());
  for (const auto& [r, c] : entries) {
    ++p.colptr[c + 1];
    p.rowind.push_back(r);
  }
  for (int j = 0; j < cols; ++j) p.colptr[j + 1] += p.colptr[j];
  return p;
}

void csc_multiply(const CscPattern& A, const double* values, const double* x, double* y) {
  std::fill(y, y + A.rows, 0.0);
  for (int j = 0; j < A.cols; ++j) {
    const double xj = x[j];
    for (int k = A.colptr[j]; k < A.colptr[j + 1]; ++k) y[A.rowind[k]] += values[k] * xj;
  }
}

}  // namespace knitsim
