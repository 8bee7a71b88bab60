// workflow::transform_file_from_fit and streamed_transform_file_from_fit:
// the file `geoanchor fit -o` streams (its records formed as they are
// written) is the file the workbench's "Save transform…" and `fit --json`
// write from records held whole, byte for byte.

#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "generated_control.hpp"
#include "geoanchor/geodesy/helmert.hpp"
#include "geoanchor/io/transform_file.hpp"
#include "geoanchor/solver/helmert_fit.hpp"
#include "geoanchor/workflow/fit_export.hpp"

namespace geoanchor::workflow {
namespace {

// issue 12 point 13
TEST(FitExport, Issue12Point13_TheStreamedFileIsTheHeldFileByteForByte) {
  // More marks than two of the writer's blocks (4096 records), one blunder
  // that data snooping removes (a note), one mark left out by the user (the
  // other note), and 3 mm noise, so that every statistic has digits.
  constexpr std::size_t kMarks = 9000;
  const auto src = testing::region(kMarks, 47.0, 8.0, 1.5, 11);
  geodesy::Helmert7<geodesy::PositionVector> truth;
  truth.t_m = Eigen::Vector3d(0.2, -0.1, 0.3);
  truth.rz = geodesy::Angle::milliarcseconds(15.0);
  truth.ds = geodesy::ScaleDifference::ppb(4.0);
  std::mt19937_64 rng(5);
  std::normal_distribution<double> noise(0.0, 0.003);
  geodesy::ControlSet set;
  set.source_name = "generated";
  for (std::size_t i = 0; i < kMarks; ++i) {
    geodesy::ControlPoint p;
    p.id = "M" + std::to_string(i);
    p.line = i + 2;
    p.source = src[i];
    p.target = geodesy::apply(truth, geodesy::RotationModel::small_angle, src[i]);
    p.target.m += Eigen::Vector3d(noise(rng), noise(rng), noise(rng));
    if (i == 4500) p.target.m.x() += 0.25;  // the blunder
    p.source_cov_m2 = p.target_cov_m2 = Eigen::Matrix3d::Identity() * (0.003 * 0.003 / 2.0);
    p.source_as_read = p.source.m;
    p.target_as_read = p.target.m;
    set.points.push_back(p);
  }
  solver::FitOptions o;
  o.model = solver::FitModel::helmert7;
  o.convention = solver::Convention::position_vector;
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

}  // namespace
}  // namespace geoanchor::workflow
