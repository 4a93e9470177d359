#include "src/io/manifest.hpp"

#include <CLI/Version.hpp>
#include <ctime>
#include <nlohmann/json.hpp>

#include "solvers/integrator.hpp"
#include "src/base/command_line.hpp"
#include "src/base/files.hpp"
#include "src/parallel/work_units.hpp"
#include "src/render/render.hpp"

// KNITSIM_GIT_COMMIT: the commit this binary was built from (generated at every build by
// src/io/git_commit.cmake); the rest set by CMakeLists.txt on this file only (configure-time
// facts).
#if __has_include("knitsim_git_commit.hpp")
#include "knitsim_git_commit.hpp"
#endif
#ifndef KNITSIM_GIT_COMMIT
#define KNITSIM_GIT_COMMIT "unknown"
#endif
#ifndef KNITSIM_VERSION
#define KNITSIM_VERSION "unknown"
#endif
#ifndef KNITSIM_BUILD_TYPE
#define KNITSIM_BUILD_TYPE "unknown"
#endif
#ifndef KNITSIM_SUNDIALS_VERSION
#define KNITSIM_SUNDIALS_VERSION "unknown"
#endif
#ifndef KNITSIM_EIGEN_VERSION
#define KNITSIM_EIGEN_VERSION "unknown"
#endif
#ifndef KNITSIM_TOMLPP_VERSION
#define KNITSIM_TOMLPP_VERSION "unknown"
#endif

namespace knitsim {


std::string version_string() {
  return std::string("knitsim ") + KNITSIM_VERSION + " (commit " + KNITSIM_GIT_COMMIT + ", " +
         KNITSIM_BUILD_TYPE + ")";
}

nlohmann::json manifest(const nlohmann::json& options) {
#if defined(__clang__)
  const std::string compiler = "clang " __clang_version__;
#elif defined(__GNUC__)
  const std::string compiler = "gcc " __VERSION__;
#else
  const std::string compiler = "unknown";
#endif
  const std::string json_version = std::to_string(NLOHMANN_JSON_VERSION_MAJOR) + "." +
                                   std::to_string(NLOHMANN_JSON_VERSION_MINOR) + "." +
                                   std::to_string(NLOHMANN_JSON_VERSION_PATCH);
  return {{"program", "knitsim"},
          {"version", KNITSIM_VERSION},
          {"git_commit", KNITSIM_GIT_COMMIT},
          {"build_type", KNITSIM_BUILD_TYPE},
          {"command", command_name()},
          {"command_line", command_line()},
          {"created_utc", utc_stamp()},
          {"options", options},
          {"libraries",
           {{"sundials", KNITSIM_SUNDIALS_VERSION},
            {"eigen", KNITSIM_EIGEN_VERSION},
            {"cairo", render_library_version()},
            {"tomlplusplus", KNITSIM_TOMLPP_VERSION},
            {"cli11", CLI11_VERSION},
            {"suitesparse", suitesparse_version()},
            {"mpi", mpi_library_version()},
            {"nlohmann_json", json_version}}},
          {"compiler", compiler}};
}

}  // namespace knitsim
