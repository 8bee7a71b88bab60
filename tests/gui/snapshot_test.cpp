// The off-screen shell renders the bundled example (with its planted
// blunder, P17 moved 0.12 m north in the target frame) and the tests look
// at pixels: where a point's ENU coordinates put it on the plan, what colour
// its arrow is, how many bars the histogram has, and that a frame is the
// same every time it is rendered.
//
// Independent of the code under test: the ENU coordinates of the marks come
// from GeographicLib's LocalCartesian; the residuals and w-tests come from
// the solver (tested against published examples in tests/solver); the
// mapping from ENU to pixels and the bins are the documented rules
// (workbench_ui.hpp), recomputed here.

#include <GeographicLib/Geocentric.hpp>
#include <GeographicLib/LocalCartesian.hpp>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "geoanchor/gui/offscreen.hpp"
#include "geoanchor/gui/palette.hpp"
#include "geoanchor/gui/workbench_ui.hpp"
#include "geoanchor/io/control_csv.hpp"

namespace geoanchor::gui {
namespace {

const std::string kControl = std::string(GEOANCHOR_FIXTURES_DIR) + "/airport_control.csv";
constexpr int kWidth_px = 1600, kHeight_px = 1000;
// The plan's mapping, recomputed here in double, and the one drawn (float
// vertex positions) agree far below a pixel.
constexpr double kMappingTol_px = 0.01;
// Lines are antialiased over about a pixel at their edges: the centre line
// of a 3 px arrow carries its colour exactly; allow for rounding in the blend.
constexpr int kColourTol = 3;  // per 8-bit channel

solver::FitOptions helmert7_pv() {
  solver::FitOptions o;
  o.model = solver::FitModel::helmert7;
  o.convention = solver::Convention::position_vector;
  return o;
}

bool near(Rgb a, Rgb b, int tol = kColourTol) {
  return std::abs(a.r - b.r) <= tol && std::abs(a.g - b.g) <= tol && std::abs(a.b - b.b) <= tol;
}

int count_near(const RgbImage& image, int cx, int cy, int radius, Rgb c) {
  int n = 0;
  for (int y = std::max(0, cy - radius); y <= std::min(image.height - 1, cy + radius); ++y) {
    for (int x = std::max(0, cx - radius); x <= std::min(image.width - 1, cx + radius); ++x) {
      n += near(image.at(x, y), c) ? 1 : 0;
    }
  }
  return n;
}

// ENU (E, N) of every mark's source position at the centroid of the source
// positions, by GeographicLib (WGS 84).
std::vector<Eigen::Vector2d> enu_by_geographiclib(const geodesy::ControlSet& set) {
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const auto& p : set.points) mean += p.source.m;
  mean /= static_cast<double>(set.points.size());
  double lat = 0, lon = 0, h = 0;
  GeographicLib::Geocentric::WGS84().Reverse(mean.x(), mean.y(), mean.z(), lat, lon, h);
  const GeographicLib::LocalCartesian lc(lat, lon, h, GeographicLib::Geocentric::WGS84());
  std::vector<Eigen::Vector2d> out;
  for (const auto& p : set.points) {
    double x = 0, y = 0, z = 0, e = 0, n = 0, u = 0;
    GeographicLib::Geocentric::WGS84().Reverse(p.source.m.x(), p.source.m.y(), p.source.m.z(), x, y, z);
    lc.Forward(x, y, z, e, n, u);
    out.emplace_back(e, n);
  }
  return out;
}

class Snapshot : public ::testing::Test {
 protected:
  Snapshot()
      : set_(io::read_control_set(kControl, io::ControlReadOptions{})),
        model_(set_, helmert7_pv()),
        ui_(model_, {}),
        renderer_(kWidth_px, kHeight_px) {}

  std::size_t index_of(const std::string& id) const {
    for (std::size_t i = 0; i < set_.points.size(); ++i) {
      if (set_.points[i].id == id) return i;
    }
    throw std::runtime_error("no point " + id);
  }

  geodesy::ControlSet set_;
  WorkbenchModel model_;
  WorkbenchUi ui_;
  OffscreenRenderer renderer_;
};

// The documented mapping: bounding box of the marks, fitted into the
// plotting area with kPlanMarginPx on each side, north up, equal scale.
Eigen::Vector2d expected_pixel(const PlanGeometry& g, const std::vector<Eigen::Vector2d>& en, const Eigen::Vector2d& p) {
  Eigen::Vector2d lo = en.front(), hi = en.front();
  for (const auto& q : en) {
    lo = lo.cwiseMin(q);
    hi = hi.cwiseMax(q);
  }
  const Eigen::Vector2d span = (hi - lo).cwiseMax(1.0), c = 0.5 * (lo + hi);
  const double s = std::min((g.right - g.left - 2 * kPlanMarginPx) / span.x(), (g.bottom - g.top - 2 * kPlanMarginPx) / span.y());
  return Eigen::Vector2d(0.5 * (g.left + g.right) + s * (p.x() - c.x()), 0.5 * (g.top + g.bottom) - s * (p.y() - c.y()));
}

TEST_F(Snapshot, TheOutliersArrowIsDrawnInTheOutlierColourWhereItsEnuCoordinatesMapTo) {
  const RgbImage image = renderer_.render(ui_, View::plan);
  ASSERT_EQ(image.width, kWidth_px);
  ASSERT_EQ(image.height, kHeight_px);
  const PlanGeometry& g = ui_.plan();
  ASSERT_TRUE(g.drawn);
  const auto en = enu_by_geographiclib(set_);
  const std::size_t i17 = index_of("P17");
  const Eigen::Vector2d p17 = expected_pixel(g, en, en[i17]);
  EXPECT_NEAR((g.pixel_of(model_.rows()[i17].plan_en_m) - p17).norm(), 0.0, kMappingTol_px);

  const solver::FitResult fit = solver::fit_helmert(set_, helmert7_pv());
  ASSERT_TRUE(fit.points[i17].outlier);
  // The arrow leaves the mark along the residual (E right, N up on screen):
  // the planted blunder points north.
  const Eigen::Vector2d r = fit.points[i17].residual_enu_m.head<2>();
  const Eigen::Vector2d dir = Eigen::Vector2d(r.x(), -r.y()).normalized();
  EXPECT_LT(dir.y(), -0.9) << "P17's residual should point north (up)";
  for (double along_px : {16.0, 30.0, 45.0, 60.0}) {
    const Eigen::Vector2d q = p17 + along_px * dir;
    const Rgb got = image.at(static_cast<int>(std::lround(q.x())), static_cast<int>(std::lround(q.y())));
    EXPECT_TRUE(near(got, palette::kOutlier))
        << "at " << along_px << " px along P17's arrow: (" << int(got.r) << "," << int(got.g) << "," << int(got.b) << ")";
  }
  // Its square, in the outlier colour, around the mark.
  EXPECT_GT(count_near(image, static_cast<int>(std::lround(p17.x())), static_cast<int>(std::lround(p17.y())), 12, palette::kOutlier), 30);

  // A used mark is a disc filled with its vertical residual's colour, and no
  // outlier colour near it.
  const std::size_t i03 = index_of("P03");
  ASSERT_TRUE(fit.points[i03].used);
  const Eigen::Vector2d p03 = expected_pixel(g, en, en[i03]);
  const Rgb fill = palette::diverging(1e3 * fit.points[i03].residual_enu_m.z() / g.du_limit_mm);
  EXPECT_TRUE(near(image.at(static_cast<int>(std::lround(p03.x())), static_cast<int>(std::lround(p03.y()))), fill));
  EXPECT_EQ(count_near(image, static_cast<int>(std::lround(p03.x())), static_cast<int>(std::lround(p03.y())), 6, palette::kOutlier), 0);
}

TEST_F(Snapshot, AMarkLeftOutIsDrawnHollowInGreyAndTheFitChanges) {
  const std::size_t i03 = index_of("P03");
  model_.set_left_out("P03", true);
  const RgbImage image = renderer_.render(ui_, View::plan);
  const auto en = enu_by_geographiclib(set_);
  const Eigen::Vector2d p03 = expected_pixel(ui_.plan(), en, en[i03]);
  const int cx = static_cast<int>(std::lround(p03.x())), cy = static_cast<int>(std::lround(p03.y()));
  EXPECT_TRUE(near(image.at(cx, cy), palette::kBackground)) << "hollow";
  EXPECT_GT(count_near(image, cx, cy, 8, palette::kLeftOut), 8) << "grey ring";
}

TEST_F(Snapshot, TheHistogramHasOneBarPerNonEmptyBinOfTheUsedPointsWTests) {
  const RgbImage image = renderer_.render(ui_, View::histogram);
  const HistogramGeometry& h = ui_.histogram();
  ASSERT_TRUE(h.drawn);
  const solver::FitResult fit = solver::fit_helmert(set_, helmert7_pv());
  // The documented bins: 0.5 wide, symmetric, reaching past every used
  // w-test and half a bin past the critical value.
  double max_abs = 0;
  std::vector<double> w;
  for (const auto& p : fit.points) {
    if (!p.used) continue;
    for (int k = 0; k < 3; ++k) {
      w.push_back(p.w_enu(k));
      max_abs = std::max(max_abs, std::abs(p.w_enu(k)));
    }
  }
  const double reach = std::max(std::ceil(max_abs / 0.5), std::ceil(fit.w_critical / 0.5) + 1.0);
  std::vector<int> counts(static_cast<std::size_t>(2 * reach), 0);
  for (double v : w) ++counts[static_cast<std::size_t>(std::floor((v + reach * 0.5) / 0.5))];
  EXPECT_EQ(h.counts, counts);
  int expected_bars = 0, seen_bars = 0;
  for (std::size_t i = 0; i < counts.size(); ++i) {
    expected_bars += counts[i] > 0 ? 1 : 0;
    const double centre = h.w_low + 0.5 * (static_cast<double>(i) + 0.5);
    const int x = static_cast<int>(std::lround(h.x_of(centre)));
    // A bar stands on the axis: look just above it, below where the normal
    // curve runs in the tails.
    bool bar = false;
    for (int dy = 2; dy <= 3; ++dy) bar = bar || near(image.at(x, static_cast<int>(std::floor(h.bottom)) - dy), palette::kBar);
    seen_bars += bar ? 1 : 0;
    EXPECT_EQ(bar, counts[i] > 0) << "bin " << i << " (" << counts[i] << " values)";
  }
  EXPECT_EQ(seen_bars, expected_bars);
  EXPECT_GE(expected_bars, 8);  // the fixture's 35 used points spread over many bins
  // The critical values are marked where |w| = w_critical.
  const int xc = static_cast<int>(std::lround(h.x_of(fit.w_critical)));
  int critical = 0;
  for (int y = static_cast<int>(h.top); y < static_cast<int>(h.bottom); ++y) critical += near(image.at(xc, y), palette::kCritical, 40) ? 1 : 0;
  EXPECT_GT(critical, 20);
}

TEST_F(Snapshot, AFrameRenderedTwiceIsPixelIdenticalAndSoIsANewRenderer) {
  for (View v : kAllViews) {
    const RgbImage a = renderer_.render(ui_, v);
    const RgbImage b = renderer_.render(ui_, v);
    EXPECT_TRUE(a.rgb == b.rgb) << to_string(v);
  }
  const RgbImage first = renderer_.render(ui_, View::workbench);
  OffscreenRenderer other(kWidth_px, kHeight_px);
  WorkbenchUi ui(model_, {});
  EXPECT_TRUE(other.render(ui, View::workbench).rgb == first.rgb);
}

TEST_F(Snapshot, EveryViewDrawsSomethingAndARefusedFitShowsWhy) {
  for (View v : kAllViews) {
    const RgbImage image = renderer_.render(ui_, v);
    std::size_t ink = 0;
    for (int y = 0; y < image.height; y += 2) {
      for (int x = 0; x < image.width; x += 2) ink += near(image.at(x, y), palette::kInk, 40) ? 1u : 0u;
    }
    EXPECT_GT(ink, 200u) << to_string(v) << " has almost no text or lines";
  }
  geodesy::ControlSet two = set_;
  two.points.resize(2);
  WorkbenchModel refused(two, helmert7_pv());
  ASSERT_FALSE(refused.fit().has_value());
  WorkbenchUi ui(refused, {});
  const RgbImage image = renderer_.render(ui, View::plan);
  EXPECT_FALSE(ui.plan().drawn);
  std::size_t red = 0;
  for (int y = 0; y < 80; ++y) {
    for (int x = 0; x < image.width; ++x) red += near(image.at(x, y), palette::kOutlier, 40) ? 1u : 0u;
  }
  EXPECT_GT(red, 50u) << "the reason is written in the outlier colour";
}

TEST(SnapshotPalette, TheDivergingScaleRunsPurpleThroughWhiteToOrangeAndIsSymmetric) {
  // ColorBrewer PuOr, 5 classes (colorbrewer2.org): #5e3c99 … #f7f7f7 … #e66101.
  EXPECT_EQ(palette::diverging(-1.0), (Rgb{0x5e, 0x3c, 0x99}));
  EXPECT_EQ(palette::diverging(0.0), (Rgb{0xf7, 0xf7, 0xf7}));
  EXPECT_EQ(palette::diverging(1.0), (Rgb{0xe6, 0x61, 0x01}));
  EXPECT_EQ(palette::diverging(5.0), palette::diverging(1.0));
  EXPECT_EQ(palette::diverging(-0.5), (Rgb{0xb2, 0xab, 0xd2}));
}

}  // namespace
}  // namespace geoanchor::gui
