#include "src/scene/yarn_cell_run.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <ctime>
#include <limits>
#include <utility>

#include "src/core/invalid_field.hpp"

namespace knitsim {

namespace {

double cpu_now() { return static_cast<double>(std::clock()) / CLOCKS_PER_SEC; }

// Measures the clearance at every residual check, then passes the check on.
class CellClearanceWatch final : public RunObserver {
 public:
  CellClearanceWatch(const YarnCell& cell, RunObserver* next) : cell_(cell), next_(next) {}
  void on_run_start() override {
    if (next_) next_->on_run_start();
  }
  void on_step(double t, double h, int order) override {
    if (next_) next_->on_step(t, h, order);
  }
  void on_check(double t, const double* x, const double* v, double residual) override {
    const double c = cell_.min_clearance(x);
    if (!(c >= min_)) min_ = c;  // NaN (infeasible) sticks
    ++checks_;
    if (next_) next_->on_check(t, x, v, residual);
  }
  double minimum() const { return min_; }
  int checks() const { return checks_; }

 private:
  const YarnCell& cell_;
  RunObserver* next_;
  double min_ = std::numeric_limits<double>::infinity();
  int checks_ = 0;
};

}  // namespace

YarnCellRun run_yarn_cell(std::shared_ptr<const YarnCellStart> start, const std::string& integrator,
                          const IntegratorOptions& options, RunObserver* observer,
                          const YarnCellState* from, CellSize size, bool ramp) {
  make_integrator(integrator);  // an unknown name is refused before anything runs
  const YarnCellStart& st = *start;
  const auto wall0 = std::chrono::steady_clock::now();
  const double cpu0 = cpu_now();
  YarnCellRun run;
  run.start = start;
  YarnCellState state = from ? *from : YarnCellState{st.start, st.width, st.height};
  const int stages = ramp && st.ramp() ? std::max(1, static_cast<int>(st.params.ramp_stages)) : 1;
  const int first = ramp ? 1 : stages;
  double min_clearance = std::numeric_limits<double>::infinity();
  long steps = 0;
  std::vector<double> x, v;
  for (int s = first; s <= stages; ++s) {
    const double c0 = cpu_now();
    const auto w0 = std::chrono::steady_clock::now();
    const YarnCell cell(st.spec(s, stages, state.courses, state.width, state.height, size));
    x.assign(cell.dof(), 0.0), v.assign(cell.dof(), 0.0);
    cell.initial_state(x.data(), v.data());
    if (s == first) {
      run.clearance_start_over_d = cell.min_clearance(x.data()) / st.d;
      min_clearance = std::min(min_clearance, run.clearance_start_over_d * st.d);
    }
    CellClearanceWatch watch(cell, observer);
    IntegratorOptions o = options;
    if (options.max_wall_seconds > 0.0) {
      const double used =
          std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
      o.max_wall_seconds = std::max(1e-3, options.max_wall_seconds - used);
    }
    if (options.max_steps > 0) o.max_steps = std::max(1L, options.max_steps - steps);
    std::unique_ptr<Integrator> integ = make_integrator(integrator);
    RunStats rs = run_to_equilibrium(cell, *integ, o, x, v, &watch);
    steps += rs.steps;
    if (!(watch.minimum() >= min_clearance)) min_clearance = watch.minimum();
    run.clearance_checks += watch.checks();
    state = {cell.courses_at(x.data()), cell.width(x.data()), cell.height(x.data())};
    YarnCellRun::Stage stage;
    stage.status = rs.status;
    stage.steps = rs.steps;
    stage.residual = rs.residual;
    stage.cpu_seconds = cpu_now() - c0;
    stage.wall_seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - w0).count();
    stage.width = state.width, stage.height = state.height;
    run.stages.push_back(stage);
    run.stats = rs;
    run.dof = cell.dof();
    if (s == stages || rs.status != RunStatus::Equilibrium) {
      const double end = cell.min_clearance(x.data());
      run.clearance_end_over_d = end / st.d;
      if (!(end >= min_clearance)) min_clearance = end;
      run.size_gradient = cell.size_gradient(x.data());
      for (int c = 0; c < cell.courses(); ++c)
        run.course_end.push_back(cell.course_length(c, x.data()));
      break;
    }
  }
  run.clearance_min_over_d = min_clearance / st.d;
  run.end = state;
  for (std::size_t c = 0; c < st.start.size(); ++c)
    run.course_knitted.push_back(st.knitted_length(static_cast<int>(c)));
  const int p = st.repeat.wales, q = st.repeat.courses;
  double sum = 0.0;
  for (const auto& course : st.cell_target)
    for (double l : course) sum += l;
  run.stitch_length = sum / (p * q);
  run.courses_per_cm = q * 1e-2 / state.height;
  run.wales_per_cm = p * 1e-2 / state.width;
  const double l_cm = run.stitch_length * 100.0;
  run.k_c = run.courses_per_cm * l_cm;
  run.k_w = run.wales_per_cm * l_cm;
  run.k_s = run.k_c * run.k_w;
  run.r = run.k_c / run.k_w;
  run.stats.steps = steps;
  run.stats.cpu_seconds = cpu_now() - cpu0;
  run.stats.wall_seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
  return run;
}

void check_cell_strain(double strain) {
  if (!(std::isfinite(strain) && strain >= 0.01 && strain <= 1.0))
    bad_field("knit.cell_strain", strain, "must be in [0.01, 1]");
}

YarnCellPull pull_yarn_cell(std::shared_ptr<const YarnCellStart> start,
                            const std::string& integrator, const IntegratorOptions& options,
                            const YarnCellState& relaxed, bool along_courses, double strain) {
  YarnCellPull out;
  out.along_courses = along_courses;
  const double W0 = relaxed.width, H0 = relaxed.height;
  const int n = std::max(1, static_cast<int>(std::ceil(strain / 0.01 - 1e-9)));
  YarnCellState state = relaxed;
  for (int k = 0; k <= n; ++k) {
    const double e = strain * k / n;
    const double x0 = state.courses[0][0].x, y0 = state.courses[0][0].y;
    if (along_courses) {
      const double f = W0 * (1.0 + e) / state.width;
      for (auto& course : state.courses)
        for (Vec3& v : course) v.x = x0 + f * (v.x - x0);
      state.width = W0 * (1.0 + e);
    } else {
      const double f = H0 * (1.0 + e) / state.height;
      for (auto& course : state.courses)
        for (Vec3& v : course) v.y = y0 + f * (v.y - y0);
      state.height = H0 * (1.0 + e);
    }
    const YarnCellRun r =
        run_yarn_cell(start, integrator, options, nullptr, &state,
                      along_courses ? CellSize::WidthHeld : CellSize::HeightHeld, false);
    state = r.end;
    const double reaction = along_courses ? r.size_gradient[0] : r.size_gradient[1];
    out.strain.push_back(e);
    out.reaction.push_back(reaction);
    out.force_per_width.push_back(reaction / (along_courses ? H0 : W0));
    out.lateral_strain.push_back(along_courses ? state.height / H0 - 1.0 : state.width / W0 - 1.0);
    out.status.push_back(r.stats.status);
    out.steps.push_back(r.stats.steps);
    out.cpu_seconds.push_back(r.stats.cpu_seconds);
    if (r.stats.status != RunStatus::Equilibrium) break;
  }
  return out;
}

}  // namespace knitsim
