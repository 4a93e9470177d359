// Paper 1's Tables 2, 4 and 6 (see src/paper/paper_data.hpp). Transcribed from
// paper_repro/data/table{2_samples,4_four_corner,6_two_corner}.csv; tests/test_synthetic_targets
// compares every field with those files.
#include "src/paper/paper_data.hpp"

#include <algorithm>
#include <set>
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

namespace {

[[noreturn]] void bad_samples(const std::string& text) {
  throw std::invalid_argument("--samples = " + text +
                              ": accepted a comma-separated list of samples or ranges within "
                              "1..9, e.g. 1-9 or 2,5-7");
}

}  // namespace

std::vector<int> parse_sample_list(const std::string& text) {
  const int count = static_cast<int>(paper_samples().size());
  const auto number = [&](const std::string& s) {
    if (s.empty() || s.size() > 2 || s.find_first_not_of("0123456789") != std::string::npos)
      bad_samples(text);
    const int v = std::stoi(s);
    if (v < 1 || v > count) bad_samples(text);
    return v;
  };
  std::set<int> samples;
  size_t start = 0;
  while (start <= text.size()) {
    const size_t comma = std::min(text.find(',', start), text.size());
    const std::string item = text.substr(start, comma - start);
    const size_t dash = item.find('-');
    const int lo = number(item.substr(0, dash));
    const int hi = dash == std::string::npos ? lo : number(item.substr(dash + 1));
    if (hi < lo) bad_samples(text);
    for (int s = lo; s <= hi; ++s) samples.insert(s);
    start = comma + 1;
  }
  return {samples.begin(), samples.end()};
}

}  // namespace knitsim
