// What a knit run writes (docs/knit.md "Outputs"; columns and keys: docs/reference/outputs.md,
// docs/summary_json.md): points.csv, typevalue.csv, centerlines.csv and .vtk, before.png and
// after.png, frames/, summary.json, state.json and manifest.json.
#pragma once

#include <filesystem>
#include <nlohmann/json.hpp>

#include "src/measure/knit_measures.hpp"
#include "src/scene/knit_run.hpp"

namespace knitsim {

// summary.json of a knit run, with its `units` map; `frames` is the list of the captured frames
// (index, check, t, residual, max_displacement_over_r), as write_knit_outputs makes it; its
// `fabric` block from `textile` (the textile measures at the end), measured here if null.
nlohmann::json knit_summary(const KnitScene& scene, const KnitResult& result,
                            const nlohmann::json& frames, const TextileMeasures* textile = nullptr);

// summary.json's `frames` list: the captured frames' index, check, t, residual and
// max_displacement_over_r (what write_knit_outputs writes without writing anything).
nlohmann::json knit_frames_json(const KnitResult& result);

// Writes into `dir` (which must exist):
//   points.csv       id,wale,level,x,y,z,x0,y0,z0: every interlacing point at the end and at rest
//   typevalue.csv    course,loop,k,x,y,z: T0..T8 of every loop at the end (loop = its wale; a
//                    tuck has no T1, T7)
//   centerlines.csv  course,u,x,y,z: each course's NURBS centreline sampled in arc length
//   centerlines.vtk  the same as VTK polylines, one per course (cell data `course`)
//   stitches.csv     the textile measures per chart cell (src/io/textile_outputs.hpp; omitted
//                    for a state that is not finite, when summary.json's `fabric` is null)
//   frames/centerlines_NNN.vtk, frames/frame_NNN.png: the captured frames (result.frames)
//   before.png, after.png: front views at rest and at the end, unless pictures = false
//   summary.json, manifest.json, and state.json (write_run_state, `model_keys` as its model:
//   what a --continue must repeat; omitted if not finite)
// Numbers in the CSV and VTK files are the shortest text that reads back as the same double. A
// state that is not finite (a diverged run) has no centrelines; its points are written as they
// are. PNGs not written and an earlier run's frames are removed from a reused folder.
void write_knit_outputs(const std::filesystem::path& dir, const KnitScene& scene,
                        const KnitResult& result, const nlohmann::json& model_keys,
                        bool pictures = true);

}  // namespace knitsim
