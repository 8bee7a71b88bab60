// Issue 42 point 6: one network, written by this test from one truth in
// STAR*NET and in geoanchor's network JSON (the same observations, the same
// texts for every value), gives the same adjustment. The truth is four
// stations in a local plane system; the observations are computed from it
// (bearings clockwise from north, slope distances and zenith angles between
// the instrument and target points) and then offset by fractions of their
// standard errors so that the adjustment has residuals to spread.

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <numbers>
#include <string>

#include "dms_text.hpp"
#include "geoanchor/solver/network_adjustment.hpp"
#include "geoanchor/workflow/adjust.hpp"
#include "temp_folder.hpp"

namespace geoanchor::solver {
namespace {

// Both inputs carry the same decimal texts, so the two networks are the
// same doubles and adjust identically; 1e-9 m leaves room for nothing else
// than the order of summation.
constexpr double kSameAdjustment_m = 1e-9;
constexpr double kDeg = std::numbers::pi / 180.0;

struct Point {
  double n, e, z;
};
const std::map<std::string, Point> kTruth = {
    {"A", {1000.0, 1000.0, 100.0}}, {"B", {1000.0, 1300.0, 105.0}}, {"C", {1250.0, 1150.0, 110.0}}, {"D", {900.0, 1200.0, 98.0}}};

double bearing_deg(const std::string& from, const std::string& to) {
  const Point a = kTruth.at(from), b = kTruth.at(to);
  double v = std::atan2(b.e - a.e, b.n - a.n) / kDeg;
  return v < 0.0 ? v + 360.0 : v;
}
double horizontal(const std::string& from, const std::string& to) {
  const Point a = kTruth.at(from), b = kTruth.at(to);
  return std::hypot(b.n - a.n, b.e - a.e);
}

// Decimal degrees as DDD-MM-SS.ssssss, shared by both files.
std::string dms(double deg) { return testing::dms_micro_text(std::fmod(deg + 360.0, 360.0)); }
std::string fixed(double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.6f", v);
  return buf;
}

struct Files {
  std::string dat, json;
};

// The network in both formats; `json` collects the measurements.
Files write_both() {
  std::string dat = "# written from one truth by network_starnet_same_test\n.3D\n.UNITS Meters DMS\n.ORDER NE AtFromTo\n.DELTA OFF\n";
  std::string stations, json;
  auto comma = [](std::string& s) { s += s.empty() ? "" : ",\n"; };
  for (const auto& [id, p] : kTruth) {
    const bool fixed_station = id == "A" || id == "B";
    const double off = fixed_station ? 0.0 : 0.25;  // approximate coordinates of the free stations
    const std::string n = fixed(p.n + off), e = fixed(p.e - off), z = fixed(p.z + off);
    dat += "C " + id + " " + n + " " + e + " " + z + (fixed_station ? " ! ! !" : "") + "\n";
    comma(stations);
    stations += R"({"id": ")" + id + R"(", "x_m": )" + n + R"(, "y_m": )" + e + R"(, "z_m": )" + z +
                (fixed_station ? R"(, "constraint": "CCC")" : "") + "}";
  }
  // M at A from B to C, with HI 1.5 and HT 1.6: angle, slope distance, zenith.
  {
    const double hi = 1.5, ht = 1.6;
    const Point a = kTruth.at("A"), c = kTruth.at("C");
    const double h = horizontal("A", "C"), dz = c.z + ht - a.z - hi;
    const std::string ang = dms(bearing_deg("A", "C") - bearing_deg("A", "B") + 1.2 / 3600.0);
    const std::string s = fixed(std::hypot(h, dz) + 0.0015), zen = dms(std::atan2(h, dz) / kDeg - 1.5 / 3600.0);
    dat += "M A-B-C " + ang + " " + s + " " + zen + " 2 0.003 3 1.5/1.6\n";
    comma(json);
    json += R"({"kind": "horizontal_angle", "at": "A", "from": "B", "to": "C", "value_dms": ")" + ang + R"(", "sigma_arcsec": 2},
{"kind": "slope_distance", "from": "A", "to": "C", "value_m": )" + s + R"(, "sigma_m": 0.003, "instrument_height_m": 1.5, "target_height_m": 1.6},
{"kind": "zenith_angle", "from": "A", "to": "C", "value_dms": ")" + zen + R"(", "sigma_arcsec": 3, "instrument_height_m": 1.5, "target_height_m": 1.6})";
  }
  // V from D to C (zenith, no heights) and an azimuth A to D.
  {
    const Point c = kTruth.at("C"), d = kTruth.at("D");
    const std::string zen = dms(std::atan2(horizontal("D", "C"), c.z - d.z) / kDeg + 2.0 / 3600.0);
    dat += "V D-C " + zen + " 3\n";
    const std::string az = dms(bearing_deg("A", "D") - 1.0 / 3600.0);
    dat += "B A-D " + az + " 2\n";
    json += R"(,
{"kind": "zenith_angle", "from": "D", "to": "C", "value_dms": ")" + zen + R"(", "sigma_arcsec": 3},
{"kind": "azimuth", "from": "A", "to": "D", "value_dms": ")" + az + R"(", "sigma_arcsec": 2})";
  }
  // A direction set at C (orientation 10°), horizontal distances and
  // elevation differences under .DELTA ON, and a levelled line.
  {
    const double orientation = 10.0;
    const std::string da = dms(bearing_deg("C", "A") - orientation), dd = dms(bearing_deg("C", "D") - orientation + 1.5 / 3600.0),
                      db = dms(bearing_deg("C", "B") - orientation - 0.8 / 3600.0);
    const std::string hd = fixed(horizontal("C", "D") - 0.002), dz = fixed(kTruth.at("D").z - kTruth.at("C").z + 0.001);
    dat += ".DELTA ON\nDB C\nDN A " + da + " 2\nDM D " + dd + " " + hd + " " + dz + " 2 0.003 0.004\nDN B " + db + " 2\nDE\n";
    const std::string hb = fixed(horizontal("D", "B") + 0.001);
    dat += "D D-B " + hb + " 0.003\n";
    const std::string lv = fixed(kTruth.at("D").z - kTruth.at("A").z - 0.0008);
    dat += "L A-D " + lv + " 150 0.001\n";
    json += R"(,
{"kind": "direction_set", "at": "C", "directions": [{"to": "A", "value_dms": ")" + da + R"(", "sigma_arcsec": 2},
  {"to": "D", "value_dms": ")" + dd + R"(", "sigma_arcsec": 2}, {"to": "B", "value_dms": ")" + db + R"(", "sigma_arcsec": 2}]},
{"kind": "horizontal_distance", "from": "C", "to": "D", "value_m": )" + hd + R"(, "sigma_m": 0.003},
{"kind": "height_difference", "from": "C", "to": "D", "value_m": )" + dz + R"(, "sigma_m": 0.004},
{"kind": "horizontal_distance", "from": "D", "to": "B", "value_m": )" + hb + R"(, "sigma_m": 0.003},
{"kind": "height_difference", "from": "A", "to": "D", "value_m": )" + lv + R"(, "sigma_m": 0.001})";
  }
  const std::string doc = R"({"schema": "geoanchor.network/1", "space": "local",
"local": {"axes": "ne", "angles": "clockwise", "dimensions": 3},
"stations": [)" + stations + R"(],
"measurements": [)" + json + "]}\n";
  return {dat, doc};
}

AdjustmentResult adjust(const std::string& file) {
  workflow::AdjustRequest request;
  request.inputs.push_back(file);
  const workflow::PreparedNetwork prepared = workflow::prepare_network(request);
  return adjust_network(prepared.network, request.options);
}

TEST(NetworkStarnetSame, StarnetAndNetworkJsonOfOneTruthAdjustTheSame) {
  testing::TempFolder dir;
  const Files f = write_both();
  std::ofstream(dir / "net.dat") << f.dat;
  std::ofstream(dir / "net.json") << f.json;
  const AdjustmentResult s = adjust((dir / "net.dat").string());
  const AdjustmentResult j = adjust((dir / "net.json").string());
  ASSERT_EQ(s.stations.size(), 4u);
  ASSERT_EQ(j.stations.size(), 4u);
  EXPECT_EQ(s.dof, j.dof);
  EXPECT_GT(s.dof, 0);
  for (const auto& a : s.stations) {
    bool found = false;
    for (const auto& b : j.stations) {
      if (b.id != a.id) continue;
      found = true;
      for (int k = 0; k < 3; ++k) EXPECT_NEAR(a.position(k), b.position(k), kSameAdjustment_m) << a.id << " axis " << k;
      // The adjustment moved the free stations from their approximations
      // to the truth, within the offsets given to the observations.
      const Point t = kTruth.at(a.id);
      EXPECT_NEAR(a.position.x(), t.n, 0.01) << a.id;
      EXPECT_NEAR(a.position.y(), t.e, 0.01) << a.id;
      EXPECT_NEAR(a.position.z(), t.z, 0.01) << a.id;
    }
    EXPECT_TRUE(found) << a.id;
  }
}

}  // namespace
}  // namespace geoanchor::solver
