// Paper 1's per-sample data (Mozafary & Payvandy 2017, Tables 2, 4 and 6), compiled in so that
// the binary needs no data files. The committed CSVs under paper_repro/data/ are the
// transcription with provenance; a test checks that these tables equal them value for value.
// Natural lengths are in metres (Table 4 prints millimetres, see paper_repro/data/README.md).
#pragma once

#include <string>
#include <vector>

namespace knitsim {

struct PaperSample {
  int sample = 0;                 // 1..9
  double areal_density = 0.0;     // g/m^2 (Table 2)
  double stiffness = 0.0;         // N/m (Table 4)
  double natural_length = 0.0;    // m (Table 4)
  double elongation_limit = 0.0;  // percent (Table 4)
  double damping = 0.0;           // N s/m (Table 4)
  char topology = 'a';            // Table 4
  double table4_error = 0.0;      // percent, four_corner fit error (Table 4)
  double table6_error = 0.0;      // percent, two_corner error of the same parameters (Table 6)
};

// The 9 samples in order. The paper's Table 6 parameters equal Table 4's.
const std::vector<PaperSample>& paper_samples();
// Sample s (1..9); throws std::invalid_argument "sample = s: must be 1..9".
const PaperSample& paper_sample(int sample);

// A --samples list: comma-separated samples or ranges, e.g. "1-9", "2,5-7" -> the samples in
// increasing order, each once. Throws std::invalid_argument "--samples = <text>: accepted ...".
std::vector<int> parse_sample_list(const std::string& text);

}  // namespace knitsim
