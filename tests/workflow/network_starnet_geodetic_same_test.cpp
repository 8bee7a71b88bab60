// Issue 42 point 6: an ellipsoidal network written by this test from one
// truth as STAR*NET (PH geodetic positions, G1–G3 GPS vectors, a slope
// distance and zenith angles under .REFRACTION, a free '*' observation)
// after a network JSON anchor that gives the frame, and as network JSON
// alone (the same values as decimal text; the coefficient as --refraction;
// the free observation as "ignore"), gives the same adjustment.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <numbers>
#include <optional>
#include <string>
#include <vector>

#include "dms_text.hpp"
#include "geoanchor/base/error.hpp"
#include "geoanchor/solver/network_adjustment.hpp"
#include "geoanchor/workflow/adjust.hpp"
#include "temp_folder.hpp"

namespace geoanchor::solver {
namespace {

// The two networks differ only in the free stations' starting latitudes
// and longitudes (DMS text against decimal degrees: an ulp or so); the
// adjustment converges from both to the same point: 1e-9 m leaves room for
// rounding only.
constexpr double kSameAdjustment_m = 1e-9;
constexpr double kDeg = std::numbers::pi / 180.0;
constexpr double kA = 6378137.0, kF = 1.0 / 298.257222101;  // GRS80, ITRF2014's ellipsoid

struct Geo {
  double lat_deg, lon_deg, h;
};
// Station positions on whole seconds, so that DMS text and decimal degrees
// say the same angle.
const std::map<std::string, Geo> kTruth = {{"A", {45.0, -120.0, 100.0}},
                                           {"B", {45.0 + 30.0 / 3600.0, -120.0, 103.0}},
                                           {"C", {45.0 + 15.0 / 3600.0, -120.0 + 40.0 / 3600.0, 98.0}},
                                           {"D", {45.0 - 20.0 / 3600.0, -120.0 + 20.0 / 3600.0, 110.0}}};

Eigen::Vector3d ecef(const Geo& g) {
  const double e2 = kF * (2.0 - kF), p = g.lat_deg * kDeg, l = g.lon_deg * kDeg;
  const double n = kA / std::sqrt(1.0 - e2 * std::sin(p) * std::sin(p));
  return {(n + g.h) * std::cos(p) * std::cos(l), (n + g.h) * std::cos(p) * std::sin(l), (n * (1.0 - e2) + g.h) * std::sin(p)};
}

std::string fixed(double v, int decimals) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*f", decimals, v);
  return buf;
}
// Whole-second DMS, sign first; STAR*NET's longitude under .LONGITUDE NegativeWest.
std::string dms(double deg) {
  const long s = std::lround(std::abs(deg) * 3600.0);
  char buf[64];
  std::snprintf(buf, sizeof buf, "%s%ld-%02ld-%02ld", deg < 0 ? "-" : "", s / 3600, (s / 60) % 60, s % 60);
  return buf;
}
std::string dms_fine(double deg) { return testing::dms_micro_text(deg); }  // DDD-MM-SS.ssssss for observed angles

struct Files {
  std::string anchor, dat, json;
};

Files write_all() {
  const std::string frame_doc = R"({"schema": "geoanchor.network/1", "frame": "ITRF2014@2020.0", "stations": [)";
  const Geo a = kTruth.at("A");
  const std::string anchor_station =
      R"({"id": "A", "lat_deg": 45, "lon_deg": -120, "h_m": 100, "constraint": "CCC"})";
  Files f;
  f.anchor = frame_doc + anchor_station + R"(], "measurements": []})" + "\n";
  f.dat = "# written from one truth by network_starnet_geodetic_same_test\n.3D\n.UNITS Meters DMS\n.ORDER NE AtFromTo\n"
          ".DELTA OFF\n.LONGITUDE NegativeWest\n.GPS WEIGHT Covariance\n.REFRACTION 0.07\n";
  std::string stations = anchor_station, json;
  for (const char* id : {"B", "C", "D"}) {
    const Geo g = kTruth.at(id);
    const std::string h = fixed(g.h + 0.3, 3);  // approximate heights of the free stations
    f.dat += std::string("PH ") + id + " " + dms(g.lat_deg) + " " + dms(g.lon_deg) + " " + h + "\n";
    char lat[64], lon[64];
    std::snprintf(lat, sizeof lat, "%.17g", g.lat_deg);
    std::snprintf(lon, sizeof lon, "%.17g", g.lon_deg);
    stations += std::string(R"(, {"id": ")") + id + R"(", "lat_deg": )" + lat + R"(, "lon_deg": )" + lon + R"(, "h_m": )" + h + "}";
  }
  // Vectors (to − from) offset by a few mm, with correlated covariances.
  const auto vector = [&](const std::string& from, const std::string& to, double ox, double oy, double oz) {
    const Eigen::Vector3d d = ecef(kTruth.at(to)) - ecef(kTruth.at(from)) + Eigen::Vector3d(ox, oy, oz);
    const std::string dx = fixed(d.x(), 4), dy = fixed(d.y(), 4), dz = fixed(d.z(), 4);
    f.dat += "G0 '" + from + " to " + to + "\nG1 " + from + "-" + to + " " + dx + " " + dy + " " + dz +
             "\nG2 4e-6 9e-6 1.6e-5\nG3 1e-6 -2e-6 3e-6\n";
    json += std::string(json.empty() ? "" : ",\n") + R"({"kind": "gnss_baseline", "from": ")" + from + R"(", "to": ")" + to +
            R"(", "dx_m": )" + dx + R"(, "dy_m": )" + dy + R"(, "dz_m": )" + dz +
            R"(, "cov_m2": [[4e-6, 1e-6, -2e-6], [1e-6, 9e-6, 3e-6], [-2e-6, 3e-6, 1.6e-5]]})";
  };
  vector("A", "B", 0.002, -0.001, 0.003);
  vector("B", "C", -0.003, 0.002, 0.001);
  vector("A", "D", 0.001, 0.002, -0.002);
  vector("C", "D", 0.002, 0.001, 0.002);
  // A slope distance and zenith angle A to C (HI 1.5, HT 1.6), a zenith
  // D to B, and a free (ignored) distance A to D.
  {
    const Eigen::Vector3d pa = ecef(a), pc = ecef(kTruth.at("C"));
    const double p = a.lat_deg * kDeg, l = a.lon_deg * kDeg;
    const Eigen::Vector3d up(std::cos(p) * std::cos(l), std::cos(p) * std::sin(l), std::sin(p));
    const Eigen::Vector3d d = pc + 1.6 * up - (pa + 1.5 * up);  // the normal at A stands in for C's: close enough for a start
    const std::string s = fixed(d.norm() + 0.002, 4), zen = dms_fine(std::acos(d.dot(up) / d.norm()) / kDeg + 2.0 / 3600.0);
    f.dat += "DV A-C " + s + " " + zen + " 0.003 3 1.5/1.6\n";
    json += R"(,
{"kind": "slope_distance", "from": "A", "to": "C", "value_m": )" + s + R"(, "sigma_m": 0.003, "instrument_height_m": 1.5, "target_height_m": 1.6},
{"kind": "zenith_angle", "from": "A", "to": "C", "value_dms": ")" + zen + R"(", "sigma_arcsec": 3, "instrument_height_m": 1.5, "target_height_m": 1.6})";
    const Eigen::Vector3d db = ecef(kTruth.at("B")) - ecef(kTruth.at("D"));
    const std::string zb = dms_fine(std::acos(db.dot(up) / db.norm()) / kDeg - 1.0 / 3600.0);
    f.dat += "V D-B " + zb + " 3\nD A-D 1000.000 *\n";
    json += R"(,
{"kind": "zenith_angle", "from": "D", "to": "B", "value_dms": ")" + zb + R"(", "sigma_arcsec": 3},
{"kind": "slope_distance", "from": "A", "to": "D", "value_m": 1000.000, "sigma_m": 1, "ignore": true})";
  }
  f.json = frame_doc + stations + R"(], "measurements": [)" + json + "]}\n";
  return f;
}

struct Adjusted {
  AdjustmentResult r;
  double refraction_k;
};
Adjusted adjust(const std::vector<std::string>& inputs, std::optional<double> refraction) {
  workflow::AdjustRequest request;
  request.inputs = inputs;
  request.options.refraction_k = refraction.value_or(0.0);
  request.refraction_given = refraction.has_value();
  const workflow::PreparedNetwork prepared = workflow::prepare_network(request);
  request.options.refraction_k = prepared.refraction_k;
  return {adjust_network(prepared.network, request.options), prepared.refraction_k};
}

TEST(NetworkStarnetSame, GeodeticStarnetAfterAJsonAnchorAndNetworkJsonAdjustTheSame) {
  testing::TempFolder dir;
  const Files f = write_all();
  std::ofstream(dir / "anchor.json") << f.anchor;
  std::ofstream(dir / "net.dat") << f.dat;
  std::ofstream(dir / "all.json") << f.json;
  const Adjusted s = adjust({(dir / "anchor.json").string(), (dir / "net.dat").string()}, std::nullopt);
  const Adjusted j = adjust({(dir / "all.json").string()}, 0.07);
  EXPECT_EQ(s.refraction_k, 0.07);  // the file's .REFRACTION
  ASSERT_EQ(s.r.stations.size(), 4u);
  ASSERT_EQ(j.r.stations.size(), 4u);
  EXPECT_EQ(s.r.dof, j.r.dof);
  EXPECT_EQ(s.r.dof, 12 + 3 - 9);  // 4 vectors and 3 terrestrial, 9 unknowns (the free distance is ignored)
  for (const auto& a : s.r.stations) {
    bool found = false;
    for (const auto& b : j.r.stations) {
      if (b.id != a.id) continue;
      found = true;
      for (int k = 0; k < 3; ++k) EXPECT_NEAR(a.position(k), b.position(k), kSameAdjustment_m) << a.id << " axis " << k;
      // Near the truth, within the offsets given to the observations.
      EXPECT_LT((a.position - ecef(kTruth.at(a.id))).norm(), 0.02) << a.id;
    }
    EXPECT_TRUE(found) << a.id;
  }
  EXPECT_NEAR(s.r.vtpv, j.r.vtpv, 1e-9 * std::max(1.0, j.r.vtpv));
}

TEST(NetworkStarnetSame, ARefractionOptionThatDiffersFromTheFilesIsRefused) {
  testing::TempFolder dir;
  const Files f = write_all();
  std::ofstream(dir / "anchor.json") << f.anchor;
  std::ofstream(dir / "net.dat") << f.dat;
  try {
    adjust({(dir / "anchor.json").string(), (dir / "net.dat").string()}, 0.13);
    ADD_FAILURE() << "adjusted";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::usage);
    EXPECT_NE(std::string(e.what()).find("--refraction 0.13 differs from the 0.07 of " + (dir / "net.dat").string() + ":8"),
              std::string::npos)
        << e.what();
  }
  // The same value is no conflict.
  EXPECT_EQ(adjust({(dir / "anchor.json").string(), (dir / "net.dat").string()}, 0.07).refraction_k, 0.07);
}

}  // namespace
}  // namespace geoanchor::solver
