// The files of a periodic-cell run (knit.model = yarn, knit.boundary = periodic;
// docs/yarn_model.md, "Periodic cell"): summary.json with the `cell` block (relaxed size,
// courses and wales per cm, the dimensional constants, clearance, yarn length kept, the stages),
// cell_yarn.csv (the relaxed yarn: course, vertex, x, y, z in m, one period of each course) and
// manifest.json; with a tensile test, its `pull` block and cell_pull.csv (one row a step).
#pragma once

#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>

#include "src/scene/yarn_cell_run.hpp"

namespace knitsim {

// summary.json's content for a cell run (without units and provenance).
// `pull`: the tensile test's steps (null: none), as summary.json's `pull` block.
nlohmann::json yarn_cell_summary(const YarnCellRun& run, const std::string& integrator,
                                 const YarnCellPull* pull = nullptr);
// Writes summary.json, cell_yarn.csv and manifest.json (last) into dir; `options` goes into the
// manifest as given.
void write_yarn_cell_outputs(const std::filesystem::path& dir, const YarnCellRun& run,
                             const std::string& integrator, const nlohmann::json& options,
                             const YarnCellPull* pull = nullptr);

}  // namespace knitsim
