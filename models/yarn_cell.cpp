#include "models/yarn_cell.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <string>

#include "models/rod_elements.hpp"
#include "src/geometry/segment_distance.hpp"

namespace knitsim {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();

double component(Vec3 v, int c) { return c == 0 ? v.x : (c == 1 ? v.y : v.z); }

}  // namespace

struct YarnCell::State {
  std::vector<Vec3> pos;  // every cell vertex
  double W = 0.0, H = 0.0;
  Vec3 at(const Ref& r) const { return pos[r.v] + Vec3{r.kx * W, r.ky * H, 0.0}; }
};

// Where an evaluation writes: the energy; the gradient dE/d(unknowns) (Force, Stiffness), the
// dense Hessian (Stiffness); dE/dW and dE/dH always (size_gradient); `bad` for an infeasible state.
struct YarnCell::Accumulator {
  double energy = 0.0;
  double* grad = nullptr;  // dof
  double* hess = nullptr;  // dof x dof, row-major
  double gW = 0.0, gH = 0.0;
  bool bad = false;
};

YarnCell::YarnCell(YarnCellSpec spec) : spec_(std::move(spec)) {
  const YarnParams& p = spec_.yarn;
  p.validate();
  d_ = p.diameter();
  d0_ = p.core_fraction * d_;
  kappa_c_ = p.contact_kappa();
  gap_ = p.same_yarn_gap * d_;
  const int q = static_cast<int>(spec_.initial.size());
  if (q == 0) throw std::invalid_argument("yarn cell: no course given");
  if (static_cast<int>(spec_.rest.size()) != q)
    throw std::invalid_argument("yarn cell: rest must have one list per course");
  if (!(std::isfinite(spec_.width) && spec_.width > 0.0 && std::isfinite(spec_.height) &&
        spec_.height > 0.0))
    throw std::invalid_argument("yarn cell: width and height must be > 0 m");
  for (int c = 0; c < q; ++c) {
    const int n = static_cast<int>(spec_.initial[c].size());
    if (n < 3) throw std::invalid_argument("yarn cell: a course has fewer than 3 vertices");
    if (static_cast<int>(spec_.rest[c].size()) != n)
      throw std::invalid_argument("yarn cell: a course needs one rest length per vertex");
    course_first_.push_back(static_cast<int>(start_.size()));
    const int first = course_first_.back();
    double arc = 0.0;
    for (int k = 0; k < n; ++k) {
      const double l = spec_.rest[c][k];
      if (!(std::isfinite(l) && l > 0.0) || !is_finite(spec_.initial[c][k]))
        throw std::invalid_argument("yarn cell: rest lengths must be > 0 and vertices finite");
      start_.push_back(spec_.initial[c][k]);
      vertex_course_.push_back(c);
      const Ref a{first + k, 0, 0};
      const Ref b = k + 1 < n ? Ref{first + k + 1, 0, 0} : Ref{first, 1, 0};
      const int samples = std::max(1, static_cast<int>(std::ceil(4.0 * l / d_)));
      edges_.push_back({a, b, l, arc, c, samples});
      arc += l;
    }
    period_.push_back(arc);
    for (int k = 0; k < n; ++k) {
      const Ref prev = k > 0 ? Ref{first + k - 1, 0, 0} : Ref{first + n - 1, -1, 0};
      const Ref next = k + 1 < n ? Ref{first + k + 1, 0, 0} : Ref{first, 1, 0};
      const double lprev = spec_.rest[c][(k + n - 1) % n];
      bends_.push_back({{prev, {first + k, 0, 0}, next}, 0.5 * (lprev + spec_.rest[c][k])});
    }
  }
  course_first_.push_back(static_cast<int>(start_.size()));
  const int nv = static_cast<int>(start_.size());
  free_index_.assign(nv, -1);
  int f = 0;
  for (int v = 1; v < nv; ++v) free_index_[v] = f++;  // course 0's vertex 0 is held
  dof_ = 3 * f;
  const bool w_free = spec_.size == CellSize::Free || spec_.size == CellSize::HeightHeld;
  const bool h_free = spec_.size == CellSize::Free || spec_.size == CellSize::WidthHeld;
  if (w_free) w_index_ = dof_++;
  if (h_free) h_index_ = dof_++;

  vertex_mass_.assign(nv, 0.0);
  double total = 0.0;
  for (const Edge& e : edges_) {
    vertex_mass_[e.a.v] += 0.5 * p.linear_density() * e.rest;
    vertex_mass_[e.b.v] += 0.5 * p.linear_density() * e.rest;
    total += p.linear_density() * e.rest;
  }
  mass_.assign(dof_, total);
  for (int v = 0; v < nv; ++v)
    if (free_index_[v] >= 0)
      for (int c = 0; c < 3; ++c) mass_[3 * free_index_[v] + c] = vertex_mass_[v];
  gamma_.assign(dof_, 1.0 / p.relaxation_time);
  if (!(std::isfinite(spec_.residual_force_scale) && spec_.residual_force_scale >= 0.0))
    throw std::invalid_argument("yarn cell: residual_force_scale must be >= 0 N");
  double mean = 0.0;
  for (double L : period_) mean += L / q;
  residual_scale_ = spec_.residual_force_scale > 0.0 ? spec_.residual_force_scale
                                                     : p.bending_rigidity / (mean * mean);
  // Dense: every (row, column).
  pattern_.rows = pattern_.cols = dof_;
  pattern_.colptr.resize(dof_ + 1);
  pattern_.rowind.resize(static_cast<std::size_t>(dof_) * dof_);
  for (int c = 0; c <= dof_; ++c) pattern_.colptr[c] = c * dof_;
  for (int c = 0; c < dof_; ++c)
    for (int r = 0; r < dof_; ++r) pattern_.rowind[static_cast<std::size_t>(c) * dof_ + r] = r;
}

void YarnCell::initial_state(double* x, double* v) const {
  for (std::size_t i = 0; i < start_.size(); ++i) {
    const int f = free_index_[i];
    if (f < 0) continue;
    x[3 * f] = start_[i].x, x[3 * f + 1] = start_[i].y, x[3 * f + 2] = start_[i].z;
  }
  if (w_index_ >= 0) x[w_index_] = spec_.width;
  if (h_index_ >= 0) x[h_index_] = spec_.height;
  std::fill(v, v + dof_, 0.0);
}

void YarnCell::unpack(const double* x, State& s) const {
  s.pos.resize(start_.size());
  for (std::size_t i = 0; i < start_.size(); ++i) {
    const int f = free_index_[i];
    s.pos[i] = f < 0 ? start_[i] : Vec3{x[3 * f], x[3 * f + 1], x[3 * f + 2]};
  }
  s.W = w_index_ >= 0 ? x[w_index_] : spec_.width;
  s.H = h_index_ >= 0 ? x[h_index_] : spec_.height;
}

double YarnCell::width(const double* x) const { return w_index_ >= 0 ? x[w_index_] : spec_.width; }
double YarnCell::height(const double* x) const {
  return h_index_ >= 0 ? x[h_index_] : spec_.height;
}

void YarnCell::fold(const Ref* refs, int n, const double* g, const double* h,
                    Accumulator& acc) const {
  // Per image its unknowns: (dof, component of y, coefficient) -- x_v's three, W, H.
  int idx[4][5], comp[4][5], count[4];
  double coef[4][5];
  for (int a = 0; a < n; ++a) {
    count[a] = 0;
    const int f = free_index_[refs[a].v];
    if (f >= 0)
      for (int c = 0; c < 3; ++c)
        idx[a][count[a]] = 3 * f + c, comp[a][count[a]] = c, coef[a][count[a]++] = 1.0;
    if (w_index_ >= 0 && refs[a].kx != 0)
      idx[a][count[a]] = w_index_, comp[a][count[a]] = 0, coef[a][count[a]++] = refs[a].kx;
    if (h_index_ >= 0 && refs[a].ky != 0)
      idx[a][count[a]] = h_index_, comp[a][count[a]] = 1, coef[a][count[a]++] = refs[a].ky;
    acc.gW += refs[a].kx * g[3 * a];
    acc.gH += refs[a].ky * g[3 * a + 1];
  }
  if (acc.grad)
    for (int a = 0; a < n; ++a)
      for (int k = 0; k < count[a]; ++k) acc.grad[idx[a][k]] += coef[a][k] * g[3 * a + comp[a][k]];
  if (!acc.hess || !h) return;
  const int m = 3 * n;
  for (int a = 0; a < n; ++a)
    for (int b = 0; b < n; ++b)
      for (int k = 0; k < count[a]; ++k)
        for (int l = 0; l < count[b]; ++l)
          acc.hess[static_cast<std::size_t>(idx[a][k]) * dof_ + idx[b][l]] +=
              coef[a][k] * coef[b][l] * h[(3 * a + comp[a][k]) * m + 3 * b + comp[b][l]];
}

void YarnCell::evaluate(const double* x, Mode mode, Accumulator& acc) const {
  State s;
  unpack(x, s);
  if (!(s.W > 0.0) || !(s.H > 0.0)) {
    acc.bad = true;
    return;
  }
  const YarnParams& p = spec_.yarn;
  const double EA = p.stretch_stiffness();
  for (const Edge& e : edges_) {
    const Vec3 u = s.at(e.b) - s.at(e.a);
    const double L = norm(u), stiff = EA / e.rest, ext = L - e.rest;
    acc.energy += 0.5 * stiff * ext * ext;
    if (mode == Mode::Energy) continue;
    const double n3[3] = {u.x / L, u.y / L, u.z / L};
    double g[6], h[36];
    for (int c = 0; c < 3; ++c) g[3 + c] = stiff * ext * n3[c], g[c] = -g[3 + c];
    if (mode == Mode::Stiffness) {
      const double t = stiff * ext / L;
      for (int a = 0; a < 3; ++a)
        for (int b = 0; b < 3; ++b) {
          const double v = (stiff - t) * n3[a] * n3[b] + (a == b ? t : 0.0);
          h[a * 6 + b] = h[(3 + a) * 6 + 3 + b] = v;
          h[a * 6 + 3 + b] = h[(3 + a) * 6 + b] = -v;
        }
    }
    const Ref refs[2] = {e.a, e.b};
    fold(refs, 2, g, mode == Mode::Stiffness ? h : nullptr, acc);
  }
  for (const Bend& b : bends_) {
    BendElement el;
    if (!bend_element(s.at(b.v[0]), s.at(b.v[1]), s.at(b.v[2]), p.bending_rigidity / (2.0 * b.lbar),
                      0.0, static_cast<int>(mode), el)) {
      acc.bad = true;
      continue;
    }
    acc.energy += el.energy;
    if (mode != Mode::Energy)
      fold(b.v, 3, el.grad, mode == Mode::Stiffness ? el.hess : nullptr, acc);
  }
  if (spec_.contact) contact_terms(s, mode, acc);
}

bool YarnCell::samples_pair(const Edge& A, double sa, const Edge& B, double sb, int sx,
                            int sy) const {
  if (A.course != B.course || sy != 0) return true;
  const double a = A.arc + sa * A.rest, b = B.arc + sb * B.rest + sx * period_[B.course];
  return std::abs(a - b) >= gap_;
}

bool YarnCell::whole(const Edge& A, const Edge& B, int sx, int sy) const {
  if (A.course != B.course || sy != 0) return true;
  const double b0 = B.arc + sx * period_[B.course];
  return std::max(A.arc, b0) - std::min(A.arc + A.rest, b0 + B.rest) >= gap_;
}

bool YarnCell::may_pair(const Edge& A, const Edge& B, int sx, int sy) const {
  if (A.course != B.course || sy != 0) return true;
  const double off = sx * period_[B.course];
  const double a_lo = A.arc + 0.5 * A.rest / A.samples,
               a_hi = A.arc + A.rest - 0.5 * A.rest / A.samples;
  const double b_lo = B.arc + off + 0.5 * B.rest / B.samples,
               b_hi = B.arc + off + B.rest - 0.5 * B.rest / B.samples;
  return std::max(b_hi - a_lo, a_hi - b_lo) >= gap_;
}

template <class Visit>
bool YarnCell::for_each_pair(const State& s, double grow, Visit visit) const {
  const int ne = static_cast<int>(edges_.size());
  std::vector<double> box(6 * static_cast<std::size_t>(ne));
  double lo[3] = {kInf, kInf, kInf}, hi[3] = {-kInf, -kInf, -kInf};
  for (int e = 0; e < ne; ++e) {
    const Vec3 a = s.at(edges_[e].a), b = s.at(edges_[e].b);
    for (int c = 0; c < 3; ++c) {
      box[6 * e + c] = std::min(component(a, c), component(b, c)) - grow;
      box[6 * e + 3 + c] = std::max(component(a, c), component(b, c)) + grow;
      lo[c] = std::min(lo[c], box[6 * e + c]);
      hi[c] = std::max(hi[c], box[6 * e + 3 + c]);
    }
  }
  // Images whose boxes can meet the cell's: |s_x| W <= the boxes' extent.
  const double kx = std::ceil((hi[0] - lo[0]) / s.W), ky = std::ceil((hi[1] - lo[1]) / s.H);
  if (!(kx <= kMaxCellShift && ky <= kMaxCellShift)) return false;
  const int KX = static_cast<int>(kx), KY = static_cast<int>(ky);
  for (int sx = -KX; sx <= KX; ++sx)
    for (int sy = -KY; sy <= KY; ++sy) {
      const double off[3] = {sx * s.W, sy * s.H, 0.0};
      const bool positive = sx > 0 || (sx == 0 && sy > 0);
      for (int i = 0; i < ne; ++i) {
        const double* bi = box.data() + 6 * i;
        for (int j = positive ? i : i + 1; j < ne; ++j) {
          const double* bj = box.data() + 6 * j;
          bool overlap = true;
          for (int c = 0; c < 3 && overlap; ++c)
            overlap = bi[c] <= bj[3 + c] + off[c] && bj[c] + off[c] <= bi[3 + c];
          if (overlap) visit(i, j, sx, sy);
        }
      }
    }
  return true;
}

void YarnCell::contact_terms(const State& s, Mode mode, Accumulator& acc) const {
  const double d2 = d_ * d_;
  const bool ok = for_each_pair(s, 0.5 * d_, [&](int i, int j, int sx, int sy) {
    const Edge &A = edges_[i], &B = edges_[j];
    if (!may_pair(A, B, sx, sy)) return;
    const Ref refs[4] = {
        A.a, A.b, {B.a.v, B.a.kx + sx, B.a.ky + sy}, {B.b.v, B.b.kx + sx, B.b.ky + sy}};
    const Vec3 pa = s.at(refs[0]), pb = s.at(refs[1]), qa = s.at(refs[2]), qb = s.at(refs[3]);
    const double w = (A.rest / A.samples) * (B.rest / B.samples) / d2;
    double g[12] = {0};
    double h[144];
    bool active = false;
    for (int k = 0; k < A.samples; ++k) {
      const double sa = (k + 0.5) / A.samples;
      const Vec3 P = (1.0 - sa) * pa + sa * pb;
      for (int m = 0; m < B.samples; ++m) {
        const double sb = (m + 0.5) / B.samples;
        const Vec3 u = P - ((1.0 - sb) * qa + sb * qb);
        const double D = norm(u);
        if (!(D < d_)) continue;
        if (!samples_pair(A, sa, B, sb, sx, sy)) continue;
        if (!(D > d0_)) {
          acc.bad = true;
          continue;
        }
        const ContactBarrier bar = contact_barrier(D, d_, d0_, kappa_c_);
        acc.energy += w * bar.e;
        if (mode == Mode::Energy) continue;
        if (!active) {
          active = true;
          if (mode == Mode::Stiffness) std::fill(h, h + 144, 0.0);
        }
        const double n3[3] = {u.x / D, u.y / D, u.z / D};
        const double coef[4] = {1.0 - sa, sa, -(1.0 - sb), -sb};
        for (int r = 0; r < 4; ++r)
          for (int c = 0; c < 3; ++c) g[3 * r + c] += coef[r] * w * bar.de * n3[c];
        if (mode != Mode::Stiffness) continue;
        double H[9];
        const double t1 = bar.de / D;
        for (int a = 0; a < 3; ++a)
          for (int b = 0; b < 3; ++b)
            H[3 * a + b] = w * ((bar.dde - t1) * n3[a] * n3[b] + (a == b ? t1 : 0.0));
        for (int r = 0; r < 4; ++r)
          for (int c = 0; c < 4; ++c)
            for (int a = 0; a < 3; ++a)
              for (int b = 0; b < 3; ++b)
                h[(3 * r + a) * 12 + 3 * c + b] += coef[r] * coef[c] * H[3 * a + b];
      }
    }
    if (active) fold(refs, 4, g, mode == Mode::Stiffness ? h : nullptr, acc);
  });
  if (!ok) acc.bad = true;
}

void YarnCell::net_force(const double* x, double* f) const {
  std::fill(f, f + dof_, 0.0);
  Accumulator acc;
  acc.grad = f;
  evaluate(x, Mode::Force, acc);
  for (int i = 0; i < dof_; ++i) f[i] = acc.bad ? kNaN : -f[i];
}

void YarnCell::conservative_acceleration(double /*t*/, const double* x, double* a) const {
  net_force(x, a);
  for (int i = 0; i < dof_; ++i) a[i] /= mass_[i];
}

void YarnCell::stiffness_values(double /*t*/, const double* x, double* values) const {
  hess_.assign(static_cast<std::size_t>(dof_) * dof_, 0.0);
  std::vector<double> grad(dof_, 0.0);
  Accumulator acc;
  acc.grad = grad.data();
  acc.hess = hess_.data();
  evaluate(x, Mode::Stiffness, acc);
  // da_c/dx = -M^-1 d2E/dx2, column-major (the dense pattern's order).
  for (int c = 0; c < dof_; ++c)
    for (int r = 0; r < dof_; ++r)
      values[static_cast<std::size_t>(c) * dof_ + r] =
          acc.bad ? kNaN : -hess_[static_cast<std::size_t>(r) * dof_ + c] / mass_[r];
}

double YarnCell::potential_energy(double /*t*/, const double* x) const {
  Accumulator acc;
  evaluate(x, Mode::Energy, acc);
  return acc.bad ? kInf : acc.energy;
}

std::array<double, 2> YarnCell::size_gradient(const double* x) const {
  std::vector<double> grad(dof_, 0.0);
  Accumulator acc;
  acc.grad = grad.data();
  evaluate(x, Mode::Force, acc);
  if (acc.bad) return {kNaN, kNaN};
  return {acc.gW, acc.gH};
}

double YarnCell::static_residual(double /*t*/, const double* x) const {
  std::vector<double> f(dof_);
  net_force(x, f.data());
  double worst = 0.0;
  const int nv3 = 3 * static_cast<int>(start_.size() - 1);
  for (int i = 0; i < nv3; i += 3) {
    const double f2 = f[i] * f[i] + f[i + 1] * f[i + 1] + f[i + 2] * f[i + 2];
    if (!(f2 <= worst)) worst = f2;  // NaN propagates
  }
  for (int i = nv3; i < dof_; ++i)
    if (!(f[i] * f[i] <= worst)) worst = f[i] * f[i];
  return std::sqrt(worst) / residual_scale_;
}

// As YarnRods::residual_roundoff: an edge's force carries EA / l eps (|y_a| + |y_b|), a bend's
// 8 B eps sum |y| / (lbar l^2).
double YarnCell::residual_roundoff(double /*t*/, const double* x) const {
  State s;
  unpack(x, s);
  constexpr double eps = std::numeric_limits<double>::epsilon();
  double worst = 0.0;
  std::vector<double> floor_(start_.size(), 0.0);
  for (const Edge& e : edges_) {
    const double r =
        spec_.yarn.stretch_stiffness() / e.rest * eps * (norm(s.at(e.a)) + norm(s.at(e.b)));
    floor_[e.a.v] += r;
    floor_[e.b.v] += r;
  }
  for (const Bend& b : bends_) {
    double sx = 0.0;
    for (const Ref& r : b.v) sx += norm(s.at(r));
    const double r = 8.0 * spec_.yarn.bending_rigidity * eps * sx / (b.lbar * b.lbar * b.lbar);
    for (const Ref& v : b.v) floor_[v.v] += r;
  }
  for (std::size_t v = 1; v < floor_.size(); ++v) worst = std::max(worst, floor_[v]);
  return worst / residual_scale_;
}

double YarnCell::admissible_step(double /*t*/, const double* x, const double* dx) const {
  State s;
  unpack(x, s);
  const double dW = w_index_ >= 0 ? dx[w_index_] : 0.0;
  const double dH = h_index_ >= 0 ? dx[h_index_] : 0.0;
  const double keep = spec_.yarn.step_keep;
  double admit = 1.0;
  // W and H stay positive.
  if (s.W + dW < keep * s.W) admit = std::min(admit, (1.0 - keep) * s.W / -dW);
  if (s.H + dH < keep * s.H) admit = std::min(admit, (1.0 - keep) * s.H / -dH);
  if (!spec_.contact) return admit;
  std::vector<Vec3> vmove(start_.size(), Vec3{});
  for (std::size_t v = 0; v < start_.size(); ++v) {
    const int f = free_index_[v];
    if (f >= 0) vmove[v] = {dx[3 * f], dx[3 * f + 1], dx[3 * f + 2]};
  }
  auto move = [&](const Ref& r) { return norm(vmove[r.v] + Vec3{r.kx * dW, r.ky * dH, 0.0}); };
  double largest = 0.0;
  for (const Edge& e : edges_) {
    const double m = std::max(move(e.a), move(e.b));
    if (!(m <= largest)) largest = m;
  }
  if (!std::isfinite(largest)) return 0.0;
  // An image s cells away moves |s_x dW| + |s_y dH| more than its cell vertex: the boxes grow by
  // that for the farthest images the vertex moves alone could bring into reach.
  const double g0 = 0.5 * d_ + largest;
  double lo[2] = {kInf, kInf}, hi[2] = {-kInf, -kInf};
  for (const Edge& e : edges_)
    for (const Ref& r : {e.a, e.b}) {
      const Vec3 y = s.at(r);
      lo[0] = std::min(lo[0], y.x), hi[0] = std::max(hi[0], y.x);
      lo[1] = std::min(lo[1], y.y), hi[1] = std::max(hi[1], y.y);
    }
  const double kx = std::ceil((hi[0] - lo[0] + 2.0 * g0) / s.W) + 1.0;
  const double ky = std::ceil((hi[1] - lo[1] + 2.0 * g0) / s.H) + 1.0;
  const double grow = g0 + kx * std::abs(dW) + ky * std::abs(dH);
  const bool ok = for_each_pair(s, grow, [&](int i, int j, int sx, int sy) {
    const Edge &A = edges_[i], &B = edges_[j];
    const Ref refs[4] = {
        A.a, A.b, {B.a.v, B.a.kx + sx, B.a.ky + sy}, {B.b.v, B.b.kx + sx, B.b.ky + sy}};
    const double reach =
        std::max(move(refs[0]), move(refs[1])) + std::max(move(refs[2]), move(refs[3]));
    if (!(reach > 0.0)) return;
    if (!may_pair(A, B, sx, sy)) return;
    const Vec3 pa = s.at(refs[0]), pb = s.at(refs[1]), qa = s.at(refs[2]), qb = s.at(refs[3]);
    const double D = closest_points(pa, pb, qa, qb).distance;
    if (D - reach >= d_) return;  // cannot come within d, let alone the core
    // The segment distance bounds every sample pair only where all of them pair (edges of one
    // pass nearer than the gap along the yarn have excluded parts, as close as they like).
    if (D > d0_ && whole(A, B, sx, sy)) {
      if (D - reach < d0_ + keep * (D - d0_))
        admit = std::min(admit, (1.0 - keep) * (D - d0_) / reach);
      return;
    }
    for (int k = 0; k < A.samples; ++k) {
      const double sa = (k + 0.5) / A.samples;
      const Vec3 P = (1.0 - sa) * pa + sa * pb;
      for (int m = 0; m < B.samples; ++m) {
        const double sb = (m + 0.5) / B.samples;
        if (!samples_pair(A, sa, B, sb, sx, sy)) continue;
        const double Ds = norm(P - ((1.0 - sb) * qa + sb * qb));
        if (!(Ds > d0_)) {
          admit = 0.0;
          return;
        }
        if (Ds - reach < d0_ + keep * (Ds - d0_))
          admit = std::min(admit, (1.0 - keep) * (Ds - d0_) / reach);
      }
    }
  });
  if (ok) return admit;
  // Too wide a search (a step long against the cell): the half step's admitted fraction, halved.
  std::vector<double> half(dx, dx + dof_);
  for (double& h : half) h *= 0.5;
  return largest > 1e-3 * d_ ? 0.5 * admissible_step(0.0, x, half.data()) : 0.0;
}

std::vector<std::vector<Vec3>> YarnCell::courses_at(const double* x) const {
  State s;
  unpack(x, s);
  std::vector<std::vector<Vec3>> out(courses());
  for (int c = 0; c < courses(); ++c)
    out[c].assign(s.pos.begin() + course_first_[c], s.pos.begin() + course_first_[c + 1]);
  return out;
}

double YarnCell::course_length(int course, const double* x) const {
  State s;
  unpack(x, s);
  double L = 0.0;
  for (const Edge& e : edges_)
    if (e.course == course) L += norm(s.at(e.b) - s.at(e.a));
  return L;
}

double YarnCell::min_clearance(const double* x) const {
  State s;
  unpack(x, s);
  if (!(s.W > 0.0) || !(s.H > 0.0)) return kNaN;
  double best = kInf;
  const bool ok = for_each_pair(s, d_, [&](int i, int j, int sx, int sy) {
    const Edge &A = edges_[i], &B = edges_[j];
    const Ref refs[4] = {
        A.a, A.b, {B.a.v, B.a.kx + sx, B.a.ky + sy}, {B.b.v, B.b.kx + sx, B.b.ky + sy}};
    const Vec3 pa = s.at(refs[0]), pb = s.at(refs[1]), qa = s.at(refs[2]), qb = s.at(refs[3]);
    if (!may_pair(A, B, sx, sy)) return;
    if (whole(A, B, sx, sy)) {
      best = std::min(best, closest_points(pa, pb, qa, qb).distance);
      return;
    }
    for (int k = 0; k < A.samples; ++k) {
      const double sa = (k + 0.5) / A.samples;
      const Vec3 P = (1.0 - sa) * pa + sa * pb;
      for (int m = 0; m < B.samples; ++m) {
        const double sb = (m + 0.5) / B.samples;
        if (samples_pair(A, sa, B, sb, sx, sy))
          best = std::min(best, norm(P - ((1.0 - sb) * qa + sb * qb)));
      }
    }
  });
  if (!ok) return kNaN;
  return best < 2.0 * d_ ? best : kInf;
}

double YarnCell::stretch_energy(const double* x) const {
  State s;
  unpack(x, s);
  double e = 0.0;
  for (const Edge& ed : edges_) {
    const double ext = norm(s.at(ed.b) - s.at(ed.a)) - ed.rest;
    e += 0.5 * spec_.yarn.stretch_stiffness() / ed.rest * ext * ext;
  }
  return e;
}

double YarnCell::bend_energy(const double* x) const {
  State s;
  unpack(x, s);
  double e = 0.0;
  for (const Bend& b : bends_) {
    BendElement el;
    e += bend_element(s.at(b.v[0]), s.at(b.v[1]), s.at(b.v[2]),
                      spec_.yarn.bending_rigidity / (2.0 * b.lbar), 0.0, 0, el)
             ? el.energy
             : kInf;
  }
  return e;
}

double YarnCell::contact_energy(const double* x) const {
  if (!spec_.contact) return 0.0;
  State s;
  unpack(x, s);
  Accumulator acc;
  contact_terms(s, Mode::Energy, acc);
  return acc.bad ? kInf : acc.energy;
}

std::string YarnCell::describe() const {
  std::ostringstream s;
  s << "yarn cell: " << courses() << " courses, " << start_.size() << " vertices, d = " << d_ * 1e3
    << " mm, EA = " << spec_.yarn.stretch_stiffness() << " N, B = " << spec_.yarn.bending_rigidity
    << " N m^2, size "
    << (spec_.size == CellSize::Free         ? "free"
        : spec_.size == CellSize::HeightHeld ? "W free, H held"
        : spec_.size == CellSize::WidthHeld  ? "H free, W held"
                                             : "held")
    << (spec_.contact ? ", contact" : ", no contact");
  return s.str();
}

namespace {

// The source polyline's edges per chart cell: fine enough that resampling it is exact to
// (l / 64)^2 of the curvature.
constexpr int kSourceVertices = 64;

// Point at arc length a along a polyline with cumulative arcs `arc`.
Vec3 at_arc(const std::vector<Vec3>& v, const std::vector<double>& arc, double a) {
  const std::size_t hi = std::clamp<std::size_t>(
      std::upper_bound(arc.begin(), arc.end(), a) - arc.begin(), 1, arc.size() - 1);
  const double s = (a - arc[hi - 1]) / (arc[hi] - arc[hi - 1]);
  return (1.0 - s) * v[hi - 1] + s * v[hi];
}

}  // namespace

bool YarnCellStart::ramp() const {
  for (std::size_t c = 0; c < start_length.size(); ++c)
    for (std::size_t k = 0; k < start_length[c].size(); ++k)
      if (target_length[c][k] != start_length[c][k]) return true;
  return false;
}

double YarnCellStart::knitted_length(int course) const {
  double L = 0.0;
  for (double l : target_length[course]) L += l;
  return L;
}

YarnCellSpec YarnCellStart::spec(int s, int n, const std::vector<std::vector<Vec3>>& initial,
                                 double w, double h, CellSize size) const {
  YarnCellSpec out;
  out.yarn = params.yarn;
  out.initial = initial.empty() ? start : initial;
  out.width = w > 0.0 ? w : width;
  out.height = h > 0.0 ? h : height;
  out.size = size;
  const double f = n > 0 ? static_cast<double>(s) / n : 1.0;
  out.rest.resize(start_length.size());
  double sum = 0.0, cells = 0.0;
  for (std::size_t c = 0; c < start_length.size(); ++c) {
    for (std::size_t k = 0; k < start_length[c].size(); ++k)
      out.rest[c].push_back(start_length[c][k] + f * (target_length[c][k] - start_length[c][k]));
    for (double t : cell_target[c]) sum += t, cells += 1.0;
  }
  // F_ref: the bending force of a loop, B / l^2 with l the knitted stitch length (as the swatch).
  const double l = sum / cells;
  out.residual_force_scale = params.yarn.bending_rigidity / (l * l);
  return out;
}

YarnCellStart build_yarn_cell_start(const KnitChart& repeat, const KnitParams& structure,
                                    const YarnKnitParams& params) {
  params.validate();
  const int p = repeat.wales, q = repeat.courses;
  if (p < 1 || q < 1 || static_cast<int>(repeat.stitches.size()) != p * q)
    throw std::invalid_argument("yarn cell: the repeat has no stitches");
  // Tiled to at least 5 x 5 (an odd number of repeats), the middle repeat interior.
  const int rx = 2 * ((5 + p - 1) / p / 2) + 1, ry = 2 * ((5 + q - 1) / q / 2) + 1;
  KnitChart chart;
  chart.wales = rx * p;
  chart.courses = ry * q;
  // Knits on the tiling's edges (edge wales, bottom course, a miss in the top course), which the
  // swatch's chart rules ask for and the interior repeat does not see.
  for (int j = 0; j < chart.courses; ++j)
    for (int i = 0; i < chart.wales; ++i) {
      const Stitch s = repeat.at(i % p, j % q);
      const bool edge =
          i == 0 || i == chart.wales - 1 || j == 0 || (j == chart.courses - 1 && s == Stitch::Miss);
      chart.stitches.push_back(edge ? Stitch::Knit : s);
    }
  YarnKnitParams fine = params;
  fine.vertices_per_loop = kSourceVertices;
  fine.stitch_length = fine.tuck_length = fine.miss_length = 0.0;
  const YarnKnit yk = build_yarn_knit(chart, structure, fine);

  YarnCellStart out;
  out.repeat = repeat;
  out.params = params;
  out.d = yk.d;
  const int per = static_cast<int>(params.vertices_per_loop), n = p * per;
  const int i0 = (rx / 2) * p, j0 = (ry / 2) * q;
  out.width = p * yk.structure.params.wale_spacing();
  out.height = q * yk.structure.params.course_spacing();
  const std::vector<std::vector<Vec3>> lines = yk.course_polylines(yk.start);
  std::vector<std::vector<double>> cell_arc(q);  // per course, the wales' boundaries (arc)
  for (int c = 0; c < q; ++c) {
    const std::vector<Vec3>& v = lines[j0 + c];
    std::vector<double> arc(v.size(), 0.0);
    for (std::size_t k = 1; k < v.size(); ++k) arc[k] = arc[k - 1] + norm(v[k] - v[k - 1]);
    auto arc_of = [&](double index) {
      const int k =
          std::clamp(static_cast<int>(std::floor(index)), 0, static_cast<int>(arc.size()) - 2);
      return arc[k] + (index - k) * (arc[k + 1] - arc[k]);
    };
    for (int i = 0; i < p; ++i)
      cell_arc[c].push_back(arc_of(yk.marks[(j0 + c) * chart.wales + i0 + i].begin));
    cell_arc[c].push_back(arc_of(yk.marks[(j0 + c) * chart.wales + i0 + p - 1].end));
    const double a0 = cell_arc[c].front(), a1 = cell_arc[c].back();
    std::vector<Vec3> s;
    for (int k = 0; k <= n; ++k) s.push_back(at_arc(v, arc, a0 + (a1 - a0) * k / n));
    const Vec3 drift = s[n] - s[0] - Vec3{out.width, 0.0, 0.0};
    for (int k = 0; k < n; ++k) s[k] = s[k] - (static_cast<double>(k) / n) * drift;
    s.pop_back();
    out.start.push_back(std::move(s));
    for (double& a : cell_arc[c]) a = (a - a0) / (a1 - a0);  // as fractions of the period
  }
  // Scaled until clear of every image at d.
  const double d = out.d;
  double scale = 1.0, clearance = 0.0;
  std::vector<std::vector<Vec3>> scaled;
  for (int pass = 0; pass < 12; ++pass) {
    scaled = out.start;
    for (auto& course : scaled)
      for (Vec3& v : course) v = scale * v;
    YarnCellSpec cs;
    cs.yarn = params.yarn;
    cs.initial = scaled;
    cs.width = scale * out.width;
    cs.height = scale * out.height;
    cs.contact = false;
    for (const auto& course : scaled) {
      std::vector<double> l;
      for (std::size_t k = 0; k < course.size(); ++k)
        l.push_back(
            norm((k + 1 < course.size() ? course[k + 1] : course[0] + Vec3{cs.width, 0.0, 0.0}) -
                 course[k]));
      cs.rest.push_back(l);
    }
    const YarnCell cell(cs);
    std::vector<double> x(cell.dof()), vel(cell.dof());
    cell.initial_state(x.data(), vel.data());
    clearance = cell.min_clearance(x.data());
    if (clearance >= kYarnStartClearance * d && clearance <= kYarnStartClearanceMax * d) break;
    scale *= std::isfinite(clearance)
                 ? 0.5 * (kYarnStartClearance + kYarnStartClearanceMax) * d / clearance
                 : 0.8;
  }
  if (!(clearance >= d))
    throw std::invalid_argument(
        "yarn cell: the start could not be made intersection-free at the yarn diameter "
        "(closest pair " +
        std::to_string(clearance / d) + " d)");
  out.start = scaled;
  out.width *= scale;
  out.height *= scale;
  out.r = scale * yk.r;
  out.start_clearance = clearance;

  // Rest lengths: the start's; the targets per the stitch type of the wale each edge lies in.
  out.start_length.resize(q);
  std::vector<std::vector<int>> edge_wale(q);
  for (int c = 0; c < q; ++c) {
    const auto& v = out.start[c];
    for (int k = 0; k < n; ++k) {
      out.start_length[c].push_back(
          norm((k + 1 < n ? v[k + 1] : v[0] + Vec3{out.width, 0.0, 0.0}) - v[k]));
      const double mid = (k + 0.5) / n;
      int i = 0;
      while (i + 1 < p && mid >= cell_arc[c][i + 1]) ++i;
      edge_wale[c].push_back(i);
    }
  }
  auto slot = [](Stitch s) { return s == Stitch::Knit ? 0 : s == Stitch::Tuck ? 1 : 2; };
  double sum[3] = {0, 0, 0};
  int count[3] = {0, 0, 0};
  out.cell_start.assign(q, std::vector<double>(p, 0.0));
  for (int c = 0; c < q; ++c)
    for (int k = 0; k < n; ++k) out.cell_start[c][edge_wale[c][k]] += out.start_length[c][k];
  for (int c = 0; c < q; ++c)
    for (int i = 0; i < p; ++i) {
      sum[slot(repeat.at(i, c))] += out.cell_start[c][i];
      ++count[slot(repeat.at(i, c))];
    }
  const double wanted[3] = {params.stitch_length, params.tuck_length, params.miss_length};
  double ratio[3] = {1.0, 1.0, 1.0};
  if (wanted[0] > 0.0 && count[0] > 0) ratio[0] = wanted[0] / (sum[0] / count[0]);
  for (int t = 1; t < 3; ++t)
    ratio[t] = wanted[t] > 0.0 && count[t] > 0 ? wanted[t] / (sum[t] / count[t]) : ratio[0];
  out.target_length.resize(q);
  out.cell_target.assign(q, std::vector<double>(p, 0.0));
  for (int c = 0; c < q; ++c)
    for (int k = 0; k < n; ++k) {
      const int i = edge_wale[c][k];
      const double t = out.start_length[c][k] * ratio[slot(repeat.at(i, c))];
      out.target_length[c].push_back(t);
      out.cell_target[c][i] += t;
    }
  return out;
}

}  // namespace knitsim
