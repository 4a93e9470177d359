#include "src/output.hpp"

#include <cairo.h>
#include <unistd.h>

#include <CLI/Version.hpp>
#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include "src/cli_options.hpp"
#include "src/lm_fit.hpp"
#include "src/render.hpp"
#include "src/work_units.hpp"

// KNITSIM_GIT_COMMIT: the commit this binary was built from (generated at every build by
// src/git_commit.cmake); the rest set by CMakeLists.txt on this file only (configure-time facts).
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

namespace fs = std::filesystem;

// ---- files and folders -----------------------------------------------------------------------

namespace {

// state.json's "format": bump the number if the layout changes (1: drape only, with the
// integrator, step and parameters in summary.json).
constexpr const char* kRunStateFormat = "knitsim run state 2";

std::string tmp_name(const fs::path& path) { return path.string() + ".tmp"; }

void commit_tmp(const fs::path& path) {
  std::error_code ec;
  fs::rename(tmp_name(path), path, ec);
  if (ec) {
    fs::remove(tmp_name(path), ec);
    throw std::runtime_error("cannot write " + path.string() + ": " + ec.message());
  }
}

std::string local_stamp() {
  const std::time_t now = std::time(nullptr);
  std::tm tm{};
  localtime_r(&now, &tm);
  char buf[32];
  std::strftime(buf, sizeof buf, "%Y%m%d-%H%M%S", &tm);
  return buf;
}

std::string utc_stamp() {
  const std::time_t now = std::time(nullptr);
  std::tm tm{};
  gmtime_r(&now, &tm);
  char buf[32];
  std::strftime(buf, sizeof buf, "%Y-%m-%dT%H:%M:%SZ", &tm);
  return buf;
}

}  // namespace

void write_file_atomic(const fs::path& path, const std::string& content) {
  write_file_atomic_with(path, [&content](const std::string& tmp) {
    std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
    out << content;
    out.close();
    if (!out) throw std::runtime_error(std::strerror(errno));
  });
}

void write_file_atomic_with(const fs::path& path,
                            const std::function<void(const std::string& tmp)>& write) {
  try {
    write(tmp_name(path));
  } catch (const std::exception& e) {
    std::error_code ec;
    fs::remove(tmp_name(path), ec);
    throw std::runtime_error("cannot write " + path.string() + ": " + e.what());
  }
  commit_tmp(path);
}

void write_json_atomic(const fs::path& path, const nlohmann::json& value) {
  write_file_atomic(path, value.dump(2) + "\n");
}

namespace {

// An existing --out folder is reused only by the command that wrote it: its manifest.json
// naming another command (e.g. a fit's folder given to drape) means results this run would
// overwrite or leave mixed with its own. Folders without a manifest, or whose manifest
// predates the "command" field, are reused as before.
void refuse_other_commands_folder(const fs::path& dir, const std::string& requested) {
  std::error_code ec;
  const fs::path path = dir / "manifest.json";
  if (!fs::is_regular_file(path, ec)) return;
  std::ifstream in(path);
  const nlohmann::json m = nlohmann::json::parse(in, nullptr, /*allow_exceptions=*/false);
  if (!m.is_object() || !m.contains("command") || !m["command"].is_string()) return;
  const std::string owner = m["command"].get<std::string>();
  if (owner.empty() || owner == command_name()) return;
  throw std::invalid_argument("--out " + requested + ": holds the results of `knitsim " + owner +
                              "` (its manifest.json); give another folder or remove that one");
}

}  // namespace

fs::path make_output_dir(const std::string& requested, const std::string& stem, bool* created_out) {
  std::error_code ec;
  fs::path dir;
  bool created = false;
  if (requested.empty()) {
    const fs::path parent = "out";
    fs::create_directories(parent, ec);
    if (ec) throw std::invalid_argument("--out (default out/): cannot create out: " + ec.message());
    const std::string base = stem + "-" + local_stamp();
    for (int k = 1; !created; ++k) {
      dir = parent / (k == 1 ? base : base + "-" + std::to_string(k));
      created = fs::create_directory(dir, ec);
      if (ec)
        throw std::invalid_argument("--out " + dir.string() + ": cannot create: " + ec.message());
    }
  } else {
    dir = requested;
    if (fs::exists(dir, ec) && !fs::is_directory(dir, ec))
      throw std::invalid_argument("--out " + requested + ": exists and is not a folder");
    refuse_other_commands_folder(dir, requested);
    created = !fs::exists(dir, ec);
    fs::create_directories(dir, ec);
    if (ec) throw std::invalid_argument("--out " + requested + ": cannot create: " + ec.message());
  }
  const fs::path probe = dir / (".knitsim-probe-" + std::to_string(::getpid()));
  std::ofstream out(probe);
  const int err = errno;
  const bool writable = static_cast<bool>(out);
  out.close();
  fs::remove(probe, ec);
  if (!writable) {
    if (created) fs::remove(dir, ec);
    throw std::invalid_argument("--out " + dir.string() + ": cannot write: " + std::strerror(err));
  }
  if (created_out) *created_out = created;
  return dir;
}

void refuse_fresh_start_over_checkpoint(const std::string& out,
                                        const std::vector<std::string>& checkpoints, bool resume) {
  if (resume || out.empty()) return;
  std::error_code ec;
  for (const std::string& name : checkpoints)
    if (fs::exists(fs::path(out) / name, ec))
      throw std::invalid_argument("--out " + out + ": holds the checkpoint " + name +
                                  " of an earlier run; add --resume to continue it, or remove "
                                  "the file (or give another folder) to start afresh");
}

void remove_stale_output(const fs::path& file) {
  std::error_code ec;
  fs::remove_all(file, ec);
  if (ec) throw std::runtime_error("cannot remove " + file.string() + ": " + ec.message());
}

void remove_if_unused(const fs::path& dir, bool created) {
  std::error_code ec;
  if (created && fs::is_empty(dir, ec) && !ec) fs::remove(dir, ec);
}

// ---- formatting --------------------------------------------------------------------------------

std::string format_number(double value, int digits) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*g", digits, value);
  return buf;
}

std::string linear_algebra_summary(const RunStats& s) {
  if (s.factorisations == 0 || !(s.factor_flops > 0.0)) return "";
  return std::to_string(s.factorisations) + " factorisations of S (" + s.factorization +
         (s.factorization == "supernodal" ? " LL^T, " : " LDL^T, ") +
         format_number(s.factor_flops, 3) + " flops each, " +
         format_number(s.factor_flops * static_cast<double>(s.factorisations) / 1e9, 3) +
         " GFlop in all)";
}

void append_number(std::string& out, double value) {
  char buf[32];  // the longest shortest form, e.g. -2.2250738585072014e-308, has 24 characters
  out.append(buf, std::to_chars(buf, buf + sizeof buf, value).ptr);
}

void append_integer(std::string& out, long long value) {
  char buf[24];
  out.append(buf, std::to_chars(buf, buf + sizeof buf, value).ptr);
}

std::string Table::text() const {
  std::vector<size_t> width(columns.size());
  for (size_t c = 0; c < columns.size(); ++c) width[c] = columns[c].size();
  for (const auto& row : rows)
    for (size_t c = 0; c < row.size() && c < width.size(); ++c)
      width[c] = std::max(width[c], row[c].size());
  std::ostringstream os;
  auto line = [&](const std::vector<std::string>& cells) {
    std::string s;
    for (size_t c = 0; c < cells.size(); ++c) {
      s += cells[c];
      if (c + 1 < cells.size()) s += std::string(width[c] - cells[c].size() + 2, ' ');
    }
    os << s << "\n";
  };
  line(columns);
  for (const auto& row : rows) line(row);
  return os.str();
}

std::string Table::csv() const {
  auto cell = [](const std::string& s) {
    if (s.find_first_of(",\"\n") == std::string::npos) return s;
    std::string q = "\"";
    for (char ch : s) q += ch == '"' ? std::string("\"\"") : std::string(1, ch);
    return q + "\"";
  };
  std::ostringstream os;
  auto line = [&](const std::vector<std::string>& cells) {
    for (size_t c = 0; c < cells.size(); ++c) os << (c ? "," : "") << cell(cells[c]);
    os << "\n";
  };
  line(columns);
  for (const auto& row : rows) line(row);
  return os.str();
}

std::string Table::markdown() const {
  std::ostringstream os;
  auto line = [&](const std::vector<std::string>& cells) {
    os << "|";
    for (const std::string& c : cells) os << " " << c << " |";
    os << "\n";
  };
  line(columns);
  os << "|";
  for (size_t c = 0; c < columns.size(); ++c) os << "---|";
  os << "\n";
  for (const auto& row : rows) line(row);
  return os.str();
}

std::string to_vtk(const VtkPolyData& d) {
  std::ostringstream os;
  os.precision(10);
  os << "# vtk DataFile Version 3.0\n" << d.title << "\nASCII\nDATASET POLYDATA\n";
  os << "POINTS " << d.points.size() << " double\n";
  for (const Vec3& p : d.points) os << p.x << " " << p.y << " " << p.z << "\n";
  size_t size = 0;
  for (const auto& poly : d.polygons) size += poly.size() + 1;
  os << "POLYGONS " << d.polygons.size() << " " << size << "\n";
  for (const auto& poly : d.polygons) {
    os << poly.size();
    for (int i : poly) os << " " << i;
    os << "\n";
  }
  if (!d.point_ints.empty() || !d.point_vectors.empty())
    os << "POINT_DATA " << d.points.size() << "\n";
  for (const auto& [name, values] : d.point_ints) {
    os << "SCALARS " << name << " int 1\nLOOKUP_TABLE default\n";
    for (int v : values) os << v << "\n";
  }
  for (const auto& [name, values] : d.point_vectors) {
    os << "VECTORS " << name << " double\n";
    for (const Vec3& v : values) os << v.x << " " << v.y << " " << v.z << "\n";
  }
  return os.str();
}

// ---- JSON ------------------------------------------------------------------------------------

nlohmann::json to_json(const DrapeParams& p) {
  return {{"width", p.width},
          {"areal_density", p.areal_density},
          {"stiffness", p.stiffness},
          {"damping", p.damping},
          {"elongation_limit", p.elongation_limit},
          {"natural_length", p.natural_length},
          {"topology", std::string(1, p.topology)},
          {"layout", to_string(p.layout)},
          {"pin_span", p.pin_span},
          {"pin_move_time", p.pin_move_time},
          {"perturbation", p.perturbation},
          {"seed", p.seed},
          {"symmetry", to_string(p.symmetry)}};
}

nlohmann::json to_json(const IntegratorOptions& o) {
  return {{"rtol", o.rtol},
          {"atol", o.atol},
          {"velocity_atol", o.velocity_atol},
          {"dt", o.dt},
          {"dt_safety", o.dt_safety},
          {"max_order", o.max_order},
          {"max_steps", o.max_steps},
          {"t_max", o.t_max},
          {"equilibrium_tol", o.equilibrium_tol},
          {"max_wall_seconds", o.max_wall_seconds},
          {"check_every", o.check_every},
          {"runaway_position", o.runaway_position},
          {"max_restarts", o.max_restarts},
          {"newton_solver", to_string(o.newton_solver)},
          {"krylov_dim", o.krylov_dim},
          {"krylov_eps_lin", o.krylov_eps_lin},
          {"gmres_preconditioner", to_string(o.gmres_preconditioner)},
          {"factorization", to_string(o.factorization)}};
}

nlohmann::json to_json(const DrapeLmOptions& o) {
  return {{"starts_per_bracket", o.starts_per_bracket},
          {"refine", o.refine},
          {"seed", o.seed},
          {"max_evaluations", o.lm.max_evaluations},
          {"initial_lambda", o.lm.initial_lambda},
          {"step_tol", o.lm.step_tol},
          {"cost_tol", o.lm.cost_tol}};
}

nlohmann::json to_json(const RunStats& s) {
  return {{"integrator", s.integrator},
          {"status", to_string(s.status)},
          {"message", s.message},
          {"t_final", s.t_final},
          {"residual", s.residual},
          {"residual_floor", s.residual_floor},
          {"dt", s.dt},
          {"dt_predicted", s.dt_predicted},
          {"dt_estimated", s.dt_estimated},
          {"steps", s.steps},
          {"rhs_evals", s.rhs_evals},
          {"jac_evals", s.jac_evals},
          {"lin_setups", s.lin_setups},
          {"factorisations", s.factorisations},
          {"factorization", s.factorization},
          {"ldl_fallbacks", s.ldl_fallbacks},
          {"factor_nonzeros", s.factor_nonzeros},
          {"factor_flops", s.factor_flops},
          {"lin_iters", s.lin_iters},
          {"nonlin_iters", s.nonlin_iters},
          {"nonlin_fails", s.nonlin_fails},
          {"err_test_fails", s.err_test_fails},
          {"restarts", s.restarts},
          {"max_order_used", s.max_order_used},
          {"wall_seconds", s.wall_seconds},
          {"cpu_seconds", s.cpu_seconds}};
}

// ---- provenance --------------------------------------------------------------------------------

namespace {
std::string& command_line_store() {
  static std::string line;
  return line;
}
std::string& command_name_store() {
  static std::string name;
  return name;
}
}  // namespace

const std::string& command_name() { return command_name_store(); }

std::string version_string() {
  return std::string("knitsim ") + KNITSIM_VERSION + " (commit " + KNITSIM_GIT_COMMIT + ", " +
         KNITSIM_BUILD_TYPE + ")";
}

void set_command_line(int argc, const char* const* argv) {
  // knitsim has no options before its subcommand (--help and --version stop there).
  command_name_store() = argc > 1 && argv[1][0] != '-' ? argv[1] : "";
  std::string line;
  for (int i = 0; i < argc; ++i) {
    std::string arg = argv[i];
    const bool plain =
        !arg.empty() && arg.find_first_of(" \t\n'\"\\$`*?;&|<>()") == std::string::npos;
    if (!plain) {  // shell-quoted, so the line can be pasted back
      std::string q = "'";
      for (char ch : arg) q += ch == '\'' ? std::string("'\\''") : std::string(1, ch);
      arg = q + "'";
    }
    line += (i ? " " : "") + arg;
  }
  command_line_store() = line;
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
          {"command_line", command_line_store()},
          {"created_utc", utc_stamp()},
          {"options", options},
          {"libraries",
           {{"sundials", KNITSIM_SUNDIALS_VERSION},
            {"eigen", KNITSIM_EIGEN_VERSION},
            {"cairo", cairo_version_string()},
            {"tomlplusplus", KNITSIM_TOMLPP_VERSION},
            {"cli11", CLI11_VERSION},
            {"suitesparse", suitesparse_version()},
            {"mpi", mpi_library_version()},
            {"nlohmann_json", json_version}}},
          {"compiler", compiler}};
}

// ---- drape outputs -----------------------------------------------------------------------------

nlohmann::json summary_units(const nlohmann::json& model) {
  nlohmann::json units = {
      {"t_start, t_final", "s"},
      {"dt", "s: the fixed step of euler, verlet, implicit-euler; 0 for adaptive integrators"},
      {"dt_estimated, dt_predicted", "s: stability limits of the explicit methods (SPEC 2.4)"},
      {"wall_seconds, cpu_seconds", "s (cpu: this process, all threads)"},
      {"factor_flops", "floating-point operations of one factorisation of S (CHOLMOD's count)"},
      {"factor_nonzeros", "entries of one factor L"},
      {"steps, rhs_evals, jac_evals, lin_setups, lin_iters, nonlin_iters, factorisations",
       "counts"}};
  units.update(model);
  return units;
}

nlohmann::json drape_summary(const Scene& scene, const DrapeResult& r) {
  const SpringNetwork& net = r.grid.network;
  nlohmann::json j = to_json(r.stats);
  j["scene"] = scene.name;
  j["source"] = scene.source;
  j["grid"] = {{"n", r.grid.n},
               {"particles", net.particle_count()},
               {"pinned", net.spec().pinned.size()},
               {"springs", net.spec().springs.size()},
               {"dof", net.dof()},
               {"integrated_dof", r.integrated_dof}};
  j["t_start"] = r.t_start;
  j["max_strain"] = r.max_strain;
  j["centre_sag_m"] = r.centre_sag;
  j["params"] = to_json(scene.params);
  j["options"] = to_json(scene.options);
  j["units"] = summary_units(
      {{"residual, residual_floor",
        "1: the static residual (SPEC 2.3), max over free particles of |spring force + weight| "
        "/ mean particle weight; residual_floor: its round-off bound"},
       {"centre_sag_m", "m"},
       {"max_strain", "1: (L - L0) / L0 of the most stretched spring, a fraction (stdout: %)"},
       {"objective", "%: the Eq. 5 error against --target"},
       {"edge_coefficients",
        "1: p0..p4 of d(s) = sum p_i s^i, s and d lengths divided by the "
        "edge's reference length (edges.csv; src/measurement.hpp)"},
       {"params",
        "width, natural_length, perturbation m; areal_density g/m^2; stiffness N/m; "
        "damping N s/m; elongation_limit %; pin_span a fraction of the width; "
        "pin_move_time s"}});
  return j;
}

namespace {

// drape.png: the oblique view of the final state, pins marked, parameters in the caption.
void write_drape_picture(const fs::path& path, const Scene& scene, const DrapeResult& r,
                         const std::vector<std::array<int, 4>>& quads) {
  const DrapeGrid& g = r.grid;
  const int side = g.n + 1;
  MeshScene mesh;
  mesh.points = r.positions;
  mesh.quads = quads;
  mesh.markers = g.network.spec().pinned;
  RenderView view;
  view.title = scene.name + ": " + r.stats.integrator + ", " + to_string(r.stats.status) +
               " at t = " + format_number(r.stats.t_final, 4) + " s";
  const DrapeParams& p = scene.params;
  view.caption = {"k = " + format_number(p.stiffness) + " N/m, c = " + format_number(p.damping) +
                      " N s/m, L0 = " + format_number(100 * p.natural_length) + " cm, topology " +
                      std::string(1, p.topology) + ", " + format_number(p.areal_density) + " g/m^2",
                  std::to_string(side) + " x " + std::to_string(side) + " particles, centre sag " +
                      format_number(100 * r.centre_sag, 3) + " cm, max strain " +
                      format_number(100 * r.max_strain, 3) + " %, residual " +
                      format_number(r.stats.residual, 2)};
  write_file_atomic_with(path, [&](const std::string& tmp) { render_mesh_png(tmp, mesh, view); });
}

}  // namespace

// ---- run state ----------------------------------------------------------------------------------

namespace {

bool all_finite(const std::vector<double>& a) {
  return std::all_of(a.begin(), a.end(), [](double d) { return std::isfinite(d); });
}

}  // namespace

void write_run_state(const fs::path& dir, const SavedRun& saved) {
  if (!all_finite(saved.state.x) || !all_finite(saved.state.v) || !std::isfinite(saved.state.t))
    return;
  write_json_atomic(dir / "state.json", {{"format", kRunStateFormat},
                                         {"command", saved.command},
                                         {"integrator", saved.integrator},
                                         {"dt", saved.dt},
                                         {"model", saved.model},
                                         {"t", saved.state.t},
                                         {"integrated_dof", saved.state.x.size()},
                                         {"x", saved.state.x},
                                         {"v", saved.state.v}});
}

namespace {

// The fields of to_json(DrapeParams) whose --set key is not "model.<field>". Older state files
// keyed them "model.<field>" too (and a refusal then named a key --set does not know);
// parse_run_state renames those.
const std::vector<std::pair<std::string, std::string>>& drape_fields_set_elsewhere() {
  static const std::vector<std::pair<std::string, std::string>> fields = {
      {"width", "fabric.width"},
      {"areal_density", "fabric.areal_density"},
      {"layout", "pins.layout"},
      {"pin_span", "pins.span"},
      {"pin_move_time", "pins.move_time"}};
  return fields;
}

}  // namespace

SavedRun parse_run_state(const std::string& text, const std::string& command) {
  SavedRun saved;
  try {
    const nlohmann::json state = nlohmann::json::parse(text);
    if (!state.is_object() || !state.contains("format") || state.at("format") != kRunStateFormat)
      throw std::invalid_argument("format is not \"" + std::string(kRunStateFormat) +
                                  "\" (not a state file of this knitsim version)");
    saved.command = state.at("command").get<std::string>();
    if (saved.command != command)
      throw std::invalid_argument("the state of a knitsim " + printable(saved.command) +
                                  " run; this is knitsim " + command);
    saved.state.t = state.at("t").get<double>();
    if (!(saved.state.t >= 0.0) || !std::isfinite(saved.state.t))
      throw std::invalid_argument("t = " + format_number(saved.state.t) +
                                  ": must be >= 0 s and finite");
    saved.state.x = state.at("x").get<std::vector<double>>();
    saved.state.v = state.at("v").get<std::vector<double>>();
    const size_t n = state.at("integrated_dof").get<size_t>();
    if (saved.state.x.size() != n || saved.state.v.size() != n)
      throw std::invalid_argument("x and v must hold integrated_dof = " + std::to_string(n) +
                                  " numbers each");
    if (!all_finite(saved.state.x) || !all_finite(saved.state.v))
      throw std::invalid_argument("x and v must be finite");
    saved.integrator = state.at("integrator").get<std::string>();
    saved.dt = state.at("dt").get<double>();
    if (!(saved.dt >= 0.0) || !std::isfinite(saved.dt))
      throw std::invalid_argument("dt = " + format_number(saved.dt) +
                                  ": must be >= 0 s and finite");
    saved.model = state.at("model");
    if (!saved.model.is_object()) throw std::invalid_argument("model is not an object");
    if (command == "drape")  // an older file's keys: "model.width" for fabric.width, ...
      for (const auto& [field, set_key] : drape_fields_set_elsewhere()) {
        const auto old = saved.model.find("model." + field);
        if (old == saved.model.end() || saved.model.contains(set_key)) continue;
        saved.model[set_key] = *old;
        saved.model.erase(old);
      }
  } catch (const nlohmann::json::exception& e) {
    // Without the library's "[json.exception.parse_error.101] " tag: what went wrong, where.
    std::string what = e.what();
    if (what.rfind("[json.exception.", 0) == 0 && what.find("] ") != std::string::npos)
      what.erase(0, what.find("] ") + 2);
    throw std::invalid_argument("not a valid state file: " + printable(what));
  }
  return saved;
}

SavedRun read_run_state(const fs::path& dir, const std::string& command) {
  // Capped like the other inputs: 256 MiB holds the state of a 1000 x 1000 grid.
  constexpr std::size_t kMaxStateFileBytes = std::size_t{256} << 20;
  const fs::path path = dir / "state.json";
  std::string text, why;
  if (!read_input_file(path.string(), kMaxStateFileBytes, text, why))
    throw std::invalid_argument(
        path.string() + ": " + why +
        (fs::exists(dir / "summary.json")
             ? " (that run's final state was not finite, or it predates state.json)"
             : " (not the output folder of a knitsim " + command + " run)"));
  try {
    return parse_run_state(text, command);
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(path.string() + ": " + e.what());
  }
}

nlohmann::json drape_model_keys(const DrapeParams& params) {
  nlohmann::json keys = nlohmann::json::object();
  const nlohmann::json fields = to_json(params);  // items() must not outlive its object
  for (const auto& [field, value] : fields.items()) {
    std::string key = "model." + field;
    for (const auto& [elsewhere, set_key] : drape_fields_set_elsewhere())
      if (field == elsewhere) key = set_key;
    keys[key] = value;
  }
  return keys;
}

RunState continue_state(const std::string& dir, const std::string& command,
                        const nlohmann::json& model, const std::string& same_what,
                        const std::string& integrator, IntegratorOptions& options) {
  const std::string where = "--continue " + dir + ": ";
  SavedRun saved;
  try {
    saved = read_run_state(dir, command);
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument("--continue: " + std::string(e.what()));
  }
  for (const auto& [key, value] : model.items())
    if (!saved.model.contains(key) || saved.model.at(key) != value) {
      const std::string here = value.dump(),
                        there = saved.model.contains(key) ? saved.model.at(key).dump() : "absent";
      const std::string differ = here.size() + there.size() <= 80
                                     ? key + " = " + here + " here, " + there + " in"
                                     : key + " differs from";  // e.g. a chart: not one line
      throw std::invalid_argument(where + differ + " the run being continued; give the same " +
                                  same_what);
    }
  if (!(saved.state.t < options.t_max))
    throw std::invalid_argument(where + "that run stopped at t = " + format_number(saved.state.t) +
                                " s, not below run.t_max = " + format_number(options.t_max) +
                                " s; raise run.t_max");
  if (options.dt == 0.0 && saved.dt > 0.0 && integrator == saved.integrator) options.dt = saved.dt;
  return saved.state;
}

void write_drape_outputs(const fs::path& dir, const Scene& scene, const DrapeResult& r,
                         const std::vector<EdgeFit>* target, bool picture) {
  const DrapeGrid& g = r.grid;
  const int side = g.n + 1;
  std::vector<int> pinned(r.positions.size(), 0);
  for (int p : g.network.spec().pinned) pinned[p] = 1;

  nlohmann::json summary = drape_summary(scene, r);
  const bool finite = std::all_of(r.positions.begin(), r.positions.end(), is_finite);
  // The edges of a run that stopped early (a flat sheet, a diverged one) may not be measurable
  // (fit_polynomial needs 5 distinct abscissae): the outputs are still written, with the reason.
  std::vector<EdgeFit> edges;
  if (finite) {
    try {
      edges = measure_edges(g, r.positions);
    } catch (const std::invalid_argument& e) {
      summary["edges_error"] = e.what();
    }
  }
  if (edges.empty()) remove_stale_output(dir / "edges.csv");
  if (!edges.empty()) {
    write_file_atomic_with(dir / "edges.csv",
                           [&](const std::string& tmp) { write_edges_csv(edges, tmp); });
    nlohmann::json coefficients = nlohmann::json::object();
    for (const EdgeFit& e : edges)
      coefficients[e.name] = std::vector<double>(e.coefficients.begin(), e.coefficients.end());
    summary["edge_coefficients"] = coefficients;
    if (target) {
      summary["objective"] = objective(*target, edges);
      nlohmann::json target_coefficients = nlohmann::json::object();
      for (const EdgeFit& e : *target)
        target_coefficients[e.name] =
            std::vector<double>(e.coefficients.begin(), e.coefficients.end());
      summary["target_edge_coefficients"] = target_coefficients;
    }
  }
  if (target)
    write_file_atomic_with(dir / "target_edges.csv",
                           [&](const std::string& tmp) { write_edges_csv(*target, tmp); });
  else
    remove_stale_output(dir / "target_edges.csv");
  write_json_atomic(dir / "summary.json", summary);

  std::ostringstream nodes;
  nodes.precision(17);
  nodes << "id,i,j,x,y,z,pinned\n";
  for (int i = 0; i < side; ++i)
    for (int j = 0; j < side; ++j) {
      const int id = g.index(i, j);
      const Vec3& p = r.positions[id];
      nodes << id << "," << i << "," << j << "," << p.x << "," << p.y << "," << p.z << ","
            << pinned[id] << "\n";
    }
  write_file_atomic(dir / "nodes.csv", nodes.str());

  write_run_state(dir, {"drape",
                        {r.stats.t_final, r.state_x, r.state_v},
                        r.stats.integrator,
                        r.stats.dt,
                        drape_model_keys(scene.params)});

  std::vector<std::array<int, 4>> quads;
  for (int i = 0; i < g.n; ++i)
    for (int j = 0; j < g.n; ++j)
      quads.push_back({g.index(i, j), g.index(i, j + 1), g.index(i + 1, j + 1), g.index(i + 1, j)});

  VtkPolyData vtk;
  vtk.title = "knitsim drape " + scene.name + " (" + r.stats.integrator + ", " +
              to_string(r.stats.status) + ", t = " + format_number(r.stats.t_final, 6) + " s)";
  vtk.points = r.positions;
  for (const auto& q : quads) vtk.polygons.emplace_back(q.begin(), q.end());
  vtk.point_ints.push_back({"pinned", pinned});
  std::vector<Vec3> displacement(r.positions.size());
  for (size_t k = 0; k < displacement.size(); ++k) displacement[k] = r.positions[k] - r.rest[k];
  vtk.point_vectors.push_back({"displacement", displacement});
  write_file_atomic(dir / "drape.vtk", to_vtk(vtk));

  if (picture)
    write_drape_picture(dir / "drape.png", scene, r, quads);
  else
    remove_stale_output(dir / "drape.png");
  write_json_atomic(dir / "manifest.json", manifest({{"scene", scene.name},
                                                     {"source", scene.source},
                                                     {"integrator", r.stats.integrator},
                                                     {"params", to_json(scene.params)},
                                                     {"options", to_json(scene.options)}}));
}

// ---- progress ----------------------------------------------------------------------------------

ProgressLine::ProgressLine(std::string label, double equilibrium_tol, bool enabled)
    : label_(std::move(label)),
      tol_(equilibrium_tol),
      active_(enabled && ::isatty(STDERR_FILENO) == 1),
      start_(Clock::now()),
      last_(start_) {}

ProgressLine::~ProgressLine() {
  if (shown_) std::fprintf(stderr, "\r\033[K");
}

void ProgressLine::on_check(double t, const double*, const double*, double residual) {
  if (!active_) return;
  if (first_residual_ < 0.0) first_residual_ = residual;
  const Clock::time_point now = Clock::now();
  if (now - last_ < std::chrono::milliseconds(100)) return;
  last_ = now;
  const double elapsed = std::chrono::duration<double>(now - start_).count();
  std::string eta;
  // Fraction of the way from the first residual to the tolerance, on a log scale.
  if (residual > tol_ && first_residual_ > residual && tol_ > 0.0) {
    const double f = std::log(first_residual_ / residual) / std::log(first_residual_ / tol_);
    if (f > 0.02) eta = "  eta ~" + format_number(elapsed * (1.0 - f) / f, 2) + " s";
  }
  std::fprintf(stderr, "\r\033[K%s  t = %.3g s  residual %.2e (tol %.0e)  elapsed %.1f s%s",
               label_.c_str(), t, residual, tol_, elapsed, eta.c_str());
  std::fflush(stderr);
  shown_ = true;
}

}  // namespace knitsim
