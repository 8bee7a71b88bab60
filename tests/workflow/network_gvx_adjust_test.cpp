// One network written by the test from one truth, once in NGS GVX 1.0 and
// once in geoanchor's network JSON (the same doubles: GVX's vectors in WGS 84
// (G1762) at their observation's middle, the points in NAD 83(2011) at
// 2010.0), adjusted as `geoanchor adjust` adjusts (prepare_network, then
// the adjustment): every adjusted coordinate the same to 1e-9 m, the same
// vᵀPv, the same solution types. The JSON side states the vectors' frame,
// epoch and solution type as docs/network-format.md says GVX means them
// (ISO 131 = WGS84(G1762); 2021-03-07T06:00 = 2021 + 65.25/365 by counting
// days; network RTK to a Fixed point = "fixed", post-processed = "ppk"), so
// a reader that took another meaning fails here.

#include <gtest/gtest.h>

#include <GeographicLib/Geocentric.hpp>

#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "geoanchor/solver/network_adjustment.hpp"
#include "geoanchor/workflow/adjust.hpp"
#include "gvx_text.hpp"
#include "temp_folder.hpp"

namespace geoanchor::workflow {
namespace {

using testing::GvxPoint;
using testing::GvxVector;
using testing::gvx_number;

// The two inputs hold the same doubles and take the same path; what may
// differ is the last bit of the epoch (counted two ways) and of the
// covariance products: far below this.
constexpr double kSameAdjustment_m = 1e-9;
constexpr double kSameVtpvRelative = 1e-9;

Eigen::Vector3d ecef(const GvxPoint& p) { return testing::gvx_ecef(p); }

struct Truth {
  std::vector<GvxPoint> points;
  std::vector<GvxVector> vectors;
  std::vector<double> epochs;             // decimal years, counted by hand
  std::vector<std::string> solutions;     // network JSON "solution"
};

Truth truth() {
  Truth t;
  t.points = {{"P1", "BASE1", 40.0, -105.25, 1650.0, "Keyed-in", "E1"},
              {"P2", "ROV1", 40.01, -105.24, 1660.1234, "Fixed", "E2"},
              {"P3", "ROV2", 39.995, -105.26, 1645.5, "Fixed", "E2"},
              {"P4", "ROV3", 40.02, -105.27, 1702.25, "Fixed", "E2"},
              {"P5", "ROV4", 40.005, -105.22, 1630.75, "Fixed", "E2"}};
  // A-priori coordinates off the truth by a few centimetres (the
  // adjustment moves the free stations), the vectors off it by millimetres.
  const Eigen::Vector3d noise[] = {{0.003, -0.002, 0.001}, {-0.001, 0.004, -0.002}, {0.002, 0.001, -0.003},
                                   {-0.004, 0.002, 0.002}, {0.001, -0.003, 0.004}, {0.002, 0.002, -0.001},
                                   {-0.002, 0.001, 0.003}, {0.003, 0.003, 0.001}};
  const std::vector<std::pair<int, int>> pairs = {{0, 1}, {0, 2}, {0, 3}, {0, 4}, {1, 2}, {1, 3}, {2, 4}, {3, 4}};
  for (std::size_t k = 0; k < pairs.size(); ++k) {
    const auto [a, b] = pairs[k];
    GvxVector v;
    v.id = "V" + std::to_string(k + 1);
    v.from = t.points[static_cast<std::size_t>(a)].id;
    v.to = t.points[static_cast<std::size_t>(b)].id;
    v.d_m = ecef(t.points[static_cast<std::size_t>(b)]) - ecef(t.points[static_cast<std::size_t>(a)]) + noise[k];
    v.sdx_m = 0.004 + 0.001 * static_cast<double>(k % 3);
    v.pxy = 0.3 - 0.1 * static_cast<double>(k % 4);
    v.setup = k < 5 ? "S1" : "S2";
    if (k >= 4) {
      v.start = "2021-03-08T00:00:00.00";  // a day later: 66.25 days into 2021 at its middle
      v.end = "2021-03-08T12:00:00.00";
    }
    t.vectors.push_back(v);
    t.epochs.push_back(2021.0 + (k >= 4 ? 66.25 : 65.25) / 365.0);
    t.solutions.push_back(k < 5 ? "fixed" : "ppk");
  }
  for (std::size_t i = 1; i < t.points.size(); ++i) t.points[i].h_m += 0.03;  // a-priori off the truth
  return t;
}

std::string json_of(const Truth& t) {
  std::string out = R"({"schema": "geoanchor.network/1", "frame": "NAD83(2011)@2010.0", "stations": [)";
  for (std::size_t i = 0; i < t.points.size(); ++i) {
    const auto& p = t.points[i];
    out += std::string(i ? ", " : "") + R"({"id": ")" + p.name + R"(", "lat_deg": )" + gvx_number(p.lat_deg) +
           R"(, "lon_deg": )" + gvx_number(p.lon_deg) + R"(, "h_m": )" + gvx_number(p.h_m) + "}";
  }
  out += R"(], "measurements": [)";
  const auto name_of = [&](const std::string& id) {
    for (const auto& p : t.points) {
      if (p.id == id) return p.name;
    }
    return std::string();
  };
  for (std::size_t k = 0; k < t.vectors.size(); ++k) {
    const auto& v = t.vectors[k];
    // Σ = D R D, D the standard deviations, R the correlations.
    const Eigen::Vector3d sd(v.sdx_m, v.sdy_m, v.sdz_m);
    Eigen::Matrix3d r;
    r << 1.0, v.pxy, v.pxz, v.pxy, 1.0, v.pyz, v.pxz, v.pyz, 1.0;
    const Eigen::Matrix3d cov = sd.asDiagonal() * r * sd.asDiagonal();
    std::string c = "[";
    for (int i = 0; i < 3; ++i) {
      c += std::string(i ? ", " : "") + "[" + gvx_number(cov(i, 0)) + ", " + gvx_number(cov(i, 1)) + ", " + gvx_number(cov(i, 2)) + "]";
    }
    out += std::string(k ? ", " : "") + R"({"kind": "gnss_baseline", "from": ")" + name_of(v.from) + R"(", "to": ")" +
           name_of(v.to) + R"(", "dx_m": )" + gvx_number(v.d_m.x()) + R"(, "dy_m": )" + gvx_number(v.d_m.y()) +
           R"(, "dz_m": )" + gvx_number(v.d_m.z()) + R"(, "cov_m2": )" + c + R"(], "frame": "WGS84(G1762)@)" +
           gvx_number(t.epochs[k]) + R"(", "solution": ")" + t.solutions[k] + R"("})";
  }
  return out + "]}";
}

solver::AdjustmentResult adjust(const std::string& file) {
  AdjustRequest request;
  request.inputs = {file};
  request.constrain = {"BASE1=CCC"};
  const PreparedNetwork prepared = prepare_network(request);
  return solver::adjust_network(prepared.network, request.options);
}

TEST(NetworkGvxAdjust, GvxAndNetworkJsonGiveTheSameAdjustment) {
  const testing::TempFolder dir("gvx_adjust");
  const Truth t = truth();
  const std::string gvx = (dir.path() / "net.gvx").string(), json = (dir.path() / "net.json").string();
  std::ofstream(gvx) << testing::gvx_document(t.points, t.vectors);
  std::ofstream(json) << json_of(t);
  const solver::AdjustmentResult a = adjust(gvx), b = adjust(json);
  ASSERT_TRUE(a.converged);
  ASSERT_TRUE(b.converged);
  ASSERT_EQ(a.stations.size(), b.stations.size());
  ASSERT_EQ(a.stations.size(), t.points.size());
  for (std::size_t i = 0; i < a.stations.size(); ++i) {
    EXPECT_EQ(a.stations[i].id, b.stations[i].id);
    const double d = (a.stations[i].position - b.stations[i].position).norm();
    EXPECT_LT(d, kSameAdjustment_m) << a.stations[i].id;  // NaN fails too
    EXPECT_TRUE(std::isfinite(d)) << a.stations[i].id;
  }
  EXPECT_GT(a.vtpv, 0.0);  // the vectors' noise leaves residuals: a test that can tell
  EXPECT_NEAR(a.vtpv, b.vtpv, kSameVtpvRelative * b.vtpv);
  // The free stations moved from their a-priori heights (3 cm off) to near the truth.
  EXPECT_GT((a.stations[1].position - a.stations[1].a_priori).norm(), 0.02);
}

}  // namespace
}  // namespace geoanchor::workflow
