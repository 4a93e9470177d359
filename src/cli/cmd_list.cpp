// knitsim list integrators|scenes|keys (docs/commands.md): what the registry, the built-in scenes
// and the scene files offer. --format markdown is what docs/generate_reference.sh commits.
#include <CLI/CLI.hpp>
#include <iostream>
#include <memory>

#include "src/base/table.hpp"
#include "src/cli/commands.hpp"
#include "src/scene/scene.hpp"

namespace knitsim {

namespace {

Table integrators_table() {
  Table t;
  t.columns = {"name", "order", "adaptive", "explicit", "description"};
  for (const IntegratorInfo& info : integrator_catalog())
    t.rows.push_back({info.name, info.order > 0 ? std::to_string(info.order) : "variable",
                      info.adaptive ? "yes" : "no", info.explicit_method ? "yes" : "no",
                      info.description});
  return t;
}

Table scenes_table() {
  Table t;
  t.columns = {"name", "description"};
  for (const auto& [name, text] : builtin_scenes())
    t.rows.push_back({name, scene_description(text)});
  return t;
}

}  // namespace

void register_list_command(CLI::App& app) {
  auto what = std::make_shared<std::string>();
  auto format = std::make_shared<std::string>("text");
  CLI::App* cmd = app.add_subcommand(
      "list", "List the integrators, the built-in scenes or the scene keys (units, defaults, "
              "accepted values)");
  cmd->add_option("what", *what, "integrators | scenes | keys")
      ->required()
      ->check(CLI::IsMember({"integrators", "scenes", "keys"}));
  cmd->add_option("--format", *format, "text | csv | markdown")
      ->capture_default_str()
      ->check(CLI::IsMember({"text", "csv", "markdown"}));
  cmd->callback([what, format] {
    const Table t = *what == "integrators" ? integrators_table()
                    : *what == "scenes"    ? scenes_table()
                                           : scene_key_table();
    std::cout << (*format == "csv" ? t.csv() : *format == "markdown" ? t.markdown() : t.text());
  });
}

}  // namespace knitsim
