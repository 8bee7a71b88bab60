#pragma once
// The off-screen shell: Mesa's OSMesa (llvmpipe, no display, no GPU) gives
// an OpenGL 3.3 core context in memory, Dear ImGui's OpenGL 3 backend draws
// the workbench's frames into it, and the pixels come back as an RGB image.
// The same frames the GLFW window shows; used by `geoanchor snapshot`,
// `geoanchor report` and the pixel tests. One renderer per thread.

#include <array>
#include <functional>
#include <memory>
#include <optional>

#include "geoanchor/gui/image.hpp"
#include "geoanchor/gui/network_ui.hpp"
#include "geoanchor/gui/workbench_ui.hpp"

namespace geoanchor::gui {

class OffscreenRenderer {
 public:
  // Throws geoanchor::Error (io) when OSMesa cannot give a 3.3 core context
  // or the fonts are missing. width and height in pixels, 64 … 8192.
  OffscreenRenderer(int width, int height);
  ~OffscreenRenderer();
  OffscreenRenderer(const OffscreenRenderer&) = delete;
  OffscreenRenderer& operator=(const OffscreenRenderer&) = delete;

  // Renders `view` until the layout has settled (auto-sized windows take a
  // frame) and returns the last frame. The mouse is outside the window, or
  // resting at `mouse_px` (x, y from the top-left corner) for the hover
  // tests; it never clicks.
  RgbImage render(WorkbenchUi& ui, View view, std::optional<std::array<float, 2>> mouse_px = std::nullopt);
  // The network view, likewise.
  RgbImage render(NetworkUi& ui, std::optional<std::array<float, 2>> mouse_px = std::nullopt);
  // One more frame, without reading it back (for benchmarks).
  void render_frame(WorkbenchUi& ui, View view);
  void render_frame(NetworkUi& ui);

  // Any frame: `draw(width, height)` between ImGui's NewFrame and Render.
  using DrawFrame = std::function<void(float width, float height)>;
  RgbImage render(const DrawFrame& draw, std::optional<std::array<float, 2>> mouse_px = std::nullopt);
  // A left click at (x, y) pixels from the top-left: the button goes down in
  // one frame and up in the next, as a user's click (for the tests of what
  // a click changes).
  void click(const DrawFrame& draw, float x, float y);
  // The mouse wheel turned by `steps` notches (positive: away from the
  // user, zooming in) with the pointer at (x, y), in one frame.
  void wheel(const DrawFrame& draw, float x, float y, float steps);

  int width() const { return width_; }
  int height() const { return height_; }

 private:
  void frame(const DrawFrame& draw);
  struct Context;
  int width_, height_;
  std::unique_ptr<Context> context_;
};

}  // namespace geoanchor::gui
