#include "src/core/sparse.hpp"

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
                            bool with_diagonal, std::vector<int>* position) {
  const size_t named = entries.size();  // the caller's pairs, before the diagonal
  if (with_diagonal) {
    if (rows != cols) throw std::logic_error("make_csc_pattern: diagonal needs a square matrix");
    for (int i = 0; i < rows; ++i) entries.emplace_back(i, i);
  }
  for (const auto& [r, c] : entries)
    if (r < 0 || r >= rows || c < 0 || c >= cols)
      throw std::logic_error("make_csc_pattern: entry outside the matrix");
  // Bucket the pairs by column (counting sort), then keep each row once per column (a marker
  // per row) and sort the column's few distinct rows: O(entries + sum of k log k over columns),
  // not one comparison sort of all pairs, since every drape of a fit builds its patterns.
  std::vector<int> start(cols + 1, 0);
  for (const auto& e : entries) ++start[e.second + 1];
  for (int j = 0; j < cols; ++j) start[j + 1] += start[j];
  std::vector<int> bucket(entries.size());  // pair indices, by column
  {
    std::vector<int> next(start.begin(), start.end() - 1);
    for (size_t k = 0; k < entries.size(); ++k)
      bucket[next[entries[k].second]++] = static_cast<int>(k);
  }

  CscPattern p;
  p.rows = rows;
  p.cols = cols;
  p.colptr.assign(cols + 1, 0);
  p.rowind.reserve(entries.size());
  std::vector<int> seen_in(rows, -1);        // the last column that listed this row
  std::vector<int> at(position ? rows : 0);  // a row's index in the column being built
  if (position) position->assign(named, -1);
  for (int j = 0; j < cols; ++j) {
    for (int k = start[j]; k < start[j + 1]; ++k) {
      const int r = entries[bucket[k]].first;
      if (seen_in[r] == j) continue;
      seen_in[r] = j;
      p.rowind.push_back(r);
    }
    std::sort(p.rowind.begin() + p.colptr[j], p.rowind.end());
    p.colptr[j + 1] = static_cast<int>(p.rowind.size());
    if (!position) continue;
    for (int e = p.colptr[j]; e < p.colptr[j + 1]; ++e) at[p.rowind[e]] = e;
    for (int k = start[j]; k < start[j + 1]; ++k)
      if (static_cast<size_t>(bucket[k]) < named)
        (*position)[bucket[k]] = at[entries[bucket[k]].first];
  }
  return p;
}

CscPattern expand_node_pattern(const CscPattern& nodes) {
  CscPattern p;
  p.rows = 3 * nodes.rows;
  p.cols = 3 * nodes.cols;
  p.colptr.assign(p.cols + 1, 0);
  p.rowind.resize(9 * static_cast<size_t>(nodes.nnz()));
  for (int c = 0; c < nodes.cols; ++c)
    for (int q = 0; q < 3; ++q) {
      for (int e = nodes.colptr[c]; e < nodes.colptr[c + 1]; ++e)
        for (int r = 0; r < 3; ++r)
          p.rowind[node_block_entry(nodes, e, c, r, q)] = 3 * nodes.rowind[e] + r;
      p.colptr[3 * c + q + 1] = node_block_entry(nodes, nodes.colptr[c + 1], c, 0, q);
    }
  return p;
}

void csc_multiply(const CscPattern& A, const double* values, const double* x, double* y) {
  std::fill(y, y + A.rows, 0.0);
  for (int j = 0; j < A.cols; ++j) {
    const double xj = x[j];
    for (int k = A.colptr[j]; k < A.colptr[j + 1]; ++k) y[A.rowind[k]] += values[k] * xj;
  }
}

bool has_node_triples(const CscPattern& p) {
  if (p.cols % 3 != 0) return false;
  for (int j = 0; j < p.cols; j += 3) {
    const int count = p.colptr[j + 1] - p.colptr[j];
    for (int d = 1; d < 3; ++d) {
      if (p.colptr[j + d + 1] - p.colptr[j + d] != count) return false;
      if (!std::equal(p.rowind.begin() + p.colptr[j], p.rowind.begin() + p.colptr[j + 1],
                      p.rowind.begin() + p.colptr[j + d]))
        return false;
    }
  }
  return true;
}

}  // namespace knitsim
