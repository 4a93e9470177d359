// Pictures rendered by the program itself (cairo, PNG): a shaded 3D view of a quad mesh (the
// draped sheet) and depth-ordered thick strokes (yarn centrelines of the knit model).
//
// Camera: orthographic. azimuth/elevation in degrees (azimuth about +z from +x, elevation above
// the x-y plane); the view fits the bounding box of everything drawn. The "front" preset
// (azimuth -90, elevation 0) looks along +y at the x-z plane (the paper-2 front view looks
// along -z at the x-y plane: use front_xy).
// Failure modes: throws std::runtime_error if the file cannot be written.
#pragma once

#include <array>
#include <string>
#include <vector>

#include "src/vec3.hpp"

namespace knitsim {

struct Rgb {
  double r = 0, g = 0, b = 0;  // 0..1
};

struct RenderView {
  int width = 1000, height = 760;  // pixels
  double azimuth_deg = -55.0;      // oblique default for the drape
  double elevation_deg = 28.0;
  bool front_xy = false;           // true: look along -z at the x-y plane (knit front view)
  std::string title;               // drawn at the top
  std::vector<std::string> caption;  // lines drawn at the bottom-left
};

// A quad mesh; quads index into points (counter-clockwise when seen from +z at rest).
struct MeshScene {
  std::vector<Vec3> points;
  std::vector<std::array<int, 4>> quads;
  std::vector<int> markers;  // point indices drawn as red dots (pins)
  Rgb color{0.36, 0.55, 0.80};
};

// One yarn (or any curve) as a polyline drawn as a shaded thick stroke of `radius` metres.
struct Stroke {
  std::vector<Vec3> points;
  double radius = 0.0;  // m; 0 = 2 px
  Rgb color{0.85, 0.35, 0.20};
};

void render_mesh_png(const std::string& path, const MeshScene& mesh, const RenderView& view);
void render_strokes_png(const std::string& path, const std::vector<Stroke>& strokes,
                        const std::vector<Vec3>& markers, const RenderView& view);

}  // namespace knitsim
