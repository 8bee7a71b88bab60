// Accuracy standards (adjust --standard): the shipped ALTA/NSPS 2021
// standard and a standard file of one's own judged on pairs and stations
// whose precision is written in the test, each verdict computed by hand
// below from the standard's published numbers; every malformed standard
// file refused naming file, key and value.

#include <gtest/gtest.h>

#include <fstream>
#include <string>
#include <vector>

#include "geoanchor/base/error.hpp"
#include "geoanchor/workflow/accuracy_standard.hpp"
#include "temp_folder.hpp"

namespace geoanchor::workflow {
namespace {

constexpr double kVerdictTol_m = 1e-12;  // sums and products of a few numbers of a few centimetres

// Two pairs and three stations: only the numbers a verdict reads.
solver::AdjustmentResult result_with(const std::vector<solver::RelativePrecision>& pairs) {
  solver::AdjustmentResult r;
  for (const char* id : {"A", "B", "C"}) {
    solver::AdjustedStation s;
    s.id = id;
    r.stations.push_back(s);
  }
  r.relative = pairs;
  return r;
}

solver::RelativePrecision pair(std::size_t from, std::size_t to, double distance_m, double horizontal_m, double a_1sigma_m,
                               double up_1sigma_m) {
  solver::RelativePrecision p;
  p.from = from;
  p.to = to;
  p.distance_m = distance_m;
  p.horizontal_distance_m = horizontal_m;
  p.ellipse.semi_major_m = a_1sigma_m;
  p.ellipse.semi_minor_m = 0.5 * a_1sigma_m;
  p.sigma_up_m = up_1sigma_m;
  return p;
}

// ALTA/NSPS Minimum Standard Detail Requirements (2021), Section 3.E:
// Relative Positional Precision is the semi-major axis of the 95 %
// relative error ellipse between two corners; allowed 2 cm + 50 ppm of the
// direct distance between them.
TEST(AccuracyStandard, AltaNspsVerdictsAsComputedByHand) {
  const AccuracyStandard s = load_standard("alta-nsps-2021");
  EXPECT_EQ(s.name, "alta-nsps-2021");
  ASSERT_TRUE(s.relative_horizontal);
  EXPECT_FALSE(s.relative_vertical || s.positional_horizontal || s.positional_vertical);
  EXPECT_NE(s.source.find("Section 3.E"), std::string::npos);
  // A–B: 150 m apart, 1σ semi-major 9.0 mm. The 95 % ellipse is √(−2 ln 0.05)
  // = 2.4477468 times it: 22.0297 mm; allowed 20 mm + 50e-6 × 150 m = 27.5 mm;
  // PASS by 5.4703 mm.
  // B–C: 40 m apart, 1σ semi-major 9.5 mm: 23.2536 mm against 20 + 2 = 22 mm;
  // FAIL by 1.2536 mm.
  const solver::AdjustmentResult r = result_with({pair(0, 1, 150.0, 149.0, 0.0090, 0.004), pair(1, 2, 40.0, 39.0, 0.0095, 0.004)});
  const StandardVerdicts v = judge_standard(s, r);
  ASSERT_TRUE(v.pair_horizontal[0] && v.pair_horizontal[1]);
  EXPECT_NEAR(v.pair_horizontal[0]->achieved_m, 0.022029721476127, kVerdictTol_m);
  EXPECT_NEAR(v.pair_horizontal[0]->allowed_m, 0.0275, kVerdictTol_m);
  EXPECT_TRUE(v.pair_horizontal[0]->pass());
  EXPECT_NEAR(v.pair_horizontal[0]->margin_m(), 0.005470278523873, kVerdictTol_m);
  EXPECT_NEAR(v.pair_horizontal[1]->achieved_m, 0.023253594891468, kVerdictTol_m);
  EXPECT_NEAR(v.pair_horizontal[1]->allowed_m, 0.022, kVerdictTol_m);
  EXPECT_FALSE(v.pair_horizontal[1]->pass());
  EXPECT_EQ(v.pass, 1u);
  EXPECT_EQ(v.fail, 1u);
  EXPECT_EQ(v.worst_kind, "pair");
  EXPECT_EQ(v.worst_index, 1u);
  EXPECT_FALSE(v.pair_vertical[0]);
}

// A standard of one's own (the format of docs/standards.md) with an up
// criterion on the horizontal distance and a positional one: 95 % up
// interval = 1.959964 σ; a station's 95 % ellipse = 2.4477468 a.
TEST(AccuracyStandard, AFileOfOnesOwnJudgesUpOnTheHorizontalDistanceAndStations) {
  testing::TempFolder dir;
  const auto file = dir / "own.json";
  std::ofstream(file) << R"({"schema": "geoanchor.accuracy-standard/1", "name": "own", "title": "t", "source": "s",
    "criteria": {
      "relative_vertical": {"quantity": "relative_up", "definition": "d", "confidence": 0.95, "constant_m": 0.010, "ppm": 100,
                            "distance": "horizontal"},
      "positional_horizontal": {"quantity": "ellipse_semi_major", "definition": "d", "confidence": 0.95, "constant_m": 0.030}}})";
  const AccuracyStandard s = load_standard(file.string());
  // A–B: up σ 4 mm → 7.8399 mm against 10 mm + 100e-6 × 149 m = 24.9 mm: PASS.
  // B–C: up σ 6 mm → 11.7598 mm against 10 + 3.9 = 13.9 mm: PASS by 2.1402 mm.
  solver::AdjustmentResult r = result_with({pair(0, 1, 150.0, 149.0, 0.009, 0.004), pair(1, 2, 40.0, 39.0, 0.009, 0.006)});
  // Stations: A 1σ semi-major 13 mm → 31.8207 mm > 30 mm: FAIL by 1.8207 mm;
  // B 10 mm → 24.4775 mm: PASS; C not in the adjustment: no verdict.
  r.stations[0].ellipse.semi_major_m = 0.013;
  r.stations[1].ellipse.semi_major_m = 0.010;
  r.stations[2].used = false;
  const StandardVerdicts v = judge_standard(s, r);
  EXPECT_NEAR(v.pair_vertical[0]->achieved_m, 0.007839855938160, kVerdictTol_m);
  EXPECT_NEAR(v.pair_vertical[0]->allowed_m, 0.0249, kVerdictTol_m);
  EXPECT_NEAR(v.pair_vertical[1]->margin_m(), 0.0139 - 0.011759783907240, kVerdictTol_m);
  EXPECT_TRUE(v.pair_vertical[1]->pass());
  EXPECT_NEAR(v.station_horizontal[0]->margin_m(), 0.030 - 0.031820708798851, kVerdictTol_m);
  EXPECT_FALSE(v.station_horizontal[0]->pass());
  EXPECT_TRUE(v.station_horizontal[1]->pass());
  EXPECT_FALSE(v.station_horizontal[2]);
  EXPECT_EQ(v.pass, 3u);
  EXPECT_EQ(v.fail, 1u);
  EXPECT_EQ(v.worst_kind, "station");
  EXPECT_EQ(v.worst_criterion, "positional_horizontal");
}

TEST(AccuracyStandard, AFileThatIsNotUnderstoodIsRefusedNamingFileKeyAndValue) {
  const std::string head = R"({"schema": "geoanchor.accuracy-standard/1", "name": "x", "title": "t", "source": "s", "criteria": )";
  const std::string good = R"({"quantity": "relative_ellipse_semi_major", "definition": "d", "confidence": 0.95, "constant_m": 0.02, "ppm": 50, "distance": "spatial"})";
  struct Case {
    std::string text;
    std::vector<std::string> message;
  };
  const std::vector<Case> cases = {
      {head + R"({"relative_horizontal": )" + good + R"(}, "colour": "red"})", {"colour", "\"red\"", "unknown key"}},
      {head + R"({"relative_horizontal": {"quantity": "relative_ellipse_semi_major", "definition": "d", "confidence": 0.95, "constant_m": 0.02, "distance": "spatial"}}})",
       {"criteria.relative_horizontal.ppm", "missing"}},
      {head + R"({"relative_horizontal": {"quantity": "relative_ellipse_semi_major", "definition": "d", "confidence": 1.5, "constant_m": 0.02, "ppm": 50, "distance": "spatial"}}})",
       {"criteria.relative_horizontal.confidence", "1.5", "(0, 1)"}},
      {head + R"({"relative_horizontal": {"quantity": "relative_ellipse_semi_major", "definition": "d", "confidence": 0.95, "constant_m": "2 cm", "ppm": 50, "distance": "spatial"}}})",
       {"constant_m", "\"2 cm\"", "not a number"}},
      {head + R"({"relative_horizontal": {"quantity": "relative_ellipse_semi_major", "definition": "d", "confidence": 0.95, "constant_m": 1e999, "ppm": 50, "distance": "spatial"}}})",
       {"1e999", "line 1"}},
      {head + R"({"relative_horizontal": {"quantity": "relative_up", "definition": "d", "confidence": 0.95, "constant_m": 0.02, "ppm": 50, "distance": "spatial"}}})",
       {"criteria.relative_horizontal.quantity", "\"relative_up\"", "relative_ellipse_semi_major"}},
      {head + R"({"relative_horizontal": {"quantity": "relative_ellipse_semi_major", "definition": "d", "confidence": 0.95, "constant_m": 0.02, "ppm": 50, "distance": "chord"}}})",
       {"distance", "\"chord\""}},
      {head + "{}}", {"criteria", "no criterion"}},
      {R"({"schema": "geoanchor.accuracy-standard/2", "name": "x", "title": "t", "source": "s", "criteria": {}})", {"schema", "/2"}},
  };
  for (const auto& c : cases) {
    SCOPED_TRACE(c.text);
    try {
      (void)parse_standard(c.text, "bad.json");
      ADD_FAILURE() << "accepted";
    } catch (const Error& e) {
      EXPECT_EQ(e.code(), "E_STANDARD");
      EXPECT_NE(std::string(e.what()).find("bad.json"), std::string::npos) << e.what();
      for (const auto& piece : c.message) EXPECT_NE(std::string(e.what()).find(piece), std::string::npos) << piece << " in " << e.what();
    }
  }
  try {
    (void)load_standard("alta-2099");
    ADD_FAILURE() << "an unknown name was accepted";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), "E_OPTION");
    EXPECT_NE(std::string(e.what()).find("alta-nsps-2021"), std::string::npos) << e.what();  // the shipped names
  }
}

}  // namespace
}  // namespace geoanchor::workflow
