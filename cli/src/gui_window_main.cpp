// geoanchor-gui: the residual workbench in a GLFW window (OpenGL 3.3 core),
// drawing the same ImGui frames as the off-screen shell. `geoanchor gui`
// starts this executable. --frames N --screenshot F.png render N frames,
// write the last one and exit (for tests and documentation).

#include <CLI/CLI.hpp>
#include <GLFW/glfw3.h>
#include <imgui.h>
#include <imgui_impl_glfw.h>
#include <imgui_impl_opengl3.h>

#include <iostream>
#include <limits>
#include <optional>
#include <vector>

#include "geoanchor/base/error.hpp"
#include "geoanchor/gui/image.hpp"
#include "geoanchor/gui/palette.hpp"
#include "geoanchor/gui/network_ui.hpp"
#include "geoanchor/gui/workbench_ui.hpp"
#include "option_parsing.hpp"
#include "version.hpp"
#include "workbench_session.hpp"

namespace {

using geoanchor::Error;
using geoanchor::ErrorKind;

struct WindowOptions {
  geoanchor::cli::WorkbenchOptions workbench;
  std::string view = "workbench";
  std::string size = "1600x1000";
  int frames = 0;  // 0: until the window is closed
  std::string screenshot;
};

void glfw_error(int code, const char* what) { std::cerr << "geoanchor-gui: GLFW error " << code << ": " << what << '\n'; }

int run(WindowOptions o) {
  const bool network = o.view == geoanchor::cli::kNetworkView;
  geoanchor::cli::check_workbench_inputs(o.workbench, network);
  const geoanchor::gui::View view = network ? geoanchor::gui::View::workbench : geoanchor::cli::parse_view(o.view, "--view");
  const auto [width, height] = geoanchor::cli::parse_size(o.size, "--size");
  std::optional<geoanchor::cli::WorkbenchSession> s;
  std::optional<geoanchor::cli::NetworkSession> ns;
  if (network) {
    ns = geoanchor::cli::open_network(o.workbench.inputs, o.workbench.network, o.workbench.convention);
    for (const auto& n : ns->prepared.notes) std::cerr << "geoanchor-gui: note: " << n << '\n';
    if (!ns->model->result()) std::cerr << "geoanchor-gui: warning: no adjustment: " << ns->model->error() << '\n';
  } else {
    s = geoanchor::cli::open_workbench(o.workbench);
    for (const auto& n : s->notes) std::cerr << "geoanchor-gui: note: " << n << '\n';
  }

  glfwSetErrorCallback(glfw_error);
  if (!glfwInit()) {
    throw Error(ErrorKind::io, "E_DISPLAY",
                "no display: the window needs X11 (is DISPLAY set?); `geoanchor snapshot` renders without one");
  }
  glfwWindowHint(GLFW_CONTEXT_VERSION_MAJOR, 3);
  glfwWindowHint(GLFW_CONTEXT_VERSION_MINOR, 3);
  glfwWindowHint(GLFW_OPENGL_PROFILE, GLFW_OPENGL_CORE_PROFILE);
  glfwWindowHint(GLFW_OPENGL_FORWARD_COMPAT, GLFW_TRUE);
  std::string inputs;
  for (const auto& in : o.workbench.inputs) inputs += (inputs.empty() ? "" : ", ") + in;
  const std::string title = (network ? "geoanchor network — " : "geoanchor workbench — ") + inputs;
  GLFWwindow* window = glfwCreateWindow(width, height, title.c_str(), nullptr, nullptr);
  if (!window) {
    glfwTerminate();
    throw Error(ErrorKind::io, "E_DISPLAY", "cannot open an OpenGL 3.3 core window");
  }
  glfwMakeContextCurrent(window);
  glfwSwapInterval(1);
  IMGUI_CHECKVERSION();
  ImGui::CreateContext();
  try {
    geoanchor::gui::WorkbenchUi::configure_context(static_cast<float>(height));
    ImGui_ImplGlfw_InitForOpenGL(window, true);
    ImGui_ImplOpenGL3_Init("#version 330 core");
    std::optional<geoanchor::gui::WorkbenchUi> ui;
    std::optional<geoanchor::gui::NetworkUi> network_ui;
    if (network) {
      network_ui.emplace(*ns->model);
    } else {
      ui.emplace(*s->model, geoanchor::gui::UiOptions{s->save_path, s->generator});
    }
    std::vector<std::uint8_t> pixels;
    for (int frame = 0; !glfwWindowShouldClose(window) && (o.frames == 0 || frame < o.frames); ++frame) {
      glfwPollEvents();
      ImGui_ImplOpenGL3_NewFrame();
      ImGui_ImplGlfw_NewFrame();
      ImGui::NewFrame();
      const ImVec2 size = ImGui::GetIO().DisplaySize;
      if (network) {
        network_ui->draw(size.x, size.y);
      } else {
        ui->draw(view, size.x, size.y);
      }
      ImGui::Render();
      int fw = 0, fh = 0;
      glfwGetFramebufferSize(window, &fw, &fh);
      glViewport(0, 0, fw, fh);
      const auto bg = geoanchor::gui::palette::kBackground;
      glClearColor(bg.r / 255.0f, bg.g / 255.0f, bg.b / 255.0f, 1.0f);
      glClear(GL_COLOR_BUFFER_BIT);
      ImGui_ImplOpenGL3_RenderDrawData(ImGui::GetDrawData());
      if (!o.screenshot.empty() && frame + 1 == o.frames) {
        pixels.assign(4 * static_cast<std::size_t>(fw) * static_cast<std::size_t>(fh), 0);
        glPixelStorei(GL_PACK_ALIGNMENT, 1);
        glReadPixels(0, 0, fw, fh, GL_RGBA, GL_UNSIGNED_BYTE, pixels.data());
        geoanchor::gui::write_png(geoanchor::gui::RgbImage::from_gl_rgba(fw, fh, pixels), o.screenshot, true);
        std::cout << "wrote " << o.screenshot << " (" << fw << "x" << fh << ")\n";
      }
      glfwSwapBuffers(window);
    }
  } catch (...) {
    ImGui::DestroyContext();
    glfwDestroyWindow(window);
    glfwTerminate();
    throw;
  }
  ImGui_ImplOpenGL3_Shutdown();
  ImGui_ImplGlfw_Shutdown();
  ImGui::DestroyContext();
  glfwDestroyWindow(window);
  glfwTerminate();
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"geoanchor-gui " GEOANCHOR_VERSION ": the residual workbench window (docs/commands/gui.md)"};
  app.footer(geoanchor::cli::kExitCodeHelp);
  WindowOptions o;
  o.workbench.argv.assign(argv, argv + argc);
  geoanchor::cli::add_workbench_options(&app, o.workbench);
  app.add_option("--view", o.view,
                 "workbench|plan|histogram|table|parameters|comparison (default workbench), or network: a survey network adjusted as by adjust");
  app.add_option("--size", o.size, "Window WIDTHxHEIGHT in pixels (default 1600x1000)");
  app.add_option("--frames", o.frames, "Render this many frames, then exit (0: until closed)")->check(geoanchor::cli::integer_range(0, std::numeric_limits<int>::max()));
  app.add_option("--screenshot", o.screenshot, "With --frames: write the last frame to this PNG");
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    // As geoanchor's own parse errors: the message, exit 2 (usage).
    std::cerr << "geoanchor-gui: error[E_USAGE]: " << e.what() << "\n(run 'geoanchor-gui --help')\n";
    return geoanchor::exit_code(ErrorKind::usage);
  }
  try {
    if (!o.screenshot.empty() && o.frames == 0) throw Error(ErrorKind::usage, "E_OPTION", "--screenshot: needs --frames N");
    return run(o);
  } catch (const Error& e) {
    std::cerr << "geoanchor-gui: error[" << e.code() << "]: " << e.what() << '\n';
    return geoanchor::exit_code(e.kind());
  } catch (const std::exception& e) {
    std::cerr << "geoanchor-gui: error[E_INTERNAL]: " << e.what() << '\n';
    return 1;
  }
}
