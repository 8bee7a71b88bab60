// The workbench's command lines: `geoanchor snapshot` with no display and
// no GPU, `geoanchor report`, and the GLFW window under Xvfb, whose frames
// must be the off-screen shell's.

#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include <cstdlib>
#include <filesystem>

#include "cli_support.hpp"
#include "geoanchor/gui/image.hpp"

namespace geoanchor {
namespace {

namespace fs = std::filesystem;
using testing::CliTest;
using testing::slurp;

const std::string kControl = std::string(GEOANCHOR_FIXTURES_DIR) + "/airport_control.csv";
// The window (GLFW under Xvfb, Mesa llvmpipe) and OSMesa rasterize the same
// draw lists; allow a small difference per channel on a few pixels anyway
// (../shared/NOTES.md).
constexpr int kWindowColourTol = 8;               // per 8-bit channel
constexpr double kWindowDifferentPixelsMax = 1e-3;  // fraction of the frame

// No X display for the off-screen commands, as on the CI machine.
const std::string kNoDisplay = "env -u DISPLAY -u WAYLAND_DISPLAY ";

class WorkbenchCli : public CliTest {};

TEST_F(WorkbenchCli, SnapshotRendersEveryViewWithoutADisplay) {
  for (const char* view : {"workbench", "plan", "histogram", "table", "parameters", "comparison"}) {
    const auto out = path(std::string(view) + ".png");
    const auto r = shell(kNoDisplay + exe() + " snapshot " + kControl + " --view " + view + " --size 1600x1000 -o " + out.string());
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_NE(r.out.find("wrote"), std::string::npos);
    const gui::RgbImage image = gui::read_png(out);
    EXPECT_EQ(image.width, 1600);
    EXPECT_EQ(image.height, 1000);
  }
  // Other sizes are honoured.
  const auto r = shell(kNoDisplay + exe() + " snapshot " + kControl + " --view plan --size 800x600 -o " + path("small.png").string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(gui::read_png(path("small.png")).width, 800);
}

TEST_F(WorkbenchCli, SnapshotRefusesBadOptionsAndLeavesNothing) {
  const struct {
    std::string args, message;
    int exit_code;
  } cases[] = {
      {"--view map -o a.png", "--view map: expected workbench, plan, histogram, table, parameters or comparison", 2},
      {"--size 1600 -o a.png", "--size 1600: expected WIDTHxHEIGHT in pixels", 2},
      {"--size 10x10 -o a.png", "--size 10x10: expected WIDTHxHEIGHT in pixels, 64 … 8192 each", 2},
      {"-o a.jpg", "-o a.jpg: expected a file name ending in .png", 2},
      {"--convention cf -o a.png", "--convention cf: expected position_vector or coordinate_frame", 2},
      {"--model helmert9 -o a.png", "--model helmert9: expected translation3", 2},
      {"--model enu-origin -o a.png", "--origin: the enu-origin model needs the origin", 2},
  };
  for (const auto& c : cases) {
    const auto r = shell("cd '" + dir_.string() + "' && " + kNoDisplay + exe() + " snapshot " + kControl + " " + c.args);
    EXPECT_EQ(r.exit_code, c.exit_code) << c.args << ": " << r.err;
    EXPECT_NE(r.err.find(c.message), std::string::npos) << c.args << ": " << r.err;
    EXPECT_TRUE(leftovers({}).empty()) << c.args;
  }
  write("exists.png", "not mine");
  const auto r = run("snapshot " + kControl + " -o " + path("exists.png").string());
  EXPECT_EQ(r.exit_code, 5) << r.err;
  EXPECT_NE(r.err.find("exists.png: exists (use --overwrite to replace it)"), std::string::npos) << r.err;
  EXPECT_EQ(slurp(path("exists.png")), "not mine");
  const auto missing = run("snapshot " + path("none.csv").string() + " -o " + path("b.png").string());
  EXPECT_EQ(missing.exit_code, 5) << missing.err;
  EXPECT_NE(missing.err.find("none.csv: cannot open control set"), std::string::npos) << missing.err;
  EXPECT_FALSE(fs::exists(path("b.png")));
}

TEST_F(WorkbenchCli, ReportWritesTheFitReportAndEveryViewAndReopensTheTransformsChoices) {
  const auto t = path("t.json");
  const auto fit = run("fit " + kControl + " --model helmert7 --convention coordinate_frame -o " + t.string());
  ASSERT_EQ(fit.exit_code, 0) << fit.err;
  const auto dir = path("report");
  const auto r = shell(kNoDisplay + exe() + " report " + kControl + " --transform " + t.string() + " -o " + dir.string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(files(dir), (std::vector<std::string>{"comparison.png", "histogram.png", "parameters.png", "plan.png", "report.txt",
                                                  "table.png", "workbench.png"}));
  const std::string text = slurp(dir / "report.txt");
  // The report section is what `fit` printed for the same choices (the
  // convention came from the transform file), and the refit matches the file.
  const std::string fit_report = fit.out.substr(0, fit.out.find("\nwrote "));
  EXPECT_NE(text.find(fit_report), std::string::npos) << "fit printed:\n" << fit_report << "\nreport has:\n" << text;
  EXPECT_NE(text.find("coordinate frame convention"), std::string::npos);
  EXPECT_NE(text.find("differ by at most 0.000 mm at the control marks"), std::string::npos) << text;
  EXPECT_NE(text.find("Model comparison"), std::string::npos);
  EXPECT_NE(text.find("sha256"), std::string::npos);
  for (const auto& f : files(dir)) {
    if (f.ends_with(".png")) {
      EXPECT_EQ(gui::read_png(dir / f).width, 1600) << f;
    }
  }
  // A second run refuses to overwrite the report, then replaces it with --overwrite.
  const auto again = run("report " + kControl + " --transform " + t.string() + " -o " + dir.string());
  EXPECT_EQ(again.exit_code, 5);
  EXPECT_NE(again.err.find("report.txt: exists (use --overwrite to replace the report)"), std::string::npos) << again.err;
  EXPECT_EQ(run("report " + kControl + " --transform " + t.string() + " -o " + dir.string() + " --overwrite").exit_code, 0);
  // Without a transform file there is nothing to report on.
  const auto none = run("report " + kControl + " -o " + path("r2").string());
  EXPECT_EQ(none.exit_code, 2);
  EXPECT_NE(none.err.find("--transform: required"), std::string::npos) << none.err;
  EXPECT_FALSE(fs::exists(path("r2")));
}

TEST_F(WorkbenchCli, ReportOnAPublishedParameterSetSaysHowFarTheRefitIs) {
  // Parameters without a fit record: the workbench fits the same model and
  // says how far that fit lies from the published set at the marks.
  const auto t = write("published.json", R"({"model": "helmert7", "convention": "position_vector",
    "source_frame": "ITRF2014@2024.5", "target_frame": "ETRF2000@2024.5",
    "parameters": {"tx_m": 0.0547, "ty_m": 0.0522, "tz_m": -0.0741, "rx_arcsec": 0.00228, "ry_arcsec": 0.01404,
                   "rz_arcsec": -0.02168, "ds_ppm": 0.00212}})");
  const auto r = run("report " + kControl + " --transform " + t.string() + " -o " + path("rep").string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::string text = slurp(path("rep") / "report.txt");
  EXPECT_NE(text.find("published parameters, no fit record"), std::string::npos) << text;
  // The fixture's targets were made with these parameters plus noise of a
  // few millimetres: the refit lies within centimetres of them at the marks.
  const auto at = text.find("differ by at most ");
  ASSERT_NE(at, std::string::npos) << text;
  const double mm = std::stod(text.substr(at + 18));
  EXPECT_GT(mm, 0.0);
  EXPECT_LT(mm, 30.0);
}

#ifdef GEOANCHOR_GUI_EXE
// Under the asan preset the window process keeps AddressSanitizer but not
// LeakSanitizer: Mesa's GL driver (swrast_dri.so, opened and closed again by
// libglvnd) leaves allocations in frames LeakSanitizer cannot name, so no
// suppression can single them out. The same UI code runs with leak checking
// in the off-screen shell. (No effect on a build without sanitizers.)
const std::string kWindow = "ASAN_OPTIONS=detect_leaks=0:abort_on_error=1 xvfb-run -a -s '-screen 0 1920x1080x24' ";

TEST_F(WorkbenchCli, TheWindowRendersUnderXvfbTheSameFramesAsTheOffScreenShell) {
  const auto window_png = path("window.png"), snapshot_png = path("snapshot.png");
  const auto w = shell(kWindow + std::string(GEOANCHOR_GUI_EXE) + " " + kControl +
                       " --size 1600x1000 --frames 4 --screenshot " + window_png.string());
  ASSERT_EQ(w.exit_code, 0) << w.err;
  const auto s = shell(kNoDisplay + exe() + " snapshot " + kControl + " --size 1600x1000 -o " + snapshot_png.string());
  ASSERT_EQ(s.exit_code, 0) << s.err;
  const gui::RgbImage a = gui::read_png(window_png), b = gui::read_png(snapshot_png);
  ASSERT_EQ(a.width, b.width);
  ASSERT_EQ(a.height, b.height);
  std::size_t different = 0;
  for (int y = 0; y < a.height; ++y) {
    for (int x = 0; x < a.width; ++x) {
      const gui::Rgb p = a.at(x, y), q = b.at(x, y);
      if (std::abs(p.r - q.r) > kWindowColourTol || std::abs(p.g - q.g) > kWindowColourTol || std::abs(p.b - q.b) > kWindowColourTol) {
        ++different;
      }
    }
  }
  EXPECT_LE(static_cast<double>(different), kWindowDifferentPixelsMax * a.width * a.height) << different << " pixels differ";
  // `geoanchor gui` starts the same window.
  const auto g = shell(kWindow + exe() + " gui " + kControl + " --frames 2");
  EXPECT_EQ(g.exit_code, 0) << g.err;
}

TEST_F(WorkbenchCli, TheWindowWithoutADisplaySaysSoAndPointsToSnapshot) {
  const auto r = shell(kNoDisplay + exe() + " gui " + kControl);
  EXPECT_EQ(r.exit_code, 5) << r.err;
  EXPECT_NE(r.err.find("no display"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("geoanchor snapshot"), std::string::npos) << r.err;
}
#endif

}  // namespace
}  // namespace geoanchor
