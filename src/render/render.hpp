// Pictures rendered by the program itself (cairo, PNG): a shaded 3D view of a quad mesh (the
// draped sheet) and depth-ordered thick strokes (yarn centrelines of the knit model).
//
// Camera: orthographic. azimuth/elevation in degrees (azimuth about +z from +x, elevation above
// the x-y plane); the view fits the bounding box of everything drawn. The "front" preset
// (azimuth -90, elevation 0) looks along +y at the x-z plane (the paper-2 front view looks
// along -z at the x-y plane: use front_xy).
// Screen: pixel x to the right, pixel y downward; the camera's right vector is
// (-sin az, cos az, 0), its up vector toward_viewer x right (world +z is up on screen for any
// elevation in (-90, 90)); depth = p . toward_viewer, larger = nearer. The drawing area is the
// picture minus a title band (top), a caption/axis-triad band (bottom) and a margin; the view
// is centred there and scaled to fit the projected extent (all points equal: 1 m spans it).
// Hidden surfaces: quads by the painter's algorithm (mean corner depth, drawn far to near);
// stroke tubes by a z-buffer on a supersampled layer (render_strokes_png). Points with a
// non-finite coordinate are skipped.
// Failure modes: std::invalid_argument for a bad RenderView (see validate) or a quad/marker
// index outside the points; std::runtime_error("cannot write PNG <path>: <cairo status>") if
// the picture cannot be created or written.
#pragma once

#include <array>
#include <string>
#include <vector>

#include "src/core/vec3.hpp"

namespace knitsim {

struct Rgb {
  double r = 0, g = 0, b = 0;  // 0..1
};

struct RenderView {
  int width = 1000, height = 760;  // pixels
  double azimuth_deg = -55.0;      // oblique default for the drape
  double elevation_deg = 28.0;
  bool front_xy = false;             // true: look along -z at the x-y plane (knit front view)
  std::string title;                 // drawn at the top
  std::vector<std::string> caption;  // lines drawn at the bottom-left

  // Throws std::invalid_argument naming the field and the accepted range: width and height in
  // [16, 16384] px, elevation_deg in [-90, 90], azimuth_deg finite.
  void validate() const;
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

// Where a world point lands in a rendered picture.
struct ScreenPoint {
  double x = 0, y = 0;  // pixels, origin top-left, y downward
  double depth = 0;     // m along the viewing direction, larger = nearer the viewer
};

// The fitted orthographic camera of one picture: pixel = origin + scale (p.right, -p.up).
struct PixelProjection {
  Vec3 right, up, toward_viewer;      // orthonormal camera basis in world coordinates
  double scale = 1.0;                 // px per m
  double origin_x = 0, origin_y = 0;  // pixel of the world origin
  ScreenPoint operator()(Vec3 p) const;
};

// The projections render_mesh_png / render_strokes_png use for these inputs (for tests and for
// annotating pictures).
PixelProjection mesh_projection(const MeshScene& mesh, const RenderView& view);
PixelProjection strokes_projection(const std::vector<Stroke>& strokes,
                                   const std::vector<Vec3>& markers, const RenderView& view);

// The draped sheet: quads filled with two-sided Lambert + ambient shading (light fixed in the
// camera frame, from the upper left and in front; the back side in a greyer tint), outlined
// thinly; the light grey floor grid and the sheet's shadow straight below it (elevations >= 5
// deg); markers as red dots on top; the title, the caption and an x-y-z axis triad.
void render_mesh_png(const std::string& path, const MeshScene& mesh, const RenderView& view);
// Yarn centrelines: every polyline segment of every stroke is a capsule (a piece of tube with
// round ends: dark outline, body shaded by the segment's angle to the light and dimmed with
// distance, a lighter highlight band), rasterised with a z-buffer on the capsule's surface
// (depth = centreline depth + sqrt(R^2 - d^2) at distance d from it) with 2 x 2 samples per
// pixel: where yarns cross the nearer one is on top sample by sample, and the pieces of a yarn
// join without seams. The cost is linear in segments times their area in pixels, with no
// per-segment drawing calls. Markers as small dots on top.
void render_strokes_png(const std::string& path, const std::vector<Stroke>& strokes,
                        const std::vector<Vec3>& markers, const RenderView& view);

// The version of the drawing library (cairo), for manifests: that of the cairo headers the
// binary was built with (libcairo2-dev requires the same libcairo2), since cairo is loaded only
// when a picture is drawn (src/render/cairo_on_demand.cpp).
std::string render_library_version();

}  // namespace knitsim
