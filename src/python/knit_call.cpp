#include "src/python/knit_call.hpp"

#include <algorithm>
#include <stdexcept>

#include "src/base/files.hpp"
#include "src/base/text.hpp"
#include "src/io/knit_outputs.hpp"
#include "src/io/textile_outputs.hpp"
#include "src/python/drape_call.hpp"

namespace knitsim {

bool is_knit_scene_path(const std::string& path) {
  const std::string ext = ".toml";
  return path.size() > ext.size() && path.compare(path.size() - ext.size(), ext.size(), ext) == 0;
}

KnitChart read_knit_input(const std::string& chart_or_scene,
                          const std::vector<std::string>& overrides, Scene& input) {
  // As the commands' run(): the chart is read before the --set keys apply.
  if (!is_knit_scene_path(chart_or_scene)) {
    KnitChart chart = read_knit_chart(knit_scene(chart_or_scene, {}));
    input = knit_scene(chart_or_scene, overrides);
    return chart;
  }
  input = load_knit_scene(chart_or_scene, overrides);
  return read_knit_chart(input);
}

std::shared_ptr<KnitCall> knit_call(const KnitRequest& request, const std::atomic<bool>* cancel,
                                    RunObserver* observer) {
  // As cmd_knit.cpp's run().
  Scene input;
  KnitChart chart = read_knit_input(request.chart_or_scene, request.overrides, input);
  bool velocity_atol_given = false;
  for (const auto& [name, value] : request.run_options) {
    apply_run_option(input.options, name, value);
    velocity_atol_given = velocity_atol_given || name == "velocity_atol";
  }
  const std::string integrator = request.integrator.empty()
                                     ? default_knit_integrator(input.knit.yarn_contact())
                                     : request.integrator;
  std::unique_ptr<Integrator> integ;
  try {
    integ = make_integrator(integrator);
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(std::string("--") + e.what());  // "--integrator = X: ..."
  }
  if (!velocity_atol_given)
    set_default_knit_velocity_atol(input.options, input.knit, integ->info());
  input.validate();
  if (request.frames < 1)
    throw std::invalid_argument("--frames = " + std::to_string(request.frames) + ": must be >= 1");

  auto call = std::make_shared<KnitCall>();
  call->scene = make_knit_scene(input, std::move(chart), request.frames);
  call->model_keys = knit_model_keys(call->scene.chart, input);
  KnitStart start = start_knit(call->scene);  // validates the parameters

  call->scene.options.interrupt = cancel;
  try {
    call->result =
        std::make_unique<KnitResult>(run_knit(std::move(start), call->scene, integrator, observer));
  } catch (const std::invalid_argument& e) {  // an option the model refuses at the start
    call->scene.options.interrupt = nullptr;
    rethrow_as_typed(e);
  }
  call->scene.options.interrupt = nullptr;  // the flag dies with the call

  const KnitResult& r = *call->result;
  if (std::all_of(r.positions.begin(), r.positions.end(), is_finite)) {
    call->textile = textile_measures(r.model, r.positions);
    call->stitches_csv = stitches_csv(*call->textile);
    call->centerlines = course_centerlines(r.model, r.positions);
  }
  call->summary =
      knit_summary(call->scene, r, knit_frames_json(r), call->textile ? &*call->textile : nullptr);
  return call;
}

std::string write_knit_call(const KnitCall& call, const std::string& folder, bool pictures) {
  const std::filesystem::path dir = make_output_dir(folder, "knit-" + call.scene.name);
  remove_stale_output(dir / "steps.csv");
  write_knit_outputs(dir, call.scene, *call.result, call.model_keys, pictures);
  return dir.string();
}

}  // namespace knitsim
