// VTK rendering into RgbImage buffers (row 0 = top, as the tracer's images): a triangle mesh with
// one colour per triangle (real rasterisation by VTK's OpenGL pipeline, lit by a headlight or
// unlit), optional line segments on top (cluster borders), with the camera conventions of
// `ptc trace` (render/camera.h: eye, unit forward / right / up, vertical field of view, pixel
// centres); and text strips (titles, legend labels) in VTK's embedded fonts.
//
// A Renderer keeps one off-screen render window for all its pictures (creating a GL context costs
// tens of milliseconds). It needs a live viz::Display (display.h) for its whole life: Debian's
// VTK renders through GLX and aborts the process without a display.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "bvh/camera.h"
#include "render/images.h"
#include "toolkit/mesh/mesh.h"
#include "viz/display.h"

namespace ptc::viz {

/// The tracer's background (render/view.h), used by every picture of a panel.
inline constexpr Rgb8 kBackground = {32, 32, 40};

struct MeshStyle {
  std::vector<Rgb8> triangle_colours;  ///< one per triangle of the mesh
  bool lighting = true;  ///< false: every pixel of a triangle is exactly its colour (tests, flat maps)
  /// Segments drawn over the surface (vertex ids of the mesh), e.g. viz::border_edges().
  std::vector<std::array<std::uint32_t, 2>> lines;
  Rgb8 line_colour = {0, 0, 0};
  float line_width = 1.0f;
  Rgb8 background = kBackground;
};

struct TextItem {
  std::string text;
  int x = 0, y = 0;     ///< anchor in pixels from the top-left corner
  int size = 14;        ///< font size in pixels
  int align = 0;        ///< -1: anchor is the left end, 0: centre, 1: right end
  Rgb8 colour = {235, 235, 235};
  bool bold = false;
};

class Renderer {
 public:
  explicit Renderer(const Display& display);
  ~Renderer();
  Renderer(const Renderer&) = delete;
  Renderer& operator=(const Renderer&) = delete;

  /// The mesh at its current positions seen by `cam`, width x height pixels. Throws
  /// std::invalid_argument for a size outside 1..8192 or a colour count != triangle count.
  [[nodiscard]] RgbImage mesh(const Mesh& mesh, const MeshStyle& style, const bvh::PinholeCamera& cam, int width, int height);

  /// A strip of `background` with the text items drawn on it (vertical anchor = the text's
  /// centre line).
  [[nodiscard]] RgbImage text(int width, int height, std::span<const TextItem> items, Rgb8 background = kBackground);

  /// Opens a window on the display showing the mesh with the camera and lets the user turn it
  /// (VTK's trackball interactor) until the window is closed.
  void interact(const Mesh& mesh, const MeshStyle& style, const bvh::PinholeCamera& cam, int width, int height,
                const std::string& title);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace ptc::viz
