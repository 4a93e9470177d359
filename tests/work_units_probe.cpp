// A small MPI program for tests/test_work_units.cpp: runs N toy units with run_work_units and
// prints their results (one JSON array) on rank 0. Each unit's result depends only on its
// index; every rank also logs the indices it ran, one a line, to LOGS/rank<r>.txt.
//   work_units_probe N CHECKPOINT RESUME(0|1) LOGS        (under mpirun or alone)
#include <cmath>
#include <exception>
#include <fstream>
#include <iostream>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "src/parallel/work_units.hpp"

int main(int argc, char** argv) {
  knitsim::ProcessGroup processes(argc, argv);
  if (argc != 5) {
    std::cerr << "usage: work_units_probe N CHECKPOINT RESUME(0|1) LOGS\n";
    return 2;
  }
  const int n = std::stoi(argv[1]);
  std::ofstream log(std::string(argv[4]) + "/rank" + std::to_string(knitsim::process_rank()) +
                    ".txt");
  std::vector<knitsim::WorkUnit> units;
  for (int i = 0; i < n; ++i)
    units.push_back({"u" + std::to_string(i), [i, &log] {
                       log << i << std::endl;
                       double sum = 0.0;  // a partial sum of pi^2 / 6: all 17 digits matter
                       for (int k = 1; k <= 1000 * (i + 1); ++k) sum += 1.0 / (double(k) * k);
                       return nlohmann::json{{"i", i}, {"sum", sum}, {"root", std::sqrt(i + 0.5)}};
                     }});
  knitsim::WorkUnitOptions options;
  options.checkpoint = argv[2];
  options.resume = std::string(argv[3]) == "1";
  options.config = {{"n", n}};
  try {
    const std::vector<nlohmann::json> results = knitsim::run_work_units(units, options);
    if (knitsim::process_rank() == 0) std::cout << nlohmann::json(results).dump() << "\n";
  } catch (const std::exception& e) {
    std::cerr << "work_units_probe: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
