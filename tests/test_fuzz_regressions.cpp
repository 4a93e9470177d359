// Every input the fuzzers were seeded with (tests/fuzz/corpus/<target>/) and every input they
// ever found a fault with (tests/fuzz/regressions/<target>/, added with its fix) replayed through
// the same checks as the fuzz targets (tests/fuzz/fuzz_inputs.hpp): the parser accepts or
// rejects with one line of std::invalid_argument, and an accepted input builds and gives finite
// numbers. Also checks that the oracle itself can fail.
#include <catch2/catch.hpp>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "tests/fuzz/fuzz_inputs.hpp"

namespace fs = std::filesystem;
using namespace knitsim::fuzz;

namespace {

std::string slurp(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

// The check of one fuzz target, by its folder name.
const FuzzEntry& entry(const std::string& name) {
  for (const FuzzEntry& e : fuzz_entries())
    if (name == e.name) return e;
  FAIL("no fuzz target named " << name);
  throw;
}

}  // namespace

TEST_CASE("fuzz corpus and regression inputs: accepted or rejected with one line, never worse") {
  const fs::path root = KNITSIM_FUZZ_DIR;
  int replayed = 0, seeds = 0;
  for (const char* set : {"corpus", "regressions"})
    for (const FuzzEntry& e : fuzz_entries()) {
      const fs::path dir = root / set / e.name;
      if (std::string(set) == "corpus") REQUIRE(fs::is_directory(dir));
      if (!fs::is_directory(dir)) continue;  // no regression input for this target (yet)
      for (const auto& file : fs::directory_iterator(dir)) {
        if (!file.is_regular_file() || file.path().filename() == "README.md") continue;
        CAPTURE(file.path().string());
        CHECK_NOTHROW(e.check(slurp(file.path())));
        ++replayed;
        if (std::string(set) == "corpus") ++seeds;
      }
    }
  CHECK(seeds >= 3 * 4);  // the seed corpus is committed: at least 4 files per target
  CHECK(replayed >= seeds);
}

TEST_CASE("the fuzz oracle accepts good input, passes plain rejections, and can fail") {
  CHECK_THROWS_AS(check_rejection_message(""), FuzzFinding);
  CHECK_THROWS_AS(check_rejection_message("line 1\nline 2"), FuzzFinding);
  CHECK_NOTHROW(check_rejection_message("model.stiffness = -1: must be > 0 N/m"));
  // Good inputs are accepted and built.
  CHECK_NOTHROW(entry("chart").check("KKK\nKTK\nKKK\n"));
  CHECK_NOTHROW(entry("scene").check("[model]\nnatural_length = 0.1\n"));
  // Rejections with one line are fine.
  CHECK_NOTHROW(entry("chart").check("KXK\n"));
  CHECK_NOTHROW(entry("scene").check("[model]\nstiffness = nan\n"));
  CHECK_NOTHROW(entry("target").check("scene,edge,kind,a,b\nfour_corner,top,point,1,nan\n"));
  // A TOML key holding a newline is printed as \x0a in the one-line message (it was printed raw
  // before printable()); the check throws FuzzFinding if the message has several lines.
  CHECK_NOTHROW(entry("scene").check("[model]\n\"stiff\\nness\" = 1\n"));
}
