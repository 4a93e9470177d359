// A periodic-cell run of the yarn model (knit.model = yarn, knit.boundary = periodic;
// models/yarn_cell.hpp, docs/yarn_model.md "Periodic cell"): the chart is one repeat of a fabric
// without edges; its cell starts from paper 2's structure (build_yarn_cell_start), its rest
// lengths are ramped to the knitted stitch length in knit.yarn_ramp stages, each relaxed to its
// steady state by the run's integrator with the cell's width and height free (or one of them
// held: a tensile step), and the relaxed dimensions are read off the cell.
//
// Failure modes: bad input throws std::invalid_argument (one line); a stage that does not reach
// its steady state ends the run with that stage's status (the later stages are not run).
#pragma once

#include <array>
#include <memory>
#include <string>
#include <vector>

#include "models/yarn_cell.hpp"
#include "solvers/integrator.hpp"

namespace knitsim {

// The state of a cell: per course its vertices, and its size, m.
struct YarnCellState {
  std::vector<std::vector<Vec3>> courses;
  double width = 0.0, height = 0.0;
};

struct YarnCellRun {
  std::shared_ptr<const YarnCellStart> start;
  struct Stage {
    RunStatus status = RunStatus::SolverFailure;
    long steps = 0;
    double residual = 0.0, cpu_seconds = 0.0, wall_seconds = 0.0;
    double width = 0.0, height = 0.0;  // at the stage's end, m
  };
  std::vector<Stage> stages;
  RunStats stats;     // the last stage's, its steps the run's; cpu and wall the run's
  YarnCellState end;  // at the end
  int dof = 0;
  // Least distance over the pairs the contact sees, in d: at the start, at the end, and over
  // every residual check of every stage.
  double clearance_start_over_d = 0.0, clearance_end_over_d = 0.0, clearance_min_over_d = 0.0;
  int clearance_checks = 0;
  std::vector<double> course_knitted, course_end;  // per course, m
  std::array<double, 2> size_gradient{0.0, 0.0};   // dE/dW, dE/dH at the end, N per cell
  // The relaxed fabric: W, H; per cm; yarn per loop (the repeat's mean knitted cell length),
  // the dimensional constants K_c = courses/cm x l (cm), K_w, K_s = K_c K_w, R = K_c / K_w.
  double courses_per_cm = 0.0, wales_per_cm = 0.0, stitch_length = 0.0;
  double k_c = 0.0, k_w = 0.0, k_s = 0.0, r = 0.0;
};

// Runs the cell: from `from` (null: the start, and the ramp's stages from the first) with the
// size mode `size` (held lengths kept at from's, or the start's); `ramp` false runs only the
// last stage (the knitted lengths), e.g. a tensile step from a relaxed state.
YarnCellRun run_yarn_cell(std::shared_ptr<const YarnCellStart> start, const std::string& integrator,
                          const IntegratorOptions& options, RunObserver* observer = nullptr,
                          const YarnCellState* from = nullptr, CellSize size = CellSize::Free,
                          bool ramp = true);

// A tensile test on a relaxed cell: the length along `direction` (x: the courses, W held; y: the
// wales, H held) stretched from `relaxed` to strain `strain` in steps of at most 0.01 (each step
// the state stretched affinely along it, which only moves points apart, then relaxed with the
// other length free). Per step: the strain, the reaction per cell dE/dW or dE/dH (N), the force
// per rest width (N/m: over H0 pulling along the courses, over W0 along the wales), the lateral
// strain of the free length, the status, steps and CPU seconds. Stops at a step that does not
// reach equilibrium.
// Throws InvalidField "knit.cell_strain = <v>: must be in [0.01, 1]" unless strain is in range.
void check_cell_strain(double strain);

struct YarnCellPull {
  bool along_courses = true;
  std::vector<double> strain, reaction, force_per_width, lateral_strain, cpu_seconds;
  std::vector<RunStatus> status;
  std::vector<long> steps;
};
YarnCellPull pull_yarn_cell(std::shared_ptr<const YarnCellStart> start,
                            const std::string& integrator, const IntegratorOptions& options,
                            const YarnCellState& relaxed, bool along_courses, double strain);

}  // namespace knitsim
