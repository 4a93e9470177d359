#include "src/render/render.hpp"

#include <cairo.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <memory>
#include <sstream>
#include <stdexcept>

#include "src/core/invalid_field.hpp"

namespace knitsim {

namespace {

constexpr double kPi = 3.14159265358979323846;

Vec3 unit(Vec3 v) {
  const double n = norm(v);
  return n > 0.0 ? (1.0 / n) * v : v;
}

Rgb scaled(Rgb c, double f) { return {c.r * f, c.g * f, c.b * f}; }
Rgb mixed(Rgb a, Rgb b, double t) {
  return {a.r + t * (b.r - a.r), a.g + t * (b.g - a.g), a.b + t * (b.b - a.b)};
}
void set_color(cairo_t* cr, Rgb c) {
  cairo_set_source_rgb(cr, std::clamp(c.r, 0.0, 1.0), std::clamp(c.g, 0.0, 1.0),
                       std::clamp(c.b, 0.0, 1.0));
}

// Picture furniture sizes scale with the picture (1 at 760 px), so small test pictures and
// large prints both keep their proportions.
double ui_scale(const RenderView& v) {
  return std::clamp(std::min(v.width, v.height) / 760.0, 0.4, 4.0);
}

// The rectangle (pixels) the scene is fitted into.
struct Area {
  double x0, y0, x1, y1;
};

Area drawing_area(const RenderView& v) {
  const double u = ui_scale(v);
  const double top = v.title.empty() ? 0.0 : 44.0 * u;
  const double bottom = std::max(14.0 * u + 17.0 * u * v.caption.size(), 74.0 * u);
  const double margin = 0.04 * std::min(v.width, v.height) + 6.0 * u;
  Area a{margin, top + margin, v.width - margin, v.height - bottom - margin};
  a.x1 = std::max(a.x1, a.x0 + 1.0);
  a.y1 = std::max(a.y1, a.y0 + 1.0);
  return a;
}

// The camera basis of the view (header: right = (-sin az, cos az, 0), up = toward x right).
PixelProjection camera(const RenderView& v) {
  PixelProjection p;
  if (v.front_xy) {
    p.right = {1, 0, 0};
    p.up = {0, 1, 0};
    p.toward_viewer = {0, 0, 1};
    return p;
  }
  const double az = v.azimuth_deg * kPi / 180.0, el = v.elevation_deg * kPi / 180.0;
  p.right = {-std::sin(az), std::cos(az), 0.0};
  p.toward_viewer = {std::cos(el) * std::cos(az), std::cos(el) * std::sin(az), std::sin(el)};
  p.up = cross(p.toward_viewer, p.right);
  return p;
}

// Fits the camera to the finite points, each padded by `pad` metres in the screen plane.
PixelProjection fitted(const RenderView& v, const std::vector<Vec3>& points, double pad) {
  PixelProjection p = camera(v);
  constexpr double inf = std::numeric_limits<double>::infinity();
  double a0 = inf, a1 = -inf, b0 = inf, b1 = -inf;
  for (const Vec3& q : points) {
    if (!is_finite(q)) continue;
    const double a = dot(q, p.right), b = dot(q, p.up);
    a0 = std::min(a0, a - pad);
    a1 = std::max(a1, a + pad);
    b0 = std::min(b0, b - pad);
    b1 = std::max(b1, b + pad);
  }
  if (a0 > a1) a0 = a1 = b0 = b1 = 0.0;  // nothing to draw
  const Area area = drawing_area(v);
  const double sx = a1 > a0 ? (area.x1 - area.x0) / (a1 - a0) : inf;
  const double sy = b1 > b0 ? (area.y1 - area.y0) / (b1 - b0) : inf;
  p.scale = std::min(sx, sy);
  if (p.scale == inf) p.scale = std::min(area.x1 - area.x0, area.y1 - area.y0);  // 1 m spans it
  p.origin_x = 0.5 * (area.x0 + area.x1) - p.scale * 0.5 * (a0 + a1);
  p.origin_y = 0.5 * (area.y0 + area.y1) + p.scale * 0.5 * (b0 + b1);
  return p;
}

// The light, fixed in the camera frame: from the upper left and in front of the picture.
Vec3 light_direction(const PixelProjection& p) {
  return unit((-0.45) * p.right + 0.65 * p.up + 0.6 * p.toward_viewer);
}

// --- cairo resources and picture furniture ----------------------------------------------

struct SurfaceDeleter {
  void operator()(cairo_surface_t* s) const { cairo_surface_destroy(s); }
};
struct ContextDeleter {
  void operator()(cairo_t* c) const { cairo_destroy(c); }
};
using Surface = std::unique_ptr<cairo_surface_t, SurfaceDeleter>;
using Context = std::unique_ptr<cairo_t, ContextDeleter>;

[[noreturn]] void write_failed(const std::string& path, cairo_status_t status) {
  throw std::runtime_error("cannot write PNG " + path + ": " + cairo_status_to_string(status));
}

struct Canvas {
  Surface surface;
  Context cr;
};

// A white picture of the view's size.
Canvas blank_canvas(const std::string& path, const RenderView& v) {
  Canvas c;
  c.surface.reset(cairo_image_surface_create(CAIRO_FORMAT_ARGB32, v.width, v.height));
  if (cairo_surface_status(c.surface.get()) != CAIRO_STATUS_SUCCESS)
    write_failed(path, cairo_surface_status(c.surface.get()));
  c.cr.reset(cairo_create(c.surface.get()));
  cairo_set_source_rgb(c.cr.get(), 1, 1, 1);
  cairo_paint(c.cr.get());
  cairo_set_line_join(c.cr.get(), CAIRO_LINE_JOIN_ROUND);
  return c;
}

void draw_text(cairo_t* cr, const std::string& s, double x, double y, double size, bool bold,
               bool centred) {
  cairo_select_font_face(cr, "sans-serif", CAIRO_FONT_SLANT_NORMAL,
                         bold ? CAIRO_FONT_WEIGHT_BOLD : CAIRO_FONT_WEIGHT_NORMAL);
  cairo_set_font_size(cr, size);
  if (centred) {
    cairo_text_extents_t e;
    cairo_text_extents(cr, s.c_str(), &e);
    x -= e.x_advance / 2.0;
  }
  cairo_move_to(cr, x, y);
  cairo_show_text(cr, s.c_str());
}

// A red dot with a dark outline.
void draw_marker(cairo_t* cr, ScreenPoint s, double radius) {
  cairo_new_path(cr);
  cairo_arc(cr, s.x, s.y, radius, 0, 2 * kPi);
  cairo_set_source_rgb(cr, 0.86, 0.08, 0.08);
  cairo_fill_preserve(cr);
  cairo_set_source_rgb(cr, 0.25, 0.0, 0.0);
  cairo_set_line_width(cr, std::max(1.0, 0.3 * radius));
  cairo_stroke(cr);
}

// x, y, z arrows of the camera in the bottom-right corner, the nearest drawn last; an axis
// pointing at the viewer shows as a dot in a circle, one pointing away as a cross in a circle.
void draw_axis_triad(cairo_t* cr, const PixelProjection& p, const RenderView& v) {
  const double u = ui_scale(v), len = 30.0 * u;
  const double cx = v.width - 62.0 * u, cy = v.height - 42.0 * u;
  struct Axis {
    Vec3 dir;
    const char* name;
    Rgb color;
  };
  Axis axes[3] = {{{1, 0, 0}, "x", {0.80, 0.15, 0.15}},
                  {{0, 1, 0}, "y", {0.15, 0.55, 0.15}},
                  {{0, 0, 1}, "z", {0.15, 0.30, 0.85}}};
  std::sort(std::begin(axes), std::end(axes), [&](const Axis& a, const Axis& b) {
    return dot(a.dir, p.toward_viewer) < dot(b.dir, p.toward_viewer);
  });
  cairo_set_line_cap(cr, CAIRO_LINE_CAP_ROUND);
  cairo_set_line_width(cr, 2.0 * u);
  for (const Axis& a : axes) {
    const double dx = dot(a.dir, p.right), dy = -dot(a.dir, p.up);
    const double ex = cx + len * dx, ey = cy + len * dy;
    set_color(cr, a.color);
    cairo_new_path(cr);
    if (std::hypot(dx, dy) < 0.2) {
      const double r = 5.0 * u;
      cairo_arc(cr, cx, cy, r, 0, 2 * kPi);
      cairo_stroke(cr);
      if (dot(a.dir, p.toward_viewer) > 0) {
        cairo_arc(cr, cx, cy, 1.5 * u, 0, 2 * kPi);
        cairo_fill(cr);
      } else {
        const double d = r * 0.7071;
        cairo_move_to(cr, cx - d, cy - d);
        cairo_line_to(cr, cx + d, cy + d);
        cairo_move_to(cr, cx - d, cy + d);
        cairo_line_to(cr, cx + d, cy - d);
        cairo_stroke(cr);
      }
      draw_text(cr, a.name, cx + r + 2.0 * u, cy - r, 12.0 * u, true, false);
      continue;
    }
    cairo_move_to(cr, cx, cy);
    cairo_line_to(cr, ex, ey);
    cairo_stroke(cr);
    // Arrow head.
    const double h = 7.0 * u, ux = dx / std::hypot(dx, dy), uy = dy / std::hypot(dx, dy);
    cairo_move_to(cr, ex + 0.4 * h * ux, ey + 0.4 * h * uy);
    cairo_line_to(cr, ex - h * ux - 0.45 * h * uy, ey - h * uy + 0.45 * h * ux);
    cairo_line_to(cr, ex - h * ux + 0.45 * h * uy, ey - h * uy - 0.45 * h * ux);
    cairo_close_path(cr);
    cairo_fill(cr);
    draw_text(cr, a.name, ex + 9.0 * u * ux - 4.0 * u, ey + 9.0 * u * uy + 4.5 * u, 13.0 * u, true,
              false);
  }
}

// Title, caption, axis triad, a thin frame; then the PNG is written.
void finish_and_write(Canvas& c, const std::string& path, const PixelProjection& p,
                      const RenderView& v) {
  cairo_t* cr = c.cr.get();
  const double u = ui_scale(v);
  draw_axis_triad(cr, p, v);
  cairo_set_source_rgb(cr, 0.1, 0.1, 0.1);
  if (!v.title.empty()) draw_text(cr, v.title, v.width / 2.0, 30.0 * u, 20.0 * u, true, true);
  cairo_set_source_rgb(cr, 0.25, 0.25, 0.25);
  for (size_t i = 0; i < v.caption.size(); ++i) {
    const double y = v.height - 12.0 * u - 17.0 * u * (v.caption.size() - 1 - i);
    draw_text(cr, v.caption[i], 12.0 * u, y, 13.0 * u, false, false);
  }
  cairo_set_source_rgb(cr, 0.78, 0.78, 0.78);
  cairo_set_line_width(cr, 1.0);
  cairo_rectangle(cr, 0.5, 0.5, v.width - 1.0, v.height - 1.0);
  cairo_stroke(cr);
  cairo_surface_flush(c.surface.get());
  const cairo_status_t status = cairo_surface_write_to_png(c.surface.get(), path.c_str());
  if (status != CAIRO_STATUS_SUCCESS) write_failed(path, status);
}

// --- the mesh -----------------------------------------------------------------------

void check_index(int index, size_t count, const char* what, size_t which) {
  if (index < 0 || static_cast<size_t>(index) >= count) {
    std::ostringstream os;
    os << what << "[" << which << "] = " << index << ": must index the " << count << " points";
    throw std::invalid_argument(os.str());
  }
}

// The floor under the sheet: a rectangle at height z, a little larger than the sheet's x-y
// extent, with grid lines every `step` metres.
struct Floor {
  bool shown = false;
  double x0 = 0, x1 = 0, y0 = 0, y1 = 0, z = 0, step = 1;
};

// A "nice" grid step (1, 2 or 5 times a power of ten) of about span / 8.
double nice_step(double span) {
  const double raw = span / 8.0, p = std::pow(10.0, std::floor(std::log10(raw)));
  const double m = raw / p;
  return (m < 1.5 ? 1.0 : m < 3.5 ? 2.0 : m < 7.5 ? 5.0 : 10.0) * p;
}

Floor floor_under(const MeshScene& mesh, const RenderView& v) {
  Floor f;
  if (v.front_xy || v.elevation_deg < 5.0) return f;
  constexpr double inf = std::numeric_limits<double>::infinity();
  double x0 = inf, x1 = -inf, y0 = inf, y1 = -inf, z0 = inf, z1 = -inf;
  for (const Vec3& q : mesh.points) {
    if (!is_finite(q)) continue;
    x0 = std::min(x0, q.x), x1 = std::max(x1, q.x);
    y0 = std::min(y0, q.y), y1 = std::max(y1, q.y);
    z0 = std::min(z0, q.z), z1 = std::max(z1, q.z);
  }
  const double span = std::max(x1 - x0, y1 - y0);
  if (!(span > 0.0)) return f;  // no points, or no x-y extent: nothing to stand on
  const double pad = 0.08 * span;
  f.shown = true;
  f.x0 = x0 - pad, f.x1 = x1 + pad, f.y0 = y0 - pad, f.y1 = y1 + pad;
  f.z = z0 - 0.06 * std::max(span, z1 - z0);
  f.step = nice_step(span);
  return f;
}

std::vector<Vec3> mesh_fit_points(const MeshScene& mesh, const Floor& f) {
  std::vector<Vec3> pts = mesh.points;
  if (f.shown)
    for (double x : {f.x0, f.x1})
      for (double y : {f.y0, f.y1}) pts.push_back({x, y, f.z});
  return pts;
}

void draw_floor(cairo_t* cr, const MeshScene& mesh, const Floor& f, const PixelProjection& p,
                double u) {
  auto line = [&](Vec3 a, Vec3 b) {
    const ScreenPoint sa = p(a), sb = p(b);
    cairo_move_to(cr, sa.x, sa.y);
    cairo_line_to(cr, sb.x, sb.y);
  };
  const Vec3 corners[4] = {
      {f.x0, f.y0, f.z}, {f.x1, f.y0, f.z}, {f.x1, f.y1, f.z}, {f.x0, f.y1, f.z}};
  cairo_new_path(cr);
  for (const Vec3& c : corners) cairo_line_to(cr, p(c).x, p(c).y);
  cairo_close_path(cr);
  cairo_set_source_rgb(cr, 0.965, 0.968, 0.975);
  cairo_fill_preserve(cr);
  cairo_set_source_rgb(cr, 0.80, 0.81, 0.83);
  cairo_set_line_width(cr, 1.0 * u);
  cairo_stroke(cr);
  // Grid lines at multiples of step, counted (x += step could stall far from the origin).
  auto multiples = [&](double lo, double hi, auto&& draw) {
    const double first = std::ceil(lo / f.step);
    const int count = static_cast<int>(std::min(100.0, std::floor(hi / f.step) - first + 1));
    for (int i = 0; i < count; ++i) draw((first + i) * f.step);
  };
  multiples(f.x0, f.x1, [&](double x) { line({x, f.y0, f.z}, {x, f.y1, f.z}); });
  multiples(f.y0, f.y1, [&](double y) { line({f.x0, y, f.z}, {f.x1, y, f.z}); });
  cairo_set_source_rgb(cr, 0.87, 0.88, 0.90);
  cairo_set_line_width(cr, 0.8 * u);
  cairo_stroke(cr);
  // The shadow of a light straight above: one fill of all quads, each wound the same way, so
  // overlaps do not darken.
  cairo_new_path(cr);
  for (const auto& q : mesh.quads) {
    ScreenPoint s[4];
    bool ok = true;
    for (int k = 0; k < 4; ++k) {
      const Vec3 w = mesh.points[q[k]];
      ok = ok && is_finite(w);
      s[k] = p({w.x, w.y, f.z});
    }
    if (!ok) continue;
    const double area =
        (s[2].x - s[0].x) * (s[3].y - s[1].y) - (s[2].y - s[0].y) * (s[3].x - s[1].x);
    const int order[4] = {0, 1, 2, 3}, reversed[4] = {0, 3, 2, 1};
    const int* o = area >= 0 ? order : reversed;
    cairo_move_to(cr, s[o[0]].x, s[o[0]].y);
    for (int k = 1; k < 4; ++k) cairo_line_to(cr, s[o[k]].x, s[o[k]].y);
    cairo_close_path(cr);
  }
  cairo_set_fill_rule(cr, CAIRO_FILL_RULE_WINDING);
  cairo_set_source_rgba(cr, 0.15, 0.18, 0.25, 0.13);
  cairo_fill(cr);
}

void draw_quads(cairo_t* cr, const MeshScene& mesh, const PixelProjection& p, double u) {
  struct Face {
    double depth;
    size_t index;
  };
  std::vector<ScreenPoint> s(mesh.points.size());
  for (size_t i = 0; i < s.size(); ++i) s[i] = p(mesh.points[i]);
  std::vector<Face> faces;
  faces.reserve(mesh.quads.size());
  double edge_px = 0.0;  // sum of the projected quad diagonals
  for (size_t i = 0; i < mesh.quads.size(); ++i) {
    const auto& q = mesh.quads[i];
    if (!(is_finite(mesh.points[q[0]]) && is_finite(mesh.points[q[1]]) &&
          is_finite(mesh.points[q[2]]) && is_finite(mesh.points[q[3]])))
      continue;
    faces.push_back({0.25 * (s[q[0]].depth + s[q[1]].depth + s[q[2]].depth + s[q[3]].depth), i});
    edge_px += std::hypot(s[q[2]].x - s[q[0]].x, s[q[2]].y - s[q[0]].y);
  }
  if (faces.empty()) return;
  std::stable_sort(faces.begin(), faces.end(),
                   [](const Face& a, const Face& b) { return a.depth < b.depth; });
  // Outlines thin out with the quads' size on screen so dense meshes do not turn dark.
  const double quad_px = edge_px / faces.size() / std::sqrt(2.0);
  cairo_set_line_width(cr, std::clamp(0.09 * quad_px, 0.35, 1.2) * std::max(1.0, u));
  const Vec3 light = light_direction(p);
  const Rgb back = mixed(mesh.color, {0.8, 0.8, 0.8}, 0.25);  // the underside: a little greyer
  for (const Face& f : faces) {
    const auto& q = mesh.quads[f.index];
    // Two-sided Lambert: |n.l|, so the underside of a fold is lit as well as the top.
    const Vec3 n =
        unit(cross(mesh.points[q[2]] - mesh.points[q[0]], mesh.points[q[3]] - mesh.points[q[1]]));
    const bool front = dot(n, p.toward_viewer) >= 0.0;
    const double lambert = std::abs(dot(n, light));
    const Rgb c = scaled(front ? mesh.color : back, 0.38 + 0.72 * lambert);
    cairo_new_path(cr);
    cairo_move_to(cr, s[q[0]].x, s[q[0]].y);
    for (int k = 1; k < 4; ++k) cairo_line_to(cr, s[q[k]].x, s[q[k]].y);
    cairo_close_path(cr);
    set_color(cr, c);
    cairo_fill_preserve(cr);
    set_color(cr, scaled(c, 0.62));
    cairo_stroke(cr);
  }
}

// --- strokes ------------------------------------------------------------------------

double max_radius(const std::vector<Stroke>& strokes) {
  double r = 0.0;
  for (const Stroke& s : strokes)
    if (std::isfinite(s.radius)) r = std::max(r, s.radius);
  return r;
}

std::vector<Vec3> stroke_fit_points(const std::vector<Stroke>& strokes,
                                    const std::vector<Vec3>& markers) {
  std::vector<Vec3> pts = markers;
  for (const Stroke& s : strokes) pts.insert(pts.end(), s.points.begin(), s.points.end());
  return pts;
}

// Samples per pixel along each axis of the tube layer (anti-aliasing by supersampling).
constexpr int kTubeSamples = 2;

// 8-bit channels of a colour, packed as 0x00RRGGBB.
uint32_t packed(Rgb c) {
  auto byte = [](double x) { return static_cast<uint32_t>(255.0 * std::clamp(x, 0.0, 1.0) + 0.5); };
  return byte(c.r) << 16 | byte(c.g) << 8 | byte(c.b);
}

// One polyline segment as a capsule, in sample units (see draw_tubes).
struct Capsule {
  double ax = 0, ay = 0, za = 0;    // first end (sample x, y) and its depth
  double ex = 0, ey = 0, ez = 0;    // second end minus the first
  double len2 = 0, nx = 0, ny = 0;  // |e|^2 on screen, unit screen normal (0 if |e| = 0)
  double R = 0, rb = 0;             // outer (body + outline) and body radius
  double shift = 0, band = 0;       // highlight centre offset along n, half width
  uint32_t body = 0, rim = 0, shine = 0;
  int i0 = 0, i1 = -1, j0 = 0, j1 = -1;  // sample bounding box, clipped to the layer
};

// The tubes of all strokes, z-buffered on a layer of ss x ss samples per pixel (ss = kTubeSamples),
// then averaged into the canvas (samples no tube covers keep the canvas pixel). Every polyline
// segment is a capsule of radius R = r + outline around its centreline; a sample at distance d from
// the segment lies on the capsule's surface at depth  centre depth + sqrt(R^2 - d^2)  (px units),
// so where yarns cross or touch the nearer surface wins sample by sample, and consecutive segments
// of a yarn join seamlessly. Colours: the outline ring (d > r) dark; the body shaded by the
// segment's angle to the light and dimmed with distance; a lighter highlight band of width r/2
// beside the centreline, shifted toward the light across the tube. The layer is processed in
// bands of rows small enough to stay in cache.
void draw_tubes(const Canvas& c, const std::vector<Stroke>& strokes, const PixelProjection& p,
                const RenderView& v) {
  const double u = ui_scale(v);
  const int ss = kTubeSamples;
  const int W = v.width * ss, H = v.height * ss;

  double d0 = std::numeric_limits<double>::infinity(), d1 = -d0;  // depth range, m
  for (const Stroke& s : strokes)
    for (const Vec3& q : s.points)
      if (is_finite(q)) d0 = std::min(d0, p(q).depth), d1 = std::max(d1, p(q).depth);
  const Vec3 light = light_direction(p);
  // The light's direction on screen.
  const double lx = dot(light, p.right), ly = -dot(light, p.up), ln = std::hypot(lx, ly);

  auto capsule = [&](const Stroke& stroke, Vec3 a, Vec3 b) {
    const ScreenPoint sa = p(a), sb = p(b);
    const double r = stroke.radius > 0.0 && std::isfinite(stroke.radius) ? stroke.radius * p.scale
                                                                         : 2.0 * u;  // px
    const double outline = std::clamp(0.16 * r, 0.6 * u, 2.5 * u);
    // A cylinder along t lit from `light` is brightest at sqrt(1 - (t.l)^2); the far side of
    // the scene is dimmed by up to 25 % (depth cue).
    const double tl = dot(unit(b - a), light);
    const double near = d1 > d0 ? (0.5 * (sa.depth + sb.depth) - d0) / (d1 - d0) : 1.0;
    const double lit = 0.55 + 0.45 * std::sqrt(std::max(0.0, 1.0 - tl * tl));
    const Rgb body = scaled(stroke.color, lit * (0.75 + 0.25 * near));
    Capsule k;
    k.body = packed(body);
    k.rim = packed(scaled(stroke.color, 0.35));
    k.shine = packed(mixed(body, {1, 1, 1}, 0.45));
    k.ax = ss * sa.x;
    k.ay = ss * sa.y;
    k.za = ss * p.scale * sa.depth;
    k.ex = ss * (sb.x - sa.x);
    k.ey = ss * (sb.y - sa.y);
    k.ez = ss * p.scale * (sb.depth - sa.depth);
    k.len2 = k.ex * k.ex + k.ey * k.ey;
    const double len = std::sqrt(k.len2);
    if (len > 0.0) k.nx = -k.ey / len, k.ny = k.ex / len;
    k.R = ss * (r + outline), k.rb = ss * r;
    k.shift = ln > 0.0 ? 0.4 * k.rb * (lx * k.nx + ly * k.ny) / ln : 0.0;
    k.band = len > 0.0 ? 0.25 * k.rb : -1.0;  // no highlight on a dot
    const double bx = k.ax + k.ex, by = k.ay + k.ey;
    k.i0 = std::max(0, static_cast<int>(std::floor(std::min(k.ax, bx) - k.R)));
    k.i1 = std::min(W - 1, static_cast<int>(std::ceil(std::max(k.ax, bx) + k.R)));
    k.j0 = std::max(0, static_cast<int>(std::floor(std::min(k.ay, by) - k.R)));
    k.j1 = std::min(H - 1, static_cast<int>(std::ceil(std::max(k.ay, by) + k.R)));
    return k;
  };
  size_t segments = 0;
  for (const Stroke& s : strokes) segments += std::max<size_t>(s.points.size(), 2) - 1;
  std::vector<Capsule> capsules;
  capsules.reserve(segments);
  for (const Stroke& s : strokes) {
    const auto& pts = s.points;
    if (pts.size() == 1 && is_finite(pts[0])) capsules.push_back(capsule(s, pts[0], pts[0]));
    for (size_t k = 0; k + 1 < pts.size(); ++k)
      if (is_finite(pts[k]) && is_finite(pts[k + 1]))
        capsules.push_back(capsule(s, pts[k], pts[k + 1]));
  }

  // Bands of kBandPixels pixel rows; each capsule listed in every band it touches.
  constexpr int kBandPixels = 8;
  const int rows = kBandPixels * ss, bands = (v.height + kBandPixels - 1) / kBandPixels;
  std::vector<std::vector<uint32_t>> in_band(bands);
  for (size_t k = 0; k < capsules.size(); ++k)
    for (int b = capsules[k].j0 / rows; b <= capsules[k].j1 / rows && b < bands; ++b)
      in_band[b].push_back(static_cast<uint32_t>(k));

  constexpr float kEmpty = -std::numeric_limits<float>::infinity();
  std::vector<float> depth(static_cast<size_t>(rows) * W);
  std::vector<uint32_t> colour(depth.size());
  cairo_surface_t* surface = c.surface.get();
  cairo_surface_flush(surface);
  unsigned char* data = cairo_image_surface_get_data(surface);
  const int stride = cairo_image_surface_get_stride(surface);
  for (int b = 0; b < bands; ++b) {
    if (in_band[b].empty()) continue;
    const int top = b * rows, bottom = std::min(H, top + rows);  // sample rows [top, bottom)
    std::fill(depth.begin(), depth.end(), kEmpty);
    for (uint32_t index : in_band[b]) {
      const Capsule& k = capsules[index];
      for (int j = std::max(k.j0, top); j <= std::min(k.j1, bottom - 1); ++j)
        for (int i = k.i0; i <= k.i1; ++i) {
          const double px = i + 0.5 - k.ax, py = j + 0.5 - k.ay;
          const double t =
              k.len2 > 0.0 ? std::clamp((px * k.ex + py * k.ey) / k.len2, 0.0, 1.0) : 0.0;
          const double dx = px - t * k.ex, dy = py - t * k.ey, d2 = dx * dx + dy * dy;
          if (d2 > k.R * k.R) continue;
          const size_t at = static_cast<size_t>(j - top) * W + i;
          const float z = static_cast<float>(k.za + t * k.ez + std::sqrt(k.R * k.R - d2));
          if (!(z > depth[at])) continue;
          depth[at] = z;
          colour[at] = d2 > k.rb * k.rb                                      ? k.rim
                       : std::abs(dx * k.nx + dy * k.ny - k.shift) <= k.band ? k.shine
                                                                             : k.body;
        }
    }
    // Average the band's samples into the canvas (ARGB32, opaque).
    for (int y = top / ss; y < bottom / ss; ++y) {
      uint32_t* row = reinterpret_cast<uint32_t*>(data + static_cast<size_t>(y) * stride);
      for (int x = 0; x < v.width; ++x) {
        uint32_t sum[3] = {0, 0, 0}, covered = 0;
        for (int j = y * ss - top; j < (y + 1) * ss - top; ++j)
          for (int i = x * ss; i < (x + 1) * ss; ++i) {
            const size_t at = static_cast<size_t>(j) * W + i;
            if (depth[at] == kEmpty) continue;
            ++covered;
            sum[0] += colour[at] >> 16 & 0xff, sum[1] += colour[at] >> 8 & 0xff;
            sum[2] += colour[at] & 0xff;
          }
        if (covered == 0) continue;
        const uint32_t n = ss * ss, rest = n - covered, old = row[x];
        sum[0] += rest * (old >> 16 & 0xff), sum[1] += rest * (old >> 8 & 0xff);
        sum[2] += rest * (old & 0xff);
        row[x] = 0xff000000u | (sum[0] + n / 2) / n << 16 | (sum[1] + n / 2) / n << 8 |
                 (sum[2] + n / 2) / n;
      }
    }
  }
  cairo_surface_mark_dirty(surface);
}

}  // namespace

void RenderView::validate() const {
  if (width < 16 || width > 16384) bad_field("width", width, "must be in [16, 16384] px");
  if (height < 16 || height > 16384) bad_field("height", height, "must be in [16, 16384] px");
  if (!(elevation_deg >= -90.0 && elevation_deg <= 90.0))
    bad_field("elevation_deg", elevation_deg, "must be in [-90, 90] degrees");
  if (!std::isfinite(azimuth_deg)) bad_field("azimuth_deg", azimuth_deg, "must be finite");
}

ScreenPoint PixelProjection::operator()(Vec3 p) const {
  return {origin_x + scale * dot(p, right), origin_y - scale * dot(p, up), dot(p, toward_viewer)};
}

PixelProjection mesh_projection(const MeshScene& mesh, const RenderView& view) {
  view.validate();
  return fitted(view, mesh_fit_points(mesh, floor_under(mesh, view)), 0.0);
}

PixelProjection strokes_projection(const std::vector<Stroke>& strokes,
                                   const std::vector<Vec3>& markers, const RenderView& view) {
  view.validate();
  return fitted(view, stroke_fit_points(strokes, markers), max_radius(strokes));
}

void render_mesh_png(const std::string& path, const MeshScene& mesh, const RenderView& view) {
  view.validate();
  for (size_t i = 0; i < mesh.quads.size(); ++i)
    for (int k : mesh.quads[i]) check_index(k, mesh.points.size(), "quads", i);
  for (size_t i = 0; i < mesh.markers.size(); ++i)
    check_index(mesh.markers[i], mesh.points.size(), "markers", i);
  const Floor floor = floor_under(mesh, view);
  const PixelProjection p = mesh_projection(mesh, view);
  const double u = ui_scale(view);
  Canvas c = blank_canvas(path, view);
  if (floor.shown) draw_floor(c.cr.get(), mesh, floor, p, u);
  draw_quads(c.cr.get(), mesh, p, u);
  for (int m : mesh.markers)
    if (is_finite(mesh.points[m])) draw_marker(c.cr.get(), p(mesh.points[m]), 5.5 * u);
  finish_and_write(c, path, p, view);
}

void render_strokes_png(const std::string& path, const std::vector<Stroke>& strokes,
                        const std::vector<Vec3>& markers, const RenderView& view) {
  const PixelProjection p = strokes_projection(strokes, markers, view);
  const double u = ui_scale(view);
  Canvas c = blank_canvas(path, view);
  draw_tubes(c, strokes, p, view);
  for (const Vec3& m : markers)
    if (is_finite(m)) draw_marker(c.cr.get(), p(m), 3.5 * u);
  finish_and_write(c, path, p, view);
}

std::string render_library_version() { return CAIRO_VERSION_STRING; }

}  // namespace knitsim
