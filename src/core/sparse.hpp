// Compressed sparse column (CSC) patterns, built once and refilled many times.
//
// Storage order (the same as SUNDIALS' CSC_MAT and Eigen's default ColMajor): column j owns
// the entries colptr[j] .. colptr[j+1]-1; their row indices are in rowind, sorted ascending
// within each column. Values live outside the pattern (a plain array of nnz doubles) so a
// pattern can be shared between many value arrays.
#pragma once

#include <cstdint>
#include <utility>
#include <vector>

namespace knitsim {

struct CscPattern {
  int rows = 0;
  int cols = 0;
  std::vector<int> colptr;  // cols + 1 entries
  std::vector<int> rowind;  // nnz entries

  int nnz() const { return colptr.empty() ? 0 : colptr.back(); }
  // Position of (row, col) in the value array, or -1 if the entry is not in the pattern.
  // O(log(entries in column)); for set-up only, never in a hot loop.
  int find(int row, int col) const;
};

// Builds a pattern from (row, col) pairs (duplicates merged). With `with_diagonal`, every
// diagonal entry of a square pattern is present even if no pair names it: SUNDIALS 6.4
// pays O(n^2) in I - gamma*J when a diagonal entry is missing. With `position`, also where
// each pair landed: (*position)[k] is pair k's index in the value array (what find() returns).
CscPattern make_csc_pattern(int rows, int cols, std::vector<std::pair<int, int>> entries,
                            bool with_diagonal, std::vector<int>* position = nullptr);

// The pattern of 3x3 blocks over a pattern of nodes: node entry (r, c) becomes the 9 entries
// (3r+p, 3c+q), p, q in 0..2. Built from the node pattern in O(nnz): a spring network's Jacobian
// from its ends' pairs, 9 times fewer pairs to sort than its entries.
CscPattern expand_node_pattern(const CscPattern& nodes);

// Position in expand_node_pattern(nodes) of the entry (3r+p, 3c+q), where e = nodes.find(r, c).
inline int node_block_entry(const CscPattern& nodes, int e, int c, int p, int q) {
  const int first = nodes.colptr[c], count = nodes.colptr[c + 1] - first;
  return 9 * first + 3 * q * count + 3 * (e - first) + p;
}

// y = A x for a CSC matrix (pattern + values).
void csc_multiply(const CscPattern& A, const double* values, const double* x, double* y);

// True if the columns come in triples 3p, 3p+1, 3p+2 with identical row lists: a spring
// network whose unknowns are every particle's x, y, z (false on a mirror-reduced drape, whose
// mirror-plane particles keep 1 or 2 coordinates).
bool has_node_triples(const CscPattern& p);

}  // namespace knitsim
