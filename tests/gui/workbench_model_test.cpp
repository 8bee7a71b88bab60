// The workbench model driven without a window: leaving a point out refits,
// and the table and the parameters are what the solver says for that set.

#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <numbers>

#include "geoanchor/base/error.hpp"
#include "geoanchor/workflow/fit_export.hpp"
#include "geoanchor/gui/workbench_model.hpp"
#include "geoanchor/io/control/control_csv.hpp"
#include "temp_folder.hpp"

namespace geoanchor::gui {
namespace {
using workflow::FitChoices;
using workflow::fit_choices_from_transform;

const std::string kControl = std::string(GEOANCHOR_FIXTURES_DIR) + "/airport_control.csv";

// The bundled example's fit: its planted blunder (P17) removed by data snooping.
solver::FitOptions helmert7_pv() {
  solver::FitOptions o;
  o.model = solver::FitModel::helmert7;
  o.convention = solver::Convention::position_vector;
  o.remove_outliers = true;
  return o;
}

const PointRow& row(const std::vector<PointRow>& rows, const std::string& id) {
  const auto it = std::find_if(rows.begin(), rows.end(), [&](const PointRow& r) { return r.id == id; });
  if (it == rows.end()) throw std::runtime_error("no row " + id);
  return *it;
}

TEST(WorkbenchModel, LeavingAPointOutRefitsAsTheSolverWouldAndPuttingItBackRestoresTheFit) {
  const geodesy::ControlSet set = io::read_control_set(kControl, io::ControlReadOptions{});
  WorkbenchModel model(set, helmert7_pv());
  ASSERT_TRUE(model.fit().has_value()) << model.error();
  const auto before = model.parameters();
  ASSERT_EQ(before.size(), 7u);
  // The fixture's planted blunder is found by data snooping and shown so.
  EXPECT_TRUE(row(model.rows(), "P17").outlier);
  EXPECT_FALSE(row(model.rows(), "P17").used);

  const unsigned generation = model.generation();
  model.set_left_out("P03", true);
  EXPECT_EQ(model.generation(), generation + 1);
  geodesy::ControlSet without = set;
  for (auto& p : without.points) p.use = p.id != "P03";
  const solver::FitResult expected = solver::fit_helmert(without, helmert7_pv());
  const auto after = model.parameters();
  ASSERT_EQ(after.size(), 7u);
  std::size_t k = 0;
  for (const auto& p : expected.parameters) {
    if (!p.estimated) continue;
    EXPECT_EQ(after[k].name, p.name);
    EXPECT_EQ(after[k].value, p.value) << p.name;
    EXPECT_EQ(after[k].sigma, p.sigma) << p.name;
    EXPECT_NE(after[k].value, before[k].value) << p.name << " did not change";
    ++k;
  }
  const auto rows = model.rows();
  const PointRow& p03 = row(rows, "P03");
  EXPECT_TRUE(p03.left_out);
  EXPECT_FALSE(p03.used);
  EXPECT_EQ(p03.note, "use = 0 in the control set");
  EXPECT_EQ(model.fit()->sigma0, expected.sigma0);

  model.set_left_out("P03", false);
  const auto restored = model.parameters();
  for (std::size_t i = 0; i < restored.size(); ++i) EXPECT_EQ(restored[i].value, before[i].value) << restored[i].name;
  model.set_left_out("NO-SUCH-ID", true);  // nothing to do, no refit
  EXPECT_EQ(model.generation(), generation + 2);
}

TEST(WorkbenchModel, ChangingModelOrConventionRefits) {
  WorkbenchModel model(io::read_control_set(kControl, io::ControlReadOptions{}), helmert7_pv());
  const auto pv = model.parameters();
  model.set_convention(solver::Convention::coordinate_frame);
  const auto cf = model.parameters();
  ASSERT_EQ(cf.size(), pv.size());
  // Switching the convention negates the rotations only (RELIABILITY.md, invariant 3).
  for (std::size_t i = 0; i < pv.size(); ++i) {
    const bool rotation = pv[i].name.rfind("r", 0) == 0;
    EXPECT_DOUBLE_EQ(cf[i].value, rotation ? -pv[i].value : pv[i].value) << pv[i].name;
  }
  model.set_model(solver::FitModel::translation3);
  std::vector<std::string> names;
  for (const auto& p : model.parameters()) names.push_back(p.name);
  EXPECT_EQ(names, (std::vector<std::string>{"tx_m", "ty_m", "tz_m"}));
}

TEST(WorkbenchModel, TheComparisonPanelFitsEveryModelOnThePointsInUse) {
  WorkbenchModel model(io::read_control_set(kControl, io::ControlReadOptions{}), helmert7_pv());
  model.set_left_out("P17", true);  // the planted blunder
  const auto rows = model.comparison();
  std::vector<std::string> names;
  for (const auto& c : rows) names.push_back(std::string(solver::to_string(c.model)));
  EXPECT_EQ(names, (std::vector<std::string>{"translation3", "helmert6", "helmert7", "molodensky-badekas"}));
  // Each row is the solver's fit of the same points without data snooping.
  solver::FitOptions o = helmert7_pv();
  o.data_snooping = false;
  geodesy::ControlSet set = model.control();
  const solver::FitResult direct = solver::fit_helmert(set, o);
  ASSERT_TRUE(rows[2].fit.has_value()) << rows[2].refused;
  EXPECT_EQ(rows[2].fit->sigma0, direct.sigma0);
  EXPECT_EQ(rows[2].parameters, 7);
  EXPECT_EQ(rows[0].parameters, 3);
  // With a-priori sigmas the AIC is Ω + 2u (Ω = σ0²·dof). (Without the
  // blunder, the fixture's millimetre-level rotations and scale do not pay
  // for their 4 parameters: translation3 has the lowest AIC.)
  for (const auto& c : rows) {
    ASSERT_TRUE(c.fit.has_value()) << c.refused;
    EXPECT_DOUBLE_EQ(c.aic, c.fit->global_test.statistic + 2.0 * c.parameters) << solver::to_string(c.model);
  }
}

TEST(WorkbenchModel, OnTheWorkerThreadTheLatestChoicesWinAndTheShownFitIsTheirs) {
  const geodesy::ControlSet set = io::read_control_set(kControl, io::ControlReadOptions{});
  WorkbenchModel model(set, helmert7_pv(), /*async_from_points=*/0);  // every refit on the worker
  model.wait();
  ASSERT_TRUE(model.fit().has_value()) << model.error();
  const auto before = model.parameters();
  // Two choices in a row: the second one queues behind the first and wins.
  model.set_left_out("P03", true);
  model.set_left_out("P04", true);
  EXPECT_TRUE(model.busy());
  EXPECT_EQ(model.parameters()[0].value, before[0].value);  // still the last shown fit
  model.wait();
  EXPECT_FALSE(model.busy());
  geodesy::ControlSet without = set;
  for (auto& p : without.points) p.use = p.id != "P03" && p.id != "P04";
  const solver::FitResult expected = solver::fit_helmert(without, helmert7_pv());
  EXPECT_EQ(model.fit()->sigma0, expected.sigma0);
  EXPECT_EQ(model.parameters()[0].value, expected.parameters[0].value);
  EXPECT_TRUE(row(model.rows(), "P04").left_out);
}

nlohmann::json read_json(const std::filesystem::path& p) {
  std::ifstream in(p);
  return nlohmann::json::parse(in);
}

// issue 12, tests that can fail, item 6: a folder of the test's own.
TEST(WorkbenchModel, SaveTransformWritesWhatGeoanchorFitWrites) {
  const testing::TempFolder folder;
  const auto& dir = folder.path();
  const auto by_fit = dir / "fit.json", by_gui = dir / "gui.json";
  const std::string cmd = std::string(GEOANCHOR_EXE) + " fit " + kControl + " --remove-outliers --model helmert7 --convention position_vector -o " +
                          by_fit.string() + " > /dev/null 2>&1";
  ASSERT_EQ(std::system(cmd.c_str()), 0);
  WorkbenchModel model(io::read_control_set(kControl, io::ControlReadOptions{}), helmert7_pv());
  model.save_transform(by_gui.string(), false, "geoanchor test");
  nlohmann::json a = read_json(by_fit), b = read_json(by_gui);
  // Everything but the command line that made it.
  a.erase("generator");
  b.erase("generator");
  EXPECT_EQ(a, b) << a.dump(1) << "\n---\n" << b.dump(1);
  // An existing file is refused unless overwrite is asked for.
  EXPECT_THROW(model.save_transform(by_gui.string(), false, "geoanchor test"), Error);
  EXPECT_NO_THROW(model.save_transform(by_gui.string(), true, "geoanchor test"));
}

// issue 12, tests that can fail, item 6: a folder of the test's own.
TEST(WorkbenchModel, ASavedTransformReopensWithItsModelConventionAndLeftOutPoints) {
  const geodesy::ControlSet set = io::read_control_set(kControl, io::ControlReadOptions{});
  solver::FitOptions o = helmert7_pv();
  o.convention = solver::Convention::coordinate_frame;
  o.model = solver::FitModel::molodensky_badekas;
  o.alpha_point = 0.01;
  WorkbenchModel model(set, o);
  model.set_left_out("P05", true);
  ASSERT_TRUE(model.fit().has_value()) << model.error();
  const testing::TempFolder folder;
  const auto path = folder / "reopen.json";
  model.save_transform(path.string(), true, "geoanchor test");
  const FitChoices c = fit_choices_from_transform(io::read_transform_file(path));
  EXPECT_EQ(c.options.model, solver::FitModel::molodensky_badekas);
  EXPECT_EQ(c.options.convention, solver::Convention::coordinate_frame);
  EXPECT_EQ(c.options.alpha_point, 0.01);
  EXPECT_EQ(c.left_out, (std::vector<std::string>{"P05"}));
  WorkbenchModel reopened(set, c.options, WorkbenchModel::kDefaultAsyncFrom, c.left_out);
  EXPECT_TRUE(row(reopened.rows(), "P05").left_out);
  ASSERT_EQ(reopened.parameters().size(), model.parameters().size());
  for (std::size_t i = 0; i < model.parameters().size(); ++i) {
    EXPECT_EQ(reopened.parameters()[i].value, model.parameters()[i].value) << model.parameters()[i].name;
  }
}

// issue 12 point 14
TEST(WorkbenchModelPoint14, TheComparisonIncludesMolodenskyBadekasWithHelmert7sResidualsAndSaysSo) {
  const geodesy::ControlSet set = io::read_control_set(kControl, io::ControlReadOptions{});
  solver::FitOptions o = helmert7_pv();
  o.model = solver::FitModel::molodensky_badekas;
  WorkbenchModel model(set, o);
  const auto& rows = model.comparison();
  const auto find = [&](solver::FitModel m) {
    const auto it = std::find_if(rows.begin(), rows.end(), [&](const auto& c) { return c.model == m; });
    if (it == rows.end()) throw std::runtime_error("no row for " + std::string(solver::to_string(m)));
    return *it;
  };
  const auto h7 = find(solver::FitModel::helmert7), mb = find(solver::FitModel::molodensky_badekas);
  ASSERT_TRUE(h7.fit && mb.fit);
  // One model in two parametrisations: the same residuals and statistics.
  constexpr double kSameFit_m = 1e-9;     // both are solved from the same centred normal equations
  constexpr double kSameSigma0 = 1e-9;    // relative
  ASSERT_TRUE(mb.fit->sigma0 && h7.fit->sigma0);
  EXPECT_NEAR(*mb.fit->sigma0, *h7.fit->sigma0, kSameSigma0 * *h7.fit->sigma0);
  EXPECT_EQ(mb.parameters, h7.parameters);
  EXPECT_NEAR(mb.aic, h7.aic, solver::kAicTie);
  for (std::size_t i = 0; i < set.points.size(); ++i) {
    EXPECT_NEAR((mb.fit->points[i].residual_enu_m - h7.fit->points[i].residual_enu_m).norm(), 0.0, kSameFit_m) << set.points[i].id;
  }
  // … but other parameters: the translation at the pivot.
  EXPECT_GT(std::abs(mb.fit->parameters[0].value - h7.fit->parameters[0].value), 0.01);
  EXPECT_NE(mb.note.find("same residuals"), std::string::npos) << mb.note;
  EXPECT_TRUE(h7.note.empty());
  // They tie for the lowest AIC or neither has it.
  const auto lowest = solver::lowest_aic(rows);
  const bool has_h7 = std::find(lowest.begin(), lowest.end(), solver::FitModel::helmert7) != lowest.end();
  const bool has_mb = std::find(lowest.begin(), lowest.end(), solver::FitModel::molodensky_badekas) != lowest.end();
  EXPECT_EQ(has_h7, has_mb);
}

// issue 12 point 14
TEST(WorkbenchModelPoint14, AReportOrViewNeverAdvisesTheModelItIsAbout) {
  const geodesy::ControlSet set = io::read_control_set(kControl, io::ControlReadOptions{});
  const std::string advice = "consider --model molodensky-badekas";
  // The bundled example under helmert7 gets the weak-geometry advice, and keeps it.
  const solver::FitResult h7 = solver::fit_helmert(set, helmert7_pv());
  const auto h7_shown = shown_warnings(h7);
  EXPECT_TRUE(std::any_of(h7_shown.begin(), h7_shown.end(), [&](const std::string& w) { return w.find(advice) != std::string::npos; }));
  // A molodensky-badekas fit never shows it, even if a warning carries it.
  solver::FitOptions o = helmert7_pv();
  o.model = solver::FitModel::molodensky_badekas;
  solver::FitResult mb = solver::fit_helmert(set, o);
  mb.warnings.push_back("weak geometry: … the transform is sound, its geocentric parameters are not individually meaningful; " + advice);
  for (const auto& w : shown_warnings(mb)) EXPECT_EQ(w.find(advice), std::string::npos) << w;
  EXPECT_EQ(shown_warnings(mb).back(),
            "weak geometry: … the transform is sound, its geocentric parameters are not individually meaningful");
  // Advice naming a longer model name is not taken for this one.
  solver::FitResult t3 = mb;
  t3.model = solver::FitModel::helmert6;
  t3.warnings = {"x; consider --model helmert6x"};
  EXPECT_EQ(shown_warnings(t3), t3.warnings);
}

// issue 12 point 14
TEST(WorkbenchModelPoint14, EachMarksEllipseCovarianceIsItsResidualsAsTheSolversTestsSeeIt) {
  // The fixture's sigmas are isotropic (3 mm source, 4 mm target per axis:
  // its header), C = (0.003² + 0.004²) m² · I. Then the solver's redundancy
  // number along local east is Q_v,EE / C_EE and its w-test v_E / sqrt(Q_v,EE)
  // (Baarda; σ0 = 1): two routes to Q_v that do not go through
  // residual_covariance_en_m2.
  constexpr double kC_m2 = 0.003 * 0.003 + 0.004 * 0.004;
  // The solver weights with C_target + J C_source Jᵀ, J ≈ I (helmert_fit.cpp):
  // a relative error of about |r| + |ds| ≈ 1e-6 here; the rest is rounding.
  constexpr double kRelTol = 1e-5;
  const geodesy::ControlSet set = io::read_control_set(kControl, io::ControlReadOptions{});
  WorkbenchModel model(set, helmert7_pv());
  ASSERT_TRUE(model.fit().has_value()) << model.error();
  const auto rows = model.rows();
  const auto& fit = *model.fit();
  std::size_t checked = 0;
  for (std::size_t i = 0; i < rows.size(); ++i) {
    const auto& p = fit.points[i];
    const Eigen::Matrix2d q = rows[i].residual_cov_en_m2;
    ASSERT_TRUE(q.allFinite()) << rows[i].id;
    for (int axis = 0; axis < 2; ++axis) {
      if (p.used) {
        EXPECT_NEAR(q(axis, axis), p.redundancy_enu(axis) * kC_m2, kRelTol * kC_m2) << rows[i].id << " axis " << axis;
      }
      if (std::abs(p.w_enu(axis)) > 0.5) {  // v / w is well conditioned
        const double sigma_v_m = std::abs(p.residual_enu_m(axis) / p.w_enu(axis));
        EXPECT_NEAR(std::sqrt(q(axis, axis)), sigma_v_m, kRelTol * sigma_v_m) << rows[i].id << " axis " << axis;
        ++checked;
      }
    }
  }
  EXPECT_GT(checked, 30u);
  // The outlier P17 is tested against the fit: its prediction covariance C + AΣAᵀ exceeds C.
  const auto p17 = std::find_if(rows.begin(), rows.end(), [](const PointRow& r) { return r.id == "P17"; });
  ASSERT_TRUE(p17->outlier);
  EXPECT_GT(p17->residual_cov_en_m2(1, 1), kC_m2);
}

// issue 12 point 14
TEST(WorkbenchModelPoint14, AConfidenceEllipseHasTheCovariancesPrincipalAxesTimesK) {
  // Q with principal standard deviations 2 and 1 mm, the major axis at
  // azimuth 30° (east of north): Q = R diag(4, 1) Rᵀ mm², R's first column
  // the unit vector (sin 30°, cos 30°) in (E, N).
  const double az = 30.0 * std::numbers::pi / 180.0;
  Eigen::Matrix2d r;
  r << std::sin(az), std::cos(az), std::cos(az), -std::sin(az);
  const Eigen::Matrix2d q = 1e-6 * (r * Eigen::Vector2d(4.0, 1.0).asDiagonal() * r.transpose());
  constexpr double kTol_m = 1e-15;
  constexpr double kTol_rad = 1e-12;
  const Ellipse e = confidence_ellipse(q, 2.0);
  EXPECT_NEAR(e.a_m, 2.0 * 0.002, kTol_m);
  EXPECT_NEAR(e.b_m, 2.0 * 0.001, kTol_m);
  EXPECT_NEAR(e.azimuth_rad, az, kTol_rad);
  // χ²(2) at 0.95 is 5.9915 (NIST/SEMATECH e-Handbook, table 1.3.6.7.4).
  EXPECT_NEAR(chi2_2d_factor(0.95), std::sqrt(5.991464547107979), 1e-12);
  // Not a covariance: NaN, never a plausible ellipse.
  EXPECT_TRUE(std::isnan(confidence_ellipse(Eigen::Matrix2d::Constant(std::nan("")), 2.0).a_m));
  Eigen::Matrix2d negative = Eigen::Matrix2d::Identity();
  negative(1, 1) = -1.0;
  EXPECT_TRUE(std::isnan(confidence_ellipse(negative, 2.0).a_m));
}

}  // namespace
}  // namespace geoanchor::gui
