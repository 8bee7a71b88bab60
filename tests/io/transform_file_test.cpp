// The transform file: what is accepted, what is refused, and that it reads
// back what it writes.

#include <gtest/gtest.h>

#include "geoanchor/geodesy/error.hpp"
#include "geoanchor/io/transform_file.hpp"

namespace geoanchor::io {
namespace {

constexpr double kRoundTripTol_m = 1e-9;  // JSON numbers are written at full precision

const char* kHelmert7 = R"({"model": "helmert7", "convention": "position_vector", "rotation_model": "small_angle",
  "source_frame": "WGS72", "target_frame": "WGS84",
  "parameters": {"tx_m": 0, "ty_m": 0, "tz_m": 4.5, "rx_arcsec": 0, "ry_arcsec": 0, "rz_arcsec": 0.554, "ds_ppm": 0.219}})";

const char* kHelmert14 = R"({"model": "helmert14", "convention": "position_vector", "reference_epoch": 1994.0,
  "parameters": {"tx_mm": -84.68, "ty_mm": -19.42, "tz_mm": 32.01, "rx_mas": 0.4254, "ry_mas": -2.2578,
                 "rz_mas": -2.4015, "ds_ppb": 9.71, "dtx_mm_per_year": 1.42, "dty_mm_per_year": 1.34,
                 "dtz_mm_per_year": 0.90, "drx_mas_per_year": -1.5461, "dry_mas_per_year": -1.1820,
                 "drz_mas_per_year": -1.1551, "dds_ppb_per_year": 0.109}})";

std::string error_of(const std::string& json) {
  try {
    parse_transform_json(json, "T.json");
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

std::string replace(std::string s, const std::string& from, const std::string& to) {
  const auto at = s.find(from);
  if (at != std::string::npos) s.replace(at, from.size(), to);
  return s;
}

TEST(TransformFile, ReadsASevenParameterSetWithFrames) {
  const TransformFile t = parse_transform_json(kHelmert7, "T.json");
  EXPECT_EQ(t.model, TransformModel::helmert7);
  EXPECT_EQ(t.convention_name(), "position_vector");
  EXPECT_EQ(t.source_frame->name(), "WGS72");
  const auto& h = std::get<geodesy::Helmert7<geodesy::PositionVector>>(t.helmert);
  EXPECT_EQ(h.t_m.z(), 4.5);
  EXPECT_DOUBLE_EQ(h.rz.arcsec(), 0.554);
  EXPECT_DOUBLE_EQ(h.ds.ppm(), 0.219);
}

TEST(TransformFile, ReadsMillimetresMasAndPpbAndNeedsAnEpochToApply) {
  const TransformFile t = parse_transform_json(kHelmert14, "T.json");
  EXPECT_TRUE(t.time_dependent());
  const auto& h = std::get<geodesy::Helmert14<geodesy::PositionVector>>(t.helmert);
  EXPECT_DOUBLE_EQ(h.at_reference_epoch.t_m.x(), -0.08468);
  EXPECT_DOUBLE_EQ(h.rates.drx_per_year.arcsec(), -0.0015461);
  EXPECT_DOUBLE_EQ(h.at_reference_epoch.ds.ppm(), 0.00971);
  try {
    t.target_from_source(std::nullopt, "points.csv:4");
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), "E_EPOCH_MISSING");
    EXPECT_NE(std::string(e.what()).find("points.csv:4"), std::string::npos);
    EXPECT_NE(std::string(e.what()).find("reference epoch 1994.0 is never substituted"), std::string::npos);
  }
}

TEST(TransformFile, RefusesWhatWouldBeSilentlyWrong) {
  EXPECT_NE(error_of(replace(kHelmert7, R"("convention": "position_vector",)", "")).find("T.json: convention: missing"),
            std::string::npos);
  EXPECT_NE(error_of(replace(kHelmert14, R"("reference_epoch": 1994.0,)", "")).find("T.json: reference_epoch: missing"),
            std::string::npos);
  EXPECT_NE(error_of(replace(kHelmert7, R"("ds_ppm": 0.219)", R"("d_ppm": 0.219)")).find("parameters.d_ppm: unknown"),
            std::string::npos);
  EXPECT_NE(error_of(replace(kHelmert7, R"("ds_ppm": 0.219)", R"("ds_ppm": 0.219, "ds_ppb": 219)")).find("given twice"),
            std::string::npos);
  EXPECT_NE(error_of(replace(kHelmert7, R"("rz_arcsec": 0.554,)", "")).find("missing rz_arcsec (or rz_mas)"),
            std::string::npos);
  EXPECT_NE(error_of(replace(kHelmert7, R"("rz_arcsec": 0.554)", R"("rz": 0.554)")).find("parameters.rz: unknown"),
            std::string::npos);
  EXPECT_NE(error_of(replace(kHelmert7, R"("ds_ppm": 0.219)", R"("ds_ppm": 0.219, "dds_ppm_per_year": 0.01)"))
                .find("parameters.dds_ppm_per_year: not a parameter of model helmert7; rates need model helmert14"),
            std::string::npos);
  EXPECT_NE(error_of(replace(kHelmert7, R"("model")", R"("modle")")).find("T.json: modle: unknown key"),
            std::string::npos);
  EXPECT_NE(error_of(replace(kHelmert7, "position_vector", "position")).find("expected position_vector or coordinate_frame"),
            std::string::npos);
  EXPECT_NE(error_of(replace(kHelmert7, "small_angle", "approx")).find("expected small_angle or exact"), std::string::npos);
  EXPECT_NE(error_of(replace(kHelmert7, "4.5", "\"4.5\"")).find("is not a number"), std::string::npos);
  EXPECT_NE(error_of("{\"model\": ").find("T.json: not valid JSON"), std::string::npos);
  EXPECT_NE(error_of(replace(kHelmert14, "1994.0", "19940")).find("not in [1900, 2200]"), std::string::npos);
}

TEST(TransformFile, WritesWhatItReads) {
  for (const char* text : {kHelmert7, kHelmert14}) {
    TransformFile t = parse_transform_json(text, "T.json");
    t.rotation_model = geodesy::RotationModel::exact;
    const TransformFile back = parse_transform_json(to_json_text(t), "written");
    EXPECT_EQ(back.model, t.model);
    EXPECT_EQ(back.rotation_model, geodesy::RotationModel::exact);
    EXPECT_EQ(back.convention_name(), t.convention_name());
    const Eigen::Vector3d x(-3789470.710, 4841770.404, -1690893.952);
    const auto epoch = geodesy::DecimalYear{2013.9};
    EXPECT_LE((back.target_from_source(epoch, "").apply(x) - t.target_from_source(epoch, "").apply(x)).norm(),
              kRoundTripTol_m);
  }
}

// The seven-parameter set above with a fit record appended: `fit` is the
// text of the extra keys (without the leading comma).
std::string helmert7_with(const std::string& fit) {
  std::string s = kHelmert7;
  s.insert(s.size() - 1, ", " + fit);
  return s;
}

std::string code_of(const std::string& json) {
  try {
    parse_transform_json(json, "T.json");
  } catch (const Error& e) {
    return e.code();
  }
  return "";
}

// issue 12 point 3
TEST(TransformFile, Point3_DuplicateKeyIsRefusedWithItsPathAndLine) {
  // nlohmann keeps the last duplicate: the file would apply coordinate_frame.
  const std::string twice = replace(kHelmert7, R"("convention": "position_vector",)",
                                    R"("convention": "position_vector", "convention": "coordinate_frame",)");
  EXPECT_EQ(code_of(twice), "E_JSON_DUPLICATE_KEY");
  EXPECT_NE(error_of(twice).find("T.json:1: convention: key given twice"), std::string::npos) << error_of(twice);
  // Nested, on a later line: the path and the line of the second one.
  const std::string nested = replace(kHelmert7, R"("rz_arcsec": 0.554,)", R"("rz_arcsec": 0.554,
      "rz_arcsec": -0.554,)");
  EXPECT_NE(error_of(nested).find("T.json:4: parameters.rz_arcsec: key given twice"), std::string::npos) << error_of(nested);
  // Inside an array of objects.
  const std::string in_points =
      helmert7_with(R"("points": [{"id": "A", "used": true}, {"id": "B", "used": true, "used": false}])");
  EXPECT_NE(error_of(in_points).find("points[1].used: key given twice"), std::string::npos) << error_of(in_points);
  // The same key in two different objects is not a duplicate.
  EXPECT_EQ(error_of(helmert7_with(R"("points": [{"id": "A", "used": true}, {"id": "B", "used": true}])")), "");
  // Malformed JSON still names the file and the position.
  EXPECT_NE(error_of("{\"model\": \"helmert7\",\n \"convention\" \"x\"}").find("T.json: not valid JSON: "), std::string::npos);
  EXPECT_NE(error_of("{\"model\": \"helmert7\",\n \"convention\" \"x\"}").find("line 2, column"), std::string::npos);
  EXPECT_NE(error_of(replace(kHelmert7, "4.5", "4e999")).find("(at line 3, column"), std::string::npos)
      << error_of(replace(kHelmert7, "4.5", "4e999"));
}

}  // namespace
}  // namespace geoanchor::io
