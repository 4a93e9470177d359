// The C++ side of the Python module's overhead benchmark (experiments/python/README.md): the
// sweep knitsim.drape runs from Python, run here by calling the module's own entry point
// (src/python/drape_call.hpp) in a loop -- the same requests, the same results built (the run,
// its measured edges and summary.json), no files written -- so that the Python loop's extra time
// is the binding's overhead.
//
//   knitsim_python_bench [--runs N] [--threads T]
//
// Runs N four_corner drapes with model.stiffness evenly from 500 to 1200 N/m (the fit box of
// paper 1's Table 3), split over T threads (run k on thread k mod T), and prints one line of JSON:
// {"runs": N, "threads": T, "seconds": wall time of the loop, "cpu_seconds": the process's CPU
// time over it (all threads), "sag_sum": sum of the centre sags}.
#include <chrono>
#include <ctime>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <thread>
#include <vector>

#include "src/base/text.hpp"
#include "src/python/drape_call.hpp"

namespace {

// The k-th stiffness of an N-run sweep, as the Python driver writes it (repr of the float).
std::string stiffness(int k, int n) {
  return knitsim::format_number(500.0 + 700.0 * k / (n > 1 ? n - 1 : 1), 17);
}

}  // namespace

int main(int argc, char** argv) {
  int runs = 1000, threads = 1;
  for (int i = 1; i + 1 < argc; i += 2) {
    if (!std::strcmp(argv[i], "--runs")) runs = std::atoi(argv[i + 1]);
    else if (!std::strcmp(argv[i], "--threads")) threads = std::atoi(argv[i + 1]);
  }
  if (runs < 1 || threads < 1 || argc % 2 != 1) {
    std::fprintf(stderr, "usage: knitsim_python_bench [--runs N >= 1] [--threads T >= 1]\n");
    return 2;
  }
  std::vector<double> sags(runs);
  const std::clock_t cpu_start = std::clock();
  const auto start = std::chrono::steady_clock::now();
  std::vector<std::thread> pool;
  for (int t = 0; t < threads; ++t)
    pool.emplace_back([t, threads, runs, &sags] {
      for (int k = t; k < runs; k += threads) {
        knitsim::DrapeRequest request;
        request.overrides = {"model.stiffness=" + stiffness(k, runs)};
        sags[k] = knitsim::drape_call(request).result.centre_sag;
      }
    });
  for (std::thread& th : pool) th.join();
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  const double cpu = static_cast<double>(std::clock() - cpu_start) / CLOCKS_PER_SEC;
  double sum = 0.0;
  for (double s : sags) sum += s;
  std::printf(
      "{\"runs\": %d, \"threads\": %d, \"seconds\": %.6f, \"cpu_seconds\": %.6f, "
      "\"sag_sum\": %.17g}\n",
      runs, threads, seconds, cpu, sum);
  return 0;
}
