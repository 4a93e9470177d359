// knitsim list integrators|scenes (SPEC 2.10): what the registry and the built-in scenes offer.
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
  CLI::App* cmd = app.add_subcommand("list", "List the integrators or the built-in scenes");
  cmd->add_option("what", *what, "integrators | scenes")
      ->required()
      ->check(CLI::IsMember({"integrators", "scenes"}));
  cmd->callback([what] {
    std::cout << (*what == "integrators" ? integrators_table() : scenes_table()).text();
  });
}

}  // namespace knitsim
