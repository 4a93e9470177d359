#include "src/base/files.hpp"
#include "src/base/text.hpp"
#include "src/render/plot.hpp"

#include <cairo.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <stdexcept>


namespace knitsim {

void LinePlot::validate() const {
  if (width < 200 || width > 8192)
    throw std::invalid_argument("width = " + std::to_string(width) + ": accepted 200..8192 px");
  if (height < 200 || height > 8192)
    throw std::invalid_argument("height = " + std::to_string(height) + ": accepted 200..8192 px");
  for (size_t i = 0; i < series.size(); ++i)
    if (series[i].x.size() != series[i].y.size())
      throw std::invalid_argument("series[" + std::to_string(i) + "] (" + series[i].label +
                                  "): x has " + std::to_string(series[i].x.size()) + " values, y " +
                                  std::to_string(series[i].y.size()) + ": must be equal");
}

std::vector<double> nice_ticks(double lo, double hi, int max_ticks) {
  if (!(std::isfinite(lo) && std::isfinite(hi)) || lo > hi || max_ticks < 2)
    throw std::invalid_argument("nice_ticks: need finite lo <= hi and max_ticks >= 2");
  if (lo == hi) {
    const double half = lo == 0.0 ? 1.0 : std::abs(lo) / 2.0;
    lo -= half;
    hi += half;
  }
  // The smallest step 1, 2, 5 x 10^k whose ticks (outer ones included) number <= max_ticks.
  double base = std::pow(10.0, std::floor(std::log10((hi - lo) / (max_ticks - 1))));
  double step = base;
  for (int m = 0;; ++m) {
    step = base * (m % 3 == 0 ? 1.0 : m % 3 == 1 ? 2.0 : 5.0);
    if (std::ceil(hi / step) - std::floor(lo / step) + 1 <= max_ticks) break;
    if (m % 3 == 2) base *= 10.0;
  }
  std::vector<double> ticks;
  // (1e-9: lo = 0.013 is tick 13 x 0.001, not 12 x 0.001, despite rounding in lo / step.)
  const long first = static_cast<long>(std::floor(lo / step + 1e-9));
  const long last = static_cast<long>(std::ceil(hi / step - 1e-9));
  for (long k = first; k <= last; ++k) ticks.push_back(k * step);
  return ticks;
}

std::vector<double> log_ticks(double lo, double hi) {
  if (!(std::isfinite(lo) && std::isfinite(hi)) || lo <= 0.0 || lo > hi)
    throw std::invalid_argument("log_ticks: need finite 0 < lo <= hi");
  const int e0 = static_cast<int>(std::floor(std::log10(lo)));
  int e1 = static_cast<int>(std::ceil(std::log10(hi)));
  if (e1 == e0) ++e1;
  std::vector<double> ticks;
  for (int e = e0; e <= e1; ++e) {
    const double p = std::pow(10.0, e);
    ticks.push_back(p);
    if (e1 - e0 <= 2 && e < e1) {
      ticks.push_back(2.0 * p);
      ticks.push_back(5.0 * p);
    }
  }
  return ticks;
}

namespace {

struct CairoDeleter {
  void operator()(cairo_surface_t* s) const { cairo_surface_destroy(s); }
  void operator()(cairo_t* c) const { cairo_destroy(c); }
};

bool drawable(double x, double y, bool log_y) {
  return std::isfinite(x) && std::isfinite(y) && (!log_y || y > 0.0);
}

// Text anchored at (x, y): halign 0 left, 0.5 centre, 1 right; vertically centred.
void draw_text(cairo_t* cr, const std::string& s, double x, double y, double size, double halign) {
  cairo_set_font_size(cr, size);
  cairo_text_extents_t e;
  cairo_text_extents(cr, s.c_str(), &e);
  cairo_move_to(cr, x - halign * e.x_advance - e.x_bearing * (1.0 - halign),
                y - e.y_bearing - e.height / 2.0);
  cairo_show_text(cr, s.c_str());
}

}  // namespace

void render_line_plot_png(const std::string& path, const LinePlot& plot) {
  plot.validate();
  double xlo = std::numeric_limits<double>::infinity(), xhi = -xlo, ylo = xlo, yhi = -xlo;
  for (const PlotSeries& s : plot.series)
    for (size_t k = 0; k < s.x.size(); ++k)
      if (drawable(s.x[k], s.y[k], plot.log_y)) {
        xlo = std::min(xlo, s.x[k]);
        xhi = std::max(xhi, s.x[k]);
        ylo = std::min(ylo, s.y[k]);
        yhi = std::max(yhi, s.y[k]);
      }
  if (!(xlo <= xhi)) throw std::invalid_argument("plot '" + plot.title + "': no drawable point");
  const std::vector<double> xt = nice_ticks(xlo, xhi);
  const std::vector<double> yt = plot.log_y ? log_ticks(ylo, yhi) : nice_ticks(ylo, yhi);
  const double x0 = xt.front(), x1 = xt.back();
  const auto ty = [&](double y) { return plot.log_y ? std::log10(y) : y; };
  const double y0 = ty(yt.front()), y1 = ty(yt.back());

  // Frame in pixels.
  const double left = 95, right = plot.width - 25.0, top = 50, bottom = plot.height - 65.0;
  const auto px = [&](double x) { return left + (x - x0) / (x1 - x0) * (right - left); };
  const auto py = [&](double y) { return bottom - (ty(y) - y0) / (y1 - y0) * (bottom - top); };

  std::unique_ptr<cairo_surface_t, CairoDeleter> surface(
      cairo_image_surface_create(CAIRO_FORMAT_ARGB32, plot.width, plot.height));
  std::unique_ptr<cairo_t, CairoDeleter> context(cairo_create(surface.get()));
  cairo_t* cr = context.get();
  cairo_set_source_rgb(cr, 1, 1, 1);
  cairo_paint(cr);
  cairo_select_font_face(cr, "sans-serif", CAIRO_FONT_SLANT_NORMAL, CAIRO_FONT_WEIGHT_NORMAL);

  // Grid lines, ticks and tick labels.
  cairo_set_line_width(cr, 1.0);
  for (double x : xt) {
    cairo_set_source_rgb(cr, 0.9, 0.9, 0.9);
    cairo_move_to(cr, px(x), top);
    cairo_line_to(cr, px(x), bottom);
    cairo_stroke(cr);
    cairo_set_source_rgb(cr, 0.1, 0.1, 0.1);
    draw_text(cr, format_number(x, 6), px(x), bottom + 14, 13, 0.5);
  }
  for (double y : yt) {
    cairo_set_source_rgb(cr, 0.9, 0.9, 0.9);
    cairo_move_to(cr, left, py(y));
    cairo_line_to(cr, right, py(y));
    cairo_stroke(cr);
    cairo_set_source_rgb(cr, 0.1, 0.1, 0.1);
    draw_text(cr, format_number(y, 6), left - 8, py(y), 13, 1.0);
  }
  cairo_set_source_rgb(cr, 0.2, 0.2, 0.2);
  cairo_rectangle(cr, left, top, right - left, bottom - top);
  cairo_stroke(cr);

  // Labels and title.
  cairo_set_source_rgb(cr, 0.1, 0.1, 0.1);
  draw_text(cr, plot.title, plot.width / 2.0, 25, 17, 0.5);
  draw_text(cr, plot.x_label, (left + right) / 2.0, plot.height - 22.0, 14, 0.5);
  cairo_save(cr);
  cairo_translate(cr, 22, (top + bottom) / 2.0);
  cairo_rotate(cr, -M_PI / 2.0);
  draw_text(cr, plot.y_label, 0, 0, 14, 0.5);
  cairo_restore(cr);

  // Series, clipped to the frame.
  cairo_save(cr);
  cairo_rectangle(cr, left, top, right - left, bottom - top);
  cairo_clip(cr);
  const double dash[] = {7.0, 5.0};
  for (const PlotSeries& s : plot.series) {
    cairo_set_source_rgb(cr, s.color.r, s.color.g, s.color.b);
    cairo_set_line_width(cr, 2.0);
    cairo_set_dash(cr, dash, s.dashed ? 2 : 0, 0.0);
    bool pen_down = false;
    for (size_t k = 0; k < s.x.size(); ++k) {
      if (!drawable(s.x[k], s.y[k], plot.log_y)) {
        pen_down = false;
        continue;
      }
      if (pen_down)
        cairo_line_to(cr, px(s.x[k]), py(s.y[k]));
      else
        cairo_move_to(cr, px(s.x[k]), py(s.y[k]));
      pen_down = true;
    }
    cairo_stroke(cr);
    cairo_set_dash(cr, dash, 0, 0.0);
    if (s.markers)
      for (size_t k = 0; k < s.x.size(); ++k)
        if (drawable(s.x[k], s.y[k], plot.log_y)) {
          cairo_arc(cr, px(s.x[k]), py(s.y[k]), 3.0, 0.0, 2.0 * M_PI);
          cairo_fill(cr);
        }
  }
  cairo_restore(cr);

  // Legend, upper right.
  const double row = 20, lx = right - 250, ly = top + 12;
  if (!plot.series.empty()) {
    cairo_set_source_rgba(cr, 1, 1, 1, 0.85);
    cairo_rectangle(cr, lx - 8, ly - 10, 250, row * plot.series.size() + 4);
    cairo_fill(cr);
  }
  for (size_t i = 0; i < plot.series.size(); ++i) {
    const PlotSeries& s = plot.series[i];
    const double y = ly + row * i;
    cairo_set_source_rgb(cr, s.color.r, s.color.g, s.color.b);
    cairo_set_line_width(cr, 2.0);
    cairo_set_dash(cr, dash, s.dashed ? 2 : 0, 0.0);
    cairo_move_to(cr, lx, y);
    cairo_line_to(cr, lx + 30, y);
    cairo_stroke(cr);
    cairo_set_dash(cr, dash, 0, 0.0);
    cairo_set_source_rgb(cr, 0.1, 0.1, 0.1);
    draw_text(cr, s.label, lx + 38, y, 13, 0.0);
  }

  cairo_surface_flush(surface.get());
  write_file_atomic_with(path, [&](const std::string& tmp) {
    const cairo_status_t status = cairo_surface_write_to_png(surface.get(), tmp.c_str());
    if (status != CAIRO_STATUS_SUCCESS)
      throw std::runtime_error("cannot write PNG " + path + ": " + cairo_status_to_string(status));
  });
}

}  // namespace knitsim
