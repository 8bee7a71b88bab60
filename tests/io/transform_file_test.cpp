// The transform file: what is accepted, what is refused, and that it reads
// back what it writes.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <random>

#include "geoanchor/base/error.hpp"
#include "geoanchor/io/transform/transform_file.hpp"

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

const char* kSigmas7 = R"("sigmas": {"tx_m": 0.05, "ty_m": 0.05, "tz_m": 0.05, "rx_arcsec": 0.002, "ry_arcsec": 0.002,
                                     "rz_arcsec": 0.002, "ds_ppm": 0.005})";

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

// issue 12 point 9
TEST(TransformFile, Point9_SigmaKeysNameTheModelsEstimatedParameters) {
  const std::string none = R"("correlation": "none")";
  EXPECT_EQ(error_of(helmert7_with(std::string(kSigmas7) + ", " + none)), "");
  // A typo.
  const std::string typo = replace(kSigmas7, "\"rz_arcsec\"", "\"rz_arcsce\"");
  EXPECT_NE(error_of(helmert7_with(typo + ", " + none))
                .find("T.json: sigmas.rz_arcsce: not a parameter of model helmert7; sigmas are read for the estimated "
                      "parameters, in the units of parameters: tx_m, ty_m, tz_m, rx_arcsec, ry_arcsec, rz_arcsec, ds_ppm"),
            std::string::npos)
      << error_of(helmert7_with(typo + ", " + none));
  // A parameter the model does not have: a rate in a 7-parameter set.
  EXPECT_NE(error_of(helmert7_with(R"("sigmas": {"dtx_m_per_year": 0.001}, "correlation": "none")"))
                .find("sigmas.dtx_m_per_year: rates are parameters of model helmert14 only"),
            std::string::npos);
  // A parameter the model holds fixed.
  const std::string helmert6 = replace(kHelmert7, "helmert7", "helmert6");
  std::string h6 = helmert6;
  h6.insert(h6.size() - 1, R"(, "sigmas": {"tx_m": 0.05, "ds_ppm": 0.005}, "correlation": "none")");
  EXPECT_NE(error_of(h6).find("sigmas.ds_ppm: model helmert6 holds ds fixed (not estimated), so it has no sigma"),
            std::string::npos)
      << error_of(h6);
  // Another unit than parameters uses: the value would be read in the wrong one.
  EXPECT_NE(error_of(helmert7_with(R"("sigmas": {"tx_mm": 50}, "correlation": "none")"))
                .find("sigmas.tx_mm: parameters states this parameter as tx_m; give its sigma in the same unit"),
            std::string::npos);
  // Negative, or not a number.
  EXPECT_NE(error_of(helmert7_with(R"("sigmas": {"tx_m": -0.05}, "correlation": "none")")).find("sigmas.tx_m: value -0.05 is not a sigma"),
            std::string::npos);
  EXPECT_NE(error_of(helmert7_with(R"("sigmas": {"tx_m": "0.05"}, "correlation": "none")")).find("sigmas.tx_m: value \"0.05\" is not a sigma"),
            std::string::npos);
  // In the file's own units they are read and held in canonical units.
  const TransformFile mm = parse_transform_json(kHelmert14, "T.json");
  std::string h14 = kHelmert14;
  h14.insert(h14.size() - 1, R"(, "sigmas": {"tx_mm": 1.5, "rz_mas": 0.2, "dds_ppb_per_year": 0.01}, "correlation": "none")");
  const TransformFile t14 = parse_transform_json(h14, "T.json");
  ASSERT_TRUE(t14.fit);
  std::map<std::string, double> read(t14.fit->sigmas.begin(), t14.fit->sigmas.end());
  ASSERT_EQ(read.size(), 3u);
  EXPECT_DOUBLE_EQ(read["tx_m"], 0.0015);
  EXPECT_DOUBLE_EQ(read["rz_arcsec"], 0.0002);
  EXPECT_DOUBLE_EQ(read["dds_ppm_per_year"], 0.00001);
  EXPECT_TRUE(t14.fit->uncorrelated);
  EXPECT_FALSE(mm.fit);
}

// issue 12 point 9
TEST(TransformFile, Point9_DerivedAndFixedParametersOfOtherModelsHaveNoSigma) {
  const std::string enu = R"({"model": "enu-origin",
    "nominal_origin": {"lat_deg": 47.4647, "lon_deg": 8.5492, "h_m": 480.05, "height_type": "ellipsoidal", "ellipsoid": "WGS84"},
    "parameters": {"shift_e_m": -0.30, "shift_n_m": 0.20, "shift_u_m": -0.05, "yaw_arcsec": 20.0},
    "sigmas": {"shift_e_m": 0.001, "shift_n_m": 0.001, "shift_u_m": 0.002, "yaw_arcsec": 0.1}, "correlation": "none"})";
  EXPECT_EQ(error_of(enu), "");
  EXPECT_NE(error_of(replace(enu, R"("yaw_arcsec": 0.1})", R"("yaw_arcsec": 0.1, "origin_lat_deg": 1e-8})"))
                .find("sigmas.origin_lat_deg: origin_lat_deg is derived from nominal_origin and the shift, not estimated"),
            std::string::npos);
  EXPECT_NE(error_of(replace(enu, R"("yaw_arcsec": 0.1})", R"("yaw_arcsec": 0.1, "ds_ppm": 0.1})"))
                .find("sigmas.ds_ppm: parameters states no ds_ppm, so it is held at 0"),
            std::string::npos);
  // helmert7 names are not enu-origin's.
  EXPECT_NE(error_of(replace(enu, R"("yaw_arcsec": 0.1})", R"("yaw_arcsec": 0.1, "tx_m": 0.1})"))
                .find("sigmas.tx_m: not a parameter of model enu-origin; sigmas are read for the estimated parameters, "
                      "in the units of parameters: shift_e_m, shift_n_m, shift_u_m, yaw_arcsec"),
            std::string::npos);
  // The Molodensky-Badekas pivot is chosen, not estimated.
  const std::string mb = R"({"model": "molodensky-badekas", "convention": "position_vector",
    "parameters": {"tx_m": 0, "ty_m": 0, "tz_m": 4.5, "rx_arcsec": 0, "ry_arcsec": 0, "rz_arcsec": 0.554, "ds_ppm": 0.219,
                   "px_m": 4271315.7, "py_m": 641096.4, "pz_m": 4678048.5},
    "sigmas": {"tx_m": 0.01, "px_m": 1.0}, "correlation": "none"})";
  EXPECT_NE(error_of(mb).find("sigmas.px_m: the pivot is chosen (the control's centroid), not estimated"), std::string::npos)
      << error_of(mb);
}

// issue 12 point 9
TEST(TransformFile, Point9_SigmasNeedACorrelationMatrixOrTheWordNone) {
  const std::string missing = helmert7_with(kSigmas7);
  EXPECT_NE(error_of(missing).find("T.json: correlation: missing; sigmas without a correlation matrix would be propagated "
                                   "as if the parameters were uncorrelated"),
            std::string::npos)
      << error_of(missing);
  const std::string t3 = R"({"model": "translation3", "parameters": {"tx_m": 1, "ty_m": 2, "tz_m": 3},
    "sigmas": {"tx_m": 0.01, "ty_m": 0.02, "tz_m": 0.03},
    "correlation_parameters": ["tx_m", "ty_m", "tz_m"],
    "correlation": [[1, 0.5, -0.2], [0.5, 1, 0.1], [-0.2, 0.1, 1]]})";
  EXPECT_EQ(error_of(t3), "");
  // Not symmetric.
  EXPECT_NE(error_of(replace(t3, "[0.5, 1, 0.1]", "[0.4, 1, 0.1]"))
                .find("correlation[1][0]: value 0.4 but correlation[0][1] is 0.5 (ty_m / tx_m); the matrix must be symmetric"),
            std::string::npos)
      << error_of(replace(t3, "[0.5, 1, 0.1]", "[0.4, 1, 0.1]"));
  // Symmetric, in [-1, 1], unit diagonal, but no covariance has these correlations.
  const std::string indefinite = replace(replace(replace(t3, "[1, 0.5, -0.2]", "[1, 0.9, -0.9]"), "[0.5, 1, 0.1]", "[0.9, 1, 0.9]"),
                                         "[-0.2, 0.1, 1]", "[-0.9, 0.9, 1]");
  EXPECT_NE(error_of(indefinite).find("T.json: correlation: not positive semi-definite (smallest eigenvalue -0.8"),
            std::string::npos)
      << error_of(indefinite);
  EXPECT_NE(error_of(replace(t3, "[0.5, 1, 0.1]", "[0.5, 0.9, 0.1]")).find("correlation[1][1]: value 0.9 on the diagonal"),
            std::string::npos);
  EXPECT_NE(error_of(replace(t3, "[1, 0.5, -0.2]", "[1, 0.5, -1.2]")).find("correlation[0][2]: value -1.2 is not a correlation in [-1, 1]"),
            std::string::npos);
  EXPECT_NE(error_of(replace(t3, "[0.5, 1, 0.1]", "[0.5, 1]")).find("correlation[1]: expected 3 values (a square matrix)"),
            std::string::npos);
  // correlation_parameters must name exactly the sigma'd parameters, each once.
  EXPECT_NE(error_of(replace(t3, R"(["tx_m", "ty_m", "tz_m"])", R"(["tx_m", "ty_m"])"))
                .find("T.json: correlation_parameters: misses tz_m, which sigmas gives"),
            std::string::npos);
  EXPECT_NE(error_of(replace(t3, R"(["tx_m", "ty_m", "tz_m"])", R"(["tx_m", "ty_m", "ty_m"])"))
                .find("correlation_parameters[2]: ty_m appears twice"),
            std::string::npos);
  EXPECT_NE(error_of(replace(t3, R"(["tx_m", "ty_m", "tz_m"])", R"(["tx_m", "ty_m", "rz_arcsec"])"))
                .find("correlation_parameters[2]: rz_arcsec has no sigma in sigmas"),
            std::string::npos);
  EXPECT_NE(error_of(replace(t3, R"("correlation_parameters": ["tx_m", "ty_m", "tz_m"],)", ""))
                .find("T.json: correlation_parameters: missing"),
            std::string::npos);
  EXPECT_NE(error_of(replace(t3, R"([[1, 0.5, -0.2], [0.5, 1, 0.1], [-0.2, 0.1, 1]])", R"("identity")"))
                .find("correlation: value \"identity\" unknown"),
            std::string::npos);
}

// issue 12 point 13: the point records of a large fit are formatted in
// blocks on several threads; written and read back, every record comes back
// exactly, in order, one a line.
TEST(TransformFile, Point13_ManyPointRecordsReadBackExactlyInOrder) {
  const std::string text = helmert7_with(std::string(kSigmas7) + R"(, "correlation": "none",
      "statistics": {"sigma0": 0.9, "dof": 12, "sigmas_scaled_by_sigma0": false, "alpha": 0.05, "alpha_point": 0.001,
                     "global_test": {"statistic": 10.8, "critical": 21.0, "critical_lower": 4.4, "passed": true, "applicable": true},
                     "warnings": []})");
  TransformFile t = parse_transform_json(text, "T.json");
  ASSERT_TRUE(t.fit);
  constexpr std::size_t kMarks = 40009;  // more blocks than the writer holds at once (16 of 2048), the last one short
  std::mt19937_64 rng(13);
  std::normal_distribution<double> g(0.0, 1.0);
  for (std::size_t i = 0; i < kMarks; ++i) {
    FitPointRecord p;
    p.id = i % 997 == 0 ? "quote\"d " + std::to_string(i) : "P" + std::to_string(i);
    p.residual_enu_m = {g(rng) * 0.003, g(rng) * 0.003, g(rng) * 0.005};
    p.w_enu = {g(rng), g(rng), i % 101 == 0 ? std::numeric_limits<double>::quiet_NaN() : g(rng)};
    p.w_test = p.w_enu[0];
    p.redundancy_enu = {0.99, 0.98, 0.97};
    p.mdb_m = 0.01 + static_cast<double>(i) * 1e-9;
    p.point_test = std::fabs(g(rng));
    p.point_test_dof = 3;
    p.point_test_p = 0.5;
    p.outlier = i % 503 == 0;
    p.used = !p.outlier;
    if (p.outlier) p.note = "w-test";
    t.fit->points.push_back(p);
  }
  const std::string written = to_json_text(t);
  const TransformFile back = parse_transform_json(written, "written");
  ASSERT_TRUE(back.fit);
  ASSERT_EQ(back.fit->points.size(), kMarks);
  const auto same = [](double a, double b) { return a == b || (std::isnan(a) && std::isnan(b)); };
  for (std::size_t i = 0; i < kMarks; ++i) {
    const FitPointRecord &a = t.fit->points[i], &b = back.fit->points[i];
    ASSERT_EQ(b.id, a.id) << i;
    for (std::size_t k = 0; k < 3; ++k) {
      ASSERT_TRUE(same(b.residual_enu_m[k], a.residual_enu_m[k]) && same(b.w_enu[k], a.w_enu[k]) &&
                  same(b.redundancy_enu[k], a.redundancy_enu[k]))
          << i;
    }
    ASSERT_TRUE(same(b.mdb_m, a.mdb_m) && same(b.point_test, a.point_test) && same(b.w_test, a.w_test)) << i;
    ASSERT_EQ(b.outlier, a.outlier) << i;
    ASSERT_EQ(b.note, a.note) << i;
  }
  // One record a line: the line after "points" holds the first mark.
  const auto at = written.find("\"points\": [\n    {\"id\": \"quote\\\"d 0\"");
  EXPECT_NE(at, std::string::npos);
  EXPECT_GT(std::count(written.begin(), written.end(), '\n'), static_cast<std::ptrdiff_t>(kMarks));
}

// issue 12 point 9: a fit record written is read back as it was.
TEST(TransformFile, Point9_FitRecordReadsBackWhatItWrites) {
  const std::string text = helmert7_with(std::string(kSigmas7) + R"(, "correlation": "none",
      "statistics": {"sigma0": 0.9, "dof": 12, "sigmas_scaled_by_sigma0": true, "alpha": 0.01, "alpha_point": 0.002,
                     "global_test": {"statistic": 10.8, "critical": 21.0, "critical_lower": 4.4, "passed": true, "applicable": true},
                     "warnings": ["w1"]},
      "points": [{"id": "A", "residual_enu_m": [0.001, -0.002, 0.003], "w_test": -1.2, "w_enu": [0.3, -1.2, 0.9],
                  "redundancy_enu": [0.8, 0.7, 0.6], "mdb_m": null, "point_test": {"statistic": 1.1, "dof": 3, "p_value": 0.8},
                  "outlier": false, "used": false, "note": "left out"}])");
  const TransformFile t = parse_transform_json(text, "T.json");
  const TransformFile back = parse_transform_json(to_json_text(t), "written");
  ASSERT_TRUE(back.fit);
  EXPECT_TRUE(back.fit->uncorrelated);
  EXPECT_EQ(back.fit->sigmas, t.fit->sigmas);
  EXPECT_EQ(back.fit->sigma0, 0.9);
  EXPECT_EQ(back.fit->dof, 12);
  EXPECT_TRUE(back.fit->sigmas_scaled_by_sigma0);
  EXPECT_EQ(back.fit->alpha, 0.01);
  EXPECT_EQ(back.fit->global_critical_lower, 4.4);
  EXPECT_EQ(back.fit->warnings, std::vector<std::string>{"w1"});
  ASSERT_EQ(back.fit->points.size(), 1u);
  EXPECT_EQ(back.fit->points[0].note, "left out");
  EXPECT_FALSE(back.fit->points[0].used);
  EXPECT_EQ(back.fit->points[0].point_test_dof, 3);
  EXPECT_TRUE(std::isnan(back.fit->points[0].mdb_m));
}

// issue 12 point 10
TEST(TransformFile, Point10_FitRecordValuesOfTheWrongTypeAndUnknownKeysAreRefused) {
  const std::string fit = std::string(kSigmas7) + R"(, "correlation": "none", )";
  auto err = [&](const std::string& extra) { return error_of(helmert7_with(fit + extra)); };
  EXPECT_NE(err(R"("statistics": {"sigma0": "0.9"})").find("T.json: statistics.sigma0: value \"0.9\" is not a number"),
            std::string::npos);
  EXPECT_NE(err(R"("statistics": {"dof": 1.5})").find("statistics.dof: value 1.5 is not a count"), std::string::npos);
  EXPECT_NE(err(R"("statistics": {"sigmas_scaled_by_sigma0": "yes"})").find("statistics.sigmas_scaled_by_sigma0: value \"yes\" is not true or false"),
            std::string::npos);
  EXPECT_NE(err(R"("statistics": {"sigma_0": 0.9})").find("statistics.sigma_0: unknown key; expected sigma0, dof"), std::string::npos);
  EXPECT_NE(err(R"("statistics": {"global_test": {"passed": "no"}})").find("statistics.global_test.passed: value \"no\""),
            std::string::npos);
  EXPECT_NE(err(R"("points": [{"id": "A", "used": "false"}])").find("T.json: points[0].used: value \"false\" is not true or false"),
            std::string::npos);
  EXPECT_NE(err(R"("points": [{"id": "A", "usde": false}])").find("points[0].usde: unknown key; expected id, residual_enu_m"),
            std::string::npos);
  EXPECT_NE(err(R"("points": [{"id": 7}])").find("points[0].id: value 7 is not a string"), std::string::npos);
  EXPECT_NE(err(R"("points": [{"id": "A", "residual_enu_m": [1, 2]}])").find("points[0].residual_enu_m: value [1,2] is not [e, n, u]"),
            std::string::npos);
  const std::string extent = R"("control_extent": {"centroid": {"lat_deg": 47.4, "lon_deg": 8.5, "h_m": 400, "ellipsoid": "WGS84"},
                                                  "hull_en_m": [[0, 0], [10, 0], [0, 10]]})";
  EXPECT_EQ(err(extent), "");
  EXPECT_NE(err(replace(extent, "\"WGS84\"", "\"GRS80\"")).find("control_extent.centroid.ellipsoid: value \"GRS80\" not read"),
            std::string::npos);
  EXPECT_NE(err(replace(extent, "\"hull_en_m\"", "\"hull_m\"")).find("control_extent.hull_m: unknown key"), std::string::npos);
  EXPECT_NE(err(replace(extent, "[10, 0]", "[10, \"0\"]")).find("control_extent.hull_en_m[1][1]: value \"0\" is not a number"),
            std::string::npos);
  // How control in a CRS was read: kept whole; roles other than source and target refused.
  const std::string crs = R"("control_crs": {"source": {"crs": "EPSG:2236", "operation": {"candidates": []}}})";
  const TransformFile with_crs = parse_transform_json(helmert7_with(fit + crs), "T.json");
  ASSERT_TRUE(with_crs.fit);
  const TransformFile crs_back = parse_transform_json(to_json_text(with_crs), "written");
  ASSERT_TRUE(crs_back.fit);
  EXPECT_EQ(crs_back.fit->control_crs_json, with_crs.fit->control_crs_json);
  EXPECT_NE(crs_back.fit->control_crs_json.find("EPSG:2236"), std::string::npos);
  EXPECT_NE(err(replace(crs, "\"source\"", "\"src\"")).find("control_crs.src: unknown key; expected source or target"),
            std::string::npos);
  EXPECT_NE(err(R"("control_crs": [])").find("control_crs: value is not a JSON object"), std::string::npos);
  // A control extent without sigmas is read, not dropped.
  const TransformFile with_extent = parse_transform_json(helmert7_with(extent), "T.json");
  ASSERT_TRUE(with_extent.fit);
  EXPECT_TRUE(with_extent.fit->extent);
  EXPECT_FALSE(with_extent.fit->sigma0.has_value());  // no statistics: σ0 unknown, not 0
}

// issue 12 point 10
TEST(TransformFile, Point10_WhatIsWrittenTwiceMustAgreeAndModelKeysAreNotIgnored) {
  // The convention stated again in alternatives and epsg_method.
  EXPECT_EQ(error_of(helmert7_with(R"("epsg_method": "EPSG:1033")")), "");
  EXPECT_NE(error_of(helmert7_with(R"("epsg_method": "EPSG:1032")"))
                .find("T.json: epsg_method: value \"EPSG:1032\" contradicts model helmert7 in convention position_vector (EPSG:1033)"),
            std::string::npos);
  const std::string alt = R"("alternatives": [{"convention": "coordinate_frame", "epsg_method": "EPSG:1032",
      "parameters": {"tx_m": 0, "ty_m": 0, "tz_m": 4.5, "rx_arcsec": 0, "ry_arcsec": 0, "rz_arcsec": -0.554, "ds_ppm": 0.219}}])";
  EXPECT_EQ(error_of(helmert7_with(alt)), "");
  EXPECT_NE(error_of(helmert7_with(replace(alt, "\"coordinate_frame\"", "\"position_vector\"")))
                .find("alternatives[0].convention: value \"position_vector\" is not the other convention"),
            std::string::npos);
  EXPECT_NE(error_of(helmert7_with(replace(alt, "-0.554", "0.554")))
                .find("alternatives[0].parameters.rz_arcsec: value 0.554 is not the coordinate_frame form (-0.554)"),
            std::string::npos);
  EXPECT_NE(error_of(helmert7_with(replace(alt, "\"epsg_method\"", "\"epsg\""))).find("alternatives[0].epsg: unknown key"),
            std::string::npos);
  EXPECT_NE(error_of(helmert7_with(R"("format_version": 2)")).find("format_version: value 2 not read"), std::string::npos);
  // Keys of other models.
  EXPECT_NE(error_of(helmert7_with(R"("grid": {"lat0_deg": 0, "lon0_deg": 0, "k0": 1})"))
                .find("T.json: grid: not read for model helmert7: only site-calibration has a grid"),
            std::string::npos);
  EXPECT_NE(error_of(helmert7_with(R"("nominal_origin": {"lat_deg": 0, "lon_deg": 0, "h_m": 0})"))
                .find("nominal_origin: not read for model helmert7"),
            std::string::npos);
  // A rotation in translation3 without a convention would default to one.
  EXPECT_NE(error_of(R"({"model": "translation3", "parameters": {"tx_m": 1, "ty_m": 2, "tz_m": 3, "rz_arcsec": 0.5}})")
                .find("T.json: convention: missing; parameters states a rotation"),
            std::string::npos);
  EXPECT_EQ(error_of(R"({"model": "translation3", "parameters": {"tx_m": 1, "ty_m": 2, "tz_m": 3}})"), "");
}

const char* kEnuOrigin = R"({"model": "enu-origin",
  "nominal_origin": {"lat_deg": 47.4647, "lon_deg": 8.5492, "h_m": 480.05, "height_type": "ellipsoidal", "ellipsoid": "WGS84"},
  "parameters": {"shift_e_m": -0.30, "shift_n_m": 0.20, "shift_u_m": -0.05, "yaw_arcsec": 20.0, "ds_ppm": 0}})";

const char* kSiteCalibration = R"({"model": "site-calibration",
  "nominal_origin": {"lat_deg": 46.6, "lon_deg": 7.4, "h_m": 600, "height_type": "ellipsoidal", "ellipsoid": "GRS80"},
  "grid": {"lat0_deg": 46.5, "lon0_deg": 7.5, "k0": 1, "false_easting_m": 0, "false_northing_m": 0, "ellipsoid": "GRS80"},
  "parameters": {"shift_e_m": 500, "shift_n_m": -300, "rotation_arcsec": 126000, "scale_ppm": 45, "vertical_shift_m": 48.2,
                 "slope_n_ppm": 0, "slope_e_ppm": 0, "centroid_e_m": 0, "centroid_n_m": 0}})";

// issue 12 point 10
TEST(TransformFile, Point10_OriginHeightTypeAndGridEllipsoidAreRead) {
  EXPECT_EQ(error_of(kEnuOrigin), "");
  EXPECT_NE(error_of(replace(kEnuOrigin, "\"height_type\": \"ellipsoidal\"", "\"height_type\": \"orthometric\""))
                .find("T.json: nominal_origin.height_type: value \"orthometric\" not read: an origin's h_m is an ellipsoidal "
                      "height"),
            std::string::npos);
  EXPECT_NE(error_of(replace(kEnuOrigin, "\"height_type\": \"ellipsoidal\"", "\"height_type\": 1"))
                .find("nominal_origin.height_type: value 1 is not a string"),
            std::string::npos);
  EXPECT_NE(error_of(replace(kEnuOrigin, "\"model\": \"enu-origin\",", "\"model\": \"enu-origin\", \"convention\": \"coordinate_frame\","))
                .find("T.json: convention: not read for model enu-origin"),
            std::string::npos);
  // The grid's ellipsoid: read, and held to the origin's (the grid is applied on it).
  const TransformFile sc = parse_transform_json(kSiteCalibration, "T.json");
  EXPECT_TRUE(sc.site_calibration->grid().ellipsoid == geodesy::Ellipsoid::grs80());
  EXPECT_NE(error_of(replace(kSiteCalibration, "\"k0\": 1, \"false_easting_m\": 0, \"false_northing_m\": 0, \"ellipsoid\": \"GRS80\"",
                             "\"k0\": 1, \"false_easting_m\": 0, \"false_northing_m\": 0, \"ellipsoid\": \"WGS84\""))
                .find("T.json: grid.ellipsoid: value \"WGS84\" differs from nominal_origin.ellipsoid GRS80"),
            std::string::npos);
  EXPECT_NE(error_of(replace(kSiteCalibration, "\"ellipsoid\": \"GRS80\"},\n  \"parameters\"", "\"ellipsoid\": \"Bessel\"},\n  \"parameters\""))
                .find("grid.ellipsoid: value \"Bessel\" unknown; expected WGS84 or GRS80"),
            std::string::npos);
  // The writer states it, and reads back.
  EXPECT_NE(to_json_text(sc).find("\"ellipsoid\": \"GRS80\""), std::string::npos);
  EXPECT_EQ(error_of(to_json_text(sc)), "");
  // The grid's origin repeated among the parameters must agree with the grid.
  EXPECT_EQ(error_of(replace(kSiteCalibration, "\"centroid_n_m\": 0}", "\"centroid_n_m\": 0, \"grid_lat0_deg\": 46.5}")), "");
  EXPECT_NE(error_of(replace(kSiteCalibration, "\"centroid_n_m\": 0}", "\"centroid_n_m\": 0, \"grid_lat0_deg\": 46.6}"))
                .find("parameters.grid_lat0_deg: value 46.6 differs from grid.lat0_deg 46.5"),
            std::string::npos);
}

}  // namespace
}  // namespace geoanchor::io

namespace geoanchor::io {
namespace {

// Issue 40 point 10: the file's rotation model, PROJ pipeline and EPSG
// method say the same; an edited rotation_model that contradicts the
// others is refused naming them, and the exact model, which no EPSG method
// describes, is written without one and reads back.
TEST(TransformFile, Issue40_AnEditedRotationModelThatContradictsThePipelineIsRefused) {
  const std::string written = to_json_text(parse_transform_json(kHelmert7, "T.json"));
  ASSERT_NE(written.find("\"epsg_method\": \"EPSG:1033\""), std::string::npos) << written;
  ASSERT_NE(written.find("\"proj_pipeline\""), std::string::npos) << written;
  const std::string edited = replace(written, "\"rotation_model\": \"small_angle\"", "\"rotation_model\": \"exact\"");
  ASSERT_NE(edited, written);
  const std::string e1 = error_of(edited);
  EXPECT_NE(e1.find("T.json: epsg_method: value \"EPSG:1033\": no EPSG method describes model helmert7 with rotation_model exact"),
            std::string::npos)
      << e1;
  // Without the method, the pipeline says it: PROJ's +exact is missing.
  std::string no_method = edited;
  const auto at = no_method.find("\"epsg_method\": \"EPSG:1033\",");
  ASSERT_NE(at, std::string::npos) << edited;
  no_method.erase(at, std::string("\"epsg_method\": \"EPSG:1033\",").size());
  const std::string e2 = error_of(no_method);
  EXPECT_NE(e2.find("T.json: proj_pipeline: contradicts the file's model, convention, rotation_model and parameters"),
            std::string::npos)
      << e2;
  EXPECT_NE(e2.find("+exact"), std::string::npos) << e2;
  // An edited parameter likewise.
  const std::string e3 = error_of(replace(written, "\"tz_m\": 4.5", "\"tz_m\": 4.6"));
  EXPECT_NE(e3.find("proj_pipeline: contradicts"), std::string::npos) << e3;
  // The exact model as written: no EPSG method, and it reads back.
  const std::string exact = to_json_text(parse_transform_json(
      replace(kHelmert7, "\"rotation_model\": \"small_angle\"", "\"rotation_model\": \"exact\""), "T.json"));
  EXPECT_EQ(exact.find("epsg_method"), std::string::npos) << exact;
  EXPECT_EQ(error_of(exact), "");
}

}  // namespace
}  // namespace geoanchor::io
