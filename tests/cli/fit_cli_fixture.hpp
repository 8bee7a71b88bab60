#pragma once
// What the fit command-line tests share (fit_cli_test.cpp,
// fit_refusals_cli_test.cpp): the FitCli fixture and the bundled control set.
// Test-only: one definition for every test file that includes it (inline).

#include <gtest/gtest.h>

#include <Eigen/Cholesky>
#include <GeographicLib/Geocentric.hpp>
#include <GeographicLib/LocalCartesian.hpp>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <numeric>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <optional>
#include <random>
#include <sstream>

#include "geoanchor/base/number_text.hpp"
#include "proj_reference.hpp"
#include "cli_support.hpp"
#include "test_support.hpp"

namespace geoanchor {
namespace fit_cli_fixture {

namespace fs = std::filesystem;
using testing::proj_radians;
using testing::ProjPipeline;

// cct against convert, both applying the same file to the same float64
// input: only rounding differs. At ECEF magnitude (|x| < 2^23 m) the float64
// spacing is 9.3e-10 m; each side rounds a handful of times (geodetic ->
// ECEF, the Helmert's products and sums, or the topocentric and tmerc
// steps), cct prints 10 decimals (±5e-11 m) and reads our 17 significant
// digits exactly. 1e-8 m is about ten spacings; measured worst: 2.8e-9 m.
// (The old 1e-4 m bound could not see a wrong parameter below 0.1 mm, e.g. a
// scale off by 0.01 ppm.)
constexpr double kCctAgreementTol_m = 1e-8;
constexpr double kUnitDiagonalTol = 1e-12;    // a correlation with itself, after rounding
constexpr double kEnuOriginCliTol_m = 0.001;  // issue acceptance: enu-origin corrected to 1 mm without noise
constexpr double kSiteRotationTol_arcsec = 0.01;  // 0.07 mm over 1.5 km
constexpr double kSiteScaleTol_ppm = 0.05;        // 0.08 mm over 1.5 km
constexpr double kSiteInverseTol_m = 1e-8;        // the inverse is exact

using testing::CliTest;
using testing::RunResult;
using testing::slurp;

class FitCli : public CliTest {};

inline std::vector<std::vector<std::string>> csv_rows(const std::string& text, std::vector<std::string>* header) {
  testing::CsvTable t = testing::parse_csv_table(text);
  *header = std::move(t.header);
  return std::move(t.rows);
}

inline std::size_t col(const std::vector<std::string>& header, const std::string& name) {
  return static_cast<std::size_t>(std::find(header.begin(), header.end(), name) - header.begin());
}

inline const std::string kControl = std::string(GEOANCHOR_FIXTURES_DIR) + "/airport_control.csv";
// The Helmert the bundled fixture was made with (kFixtureTruth in
// fit_cli_test.cpp), parameter by parameter.
inline const std::map<std::string, double> kFixtureTruthPv = {{"tx_m", 0.0547},         {"ty_m", 0.0522},
                                                        {"tz_m", -0.0741},       {"rx_arcsec", 0.00228},
                                                        {"ry_arcsec", 0.01404},  {"rz_arcsec", -0.02168},
                                                        {"ds_ppm", 0.00212}};
// For an unbiased fit with honest sigmas each (estimate - truth) / σ is
// standard normal, and P(|Z| > 4) = 6.3e-5: a correct fit of this fixture
// fails the 7 parameter checks with probability below 4.4e-4 per convention,
// and its 108 mark-and-axis checks below 0.7 %, while a bias of a few σ (a
// blunder kept, a unit or sign slip) fails. 3σ would fail a correct fit of
// 108 checks 25 % of the time; 5σ would let a 4σ bias through.
constexpr double kTruthSigmas = 4.0;


}  // namespace fit_cli_fixture
}  // namespace geoanchor
