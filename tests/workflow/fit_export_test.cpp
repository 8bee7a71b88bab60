// workflow::transform_file_from_fit and streamed_transform_file_from_fit:
// the file `geoanchor fit -o` streams (its records formed as they are
// written) is the file the workbench's "Save transform…" and `fit --json`
// write from records held whole, byte for byte.

#include <gtest/gtest.h>

#include <algorithm>
#include <limits>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "accuracy.hpp"
#include "generated_control.hpp"
#include "geoanchor/geodesy/helmert.hpp"
#include "geoanchor/io/transform/transform_file.hpp"
#include "geoanchor/solver/helmert_fit.hpp"
#include "geoanchor/workflow/fit_export.hpp"

namespace geoanchor::workflow {
namespace {

// Bounds on how far east (west) of the marks' centroid the hull reaches
// without and with a mark placed 3° east (west) of the region: such a mark
// is about 228 km away at 47° N; the region's marks lie within 1.5° of
// 8° E, at most about 117 km (at its southern edge, 45.5° N).
constexpr double kRegionEast_m = 130e3;
constexpr double kBlunderEast_m = 180e3;

// `marks` marks within 1.5° of (47° N, 8° E) related by a small Helmert
// transform, 3 mm noise in the target (every statistic has digits), and
// the target of mark `blunder` 0.25 m off. When `outside` the blunder is a
// mark 3° east of the others (a vertex of their hull), and mark blunder + 1
// one 3° west; else both are the region's.
geodesy::ControlSet generated_set(std::size_t marks, std::size_t blunder, bool outside = false) {
  auto src = testing::region(marks, 47.0, 8.0, 1.5, 11);
  if (outside) src[blunder] = testing::region(1, 47.0, 11.0, 0.0, 3).front();
  if (outside) src[blunder + 1] = testing::region(1, 47.0, 5.0, 0.0, 3).front();
  geodesy::Helmert7<geodesy::PositionVector> truth;
  truth.t_m = Eigen::Vector3d(0.2, -0.1, 0.3);
  truth.rz = geodesy::Angle::milliarcseconds(15.0);
  truth.ds = geodesy::ScaleDifference::ppb(4.0);
  std::mt19937_64 rng(5);
  std::normal_distribution<double> noise(0.0, 0.003);
  geodesy::ControlSet set;
  set.source_name = "generated";
  for (std::size_t i = 0; i < marks; ++i) {
    geodesy::ControlPoint p;
    p.id = "M" + std::to_string(i);
    p.line = i + 2;
    p.source = src[i];
    p.target = geodesy::apply(truth, geodesy::RotationModel::small_angle, src[i]);
    p.target.m += Eigen::Vector3d(noise(rng), noise(rng), noise(rng));
    if (i == blunder) p.target.m.x() += 0.25;
    p.source_cov_m2 = p.target_cov_m2 = Eigen::Matrix3d::Identity() * (0.003 * 0.003 / 2.0);
    p.source_as_read = p.source.m;
    p.target_as_read = p.target.m;
    set.points.push_back(p);
  }
  return set;
}

// issue 12 point 13
TEST(FitExport, Issue12Point13_TheStreamedFileIsTheHeldFileByteForByte) {
  // More marks than two of the writer's blocks (2048 records), one blunder
  // that data snooping removes (a note), one mark left out by the user (the
  // other note).
  constexpr std::size_t kMarks = 9000;
  const geodesy::ControlSet set = generated_set(kMarks, 4500);
  solver::FitOptions o;
  o.model = solver::FitModel::helmert7;
  o.convention = solver::Convention::position_vector;
  o.remove_outliers = true;
  const solver::FitResult r = solver::fit_helmert(set, o);
  ASSERT_TRUE(r.points[4500].outlier) << "the blunder was meant to be removed";
  const std::vector<std::string> left_out{"M17"};
  const std::string generator = "geoanchor test";

  const std::string held = io::to_json_text(transform_file_from_fit(r, set, o, left_out, generator));
  const StreamedTransformFile streamed = streamed_transform_file_from_fit(r, set, o, left_out, generator);
  EXPECT_TRUE(streamed.file.fit && streamed.file.fit->points.empty());
  EXPECT_EQ(streamed.points.count, kMarks);
  std::ostringstream text;
  io::write_json(text, streamed.file, streamed.points);
  const std::string written = text.str();
  ASSERT_EQ(written.size(), held.size());
  EXPECT_TRUE(written == held) << "first difference at byte "
                               << std::mismatch(written.begin(), written.end(), held.begin()).first - written.begin();
  // And it says what it should: every mark a line, the two notes.
  EXPECT_GT(static_cast<std::size_t>(std::count(written.begin(), written.end(), '\n')), kMarks);
  EXPECT_NE(written.find("{\"id\": \"M17\", "), std::string::npos);
  EXPECT_NE(written.find(kLeftOutInWorkbench), std::string::npos);
  EXPECT_NE(written.find("{\"id\": \"M4500\", "), std::string::npos);
  EXPECT_NE(written.find("\"note\": \"data snooping"), std::string::npos);
  // A held fit record is refused by the streaming writer (its records would
  // be written twice or not at all).
  std::ostringstream refused;
  EXPECT_THROW(io::write_json(refused, transform_file_from_fit(r, set, o, left_out, generator), streamed.points),
               std::logic_error);
}

// issue 12 point 13: fit_for_export forms the extent during the solve from
// the marks to be used; its file is the one formed from the fit's own used
// marks, also where data snooping removed a mark of the hull. A mark 3° west
// that the set leaves out (use = false) is never in the hull.
TEST(FitExport, Issue12Point13_AFitForExportWritesTheFileOfItsFit) {
  constexpr std::size_t kMarks = 3000, kBlunder = 1234;
  geodesy::ControlSet set = generated_set(kMarks, kBlunder, true);
  set.points[kBlunder + 1].use = false;
  const std::string generator = "geoanchor test";
  const auto text_of = [&](const StreamedTransformFile& f) {
    std::ostringstream out;
    io::write_json(out, f.file, f.points);
    return out.str();
  };
  for (const bool snooping : {false, true}) {
    SCOPED_TRACE(snooping ? "data snooping" : "no data snooping");
    solver::FitOptions o;
    o.model = solver::FitModel::helmert7;
    o.convention = solver::Convention::position_vector;
    o.remove_outliers = snooping;
    const FitForExport fitted = fit_for_export(set, o);
    ASSERT_EQ(fitted.fit.points[kBlunder].used, !snooping) << "the blunder was meant to be removed by snooping alone";
    ASSERT_TRUE(fitted.extent);
    const std::string planned = text_of(streamed_transform_file_from_fit(fitted, set, o, {}, generator));
    const std::string formed = text_of(streamed_transform_file_from_fit(fitted.fit, set, o, {}, generator));
    EXPECT_TRUE(planned == formed) << "first difference at byte "
                                   << std::mismatch(planned.begin(), planned.end(), formed.begin()).first - planned.begin();
    // The blunder 3° east is a vertex of the hull when used: the hull
    // reaches past 200 km east of the centroid then, and stays within the
    // region's 1.5° (115 km) when it is removed.
    double east_m = -std::numeric_limits<double>::infinity(), west_m = east_m;
    for (const auto& v : fitted.extent->hull_en_m) {
      east_m = testing::nan_max(east_m, v[0]);
      west_m = testing::nan_max(west_m, -v[0]);
    }
    EXPECT_LT(west_m, kRegionEast_m) << "the mark left out is in the hull";
    if (snooping) {
      EXPECT_LT(east_m, kRegionEast_m);
    } else {
      EXPECT_GT(east_m, kBlunderEast_m);
    }
  }
}

}  // namespace
}  // namespace geoanchor::workflow
