// Error models in geoanchor's network JSON (issue 43 point 2;
// docs/network-format.md "Error models"): each term read in the unit its
// key names, given to measurements by name, a measurement's own sigma
// optional under a model; everything else refused by its path.

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <string>

#include "geoanchor/base/error.hpp"
#include "geoanchor/io/network/network_input.hpp"

namespace geoanchor::io {
namespace {

constexpr double kArcsec = std::numbers::pi / 648000.0;
constexpr double kExact = 1e-18;  // unit conversions of decimal inputs: a few ulps

const std::string kHead = R"({"schema": "geoanchor.network/1", "frame": "GDA2020",
  "stations": [{"id": "A", "lat_deg": -35.3, "lon_deg": 149.1, "h_m": 600.0, "constraint": "CCC"},
               {"id": "B", "lat_deg": -35.31, "lon_deg": 149.11, "h_m": 610.0}],
)";

geodesy::Network read(const std::string& body) {
  geodesy::Network net;
  read_network_text(kHead + body + "}", "net.json", net);
  return net;
}

TEST(NetworkErrorModels, Issue43_ModelsAreReadInTheirUnitsAndGivenByName) {
  const geodesy::Network net = read(R"("error_models": {
      "TS": {"distance_constant_mm": 1.0, "distance_ppm": 1.5, "direction_pointing_arcsec": 1.0, "direction_reading_arcsec": 0.5,
             "zenith_pointing_arcsec": 1.5, "zenith_reading_arcsec": 2.0, "instrument_centring_mm": 0.8, "target_centring_mm": 1.2,
             "instrument_height_mm": 1.0, "target_height_mm": 1.5, "description": "a total station"},
      "RX": {"gnss_horizontal_mm": 8, "gnss_horizontal_ppm": 1, "gnss_vertical_mm": 15, "gnss_vertical_ppm": 2}},
    "measurements": [
      {"kind": "slope_distance", "from": "A", "to": "B", "value_m": 1500.0, "error_model": "TS"},
      {"kind": "slope_distance", "from": "A", "to": "B", "value_m": 1500.0, "sigma_m": 0.002, "error_model": "TS"},
      {"kind": "zenith_angle", "from": "A", "to": "B", "value_deg": 89.6, "error_model": "TS"},
      {"kind": "direction_set", "at": "A", "error_model": "TS", "directions": [{"to": "B", "value_deg": 10.0}]},
      {"kind": "gnss_baseline", "from": "A", "to": "B", "dx_m": 1.0, "dy_m": 2.0, "dz_m": 3.0, "error_model": "RX"}]
  )");
  ASSERT_EQ(net.error_models.size(), 2u);
  // Held in the order of their names.
  ASSERT_EQ(net.error_models[0].name, "RX");
  const auto& ts = net.error_models[1];
  EXPECT_EQ(ts.name, "TS");
  EXPECT_NEAR(ts.distance_constant_m, 0.001, kExact);
  EXPECT_EQ(ts.distance_ppm, 1.5);
  EXPECT_NEAR(ts.direction_pointing_rad, 1.0 * kArcsec, kExact);
  EXPECT_NEAR(ts.direction_reading_rad, 0.5 * kArcsec, kExact);
  EXPECT_NEAR(ts.zenith_pointing_rad, 1.5 * kArcsec, kExact);
  EXPECT_NEAR(ts.zenith_reading_rad, 2.0 * kArcsec, kExact);
  EXPECT_NEAR(ts.instrument_centring_m, 0.0008, kExact);
  EXPECT_NEAR(ts.target_centring_m, 0.0012, kExact);
  EXPECT_NEAR(ts.instrument_height_m, 0.001, kExact);
  EXPECT_NEAR(ts.target_height_m, 0.0015, kExact);
  const auto& rx = net.error_models[0];
  EXPECT_NEAR(rx.gnss_horizontal_m, 0.008, kExact);
  EXPECT_EQ(rx.gnss_horizontal_ppm, 1.0);
  EXPECT_NEAR(rx.gnss_vertical_m, 0.015, kExact);
  EXPECT_EQ(rx.gnss_vertical_ppm, 2.0);
  ASSERT_EQ(net.measurements.size(), 5u);
  for (const auto& m : net.measurements) ASSERT_TRUE(m.error_model) << m.source;
  EXPECT_EQ(*net.measurements[0].error_model, 1u);
  EXPECT_EQ(*net.measurements[4].error_model, 0u);
  // Without its own sigma the model alone (0 until adjust adds it); with
  // one, it stays and the model is added to it.
  EXPECT_EQ(net.measurements[0].covariance(0, 0), 0.0);
  EXPECT_NEAR(net.measurements[1].covariance(0, 0), 0.002 * 0.002, kExact);
  EXPECT_EQ(net.measurements[2].covariance(0, 0), 0.0);
  EXPECT_EQ(net.measurements[3].covariance(0, 0), 0.0);  // the set's model is each direction's
  EXPECT_TRUE(net.measurements[4].covariance.isZero());
}

TEST(NetworkErrorModels, Issue43_WhatIsNotUnderstoodIsRefusedByItsPath) {
  struct Case {
    std::string body, message;
  };
  const std::string m = R"("measurements": [{"kind": "slope_distance", "from": "A", "to": "B", "value_m": 1500.0, "error_model": "TS"}])";
  const Case cases[] = {
      {R"("error_models": {"TS": {"distance_constant_cm": 1.0}}, )" + m, "net.json.error_models.TS.distance_constant_cm: unknown key"},
      {R"("error_models": {"TS": {"distance_ppm": -1.0}}, )" + m, "net.json.error_models.TS.distance_ppm: value -1 must be >= 0"},
      {R"("error_models": {"TS": {"distance_ppm": 0.0}}, )" + m, "net.json.error_models.TS: no term above 0"},
      {R"("error_models": {"TS": {"distance_ppm": "2"}}, )" + m, "distance_ppm"},
      {R"("error_models": [], )" + m, "net.json.error_models: expected an object of named error models"},
      {R"("error_models": {"EDM": {"distance_ppm": 2}}, )" + m, "'TS' names no error model of the file; expected one of EDM"},
      {m, "'TS' names no error model of the file (it has no error_models)"},
      {R"("measurements": [{"kind": "slope_distance", "from": "A", "to": "B", "value_m": 1500.0}])",
       "net.json: measurements[0].sigma_m: missing (or give an error_model that gives it)"},
      {R"("measurements": [{"kind": "zenith_angle", "from": "A", "to": "B", "value_deg": 89.0}])",
       "(or an error_model that gives it)"},
      {R"("measurements": [{"kind": "gnss_baseline", "from": "A", "to": "B", "dx_m": 1, "dy_m": 2, "dz_m": 3}])",
       "no covariance: give cov_m2 (3×3, m²), sigma_m or an error_model"},
  };
  for (const auto& c : cases) {
    try {
      read(c.body);
      ADD_FAILURE() << "read: " << c.body;
    } catch (const Error& e) {
      EXPECT_EQ(e.code(), "E_NETWORK") << e.what();
      EXPECT_NE(std::string(e.what()).find(c.message), std::string::npos) << e.what();
    }
  }
}

}  // namespace
}  // namespace geoanchor::io
