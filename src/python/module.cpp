// The Python module `knitsim` (docs/python.md): knitsim.drape and the lists of the command line,
// over the same functions (drape_call.hpp), numbers bit for bit the CLI's.
//
// Errors: std::invalid_argument (bad input, with the CLI's one-line message) -> ValueError;
// OutputError and OutputFolderBusy (result.write) -> OSError; a run's numerical failure is its
// status. The GIL is released while a call solves and while it writes. Ctrl-C: Python's own
// SIGINT handler only marks the signal; a call on the main thread looks for it (GIL taken for a
// moment, at most every kSignalPoll of wall time, from its run observer), sets the call's own
// cancel flag, and once the run has ended with status interrupted re-raises the KeyboardInterrupt
// with the partial result as its `.result`. Nothing here touches MPI (src/parallel loads it only
// under an MPI launcher) or the command line's signal handlers.
#include <pybind11/pybind11.h>
#include <pybind11/numpy.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <memory>
#include <string>
#include <type_traits>

#include "src/base/files.hpp"
#include "src/base/table.hpp"
#include "src/base/text.hpp"
#include "src/io/manifest.hpp"
#include "src/python/drape_call.hpp"
#include "src/python/fit_call.hpp"
#include "src/python/knit_call.hpp"
#include "src/python/tensile_call.hpp"

namespace py = pybind11;

namespace knitsim {

namespace {

constexpr auto kSignalPoll = std::chrono::milliseconds(20);

// The main thread's id: Python runs signal handlers there only.
unsigned long g_main_thread = 0;

// Looks for a pending signal from the solving thread (main thread only), at most every
// kSignalPoll: PyErr_CheckSignals runs Python's handler, whose exception (KeyboardInterrupt for
// SIGINT) is kept for the caller and sets `cancel`.
class SignalPoll final : public RunObserver {
 public:
  explicit SignalPoll(std::atomic<bool>* cancel)
      : cancel_(cancel),
        active_(PyThread_get_thread_ident() == g_main_thread),
        last_(std::chrono::steady_clock::now()) {}

  void on_step(double, double, int) override { poll(); }
  void on_run_start() override { poll(); }
  void on_check(double, const double*, const double*, double) override { poll(); }

  // From the solving thread, without the GIL (a run observer's call, the ICA's stop question).
  void poll() {
    if (!active_ || error_) return;
    const auto now = std::chrono::steady_clock::now();
    if (now - last_ < kSignalPoll) return;
    last_ = now;
    py::gil_scoped_acquire gil;
    if (PyErr_CheckSignals() == 0) return;
    PyObject *type, *value, *trace;
    PyErr_Fetch(&type, &value, &trace);
    PyErr_NormalizeException(&type, &value, &trace);
    type_ = py::reinterpret_steal<py::object>(type);
    value_ = py::reinterpret_steal<py::object>(value);
    trace_ = py::reinterpret_steal<py::object>(trace);
    error_ = true;
    cancel_->store(true, std::memory_order_relaxed);
  }

  // With the GIL: the exception a handler raised during the run, or a signal that came after
  // the last poll (then the result is complete). Returns true and leaves the exception set.
  bool raised() {
    if (error_) {
      PyErr_Restore(type_.release().ptr(), value_.release().ptr(), trace_.release().ptr());
      return true;
    }
    return active_ && PyErr_CheckSignals() != 0;
  }

 private:
  std::atomic<bool>* cancel_;
  bool active_;
  bool error_ = false;
  std::chrono::steady_clock::time_point last_;
  py::object type_, value_, trace_;
};

// Runs `solve(signals)` (it returns the call's result as a shared pointer) without the GIL,
// polling for signals; a signal or a handler's exception during the run is raised after it
// (KeyboardInterrupt carrying the partial result as .result). One path for every solving call.
template <class Solve>
py::object solve_without_gil(std::atomic<bool>* cancel, Solve&& solve) {
  SignalPoll signals(cancel);
  decltype(solve(signals)) call;
  {
    py::gil_scoped_release release;
    call = solve(signals);
  }
  py::object result = py::cast(call);
  if (signals.raised()) {
    py::error_already_set e;
    if (PyExceptionInstance_Check(e.value().ptr())) e.value().attr("result") = result;
    throw e;
  }
  return result;
}

// A Python value as the text --set or a run flag takes: str as is, a float (numpy's float64
// included) by the plain float's repr (the shortest text that reads back as the same double),
// anything else by str().
std::string value_text(const py::handle& v) {
  if (py::isinstance<py::str>(v)) return v.cast<std::string>();
  if (PyFloat_Check(v.ptr()))  // numpy's float64 too, by the plain float's repr
    return py::repr(py::float_(PyFloat_AsDouble(v.ptr()))).cast<std::string>();
  return py::str(v).cast<std::string>();
}

// scene and target: a str or an os.PathLike.
std::string path_text(const py::handle& v, const char* what) {
  auto checked = [what](std::string text) {
    if (text.find('\0') != std::string::npos)  // the C library would read a shorter path
      throw std::invalid_argument(std::string(what) + " " + printable(text) +
                                  ": a name or path holds no NUL byte");
    return text;
  };
  if (py::isinstance<py::str>(v)) return checked(v.cast<std::string>());
  if (py::hasattr(v, "__fspath__")) {
    py::object p = py::module_::import("os").attr("fspath")(v);
    if (py::isinstance<py::str>(p)) return checked(p.cast<std::string>());
  }
  throw std::invalid_argument(std::string(what) + ": expected a str or os.PathLike, got " +
                              py::str(py::type::of(v).attr("__name__")).cast<std::string>());
}

// overrides: {"model.stiffness": 900, ...} or ["model.stiffness=900", ...], as --set takes them.
std::vector<std::string> override_list(const py::handle& overrides) {
  std::vector<std::string> sets;
  if (overrides.is_none()) return sets;
  if (py::isinstance<py::dict>(overrides)) {
    for (const auto& [key, value] : py::reinterpret_borrow<py::dict>(overrides)) {
      if (!py::isinstance<py::str>(key))
        throw std::invalid_argument("overrides: keys are scene keys as text (\"model.stiffness\"), "
                                    "got " + py::repr(key).cast<std::string>());
      sets.push_back(key.cast<std::string>() + "=" + value_text(value));
    }
    return sets;
  }
  if (py::isinstance<py::str>(overrides) || !py::isinstance<py::iterable>(overrides))
    throw std::invalid_argument(
        "overrides: expected a dict {\"model.stiffness\": 900} or a list of \"key=value\"");
  for (const py::handle& item : overrides) {
    if (!py::isinstance<py::str>(item))
      throw std::invalid_argument("overrides: a list holds \"key=value\" texts, got " +
                                  py::repr(item).cast<std::string>());
    sets.push_back(item.cast<std::string>());
  }
  return sets;
}

py::array_t<double> points_array(const std::vector<Vec3>& points) {
  static_assert(sizeof(Vec3) == 3 * sizeof(double) && std::is_standard_layout_v<Vec3>);
  py::array_t<double> a({static_cast<py::ssize_t>(points.size()), py::ssize_t{3}});
  if (!points.empty()) std::memcpy(a.mutable_data(), points.data(), points.size() * sizeof(Vec3));
  return a;
}

py::array_t<double> vector_array(const double* data, std::size_t n) {
  py::array_t<double> a(static_cast<py::ssize_t>(n));
  if (n) std::memcpy(a.mutable_data(), data, n * sizeof(double));
  return a;
}

py::object json_to_python(const nlohmann::json& j) {
  return py::module_::import("json").attr("loads")(j.dump());
}

py::list table_rows(const Table& t, const std::vector<std::string>& names) {
  py::list rows;
  for (const auto& row : t.rows) {
    py::dict d;
    for (std::size_t c = 0; c < names.size() && c < row.size(); ++c) d[names[c].c_str()] = row[c];
    rows.append(d);
  }
  return rows;
}

using CallPtr = std::shared_ptr<DrapeCall>;

// knitsim.Cancel: a flag another thread sets to end the runs given it (status interrupted).
struct Cancel {
  std::shared_ptr<std::atomic<bool>> flag = std::make_shared<std::atomic<bool>>(false);
};

// The call's own flag, or the one of `cancel` (a knitsim.Cancel) when given.
std::shared_ptr<std::atomic<bool>> cancel_flag(const py::object& cancel) {
  if (cancel.is_none()) return std::make_shared<std::atomic<bool>>(false);
  if (!py::isinstance<Cancel>(cancel))
    throw std::invalid_argument("cancel: expected a knitsim.Cancel, got " +
                                py::str(py::type::of(cancel).attr("__name__")).cast<std::string>());
  return cancel.cast<Cancel&>().flag;
}

py::object drape(const py::object& scene, const py::object& overrides, const py::object& integrator,
                 const py::object& target, const py::object& cancel_token,
                 const py::kwargs& run_options) {
  DrapeRequest request;
  request.scene = path_text(scene, "scene");
  request.overrides = override_list(overrides);
  if (!integrator.is_none()) {
    if (!py::isinstance<py::str>(integrator))
      throw std::invalid_argument("--integrator: expected a name (knitsim.integrators())");
    request.integrator = integrator.cast<std::string>();
  }
  if (!target.is_none()) request.target = path_text(target, "--target");
  for (const auto& [name, value] : run_options)
    request.run_options.emplace_back(name.cast<std::string>(), value_text(value));

  const std::shared_ptr<std::atomic<bool>> cancel = cancel_flag(cancel_token);
  return solve_without_gil(cancel.get(), [&](SignalPoll& signals) {
    return CallPtr(std::make_shared<DrapeCall>(drape_call(request, cancel.get(), &signals)));
  });
}


// knitsim.knit: the knit run of `knitsim knit` (knit_call.hpp).
py::object knit(const py::object& chart_or_scene, const py::object& overrides,
                const py::object& integrator, int frames, const py::object& cancel_token,
                const py::kwargs& run_options) {
  KnitRequest request;
  request.chart_or_scene = path_text(chart_or_scene, "chart_or_scene");
  request.overrides = override_list(overrides);
  if (!integrator.is_none()) {
    if (!py::isinstance<py::str>(integrator))
      throw std::invalid_argument("--integrator: expected a name (knitsim.integrators())");
    request.integrator = integrator.cast<std::string>();
  }
  request.frames = frames;
  for (const auto& [name, value] : run_options)
    request.run_options.emplace_back(name.cast<std::string>(), value_text(value));

  const std::shared_ptr<std::atomic<bool>> cancel = cancel_flag(cancel_token);
  return solve_without_gil(cancel.get(), [&](SignalPoll& signals) {
    return knit_call(request, cancel.get(), &signals);
  });
}

// A CSV the command writes as {column: array}: numbers as float64 (an empty field as NaN), the
// columns named in `ints` as int, those in `texts` as str; parsed from the text the command
// writes, so the values are the file's, bit for bit.
py::dict csv_columns(const std::string& csv, const std::vector<std::string>& ints,
                     const std::vector<std::string>& texts) {
  auto among = [](const std::vector<std::string>& names, const std::string& name) {
    return std::find(names.begin(), names.end(), name) != names.end();
  };
  py::dict out;
  if (csv.empty()) return out;
  std::vector<std::string> names;
  std::vector<std::vector<std::string>> cols;
  std::size_t pos = 0;
  bool header = true;
  while (pos < csv.size()) {
    std::size_t end = csv.find('\n', pos);
    if (end == std::string::npos) end = csv.size();
    const std::string line = csv.substr(pos, end - pos);
    pos = end + 1;
    if (line.empty()) continue;
    std::vector<std::string> fields;
    std::size_t a = 0;
    while (true) {
      const std::size_t b = line.find(',', a);
      fields.push_back(line.substr(a, b == std::string::npos ? std::string::npos : b - a));
      if (b == std::string::npos) break;
      a = b + 1;
    }
    if (header) {
      names = fields;
      cols.resize(names.size());
      header = false;
      continue;
    }
    for (std::size_t c = 0; c < names.size(); ++c)
      cols[c].push_back(c < fields.size() ? fields[c] : "");
  }
  for (std::size_t c = 0; c < names.size(); ++c) {
    const std::vector<std::string>& col = cols[c];
    const auto n = static_cast<py::ssize_t>(col.size());
    if (among(texts, names[c])) {
      py::list l;
      for (const std::string& v : col) l.append(v);
      out[names[c].c_str()] = py::module_::import("numpy").attr("array")(l, "U");
    } else if (among(ints, names[c])) {
      py::array_t<long long> a(n);
      for (py::ssize_t i = 0; i < n; ++i)
        a.mutable_at(i) = std::strtoll(col[i].c_str(), nullptr, 10);
      out[names[c].c_str()] = a;
    } else {
      py::array_t<double> a(n);
      for (py::ssize_t i = 0; i < n; ++i)
        a.mutable_at(i) = col[i].empty() ? std::numeric_limits<double>::quiet_NaN()
                                         : std::strtod(col[i].c_str(), nullptr);
      out[names[c].c_str()] = a;
    }
  }
  return out;
}

// knitsim.tensile: the tensile test of `knitsim tensile` (tensile_call.hpp).
py::object tensile(const py::object& chart_or_scene, const py::object& overrides,
                   const std::string& direction, int steps, double strain, double gauge_ratio,
                   bool unload, int outputs, const py::object& integrator,
                   const py::object& cancel_token, const py::kwargs& run_options) {
  TensileRequest request;
  request.chart_or_scene = path_text(chart_or_scene, "chart_or_scene");
  request.overrides = override_list(overrides);
  // The command solves every step with the equilibrium solver and has no --integrator.
  if (!integrator.is_none() &&
      !(py::isinstance<py::str>(integrator) && integrator.cast<std::string>() == "equilibrium"))
    throw std::invalid_argument("--integrator = " + printable(py::str(integrator).cast<std::string>()) +
                                ": tensile solves each step with equilibrium (the only one)");
  request.test.direction = direction;
  request.test.steps = steps;
  request.test.strain = strain;
  request.test.gauge_ratio = gauge_ratio;
  request.test.unload = unload;
  request.test.outputs = outputs;
  for (const auto& [name, value] : run_options)
    request.run_options.emplace_back(name.cast<std::string>(), value_text(value));

  const std::shared_ptr<std::atomic<bool>> cancel = cancel_flag(cancel_token);
  return solve_without_gil(cancel.get(), [&](SignalPoll& signals) {
    return tensile_call(request, cancel.get(), &signals);
  });
}

// tensile.csv as {column: array}: step and newton_steps int, status str, the rest float64.
py::dict tensile_columns(const std::string& csv) {
  return csv_columns(csv, {"step", "newton_steps"}, {"status"});
}

// stitches.csv as {column: array}: wale, course and held_over int, stitch str ('K', 'T', 'M'),
// the measures float64 (NaN where the cell has none).
py::dict stitches_columns(const std::string& csv) {
  return csv_columns(csv, {"wale", "course", "held_over"}, {"stitch"});
}

// The key table's rows as help lines "  key (unit; default D; accepted): meaning", by column name
// (the table's columns: key, model, unit, default, accepted, meaning); `keep(key, model)` picks
// the rows.
template <typename Keep>
std::string key_lines(Keep keep) {
  const Table keys = scene_key_table();
  auto col = [&keys](const char* name) {
    for (std::size_t c = 0; c < keys.columns.size(); ++c)
      if (keys.columns[c] == name) return c;
    throw std::logic_error(std::string("scene_key_table has no column ") + name);
  };
  const std::size_t key = col("key"), model = col("model"), unit = col("unit"),
                    def = col("default"), accepted = col("accepted"), meaning = col("meaning");
  std::string doc;
  for (const auto& row : keys.rows)
    if (keep(row[key], row[model]))
      doc += "  " + row[key] + " (" + row[unit] + "; default " + row[def] + "; " +
             row[accepted] + "): " + row[meaning] + "\n";
  return doc;
}

// The knit and run keys of the parameter table, for knit's and tensile's docstrings.
std::string knit_key_lines() {
  return key_lines([](const std::string& key, const std::string& model) {
    return model != "fit" &&
           (key.rfind("knit.", 0) == 0 || key.rfind("yarn.", 0) == 0 ||
            key.rfind("run.", 0) == 0 || key.rfind("--", 0) == 0);
  });
}

std::string knit_doc() {
  std::string doc =
      "knit(chart_or_scene, overrides=None, integrator=None, frames=4, cancel=None, "
      "**run_options)\n"
      "\n"
      "Run a stitch chart's interlacing-point network to its steady state, as `knitsim knit` "
      "does (the same numbers, bit for bit), and return a KnitResult (positions, "
      "rest_positions, centerlines, stitches, summary, status; result.write(folder) writes the "
      "command's files).\n"
      "\n"
      "chart_or_scene: a stitch chart file (as --chart, e.g. models/charts/single_tuck.chart) or "
      "a knit scene ending in .toml (as --scene; docs/knit.md).\n"
      "overrides: {key: value} (or [\"key=value\", ...]) of the knit.* and run.* keys below, as "
      "--set takes them, e.g. {\"knit.network\": \"paper\"}.\n"
      "integrator: a name of knitsim.integrators(); None = the command's default (equilibrium "
      "with yarn contact, else cvode-bdf).\n"
      "frames: captured frames (--frames), >= 1.\n"
      "cancel: a knitsim.Cancel another thread may set() to end the run (status interrupted).\n"
      "run_options: the run flags of `knitsim knit` by name:";
  for (const auto& [name, flag] : run_option_flags()) doc += " " + name;
  doc +=
      ".\n\n"
      "Bad input raises ValueError with the command line's one-line message (a bad chart names "
      "its row and column); a run that does not reach its steady state returns its status. "
      "Ctrl-C ends the run (status interrupted) and raises KeyboardInterrupt with the partial "
      "result as .result.\n"
      "\n"
      "Knit and run keys (unit; default; accepted values; meaning):\n";
  doc += knit_key_lines();
  return doc;
}

std::string tensile_doc() {
  std::string doc =
      "tensile(chart_or_scene, overrides=None, direction='wale', steps=20, strain=0.2, "
      "gauge_ratio=2.0, unload=False, outputs=3, integrator=None, cancel=None, **run_options)\n"
      "\n"
      "Quasi-static tensile test of a stitch chart, as `knitsim tensile` does (the same curve, "
      "bit for bit; docs/knit.md, \"Under load\"): a strip of the chart clamped at two "
      "opposite edges, one edge moved in equal steps, each step's equilibrium certified. Returns "
      "a TensileResult: the columns of tensile.csv as arrays (step, strain, displacement_m, "
      "force_N, force_per_width_N_per_m, lateral_strain, energy_J, step_status, newton_steps; "
      "all of them in .curve), summary (summary.json), status; result.write(folder) writes "
      "tensile.csv, tensile.png, summary.json and manifest.json, but not the kept steps' "
      "step_NNN/ knit outputs the command also writes (they need the model in each step's "
      "state, which only the run holds; their positions are in result.states).\n"
      "\n"
      "chart_or_scene: a stitch chart file (as --chart) or a knit scene ending in .toml (as "
      "--scene).\n"
      "overrides: {key: value} (or [\"key=value\", ...]) of the knit.* and run.* keys below, as "
      "--set takes them, e.g. {\"knit.contact\": 0}; knit.pins and knit.clamps are the test's "
      "own.\n"
      "direction: wale (bottom edge held, top edge moved) or course (left held, right moved).\n"
      "steps: equal loading steps, 1 to 100000 (--steps).\n"
      "strain: engineering strain of the clamp distance at the last step, in (0, 1] "
      "(--strain).\n"
      "gauge_ratio: clamp distance / width of the strip, in (0, 100] (--gauge-ratio).\n"
      "unload: then unload back to 0 along the same steps (--unload).\n"
      "outputs: steps whose whole state is kept (result.states), 0 to 1000 (--outputs).\n"
      "integrator: None or 'equilibrium' (the command has no other).\n"
      "cancel: a knitsim.Cancel another thread may set() to end the test (the step's status "
      "interrupted).\n"
      "run_options: the run flags of `knitsim tensile` by name:";
  for (const auto& [name, flag] : run_option_flags()) doc += " " + name;
  doc +=
      ".\n\n"
      "Bad input raises ValueError with the command line's one-line message (e.g. \"--steps = "
      "0: ...\"); a step that does not reach equilibrium ends the test with its status "
      "(result.status, the curve so far kept). Ctrl-C ends the test (status interrupted) and "
      "raises KeyboardInterrupt with the partial result as .result.\n"
      "\n"
      "Knit and run keys (unit; default; accepted values; meaning):\n";
  doc += knit_key_lines();
  return doc;
}

// knitsim.fit: the ICA fit of `knitsim fit` (fit_call.hpp).
py::object fit(const py::object& target, const py::object& scene, const py::object& overrides,
               const py::object& integrator, const py::object& bounds, const py::kwargs& options) {
  FitRequest request;
  request.target = path_text(target, "--target");
  request.scene = path_text(scene, "--scene");
  request.overrides = override_list(overrides);
  if (!integrator.is_none()) {
    if (!py::isinstance<py::str>(integrator))
      throw std::invalid_argument("--integrator: expected a name (knitsim.integrators())");
    request.integrator = integrator.cast<std::string>();
  }
  if (!bounds.is_none()) {
    if (!py::isinstance<py::dict>(bounds))
      throw std::invalid_argument("bounds: expected a dict {gene: (lower, upper)}");
    for (const auto& [gene, box] : py::reinterpret_borrow<py::dict>(bounds)) {
      const std::string name = py::str(gene).cast<std::string>();
      double lower = 0.0, upper = 0.0;
      try {
        auto pair = box.cast<std::pair<double, double>>();
        lower = pair.first, upper = pair.second;
      } catch (const py::cast_error&) {
        throw std::invalid_argument("bounds." + name + ": expected (lower, upper), got " +
                                    py::repr(box).cast<std::string>());
      }
      request.bounds.emplace_back(name, lower, upper);
    }
  }
  for (const auto& [name, value] : options)
    request.options.emplace_back(name.cast<std::string>(), value_text(value));

  std::atomic<bool> cancel{false};
  return solve_without_gil(&cancel, [&](SignalPoll& signals) {
    return std::make_shared<FitCall>(fit_call(request, [&signals, &cancel] {
      signals.poll();
      return cancel.load(std::memory_order_relaxed);
    }));
  });
}

std::string fit_doc() {
  std::string doc =
      "fit(target, scene='four_corner', overrides=None, integrator=None, bounds=None, **options)\n"
      "\n"
      "Fit the drape model's parameters to target edges with the ICA, as `knitsim fit` does "
      "(the same fit, bit for bit), and return a FitResult (params, objective, evaluations, "
      "history, best_country, status, summary, and the fitted drape as a DrapeResult; "
      "result.write(folder) writes the command's files).\n"
      "\n"
      "target: the target edges CSV (docs/fitting.md).\n"
      "scene, overrides, integrator: the base scene, as for drape() (fabric, pins, run options).\n"
      "bounds: {gene: (lower, upper)} of the search box (genes: stiffness N/m, damping N s/m, "
      "elongation_limit %, natural_length m, topology 0..3), default paper 1's Table 3.\n"
      "options: the flags of `knitsim fit` by name:";
  for (const auto& [name, flag] : fit_option_flags()) doc += " " + name;
  doc +=
      " (rtol defaults to 1e-8, as for the command).\n\n"
      "Ctrl-C ends the fit at the end of its current decade (status interrupted) and raises "
      "KeyboardInterrupt with the result so far as .result.\n"
      "\n"
      "The ICA's options (unit; default; accepted values; meaning):\n";
  doc += key_lines([](const std::string& key, const std::string& model) {
    if (model != "fit") return false;
    for (const auto& [name, flag] : fit_option_flags())
      if (flag == key) return true;
    return false;
  });
  return doc;
}

// help(knitsim.drape): the signature's meaning, then the scene keys from the key table (as
// `knitsim list keys` prints them) and the run options.
std::string drape_doc() {
  std::string doc =
      "drape(scene='four_corner', overrides=None, integrator=None, target=None, cancel=None, "
      "**run_options)\n"
      "\n"
      "Hang a fabric and run it to equilibrium, as `knitsim drape` does (the same numbers, bit "
      "for bit), and return a DrapeResult (positions, rest_positions, edges, summary, status, "
      "certificate; result.write(folder) writes the command's files).\n"
      "\n"
      "scene: a built-in scene (four_corner, two_corner, two_corner_slack) or a TOML path.\n"
      "overrides: {key: value} (or [\"key=value\", ...]) of the scene keys below, as --set "
      "takes them, e.g. {\"model.stiffness\": 900}.\n"
      "integrator: a name of knitsim.integrators(); None = equilibrium.\n"
      "target: target edges CSV (docs/fitting.md): adds the Eq. 5 objective to the summary.\n"
      "cancel: a knitsim.Cancel another thread may set() to end the run (status interrupted, "
      "returned: no exception).\n"
      "run_options: the run flags of `knitsim drape` by name, e.g. rtol=1e-8, max_wall=5:";
  for (const auto& [name, flag] : run_option_flags()) doc += " " + name;
  doc +=
      ".\n\n"
      "Bad input raises ValueError with the command line's one-line message; a run that does "
      "not reach equilibrium returns its status. Ctrl-C ends the run (status interrupted) and "
      "raises KeyboardInterrupt with the partial result as .result.\n"
      "\n"
      "Scene keys (unit; default; accepted values; meaning):\n";
  doc += key_lines([](const std::string&, const std::string& model) { return model != "fit"; });
  return doc;
}

}  // namespace

}  // namespace knitsim

PYBIND11_MODULE(knitsim, m) {
  using namespace knitsim;
  g_main_thread = py::module_::import("threading")
                      .attr("main_thread")()
                      .attr("ident")
                      .cast<unsigned long>();
  m.doc() =
      "knitsim from Python: mass-spring models of knitted fabric (docs/python.md). drape(), "
      "knit(), tensile(), fit(), list_keys(), integrators(), scenes(); results hold numpy arrays and "
      "summary.json as a dict.";
  m.attr("__version__") = KNITSIM_VERSION;
  m.attr("build") = py::dict(py::arg("version") = version_string(),
                             py::arg("python") = KNITSIM_PYTHON_EXECUTABLE,
                             py::arg("python_version") = KNITSIM_PYTHON_VERSION);

  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const OutputError& e) {
      PyErr_SetString(PyExc_OSError, e.what());
    } catch (const OutputFolderBusy& e) {
      PyErr_SetString(PyExc_OSError, e.what());
    }
  });

  py::class_<DrapeCall, std::shared_ptr<DrapeCall>>(
      m, "DrapeResult",
      "One drape run: arrays in SI units (m), summary.json as a dict. Particle id k is row k "
      "of positions; index[i, j] is the id of grid node (i, j) (nodes.csv's order).")
      .def_property_readonly(
          "positions", [](const DrapeCall& c) { return points_array(c.result.positions); },
          "all particles (pins included) at t_final, n x 3, m")
      .def_property_readonly(
          "rest_positions", [](const DrapeCall& c) { return points_array(c.result.rest); },
          "all particles at t = 0 (the flat sheet), n x 3, m")
      .def_property_readonly(
          "index",
          [](const DrapeCall& c) {
            const int side = c.result.grid.n + 1;
            py::array_t<int> a({side, side});
            for (int i = 0; i < side; ++i)
              for (int j = 0; j < side; ++j) a.mutable_at(i, j) = c.result.grid.index(i, j);
            return a;
          },
          "(n+1) x (n+1) particle ids: index[i, j] = id of grid node (i, j)")
      .def_property_readonly(
          "pinned",
          [](const DrapeCall& c) {
            const auto& p = c.result.grid.network.spec().pinned;
            py::array_t<int> a(static_cast<py::ssize_t>(p.size()));
            for (std::size_t k = 0; k < p.size(); ++k) a.mutable_at(k) = p[k];
            return a;
          },
          "ids of the pinned particles")
      .def_property_readonly(
          "edges",
          [](const DrapeCall& c) {
            py::dict d;
            for (const EdgeFit& e : c.report.edges)
              d[e.name.c_str()] = py::dict(
                  py::arg("s") = vector_array(e.points.s.data(), e.points.s.size()),
                  py::arg("d") = vector_array(e.points.d.data(), e.points.d.size()),
                  py::arg("coefficients") =
                      vector_array(e.coefficients.data(), e.coefficients.size()));
            return d;
          },
          "the measured edges (edges.csv): {name: {s, d, coefficients p0..p4}}, normalised; "
          "empty where the final state is not measurable (summary['edges_error'])")
      .def_property_readonly(
          "summary", [](const DrapeCall& c) { return json_to_python(c.report.summary); },
          "summary.json as a dict, with its 'units' map")
      .def_property_readonly(
          "status", [](const DrapeCall& c) { return to_string(c.result.stats.status); },
          "equilibrium, interrupted, time_limit, ... (summary['status'])")
      .def_property_readonly(
          "message", [](const DrapeCall& c) { return c.result.stats.message; },
          "why the run stopped")
      .def_property_readonly(
          "certificate", [](const DrapeCall& c) { return c.result.stats.certificate; },
          "stable_minimum, inconclusive, or '' where the stop did not pass")
      .def_property_readonly(
          "centre_sag", [](const DrapeCall& c) { return c.result.centre_sag; },
          "m: mean pin height minus the height of the grid centre")
      .def_property_readonly(
          "max_strain", [](const DrapeCall& c) { return c.result.max_strain; },
          "largest spring strain (L - L0) / L0, a fraction")
      .def_property_readonly(
          "scene", [](const DrapeCall& c) { return c.scene.name; }, "scene.name")
      .def_property_readonly(
          "integrator", [](const DrapeCall& c) { return c.integrator; }, "the integrator's name")
      .def(
          "write",
          [](const CallPtr& c, const py::object& folder, bool pictures) {
            const std::string dir = path_text(folder, "--out");
            std::string written;
            {
              py::gil_scoped_release release;
              written = write_drape_call(*c, dir, pictures);
            }
            return written;
          },
          py::arg("folder"), py::arg("pictures") = true,
          "Writes the files of `knitsim drape --out folder` (summary.json, nodes.csv, edges.csv, "
          "drape.vtk, drape.png unless pictures=False, state.json, manifest.json); returns the "
          "folder.")
      .def("__repr__", [](const DrapeCall& c) {
        return "<knitsim.DrapeResult " + c.scene.name + " " + c.integrator + ": " +
               to_string(c.result.stats.status) + ", centre sag " +
               format_number(100 * c.result.centre_sag, 4) + " cm>";
      });

  static const std::string doc = drape_doc();
  py::class_<Cancel>(m, "Cancel",
                     "A cancel flag for drape(cancel=...): set() from any thread ends the runs "
                     "given it at their next residual check, with status interrupted.")
      .def(py::init<>())
      .def("set", [](Cancel& c) { c.flag->store(true); }, "Ask the runs to stop.")
      .def("is_set", [](const Cancel& c) { return c.flag->load(); });
  m.def("drape", &drape, py::arg("scene") = "four_corner", py::arg("overrides") = py::none(),
        py::arg("integrator") = py::none(), py::arg("target") = py::none(),
        py::arg("cancel") = py::none(), doc.c_str());


  using KnitPtr = std::shared_ptr<KnitCall>;
  py::class_<KnitCall, KnitPtr>(
      m, "KnitResult",
      "One knit run: arrays in SI units (m), summary.json as a dict. Point id k is row k of "
      "positions (points.csv's order).")
      .def_property_readonly(
          "positions", [](const KnitCall& c) { return points_array(c.result->positions); },
          "every interlacing point at the end, n x 3, m (points.csv x, y, z)")
      .def_property_readonly(
          "rest_positions",
          [](const KnitCall& c) { return points_array(c.result->model.rest_positions()); },
          "every interlacing point at rest, n x 3, m (points.csv x0, y0, z0)")
      .def_property_readonly(
          "wale",
          [](const KnitCall& c) {
            const auto& p = c.result->model.points;
            py::array_t<int> a(static_cast<py::ssize_t>(p.size()));
            for (std::size_t k = 0; k < p.size(); ++k) a.mutable_at(k) = p[k].wale;
            return a;
          },
          "each point's wale (points.csv wale)")
      .def_property_readonly(
          "level",
          [](const KnitCall& c) {
            const auto& p = c.result->model.points;
            py::array_t<int> a(static_cast<py::ssize_t>(p.size()));
            for (std::size_t k = 0; k < p.size(); ++k) a.mutable_at(k) = p[k].level;
            return a;
          },
          "each point's level (points.csv level)")
      .def_property_readonly(
          "centerlines",
          [](const KnitCall& c) {
            py::list l;
            for (const CurveSamples& s : c.centerlines) l.append(points_array(s.points));
            return l;
          },
          "per course from the bottom, its centreline at the end sampled in arc length, an "
          "m x 3 array in m (centerlines.csv); empty for an end state that is not finite")
      .def_property_readonly(
          "rest_centerlines",
          [](const KnitCall& c) {
            py::list l;
            for (const CurveSamples& s :
                 course_centerlines(c.result->model, c.result->model.rest_positions()))
              l.append(points_array(s.points));
            return l;
          },
          "per course, its centreline at rest (the one before.png draws), an m x 3 array in m")
      .def_property_readonly(
          "centerline_u",
          [](const KnitCall& c) {
            py::list l;
            for (const CurveSamples& s : c.centerlines)
              l.append(vector_array(s.u.data(), s.u.size()));
            return l;
          },
          "per course, the curve parameters of its centerlines samples (centerlines.csv u)")
      .def_property_readonly(
          "stitches", [](const KnitCall& c) { return stitches_columns(c.stitches_csv); },
          "stitches.csv as {column: array}, one row per chart cell (wale, course, held_over "
          "int; stitch str; the measures float64 in m, NaN where the cell has none); empty "
          "for an end state that is not finite")
      .def_property_readonly(
          "summary", [](const KnitCall& c) { return json_to_python(c.summary); },
          "summary.json as a dict, with its 'units', 'yarn' and 'fabric' blocks")
      .def_property_readonly(
          "status", [](const KnitCall& c) { return to_string(c.result->stats.status); },
          "equilibrium, interrupted, time_limit, ... (summary['status'])")
      .def_property_readonly(
          "message", [](const KnitCall& c) { return c.result->stats.message; },
          "why the run stopped")
      .def_property_readonly(
          "certificate", [](const KnitCall& c) { return c.result->stats.certificate; },
          "stable_minimum, inconclusive, or '' where the stop did not pass")
      .def_property_readonly(
          "chart", [](const KnitCall& c) { return c.scene.name; }, "the chart's name")
      .def_property_readonly(
          "integrator", [](const KnitCall& c) { return c.result->stats.integrator; },
          "the integrator's name")
      .def(
          "write",
          [](const KnitPtr& c, const py::object& folder, bool pictures) {
            const std::string dir = path_text(folder, "--out");
            std::string written;
            {
              py::gil_scoped_release release;
              written = write_knit_call(*c, dir, pictures);
            }
            return written;
          },
          py::arg("folder"), py::arg("pictures") = true,
          "Writes the files of `knitsim knit --out folder` (points.csv, typevalue.csv, "
          "centerlines.csv/.vtk, stitches.csv, frames/, before.png and after.png unless "
          "pictures=False, summary.json, state.json, manifest.json); returns the folder.")
      .def("__repr__", [](const KnitCall& c) {
        return "<knitsim.KnitResult " + c.scene.name + " " + c.result->stats.integrator + ": " +
               to_string(c.result->stats.status) + ", " +
               std::to_string(c.result->positions.size()) + " points>";
      });
  static const std::string knit_docstring = knit_doc();
  m.def("knit", &knit, py::arg("chart_or_scene"), py::arg("overrides") = py::none(),
        py::arg("integrator") = py::none(), py::arg("frames") = 4,
        py::arg("cancel") = py::none(), knit_docstring.c_str());

  using TensilePtr = std::shared_ptr<TensileCall>;
  auto curve_column = [](const char* name) {
    return [name](const TensileCall& c) { return py::object(tensile_columns(c.csv)[name]); };
  };
  py::class_<TensileCall, TensilePtr>(
      m, "TensileResult",
      "One tensile test: tensile.csv's columns as arrays (one row per step, the rest state step "
      "0 first), summary.json as a dict.")
      .def_property_readonly(
          "curve", [](const TensileCall& c) { return tensile_columns(c.csv); },
          "tensile.csv as {column: array} (step, newton_steps int; status str; the rest "
          "float64), the file's numbers bit for bit")
      .def_property_readonly("step", curve_column("step"), "step number, 0 = settled at rest")
      .def_property_readonly("strain", curve_column("strain"),
                             "engineering strain of the clamp distance, 1")
      .def_property_readonly("displacement_m", curve_column("displacement_m"),
                             "the moving clamp's displacement along the pull, m")
      .def_property_readonly("force_N", curve_column("force_N"),
                             "the moving clamp's reaction along the pull, N (tension > 0)")
      .def_property_readonly("force_per_width_N_per_m", curve_column("force_per_width_N_per_m"),
                             "force per rest width, N/m")
      .def_property_readonly("lateral_strain", curve_column("lateral_strain"),
                             "width change at mid-length over the rest width, 1")
      .def_property_readonly("energy_J", curve_column("energy_J"), "potential energy, J")
      .def_property_readonly("step_status", curve_column("status"),
                             "each step's status (tensile.csv status)")
      .def_property_readonly("newton_steps", curve_column("newton_steps"),
                             "each step's Newton steps")
      .def_property_readonly(
          "reactions",
          [](const TensileCall& c) {
            const auto& steps = c.result.steps;
            py::array_t<double> a({static_cast<py::ssize_t>(steps.size()), py::ssize_t{2},
                                   py::ssize_t{3}});
            std::fill(a.mutable_data(), a.mutable_data() + a.size(),
                      std::numeric_limits<double>::quiet_NaN());
            for (std::size_t k = 0; k < steps.size(); ++k)
              for (std::size_t j = 0; j < 2 && j < steps[k].reactions.size(); ++j) {
                const Vec3& f = steps[k].reactions[j];
                a.mutable_at(k, j, 0) = f.x;
                a.mutable_at(k, j, 1) = f.y;
                a.mutable_at(k, j, 2) = f.z;
              }
            return a;
          },
          "steps x 2 x 3, N: the force each clamp (fixed, moving) exerts on the fabric")
      .def_property_readonly(
          "rest_positions",
          [](const TensileCall& c) { return points_array(c.result.model.rest_positions()); },
          "the specimen's interlacing points at rest, n x 3, m")
      .def_property_readonly(
          "states",
          [](const TensileCall& c) {
            py::dict d;
            for (const TensileResult::Kept& k : c.result.kept)
              d[py::int_(k.step)] = points_array(k.positions);
            return d;
          },
          "{step: n x 3 positions, m} at the kept steps (outputs=)")
      .def_property_readonly(
          "summary", [](const TensileCall& c) { return json_to_python(c.summary); },
          "summary.json as a dict, with its 'units' map")
      .def_property_readonly(
          "status", [](const TensileCall& c) { return c.summary["status"].get<std::string>(); },
          "complete, or the status of the step that did not reach equilibrium (interrupted, "
          "...; summary['status'])")
      .def_property_readonly(
          "complete", [](const TensileCall& c) { return c.result.complete; },
          "every step reached equilibrium")
      .def_property_readonly(
          "message",
          [](const TensileCall& c) {
            return c.result.steps.empty() ? std::string() : c.result.steps.back().stats.message;
          },
          "why the last step's solve stopped")
      .def_property_readonly(
          "chart", [](const TensileCall& c) { return c.scene.name; }, "the chart's name")
      .def(
          "write",
          [](const TensilePtr& c, const py::object& folder, bool pictures) {
            const std::string dir = path_text(folder, "--out");
            std::string written;
            {
              py::gil_scoped_release release;
              written = write_tensile_call(*c, dir, pictures);
            }
            return written;
          },
          py::arg("folder"), py::arg("pictures") = true,
          "Writes the files of `knitsim tensile --out folder` but the step_NNN/ folders "
          "(tensile.csv, tensile.png unless pictures=False, summary.json, manifest.json); "
          "returns the folder.")
      .def("__repr__", [](const TensileCall& c) {
        return "<knitsim.TensileResult " + c.scene.name + " " + c.test.direction + ": " +
               c.summary["status"].get<std::string>() + ", " +
               std::to_string(c.result.steps.size()) + " steps>";
      });
  static const std::string tensile_docstring = tensile_doc();
  m.def("tensile", &tensile, py::arg("chart_or_scene"), py::arg("overrides") = py::none(),
        py::arg("direction") = "wale", py::arg("steps") = 20, py::arg("strain") = 0.2,
        py::arg("gauge_ratio") = 2.0, py::arg("unload") = false, py::arg("outputs") = 3,
        py::arg("integrator") = py::none(), py::arg("cancel") = py::none(),
        tensile_docstring.c_str());

  py::class_<FitCall, std::shared_ptr<FitCall>>(
      m, "FitResult", "One ICA fit: the best parameters, their objective, the history.")
      .def_property_readonly(
          "status", [](const FitCall& c) { return to_string(c.fit.status); },
          "decade_limit, one_empire, all_failed or interrupted")
      .def_property_readonly(
          "message", [](const FitCall& c) { return c.fit.message; }, "the ICA's")
      .def_property_readonly(
          "params",
          [](const FitCall& c) {
            const DrapeParams& p = c.fit.params;
            return py::dict(py::arg("stiffness") = p.stiffness, py::arg("damping") = p.damping,
                            py::arg("elongation_limit") = p.elongation_limit,
                            py::arg("natural_length") = p.natural_length,
                            py::arg("topology") = std::string(1, p.topology));
          },
          "the fitted parameters: stiffness N/m, damping N s/m, elongation_limit %, "
          "natural_length m, topology")
      .def_property_readonly(
          "objective", [](const FitCall& c) { return c.fit.objective; },
          "%: the Eq. 5 error of the best country")
      .def_property_readonly(
          "evaluations", [](const FitCall& c) { return c.fit.evaluations; }, "drapes run")
      .def_property_readonly(
          "failed_evaluations", [](const FitCall& c) { return c.fit.failed_evaluations; },
          "drapes that did not reach equilibrium or could not be measured")
      .def_property_readonly(
          "best_country",
          [](const FitCall& c) { return vector_array(c.fit.best_x.data(), c.fit.best_x.size()); },
          "the best country: stiffness, damping, elongation_limit, natural_length, topology gene")
      .def_property_readonly(
          "history",
          [](const FitCall& c) {
            py::list l;
            for (const IcaDecade& d : c.fit.history)
              l.append(py::dict(py::arg("decade") = d.decade, py::arg("best") = d.best_cost,
                                py::arg("mean") = d.mean_cost, py::arg("empires") = d.empires,
                                py::arg("evaluations") = d.evaluations));
            return l;
          },
          "history.csv's rows: [{decade, best, mean, empires, evaluations}]")
      .def_property_readonly(
          "wall_seconds", [](const FitCall& c) { return c.fit.wall_seconds; }, "s")
      .def_property_readonly(
          "integrator", [](const FitCall& c) { return c.integrator; }, "of every evaluation")
      .def_property_readonly(
          "target_scene", [](const FitCall& c) { return c.target_scene; },
          "the target's scene the drapes were compared with")
      .def_property_readonly(
          "drape", [](const FitCall& c) { return c.drape; },
          "the fitted drape re-run (a DrapeResult with the objective against the target in its "
          "summary), None for a fit cut short")
      .def_property_readonly(
          "summary", [](const FitCall& c) { return json_to_python(c.report.summary); },
          "summary.json of `knitsim fit` as a dict, with its 'units' map")
      .def(
          "write",
          [](const std::shared_ptr<FitCall>& c, const py::object& folder, bool pictures) {
            const std::string dir = path_text(folder, "--out");
            std::string written;
            {
              py::gil_scoped_release release;
              written = write_fit_call(*c, dir, pictures);
            }
            return written;
          },
          py::arg("folder"), py::arg("pictures") = true,
          "Writes the files of `knitsim fit --out folder` but its checkpoint (history.csv, "
          "drape/ with drape.png unless pictures=False, summary.json, manifest.json); returns "
          "the folder.")
      .def("__repr__", [](const FitCall& c) {
        return "<knitsim.FitResult " + std::string(to_string(c.fit.status)) + ": objective " +
               format_number(c.fit.objective, 4) + " % after " +
               std::to_string(c.fit.evaluations) + " drapes>";
      });
  static const std::string fit_docstring = fit_doc();
  m.def("fit", &fit, py::arg("target"), py::arg("scene") = "four_corner",
        py::arg("overrides") = py::none(), py::arg("integrator") = py::none(),
        py::arg("bounds") = py::none(), fit_docstring.c_str());

  m.def(
      "list_keys",
      [] {
        const Table t = scene_key_table();
        return table_rows(t, t.columns);
      },
      "The scene keys as `knitsim list keys` lists them: [{key, model, unit, default, accepted, "
      "meaning}].");
  m.def(
      "integrators",
      [] {
        py::list l;
        for (const IntegratorInfo& i : integrator_catalog())
          l.append(py::dict(py::arg("name") = i.name, py::arg("order") = i.order,
                            py::arg("adaptive") = i.adaptive,
                            py::arg("explicit") = i.explicit_method,
                            py::arg("description") = i.description));
        return l;
      },
      "The integrators as `knitsim list integrators` lists them: [{name, order (0 = variable), "
      "adaptive, explicit, description}].");
  m.def(
      "scenes",
      [] {
        py::list l;
        for (const auto& [name, text] : builtin_scenes()) l.append(name);
        return l;
      },
      "The built-in scene names.");
}
