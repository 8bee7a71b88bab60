// The workbench's command lines: `geoanchor snapshot` with no display and
// no GPU, `geoanchor report`, and the GLFW window under Xvfb, whose frames
// must be the off-screen shell's.

#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <random>
#include <regex>
#include <set>
#include <sstream>

#include "cli_support.hpp"
#include "geoanchor/gui/image.hpp"

namespace geoanchor {
namespace {

namespace fs = std::filesystem;
using testing::CliTest;
using testing::slurp;

const std::string kControl = std::string(GEOANCHOR_FIXTURES_DIR) + "/airport_control.csv";
// The bundled airport network: 11 stations; 16 baselines, 24 slope
// distances, 24 zenith angles and 24 directions are lines, the reference
// stations' point cluster is none (make_airport_network.py).
const std::string kNetwork = std::string(GEOANCHOR_FIXTURES_DIR) + "/airport_network/lszh_network.json";
constexpr std::size_t kNetworkStations = 11, kNetworkLines = 16 + 24 + 24 + 24, kNetworkMeasurements = kNetworkLines + 1;
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
  // Other sizes are honoured, down to the smallest at which every text fits.
  const auto r = shell(kNoDisplay + exe() + " snapshot " + kControl + " --view plan --size 1280x800 -o " + path("small.png").string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(gui::read_png(path("small.png")).width, 1280);
}

TEST_F(WorkbenchCli, SnapshotRefusesBadOptionsAndLeavesNothing) {
  const struct {
    std::string args, message;
    int exit_code;
  } cases[] = {
      {"--view map -o a.png", "--view map: expected workbench, plan, histogram, table, parameters, comparison or network", 2},
      {"--size 1600 -o a.png", "--size 1600: expected WIDTHxHEIGHT in pixels", 2},
      {"--size 10x10 -o a.png", "--size 10x10: expected WIDTHxHEIGHT in pixels, 1280 … 8192 wide and 800 … 8192 tall", 2},
      {"--size 1279x800 -o a.png", "--size 1279x800: expected WIDTHxHEIGHT in pixels, 1280 … 8192 wide", 2},
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

// issue 14 point 10
TEST_F(WorkbenchCli, Issue14_SnapshotDrawsANetworkAndSaysWhatItShows) {
  const auto out = path("net.png");
  const auto r = shell(kNoDisplay + exe() + " snapshot " + kNetwork + " --view network --json -o " + out.string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["view"], "network");
  EXPECT_TRUE(j["control"].is_null());
  EXPECT_EQ(j["inputs"].size(), 1u);
  EXPECT_EQ(j["network"]["stations"], kNetworkStations);
  EXPECT_TRUE(j["network"]["adjusted"].get<bool>());
  std::size_t lines = 0;
  for (const auto& [cls, n] : j["network"]["lines"].items()) lines += n.get<std::size_t>();
  EXPECT_EQ(lines, kNetworkLines);
  EXPECT_EQ(j["network"]["lines"]["outlier"], 0);
  // The legend's classes count measurements: each in one class.
  EXPECT_EQ(j["network"]["measurements"], kNetworkMeasurements);
  std::size_t classified = 0;
  for (const auto& [cls, n] : j["network"]["measurements_by_class"].items()) classified += n.get<std::size_t>();
  EXPECT_EQ(classified, kNetworkMeasurements);
  EXPECT_EQ(j["network"]["ellipses"], kNetworkStations);
  EXPECT_GE(j["network"]["ellipse_exaggeration"].get<double>(), 1.0);
  const gui::RgbImage image = gui::read_png(out);
  EXPECT_EQ(image.width, 1600);
  // The text form says the same in words; the DynAdjust sample's two files make one network.
  const std::string n = std::string(GEOANCHOR_FIXTURES_DIR) + "/networks/dynadjust/";
  const auto d = shell(kNoDisplay + exe() + " snapshot " + n + "gnss-networkstn.xml " + n + "gnss-networkmsr.xml --view network --size 1280x800 -o " +
                       path("dyn.png").string());
  ASSERT_EQ(d.exit_code, 0) << d.err;
  EXPECT_NE(d.out.find("view network: 43 stations"), std::string::npos) << d.out;
  EXPECT_NE(d.out.find("error ellipses at 95 %"), std::string::npos) << d.out;
}

// issue 14 point 10
TEST_F(WorkbenchCli, Issue14_NetworkAndFitOptionsBelongToTheirViewsAndABadNetworkLeavesNothing) {
  const struct {
    std::string args, message;
    int exit_code;
  } cases[] = {
      {kControl + " --frame GDA2020 -o a.png", "--frame: only with --view network", 2},
      {kControl + " --free -o a.png", "--free: only with --view network", 2},
      {kControl + " --remove-outliers --no-snooping -o a.png", "--remove-outliers and --no-snooping: give one", 2},
      {kControl + " " + kControl + " -o a.png", "CONTROL: expected one control set, got 2 files", 2},
      {kNetwork + " --view network --model helmert7 -o a.png", "--model: not with --view network", 2},
      {kNetwork + " --view network --transform t.json -o a.png", "--transform: not with --view network", 2},
      {kNetwork + " --view network --convention position_vector -o a.png", "--convention: with --view network only with --estimate-helmert", 2},
      {kNetwork + " --view network --free --constrain P01=CCC -o a.png", "--free with --constrain: give one datum", 2},
      {kNetwork + " --view network --constrain NOPE=CCC -o a.png", "--constrain NOPE=CCC: no station NOPE", 2},
  };
  for (const auto& c : cases) {
    const auto r = shell("cd '" + dir_.string() + "' && " + kNoDisplay + exe() + " snapshot " + c.args);
    EXPECT_EQ(r.exit_code, c.exit_code) << c.args << ": " << r.err;
    EXPECT_NE(r.err.find(c.message), std::string::npos) << c.args << ": " << r.err;
    EXPECT_TRUE(leftovers({}).empty()) << c.args;
  }
  const auto r = shell("cd '" + dir_.string() + "' && " + kNoDisplay + exe() + " report " + kNetwork + " --view plan -o rep");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("--view plan: expected network"), std::string::npos) << r.err;
  EXPECT_TRUE(leftovers({}).empty());
}

// issue 14 point 10
TEST_F(WorkbenchCli, Issue14_ANetworkReportHoldsAdjustsReportAndThePictureAndReplacesAFitReportOnlyWhenAsked) {
  const auto dir = path("report");
  const auto r = shell(kNoDisplay + exe() + " report " + kNetwork + " --view network -o " + dir.string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(files(dir), (std::vector<std::string>{"network.png", "report.txt"}));
  const std::string text = slurp(dir / "report.txt");
  // adjust's own report, for the same inputs.
  const auto adjust = run("adjust " + kNetwork + " -o " + path("stations.csv").string() + " --report " + path("adjust.txt").string());
  ASSERT_EQ(adjust.exit_code, 0) << adjust.err;
  const std::string adjust_text = slurp(path("adjust.txt"));
  EXPECT_NE(text.find(adjust_text), std::string::npos) << "adjust wrote:\n" << adjust_text << "\nthe report has:\n" << text;
  EXPECT_NE(text.find("network.png: " + std::to_string(kNetworkStations) + " stations, " + std::to_string(kNetworkMeasurements) + " measurements ("),
            std::string::npos)
      << text;
  EXPECT_NE(text.find("drawn as " + std::to_string(kNetworkLines) + " lines"), std::string::npos)
      << text;
  EXPECT_NE(text.find("sha256"), std::string::npos);
  // A fit's report in the same folder: refused, then replacing the network's files with --overwrite.
  const auto t = path("t.json");
  ASSERT_EQ(run("fit " + kControl + " --remove-outliers --model helmert7 --convention position_vector -o " + t.string()).exit_code, 0);
  const auto fit = run("report " + kControl + " --transform " + t.string() + " -o " + dir.string());
  EXPECT_EQ(fit.exit_code, 5);
  EXPECT_NE(fit.err.find("exists (use --overwrite to replace the report)"), std::string::npos) << fit.err;
  EXPECT_EQ(files(dir), (std::vector<std::string>{"network.png", "report.txt"}));
  ASSERT_EQ(run("report " + kControl + " --transform " + t.string() + " -o " + dir.string() + " --overwrite").exit_code, 0);
  EXPECT_FALSE(fs::exists(dir / "network.png"));
  // And back: the fit report's pictures go.
  ASSERT_EQ(shell(kNoDisplay + exe() + " report " + kNetwork + " --view network --overwrite -o " + dir.string()).exit_code, 0);
  EXPECT_EQ(files(dir), (std::vector<std::string>{"network.png", "report.txt"}));
}

TEST_F(WorkbenchCli, ReportWritesTheFitReportAndEveryViewAndReopensTheTransformsChoices) {
  const auto t = path("t.json");
  const auto fit = run("fit " + kControl + " --remove-outliers --model helmert7 --convention coordinate_frame -o " + t.string());
  ASSERT_EQ(fit.exit_code, 0) << fit.err;
  const auto dir = path("report");
  const auto r = shell(kNoDisplay + exe() + " report " + kControl + " --transform " + t.string() + " -o " + dir.string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  // The 36 marks' table takes two pages at 1600x1000.
  EXPECT_EQ(files(dir), (std::vector<std::string>{"comparison.png", "histogram.png", "parameters.png", "plan.png", "report.txt",
                                                  "table-2.png", "table.png", "workbench.png"}));
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

// --- issue 12 point 14: reports that never mislead ---------------------------

// A control set of `n` marks over about 3 km around LSZH, written like the
// bundled example (geodetic in both frames, σ 3 mm and 4 mm), targets a few
// centimetres off plus about 4 mm of noise: ids M001 … in input order.
std::string generated_control(int n) {
  std::mt19937_64 rng(14);
  std::uniform_real_distribution<double> dlat(-0.0135, 0.0135), dlon(-0.02, 0.02), dh(-20.0, 20.0);
  std::normal_distribution<double> noise_deg(0.0, 3.6e-8), noise_m(0.0, 0.004);
  std::ostringstream csv;
  csv.precision(12);
  csv << "# source_frame = ITRF2014@2024.5\n# target_frame = ETRF2000@2024.5\n"
      << "id,lat_src_deg,lon_src_deg,h_src_m,lat_dst_deg,lon_dst_deg,h_dst_m,sigma_src_m,sigma_dst_m\n";
  for (int i = 1; i <= n; ++i) {
    const double lat = 47.4582 + dlat(rng), lon = 8.5555 + dlon(rng), h = 430.0 + dh(rng);
    char id[16];
    std::snprintf(id, sizeof id, "M%03d", i);
    csv << id << ',' << lat << ',' << lon << ',' << h << ',' << lat - 4.6e-6 + noise_deg(rng) << ',' << lon - 6.8e-6 + noise_deg(rng)
        << ',' << h + 0.005 + noise_m(rng) << ",0.003,0.004\n";
  }
  return csv.str();
}

// The rows of a point-table picture counted from its pixels alone (the
// table view, full frame): below the header's pale blue, the rows alternate
// white and a light grey; a row is whole when its stripe is as tall as most.
std::size_t whole_table_rows(const gui::RgbImage& image) {
  const int x = image.width * 3 / 4;  // in the status column, right of its text
  const auto is_row = [](gui::Rgb c) { return c.r == c.g && c.g == c.b && c.r >= 230; };
  const auto is_header = [](gui::Rgb c) { return c.b > c.r + 20; };
  int y = 0;
  while (y < image.height && !is_header(image.at(x, y))) ++y;
  while (y < image.height && is_header(image.at(x, y))) ++y;
  std::vector<int> runs;
  int start = y;
  gui::Rgb current = image.at(x, y);
  for (; y < image.height && is_row(image.at(x, y)); ++y) {
    if (!(image.at(x, y) == current)) {
      runs.push_back(y - start);
      start = y;
      current = image.at(x, y);
    }
  }
  runs.push_back(y - start);
  std::vector<int> sorted = runs;
  std::sort(sorted.begin(), sorted.end());
  const int typical = sorted[sorted.size() / 2];
  return static_cast<std::size_t>(std::count_if(runs.begin(), runs.end(), [&](int r) { return r >= typical - 1; }));
}

// issue 12 point 14
TEST_F(WorkbenchCli, Point14_ReportPagesTheTableSoThatEveryMarkOfA120MarkSetIsInAPicture) {
  const auto control = write("big.csv", generated_control(120));
  const auto t = path("t.json");
  const auto fit = run("fit " + control.string() + " --model helmert7 --convention position_vector -o " + t.string());
  ASSERT_EQ(fit.exit_code, 0) << fit.err;
  const auto dir = path("rep");
  const auto r = shell(kNoDisplay + exe() + " report " + control.string() + " --transform " + t.string() + " -o " + dir.string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::string text = slurp(dir / "report.txt");
  // report.txt lists what each page holds: "  table-2.png: marks 36–70 of 120 (sorted by id ▲): M036, …".
  const std::regex page_line(R"(\n  (table(-[0-9]+)?\.png): marks ([0-9]+)–([0-9]+) of 120 \(sorted by id ▲\): ([^\n]*))");
  std::vector<std::string> ids, pages;
  for (auto it = std::sregex_iterator(text.begin(), text.end(), page_line); it != std::sregex_iterator(); ++it) {
    const std::smatch& m = *it;
    pages.push_back(m[1]);
    std::vector<std::string> on_page;
    std::istringstream list(m[5].str());
    for (std::string id; std::getline(list, id, ',');) on_page.push_back(id.substr(id.find_first_not_of(' ')));
    EXPECT_EQ(on_page.size(), std::stoul(m[4]) - std::stoul(m[3]) + 1) << m[0];
    // Counted in the picture by its pixels, not by the report's own numbers.
    ASSERT_TRUE(fs::exists(dir / m[1].str())) << m[1];
    EXPECT_EQ(whole_table_rows(gui::read_png(dir / m[1].str())), on_page.size()) << m[1];
    ids.insert(ids.end(), on_page.begin(), on_page.end());
  }
  ASSERT_GE(pages.size(), 2u) << "120 rows do not fit one 1600x1000 page:\n" << text;
  EXPECT_EQ(pages.front(), "table.png");
  EXPECT_EQ(pages[1], "table-2.png");
  // Every mark exactly once, in id order.
  std::vector<std::string> expected;
  for (int i = 1; i <= 120; ++i) {
    char id[16];
    std::snprintf(id, sizeof id, "M%03d", i);
    expected.push_back(id);
  }
  EXPECT_EQ(ids, expected);
  // No page beyond those listed, and the workbench picture says its table panel holds a part.
  EXPECT_FALSE(fs::exists(dir / ("table-" + std::to_string(pages.size() + 1) + ".png")));
  EXPECT_NE(text.find("workbench.png: its table panel shows marks 1–"), std::string::npos) << text;
  EXPECT_NE(r.out.find("(the table on " + std::to_string(pages.size()) + " pages)"), std::string::npos) << r.out;
  // A later report of fewer marks, with --overwrite, leaves no page of the earlier one behind.
  const auto small = run("report " + kControl + " --transform " + t.string() + " --model helmert7 -o " + dir.string() + " --overwrite");
  ASSERT_EQ(small.exit_code, 0) << small.err;
  const std::string small_text = slurp(dir / "report.txt");
  std::size_t small_pages = 0;
  const std::regex small_page_line(R"(\n  table(-[0-9]+)?\.png: marks)");
  for (auto it = std::sregex_iterator(small_text.begin(), small_text.end(), small_page_line);
       it != std::sregex_iterator(); ++it) {
    ++small_pages;
  }
  ASSERT_LT(small_pages, pages.size());
  for (std::size_t page = small_pages + 1; page <= pages.size(); ++page) {
    EXPECT_FALSE(fs::exists(dir / ("table-" + std::to_string(page) + ".png"))) << page;
  }
  // And without --overwrite an earlier report's later page is refused like the others.
  write("rep2/table-3.png", "old");
  const auto refused = run("report " + kControl + " --transform " + t.string() + " -o " + path("rep2").string());
  EXPECT_EQ(refused.exit_code, 5) << refused.err;
  EXPECT_NE(refused.err.find("table-3.png: exists (use --overwrite to replace the report)"), std::string::npos) << refused.err;
  EXPECT_EQ(files(path("rep2")), std::vector<std::string>{"table-3.png"});
}

// issue 12 point 14
TEST_F(WorkbenchCli, Point14_AReportOnAMolodenskyBadekasFitNeverAdvisesItAndComparesItWithHelmert7) {
  const auto t = path("mb.json");
  const auto fit = run("fit " + kControl + " --remove-outliers --model molodensky-badekas --convention position_vector -o " + t.string());
  ASSERT_EQ(fit.exit_code, 0) << fit.err;
  const auto r = run("report " + kControl + " --transform " + t.string() + " -o " + path("rep").string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::string text = slurp(path("rep") / "report.txt");
  EXPECT_EQ(text.find("consider --model molodensky-badekas"), std::string::npos) << text;
  EXPECT_EQ(r.err.find("consider --model molodensky-badekas"), std::string::npos) << r.err;
  // The comparison has the fitted model, marked, and says what it is.
  const auto comparison = text.substr(text.find("Model comparison"));
  EXPECT_NE(comparison.find("  ▶ molodensky-badekas  "), std::string::npos) << comparison;
  EXPECT_NE(comparison.find("(molodensky-badekas: helmert7 about the pivot"), std::string::npos) << comparison;
  // Under helmert7 the same report still gives the advice (it is about another model).
  const auto h7 = run("report " + kControl + " --transform " + t.string() + " --model helmert7 -o " + path("rep7").string());
  ASSERT_EQ(h7.exit_code, 0) << h7.err;
  EXPECT_NE(slurp(path("rep7") / "report.txt").find("consider --model molodensky-badekas"), std::string::npos);
}

// issue 12 point 14
TEST_F(WorkbenchCli, Point14_TheReportSaysEveryMarkIsLabelledOnThePlanAndDrawsItsEllipse) {
  const auto t = path("t.json");
  ASSERT_EQ(run("fit " + kControl + " --remove-outliers --model helmert7 --convention position_vector -o " + t.string()).exit_code, 0);
  const auto r = run("report " + kControl + " --transform " + t.string() + " -o " + path("rep").string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::string text = slurp(path("rep") / "report.txt");
  EXPECT_NE(text.find("36 of 36 marks labelled with their id"), std::string::npos) << text;
  EXPECT_NE(text.find("36 residual ellipses (95 %, 2.4477 σ of the a-posteriori residual covariance)"), std::string::npos) << text;
}

#ifdef GEOANCHOR_GUI_EXE
// Under the asan preset the window process keeps AddressSanitizer but not
// LeakSanitizer: Mesa's GL driver (swrast_dri.so, opened and closed again by
// libglvnd) leaves allocations in frames LeakSanitizer cannot name, so no
// suppression can single them out. The same UI code runs with leak checking
// in the off-screen shell. (No effect on a build without sanitizers.)
const std::string kWindow = "ASAN_OPTIONS=detect_leaks=0:abort_on_error=1 xvfb-run -a -s '-screen 0 1920x1080x24' ";

// The window's frame and the off-screen shell's agree to within the
// software rasterisers' differences.
void expect_same_frame(const fs::path& window_png, const fs::path& snapshot_png) {
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
}

TEST_F(WorkbenchCli, TheWindowRendersUnderXvfbTheSameFramesAsTheOffScreenShell) {
  const auto window_png = path("window.png"), snapshot_png = path("snapshot.png");
  const auto w = shell(kWindow + std::string(GEOANCHOR_GUI_EXE) + " " + kControl +
                       " --size 1600x1000 --frames 4 --screenshot " + window_png.string());
  ASSERT_EQ(w.exit_code, 0) << w.err;
  const auto s = shell(kNoDisplay + exe() + " snapshot " + kControl + " --size 1600x1000 -o " + snapshot_png.string());
  ASSERT_EQ(s.exit_code, 0) << s.err;
  expect_same_frame(window_png, snapshot_png);
  // `geoanchor gui` starts the same window.
  const auto g = shell(kWindow + exe() + " gui " + kControl + " --frames 2");
  EXPECT_EQ(g.exit_code, 0) << g.err;
}

// issue 14 point 10
TEST_F(WorkbenchCli, Issue14_TheWindowDrawsTheNetworkViewAsTheOffScreenShellDoes) {
  const auto window_png = path("window.png"), snapshot_png = path("snapshot.png");
  const auto w = shell(kWindow + std::string(GEOANCHOR_GUI_EXE) + " " + kNetwork +
                       " --view network --size 1600x1000 --frames 4 --screenshot " + window_png.string());
  ASSERT_EQ(w.exit_code, 0) << w.err;
  const auto s = shell(kNoDisplay + exe() + " snapshot " + kNetwork + " --view network --size 1600x1000 -o " + snapshot_png.string());
  ASSERT_EQ(s.exit_code, 0) << s.err;
  expect_same_frame(window_png, snapshot_png);
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
