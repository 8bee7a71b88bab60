#include "geoanchor/gui/offscreen.hpp"

#include <GL/osmesa.h>
#include <imgui.h>
#include <imgui_impl_opengl3.h>

#include <cfloat>
#include <string>
#include <vector>

#include "geoanchor/base/error.hpp"
#include "geoanchor/gui/palette.hpp"

namespace geoanchor::gui {

struct OffscreenRenderer::Context {
  OSMesaContext gl = nullptr;
  std::vector<std::uint8_t> buffer;  // RGBA, bottom row first
  ImGuiContext* imgui = nullptr;
  bool backend = false;
};

OffscreenRenderer::OffscreenRenderer(int width, int height)
    : width_(width), height_(height), context_(std::make_unique<Context>()) {
  if (width < 64 || height < 64 || width > 8192 || height > 8192) {
    throw Error(ErrorKind::usage, "E_OPTION",
                "size " + std::to_string(width) + "x" + std::to_string(height) + ": expected 64 … 8192 pixels each way");
  }
  const int attributes[] = {OSMESA_FORMAT,  OSMESA_RGBA,         OSMESA_DEPTH_BITS,            0,
                            OSMESA_PROFILE, OSMESA_CORE_PROFILE, OSMESA_CONTEXT_MAJOR_VERSION, 3,
                            OSMESA_CONTEXT_MINOR_VERSION, 3,     0};
  context_->gl = OSMesaCreateContextAttribs(attributes, nullptr);
  if (!context_->gl) throw Error(ErrorKind::io, "E_GL", "OSMesa: no OpenGL 3.3 core context (libosmesa6 with llvmpipe is needed)");
  context_->buffer.assign(4 * static_cast<std::size_t>(width) * static_cast<std::size_t>(height), 0);
  if (!OSMesaMakeCurrent(context_->gl, context_->buffer.data(), GL_UNSIGNED_BYTE, width, height)) {
    OSMesaDestroyContext(context_->gl);
    throw Error(ErrorKind::io, "E_GL", "OSMesa: cannot make the off-screen context current");
  }
  context_->imgui = ImGui::CreateContext();
  ImGui::SetCurrentContext(context_->imgui);
  try {
    WorkbenchUi::configure_context(static_cast<float>(height));
  } catch (...) {
    ImGui::DestroyContext(context_->imgui);
    OSMesaDestroyContext(context_->gl);
    throw;
  }
  ImGuiIO& io = ImGui::GetIO();
  io.DisplaySize = ImVec2(static_cast<float>(width), static_cast<float>(height));
  io.DeltaTime = 1.0f / 60.0f;
  io.MousePos = ImVec2(-FLT_MAX, -FLT_MAX);
  context_->backend = ImGui_ImplOpenGL3_Init("#version 330 core");
  if (!context_->backend) {
    ImGui::DestroyContext(context_->imgui);
    OSMesaDestroyContext(context_->gl);
    throw Error(ErrorKind::io, "E_GL", "OSMesa: the ImGui OpenGL 3 backend did not start");
  }
}

OffscreenRenderer::~OffscreenRenderer() {
  ImGui::SetCurrentContext(context_->imgui);
  if (context_->backend) ImGui_ImplOpenGL3_Shutdown();
  ImGui::DestroyContext(context_->imgui);
  OSMesaDestroyContext(context_->gl);
}

void OffscreenRenderer::frame(const DrawFrame& draw) {
  OSMesaMakeCurrent(context_->gl, context_->buffer.data(), GL_UNSIGNED_BYTE, width_, height_);
  ImGui::SetCurrentContext(context_->imgui);
  ImGui_ImplOpenGL3_NewFrame();
  ImGui::NewFrame();
  draw(static_cast<float>(width_), static_cast<float>(height_));
  ImGui::Render();
  glViewport(0, 0, width_, height_);
  const Rgb bg = palette::kBackground;
  glClearColor(bg.r / 255.0f, bg.g / 255.0f, bg.b / 255.0f, 1.0f);
  glClear(GL_COLOR_BUFFER_BIT);
  ImGui_ImplOpenGL3_RenderDrawData(ImGui::GetDrawData());
  glFinish();
}

void OffscreenRenderer::render_frame(WorkbenchUi& ui, View view) {
  frame([&](float w, float h) { ui.draw(view, w, h); });
}

void OffscreenRenderer::render_frame(NetworkUi& ui) {
  frame([&](float w, float h) { ui.draw(w, h); });
}

RgbImage OffscreenRenderer::render(const DrawFrame& draw, std::optional<std::array<float, 2>> mouse_px) {
  ImGui::SetCurrentContext(context_->imgui);
  ImGui::GetIO().MousePos = mouse_px ? ImVec2((*mouse_px)[0], (*mouse_px)[1]) : ImVec2(-FLT_MAX, -FLT_MAX);
  // Auto-sized windows and tables measure in their first frame.
  for (int i = 0; i < 3; ++i) frame(draw);
  ImGui::GetIO().MousePos = ImVec2(-FLT_MAX, -FLT_MAX);
  return RgbImage::from_gl_rgba(width_, height_, context_->buffer);
}

RgbImage OffscreenRenderer::render(WorkbenchUi& ui, View view, std::optional<std::array<float, 2>> mouse_px) {
  return render([&](float w, float h) { ui.draw(view, w, h); }, mouse_px);
}

RgbImage OffscreenRenderer::render(NetworkUi& ui, std::optional<std::array<float, 2>> mouse_px) {
  return render([&](float w, float h) { ui.draw(w, h); }, mouse_px);
}

void OffscreenRenderer::click(const DrawFrame& draw, float x, float y) {
  ImGui::SetCurrentContext(context_->imgui);
  ImGuiIO& io = ImGui::GetIO();
  io.MousePos = ImVec2(x, y);
  frame(draw);  // the mouse arrives: hover is known
  io.MouseDown[0] = true;
  frame(draw);
  io.MouseDown[0] = false;
  frame(draw);
  io.MousePos = ImVec2(-FLT_MAX, -FLT_MAX);
}

void OffscreenRenderer::wheel(const DrawFrame& draw, float x, float y, float steps) {
  ImGui::SetCurrentContext(context_->imgui);
  ImGuiIO& io = ImGui::GetIO();
  io.MousePos = ImVec2(x, y);
  frame(draw);  // the mouse arrives: hover is known
  io.MouseWheel = steps;  // ImGui 1.86 (Debian 12) reads it in the next frame and clears it
  frame(draw);
  io.MousePos = ImVec2(-FLT_MAX, -FLT_MAX);
}

}  // namespace geoanchor::gui
