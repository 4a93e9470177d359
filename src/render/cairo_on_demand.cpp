// The cairo functions src/render draws with, loaded on the first picture
// (src/core/on_demand.hpp). Linked at start-up, cairo and its dependencies (pixman, fontconfig,
// freetype, libpng, X11/xcb, ...) would add to every run's start-up, pictures or not
// (experiments/benchmark/README.md, "Process start"). render.cpp and plot.cpp call cairo by its
// own names; these forwarders, of cairo.h's names and prototypes, load libcairo.so.2 on first
// call, the library the dynamic linker would have linked, so the pictures are the same byte for
// byte. A function render.cpp or plot.cpp starts to use must be added here (the link fails
// until it is).
#include <cairo.h>

#include "src/core/on_demand.hpp"

#define KNITSIM_CAIRO(RETURN, NAME, PARAMS, ARGS)                                                \
  KNITSIM_FORWARD_ON_DEMAND("libcairo.so.2", "pictures; Debian package libcairo2", RETURN, NAME, \
                            PARAMS, ARGS)

KNITSIM_CAIRO(void, cairo_arc,
              (cairo_t * cr, double xc, double yc, double radius, double angle1, double angle2),
              (cr, xc, yc, radius, angle1, angle2))
KNITSIM_CAIRO(void, cairo_clip, (cairo_t * cr), (cr))
KNITSIM_CAIRO(void, cairo_close_path, (cairo_t * cr), (cr))
KNITSIM_CAIRO(cairo_t*, cairo_create, (cairo_surface_t * target), (target))
KNITSIM_CAIRO(void, cairo_destroy, (cairo_t * cr), (cr))
KNITSIM_CAIRO(void, cairo_fill, (cairo_t * cr), (cr))
KNITSIM_CAIRO(void, cairo_fill_preserve, (cairo_t * cr), (cr))
KNITSIM_CAIRO(cairo_surface_t*, cairo_image_surface_create,
              (cairo_format_t format, int width, int height), (format, width, height))
KNITSIM_CAIRO(unsigned char*, cairo_image_surface_get_data, (cairo_surface_t * surface), (surface))
KNITSIM_CAIRO(int, cairo_image_surface_get_stride, (cairo_surface_t * surface), (surface))
KNITSIM_CAIRO(void, cairo_line_to, (cairo_t * cr, double x, double y), (cr, x, y))
KNITSIM_CAIRO(void, cairo_move_to, (cairo_t * cr, double x, double y), (cr, x, y))
KNITSIM_CAIRO(void, cairo_new_path, (cairo_t * cr), (cr))
KNITSIM_CAIRO(void, cairo_paint, (cairo_t * cr), (cr))
KNITSIM_CAIRO(void, cairo_rectangle,
              (cairo_t * cr, double x, double y, double width, double height),
              (cr, x, y, width, height))
KNITSIM_CAIRO(void, cairo_restore, (cairo_t * cr), (cr))
KNITSIM_CAIRO(void, cairo_rotate, (cairo_t * cr, double angle), (cr, angle))
KNITSIM_CAIRO(void, cairo_save, (cairo_t * cr), (cr))
KNITSIM_CAIRO(void, cairo_select_font_face,
              (cairo_t * cr, const char* family, cairo_font_slant_t slant,
               cairo_font_weight_t weight),
              (cr, family, slant, weight))
KNITSIM_CAIRO(void, cairo_set_dash,
              (cairo_t * cr, const double* dashes, int num_dashes, double offset),
              (cr, dashes, num_dashes, offset))
KNITSIM_CAIRO(void, cairo_set_fill_rule, (cairo_t * cr, cairo_fill_rule_t fill_rule),
              (cr, fill_rule))
KNITSIM_CAIRO(void, cairo_set_font_size, (cairo_t * cr, double size), (cr, size))
KNITSIM_CAIRO(void, cairo_set_line_cap, (cairo_t * cr, cairo_line_cap_t line_cap), (cr, line_cap))
KNITSIM_CAIRO(void, cairo_set_line_join, (cairo_t * cr, cairo_line_join_t line_join),
              (cr, line_join))
KNITSIM_CAIRO(void, cairo_set_line_width, (cairo_t * cr, double width), (cr, width))
KNITSIM_CAIRO(void, cairo_set_source_rgb, (cairo_t * cr, double red, double green, double blue),
              (cr, red, green, blue))
KNITSIM_CAIRO(void, cairo_set_source_rgba,
              (cairo_t * cr, double red, double green, double blue, double alpha),
              (cr, red, green, blue, alpha))
KNITSIM_CAIRO(void, cairo_show_text, (cairo_t * cr, const char* utf8), (cr, utf8))
KNITSIM_CAIRO(const char*, cairo_status_to_string, (cairo_status_t status), (status))
KNITSIM_CAIRO(void, cairo_stroke, (cairo_t * cr), (cr))
KNITSIM_CAIRO(void, cairo_surface_destroy, (cairo_surface_t * surface), (surface))
KNITSIM_CAIRO(void, cairo_surface_flush, (cairo_surface_t * surface), (surface))
KNITSIM_CAIRO(void, cairo_surface_mark_dirty, (cairo_surface_t * surface), (surface))
KNITSIM_CAIRO(cairo_status_t, cairo_surface_status, (cairo_surface_t * surface), (surface))
KNITSIM_CAIRO(cairo_status_t, cairo_surface_write_to_png,
              (cairo_surface_t * surface, const char* filename), (surface, filename))
KNITSIM_CAIRO(void, cairo_text_extents,
              (cairo_t * cr, const char* utf8, cairo_text_extents_t* extents), (cr, utf8, extents))
KNITSIM_CAIRO(void, cairo_translate, (cairo_t * cr, double tx, double ty), (cr, tx, ty))
