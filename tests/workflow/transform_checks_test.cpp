// The plausibility warnings `convert` and `apply` give for the transform file
// they apply (issue 12 point 7): the limits fit warns with, 1 km, 10″ and
// 100 ppm (RELIABILITY #15), named with the value, for every model that is a
// datum transform; nothing for a local map's placement.

#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "geoanchor/base/error.hpp"
#include "geoanchor/io/transform/transform_file.hpp"
#include "geoanchor/workflow/transform_checks.hpp"

namespace geoanchor::workflow {
namespace {

using geodesy::DecimalYear;

io::TransformFile parse(const std::string& text) { return io::parse_transform_json(text, "T.json"); }

std::string helmert7(const std::string& parameters) {
  return R"({"model": "helmert7", "convention": "position_vector", "parameters": {)" + parameters + "}}";
}
const std::string kZeroTranslation = R"("tx_m": 0, "ty_m": 0, "tz_m": 0, )";

// issue 12 point 7
TEST(TransformChecks, Point7_Helmert7BeyondFitsLimitsIsNamedWithValueAndLimit) {
  // rx = 20″: 20 / 206264.806 × 6371 km = 617.7 m at the Earth's mean radius.
  const auto rx = implausible_transform_warnings(
      parse(helmert7(kZeroTranslation + R"("rx_arcsec": 20, "ry_arcsec": 0, "rz_arcsec": 0, "ds_ppm": 0)")), "T.json",
      std::nullopt);
  ASSERT_EQ(rx.size(), 1u);
  EXPECT_EQ(rx[0].rfind("T.json: rx = 20″ is implausible for a datum transform (> 10″, 618 m at the Earth's surface)", 0), 0u)
      << rx[0];
  // ds = 200 ppm (given as 200000 ppb: the unit read does not matter).
  const auto ds = implausible_transform_warnings(
      parse(helmert7(kZeroTranslation + R"("rx_arcsec": 0, "ry_arcsec": 0, "rz_arcsec": 0, "ds_ppb": 200000)")), "T.json",
      std::nullopt);
  ASSERT_EQ(ds.size(), 1u);
  EXPECT_EQ(ds[0].rfind("T.json: ds = 200 ppm is implausible for a datum transform (> 100 ppm", 0), 0u) << ds[0];
  // tx = 1e300 m: finite, and absurd.
  const auto tx = implausible_transform_warnings(
      parse(R"({"model": "translation3", "parameters": {"tx_m": 1e300, "ty_m": 0, "tz_m": 0}})"), "T.json", std::nullopt);
  ASSERT_EQ(tx.size(), 1u);
  EXPECT_EQ(tx[0].rfind("T.json: tx = 1e+300 m is implausible for a datum transform (> 1e+03 m)", 0), 0u) << tx[0];
  // At the limits themselves (they are inclusive): nothing.
  EXPECT_TRUE(implausible_transform_warnings(
                  parse(helmert7(R"("tx_m": 1000, "ty_m": -1000, "tz_m": 0, "rx_arcsec": 10, "ry_arcsec": -10, )"
                                 R"("rz_arcsec": 0, "ds_ppm": -100)")),
                  "T.json", std::nullopt)
                  .empty());
}

// issue 12 point 7
TEST(TransformChecks, Point7_MolodenskyBadekasIsCheckedAsAHelmert) {
  const auto w = implausible_transform_warnings(parse(R"({"model": "molodensky-badekas", "convention": "coordinate_frame",
    "parameters": {"tx_m": 0, "ty_m": 0, "tz_m": 4.5, "rx_arcsec": 0, "ry_arcsec": 0, "rz_arcsec": 25, "ds_ppm": 0.2,
                   "px_m": 4271315.7, "py_m": 641096.4, "pz_m": 4678048.5}})"),
                                                "MB.json", std::nullopt);
  ASSERT_EQ(w.size(), 1u);
  EXPECT_EQ(w[0].rfind("MB.json: rz = 25″ is implausible", 0), 0u) << w[0];
}

// issue 12 point 7
TEST(TransformChecks, Point7_Helmert14IsCheckedAtBothEndsOfTheEpochsOfUseNamingTheEpoch) {
  // rz = 5″ + 1″/yr × (t − 2020): 6″ in 2021 (plausible), 15″ in 2030, −5″ in 2010.
  const auto t = parse(R"({"model": "helmert14", "convention": "position_vector", "reference_epoch": 2020.0,
    "parameters": {"tx_m": 0, "ty_m": 0, "tz_m": 0, "rx_arcsec": 0, "ry_arcsec": 0, "rz_arcsec": 5, "ds_ppm": 0,
                   "dtx_m_per_year": 0, "dty_m_per_year": 0, "dtz_m_per_year": 0, "drx_arcsec_per_year": 0,
                   "dry_arcsec_per_year": 0, "drz_arcsec_per_year": 1, "dds_ppm_per_year": 0}})");
  const auto w = implausible_transform_warnings(t, "T14.json", EpochSpan{DecimalYear{2021.0}, DecimalYear{2030.0}});
  ASSERT_EQ(w.size(), 1u);
  EXPECT_EQ(w[0].rfind("T14.json at epoch 2030: rz = 15″ is implausible for a datum transform (> 10″", 0), 0u) << w[0];
  EXPECT_TRUE(implausible_transform_warnings(t, "T14.json", EpochSpan{DecimalYear{2010.0}, DecimalYear{2021.0}}).empty());
  // The reference epoch is never substituted: without an epoch of use, nothing is applied and nothing checked.
  EXPECT_TRUE(implausible_transform_warnings(t, "T14.json", std::nullopt).empty());
}

// issue 12 point 7
TEST(TransformChecks, Point7_ALocalMapsPlacementIsNotADatumTransformAndIsNotWarned) {
  // A map anchored 5 km away, drawn 30° off north, 300 ppm long (ground distances at 1.9 km height).
  const auto enu = parse(R"({"model": "enu-origin",
    "nominal_origin": {"lat_deg": 47.4647, "lon_deg": 8.5492, "h_m": 480.05, "height_type": "ellipsoidal", "ellipsoid": "WGS84"},
    "parameters": {"shift_e_m": 5000, "shift_n_m": 0, "shift_u_m": 0, "yaw_arcsec": 108000, "ds_ppm": 300}})");
  EXPECT_TRUE(implausible_transform_warnings(enu, "E.json", std::nullopt).empty());
  const auto site = parse(R"({"model": "site-calibration",
  "nominal_origin": {"lat_deg": 46.6, "lon_deg": 7.4, "h_m": 600, "height_type": "ellipsoidal", "ellipsoid": "GRS80"},
  "grid": {"lat0_deg": 46.5, "lon0_deg": 7.5, "k0": 1, "false_easting_m": 0, "false_northing_m": 0, "ellipsoid": "GRS80"},
  "parameters": {"shift_e_m": 500000, "shift_n_m": -300, "rotation_arcsec": 126000, "scale_ppm": 450, "vertical_shift_m": 48.2,
                 "slope_n_ppm": 0, "slope_e_ppm": 0, "centroid_e_m": 0, "centroid_n_m": 0}})");
  EXPECT_TRUE(implausible_transform_warnings(site, "S.json", std::nullopt).empty());
}

// issue 12 point 7: a NaN or infinite parameter never reaches the check.
TEST(TransformChecks, Point7_ANumberBeyondDoublesRangeIsRefusedWhenTheFileIsRead) {
  try {
    parse(R"({"model": "translation3", "parameters": {"tx_m": 1e400, "ty_m": 0, "tz_m": 0}})");
    ADD_FAILURE() << "1e400 was read";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), "E_JSON") << e.what();
    EXPECT_NE(std::string(e.what()).find("T.json"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("1e400"), std::string::npos) << e.what();
  }
  // JSON has no NaN or Infinity literal.
  for (const char* v : {"NaN", "Infinity", "-Infinity"}) {
    EXPECT_THROW(parse(std::string(R"({"model": "translation3", "parameters": {"tx_m": )") + v + R"(, "ty_m": 0, "tz_m": 0}})"),
                 Error)
        << v;
  }
}

}  // namespace
}  // namespace geoanchor::workflow
