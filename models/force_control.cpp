#include "models/force_control.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <stdexcept>

namespace knitsim {

namespace {

double component_of(const Vec3& v, int c) { return c == 0 ? v.x : c == 1 ? v.y : v.z; }
void add_component(Vec3& v, int c, double d) { (c == 0 ? v.x : c == 1 ? v.y : v.z) += d; }
bool finite(const Vec3& v) {
  return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

}  // namespace

ForceControl::ForceControl(MechanicalSystem& inner, std::vector<ForceBar> bars,
                           std::vector<PointLoad> loads, double residual_force_scale,
                           double fd_step)
    : inner_(inner),
      held_(inner.held_points()
                ? *inner.held_points()
                : throw std::invalid_argument("force control: the model holds no points")),
      bars_(std::move(bars)),
      loads_(std::move(loads)),
      residual_scale_(residual_force_scale),
      fd_step_(fd_step),
      n_(inner.dof()) {
  if (!(fd_step_ > 0.0) || !(residual_scale_ > 0.0))
    throw std::invalid_argument("force control: fd_step and residual_force_scale must be > 0");
  for (std::size_t b = 0; b < bars_.size(); ++b) {
    if (bars_[b].held.empty()) throw std::invalid_argument("force control: a bar without points");
    for (int k : bars_[b].held)
      if (k < 0 || k >= held_.held_count())
        throw std::invalid_argument("force control: held point out of range");
    if (!finite(bars_[b].force)) throw std::invalid_argument("force control: non-finite force");
    for (int c = 0; c < 3; ++c)
      if (component_of(bars_[b].force, c) != 0.0) {
        bar_of_.push_back(static_cast<int>(b));
        comp_.push_back(c);
      }
  }
  for (const PointLoad& p : loads_)
    if (p.dof < 0 || p.dof + 2 >= n_ || !finite(p.force))
      throw std::invalid_argument("force control: a point load's dof is out of range");
  const int m = unknowns();
  base_ = held_.held_positions(0.0);
  u0_.assign(m, 0.0);
  held_u_.assign(m, 0.0);

  const std::vector<double>& mi = inner_.mass();
  const std::vector<double>& gi = inner_.damping_rate();
  const double mean_mass = n_ ? std::accumulate(mi.begin(), mi.end(), 0.0) / n_ : 1.0;
  const double mean_gamma = n_ ? std::accumulate(gi.begin(), gi.end(), 0.0) / n_ : 0.0;
  mass_ = mi, gamma_ = gi;
  for (int j = 0; j < m; ++j) {
    mass_.push_back(mean_mass * static_cast<double>(bars_[bar_of_[j]].held.size()));
    gamma_.push_back(mean_gamma);
  }

  // The inner pattern with m dense rows and columns appended.
  const CscPattern& p = inner_.stiffness_pattern();
  pattern_.rows = pattern_.cols = n_ + m;
  pattern_.colptr.assign(1, 0);
  for (int c = 0; c < n_; ++c) {
    for (int e = p.colptr[c]; e < p.colptr[c + 1]; ++e) pattern_.rowind.push_back(p.rowind[e]);
    inner_nnz_end_.push_back(static_cast<int>(pattern_.rowind.size()));
    for (int j = 0; j < m; ++j) pattern_.rowind.push_back(n_ + j);
    pattern_.colptr.push_back(static_cast<int>(pattern_.rowind.size()));
  }
  for (int j = 0; j < m; ++j) {
    for (int r = 0; r < n_ + m; ++r) pattern_.rowind.push_back(r);
    pattern_.colptr.push_back(static_cast<int>(pattern_.rowind.size()));
  }
}

void ForceControl::set_load(double s) {
  if (!(s >= 0.0 && s <= 1.0)) throw std::invalid_argument("force control: load outside [0, 1]");
  load_ = s;
}

void ForceControl::hold(const double* u) const {
  const int m = unknowns();
  if (held_valid_ && std::equal(u, u + m, held_u_.begin())) return;
  std::vector<Vec3> p = base_;
  for (int j = 0; j < m; ++j)
    for (int k : bars_[bar_of_[j]].held) add_component(p[k], comp_[j], u[j]);
  // The inner model's held positions are this object's scratch (see the header).
  held_.set_held_positions(p);
  std::copy(u, u + m, held_u_.begin());
  held_valid_ = true;
}

void ForceControl::hold_at(const double* x) {
  hold(x + n_);
  std::copy(x + n_, x + n_ + unknowns(), u0_.begin());
}

void ForceControl::set_held_positions(const std::vector<Vec3>& p) {
  if (static_cast<int>(p.size()) != held_.held_count())
    throw std::invalid_argument("force control: wrong number of held positions");
  for (const Vec3& q : p)
    if (!finite(q)) throw std::invalid_argument("force control: non-finite held position");
  base_ = p;
  held_valid_ = false;
  hold(u0_.data());
}

void ForceControl::held_reactions(double t, const double* x, std::vector<Vec3>& out) const {
  hold(x + n_);
  held_.held_reactions(t, x, out);
}

std::vector<Vec3> ForceControl::bar_displacements(const double* x) const {
  std::vector<Vec3> d(bars_.size());
  for (int j = 0; j < unknowns(); ++j) add_component(d[bar_of_[j]], comp_[j], x[n_ + j]);
  return d;
}

Vec3 ForceControl::applied_load() const {
  Vec3 f{};
  for (const ForceBar& b : bars_) f = f + load_ * b.force;
  for (const PointLoad& p : loads_) f = f + load_ * p.force;
  return f;
}

void ForceControl::bar_forces(double t, const double* x, double* f) const {
  hold(x + n_);
  held_.held_reactions(t, x, scratch_r_);
  for (int j = 0; j < unknowns(); ++j) {
    double R = 0.0;
    for (int k : bars_[bar_of_[j]].held) R += component_of(scratch_r_[k], comp_[j]);
    f[j] = load_ * component_of(bars_[bar_of_[j]].force, comp_[j]) - R;
  }
}

void ForceControl::initial_state(double* x, double* v) const {
  inner_.initial_state(x, v);
  for (int j = 0; j < unknowns(); ++j) x[n_ + j] = u0_[j], v[n_ + j] = 0.0;
}

void ForceControl::conservative_acceleration(double t, const double* x, double* a) const {
  hold(x + n_);
  inner_.conservative_acceleration(t, x, a);
  const std::vector<double>& mi = inner_.mass();
  for (const PointLoad& p : loads_)
    for (int c = 0; c < 3; ++c) a[p.dof + c] += load_ * component_of(p.force, c) / mi[p.dof + c];
  bar_forces(t, x, a + n_);
  for (int j = 0; j < unknowns(); ++j) a[n_ + j] /= mass_[n_ + j];
}

void ForceControl::constant_acceleration(double t, double* a) const {
  inner_.constant_acceleration(t, a);
  const std::vector<double>& mi = inner_.mass();
  for (const PointLoad& p : loads_)
    for (int c = 0; c < 3; ++c) a[p.dof + c] += load_ * component_of(p.force, c) / mi[p.dof + c];
  for (int j = 0; j < unknowns(); ++j)
    a[n_ + j] = load_ * component_of(bars_[bar_of_[j]].force, comp_[j]) / mass_[n_ + j];
}

void ForceControl::stiffness_values(double t, const double* x, double* values) const {
  const int m = unknowns();
  const CscPattern& p = inner_.stiffness_pattern();
  // Bar columns by central differences: da_i/du_j (inner rows), dF_bar,k/du_j (bar rows).
  std::vector<double> col(static_cast<std::size_t>(n_) * m), bar(static_cast<std::size_t>(m) * m);
  std::vector<double> xs(x, x + n_ + m);
  scratch_a_.resize(n_ + m), scratch_b_.resize(n_ + m);
  std::vector<double> fa(m), fb(m);
  for (int j = 0; j < m; ++j) {
    xs[n_ + j] = x[n_ + j] + fd_step_;
    hold(xs.data() + n_);
    inner_.conservative_acceleration(t, xs.data(), scratch_a_.data());
    bar_forces(t, xs.data(), fa.data());
    xs[n_ + j] = x[n_ + j] - fd_step_;
    hold(xs.data() + n_);
    inner_.conservative_acceleration(t, xs.data(), scratch_b_.data());
    bar_forces(t, xs.data(), fb.data());
    xs[n_ + j] = x[n_ + j];
    for (int i = 0; i < n_; ++i)
      col[static_cast<std::size_t>(j) * n_ + i] = (scratch_a_[i] - scratch_b_[i]) / (2 * fd_step_);
    for (int k = 0; k < m; ++k) bar[j * m + k] = (fa[k] - fb[k]) / (2 * fd_step_);  // dF_k/du_j
  }
  hold(x + n_);
  scratch_k_.resize(p.nnz());
  inner_.stiffness_values(t, x, scratch_k_.data());
  const std::vector<double>& mi = inner_.mass();
  int out = 0;
  for (int c = 0; c < n_; ++c) {
    for (int e = p.colptr[c]; e < p.colptr[c + 1]; ++e) values[out++] = scratch_k_[e];
    // M_bar da_bar,j/dx_c = m_c da_c/du_j (the Hessian's symmetry).
    for (int j = 0; j < m; ++j)
      values[out++] = mi[c] * col[static_cast<std::size_t>(j) * n_ + c] / mass_[n_ + j];
  }
  for (int j = 0; j < m; ++j) {
    for (int i = 0; i < n_; ++i) values[out++] = col[static_cast<std::size_t>(j) * n_ + i];
    for (int k = 0; k < m; ++k)  // symmetrised in force units
      values[out++] = 0.5 * (bar[j * m + k] + bar[k * m + j]) / mass_[n_ + k];
  }
}

double ForceControl::static_residual(double t, const double* x) const {
  hold(x + n_);
  // The inner model's residual does not see the point loads: with them, the net forces here.
  double r = loads_.empty() ? inner_.static_residual(t, x) : 0.0;
  if (!loads_.empty()) {
    scratch_a_.resize(n_ + unknowns());
    conservative_acceleration(t, x, scratch_a_.data());
    const std::vector<double>& mi = inner_.mass();
    for (int i = 0; i + 2 < n_; i += 3) {
      const double fx = mi[i] * scratch_a_[i], fy = mi[i + 1] * scratch_a_[i + 1],
                   fz = mi[i + 2] * scratch_a_[i + 2];
      const double f = std::sqrt(fx * fx + fy * fy + fz * fz) / residual_scale_;
      if (!(f <= r)) r = f;
    }
  }
  std::vector<double> f(unknowns());
  bar_forces(t, x, f.data());
  for (double fj : f)
    if (!(std::abs(fj) / residual_scale_ <= r)) r = std::abs(fj) / residual_scale_;
  return r;
}

double ForceControl::residual_roundoff(double t, const double* x) const {
  hold(x + n_);
  return inner_.residual_roundoff(t, x);
}

double ForceControl::admissible_step(double t, const double* x, const double* dx) const {
  hold(x + n_);  // the bars' move is not checked against the inner model's barriers
  return inner_.admissible_step(t, x, dx);
}

bool ForceControl::update(double t, const double* x) {
  hold(x + n_);
  return inner_.update(t, x);
}

double ForceControl::potential_energy(double t, const double* x) const {
  hold(x + n_);
  double e = inner_.potential_energy(t, x);
  for (int j = 0; j < unknowns(); ++j)
    e -= load_ * component_of(bars_[bar_of_[j]].force, comp_[j]) * x[n_ + j];
  for (const PointLoad& p : loads_)
    for (int c = 0; c < 3; ++c) e -= load_ * component_of(p.force, c) * x[p.dof + c];
  return e;
}

std::string ForceControl::describe() const {
  return inner_.describe() + ", " + std::to_string(bars_.size()) + " clamp(s) under force (" +
         std::to_string(unknowns()) + " bar unknowns), " + std::to_string(loads_.size()) +
         " point load(s)";
}

}  // namespace knitsim
