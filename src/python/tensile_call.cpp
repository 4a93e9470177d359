#include "src/python/tensile_call.hpp"

#include <optional>
#include <stdexcept>

#include "src/base/files.hpp"
#include "src/base/text.hpp"
#include "src/io/tensile_outputs.hpp"
#include "src/python/drape_call.hpp"
#include "src/python/knit_call.hpp"

namespace knitsim {

std::shared_ptr<TensileCall> tensile_call(const TensileRequest& request,
                                          const std::atomic<bool>* cancel,
                                          RunObserver* observer) {
  // As cmd_tensile.cpp's run(): the chart is read before the --set keys apply; everything is
  // checked before the run.
  Scene input;
  KnitChart chart = read_knit_input(request.chart_or_scene, request.overrides, input);
  for (const auto& [name, value] : request.run_options)
    apply_run_option(input.options, name, value);
  input.validate();
  request.test.validate();

  KnitScene scene = make_knit_scene(input, std::move(chart), 1);
  tensile_specimen(scene.chart, request.test, scene.params);
  if (scene.params.pins != KnitPins::None || !scene.params.clamps.empty())
    throw std::invalid_argument(
        std::string(scene.params.pins != KnitPins::None ? "knit.pins" : "knit.clamps") +
        ": tensile clamps the specimen itself (--direction); leave knit.pins and knit.clamps "
        "unset");

  scene.options.interrupt = cancel;
  std::optional<TensileResult> result;
  try {
    result.emplace(run_tensile(scene, request.test, observer));
  } catch (const std::invalid_argument& e) {  // an option the model refuses at the start
    rethrow_as_typed(e);
  }
  scene.options.interrupt = nullptr;  // the flag dies with the call
  std::string csv = tensile_csv(*result);
  nlohmann::json summary = tensile_summary(scene, request.test, *result);
  auto call = std::make_shared<TensileCall>(TensileCall{
      std::move(scene), request.test, std::move(*result), std::move(csv), std::move(summary)});
  return call;
}

std::string write_tensile_call(const TensileCall& call, const std::string& folder,
                               bool pictures) {
  const std::filesystem::path dir = make_output_dir(folder, "tensile-" + call.scene.name);
  write_tensile_outputs(dir, call.scene, call.test, call.result, pictures);
  return dir.string();
}

}  // namespace knitsim
