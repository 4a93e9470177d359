// Provenance: the version line and manifest.json, which every output folder holds.
#pragma once

#include <nlohmann/json.hpp>
#include <string>

namespace knitsim {

// "knitsim <version> (commit <hash>, <build type>)", for --version.
std::string version_string();
// manifest.json: program and version, git commit (at build time), build type, command
// (command_name()) and command line, `options` as given, library versions (SUNDIALS, Eigen, cairo,
// toml++, CLI11, nlohmann-json, SuiteSparse, MPI), compiler, UTC creation time. No host or user
// names.
nlohmann::json manifest(const nlohmann::json& options);

}  // namespace knitsim
