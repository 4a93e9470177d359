// A small line plot written with cairo (PNG): the ICA convergence curves of paper 1 Fig. 13
// (best and mean cost per decade) and similar data-only figures.
//
// Layout: a plot frame inside margins (left for the y tick labels and the rotated y label,
// bottom for the x tick labels and the x label, top for the title); series drawn as polylines
// in data order, clipped to the frame; the legend (line sample + label per series) in the
// frame's upper-right corner.
// Axes: x linear; y linear or logarithmic (base 10). The axis range is the data range widened
// to the outer ticks (nice_ticks / log_ticks). Points whose x or y is not finite, or whose y is
// <= 0 on a log axis, are skipped (a polyline breaks there).
// Failure modes: std::invalid_argument for a bad LinePlot (see validate) or a plot without any
// drawable point; std::runtime_error("cannot write PNG <path>: <cairo status>").
#pragma once

#include <string>
#include <vector>

#include "src/render/render.hpp"

namespace knitsim {

struct PlotSeries {
  std::string label;      // legend text
  std::vector<double> x;  // same length as y
  std::vector<double> y;
  Rgb color{0.12, 0.35, 0.70};
  bool dashed = false;
  bool markers = false;  // a dot at every point
};

struct LinePlot {
  int width = 900, height = 600;  // pixels
  std::string title, x_label, y_label;
  bool log_y = false;
  std::vector<PlotSeries> series;

  // Throws std::invalid_argument naming the field: width and height in [200, 8192] px, every
  // series with x.size() == y.size().
  void validate() const;
};

// Tick values of a linear axis covering [lo, hi]: multiples of a step 1, 2 or 5 x 10^k chosen
// so that there are at most `max_ticks` (>= 2) ticks; the first tick <= lo, the last >= hi.
// lo == hi gives the ticks of [lo - 1, lo + 1] (or of lo +- |lo|/2 when lo != 0).
std::vector<double> nice_ticks(double lo, double hi, int max_ticks = 8);
// Tick values of a log axis covering [lo, hi] (0 < lo <= hi): the powers of ten from
// 10^floor(log10 lo) to 10^ceil(log10 hi) (at least two); when that spans at most two decades,
// also 2 and 5 times each power, within the outer powers.
std::vector<double> log_ticks(double lo, double hi);

void render_line_plot_png(const std::string& path, const LinePlot& plot);

}  // namespace knitsim
