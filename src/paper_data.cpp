// Paper 1's Tables 2, 4 and 6 (see src/paper_data.hpp). Transcribed from
// paper_repro/data/table{2_samples,4_four_corner,6_two_corner}.csv; tests/test_synthetic_targets
// compares every field with those files.
#include "src/paper_data.hpp"

#include <stdexcept>
#include <string>

namespace knitsim {

const std::vector<PaperSample>& paper_samples() {
  // sample, g/m^2, k N/m, L0 m, eps %, c N s/m, topology, Table 4 error %, Table 6 error %
  static const std::vector<PaperSample> samples = {
      {1, 41.65, 852.0, 0.049, 5.0, 12.0, 'a', 1.1, 2.5},
      {2, 44.14, 942.0, 0.047, 7.0, 10.0, 'a', 0.7, 2.3},
      {3, 46.76, 988.0, 0.053, 6.0, 10.0, 'a', 0.4, 2.7},
      {4, 44.63, 945.0, 0.040, 5.0, 10.0, 'a', 2.5, 2.7},
      {5, 49.62, 1034.0, 0.049, 7.0, 11.0, 'a', 2.5, 2.2},
      {6, 27.6, 674.0, 0.040, 5.0, 10.0, 'a', 0.3, 2.5},
      {7, 51.16, 1092.0, 0.040, 5.0, 10.0, 'a', 2.2, 2.5},
      {8, 54.41, 1100.0, 0.055, 6.0, 10.0, 'a', 2.6, 2.0},
      {9, 58.26, 1100.0, 0.050, 5.0, 13.0, 'a', 2.4, 2.6},
  };
  return samples;
}

const PaperSample& paper_sample(int sample) {
  const std::vector<PaperSample>& all = paper_samples();
  if (sample < 1 || sample > static_cast<int>(all.size()))
    throw std::invalid_argument("sample = " + std::to_string(sample) + ": must be 1..9");
  return all[sample - 1];
}

}  // namespace knitsim
