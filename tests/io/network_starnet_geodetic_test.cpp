// Issue 42 point 6: STAR*NET geodetic positions (P, PH, E, EH), GPS
// vectors (G0–G3), .REFRACTION, .LONGITUDE, .GPS WEIGHT, .ELEVATION and
// free ('*') observations. Each is read with its meaning — the values below
// are worked by hand from the definitions (STAR*NET V6 manual chapter 5:
// P lines, .LONGITUDE's sign convention, .REFRACTION; the vector lines as
// Carlson SurvNet's description of STAR*NET vector files states them: G2
// the variances or standard errors of ΔX ΔY ΔZ, G3 the covariances or
// correlations XY XZ YZ) — and refused by name otherwise.

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <string>
#include <vector>

#include "geoanchor/base/error.hpp"
#include "geoanchor/io/network/network_input.hpp"
#include "geoanchor/io/network/station_geoid.hpp"

namespace geoanchor::io {
namespace {

using geodesy::MeasurementKind;
using geodesy::Network;

constexpr double kDeg = std::numbers::pi / 180.0;
// ECEF from the closed-form formula below and from the reader's converter:
// the same expression up to rounding of 6.4e6 m values.
constexpr double kEcef_m = 1e-8;
// Values parsed from decimal text: a few ulp.
constexpr double kExact = 1e-15;

// GRS80 (ITRF2014's ellipsoid): a and f as defined (Moritz 1980).
constexpr double kA = 6378137.0;
constexpr double kF = 1.0 / 298.257222101;

// The textbook geodetic → ECEF: N = a / sqrt(1 − e² sin²φ);
// X = (N + h) cosφ cosλ, Y = (N + h) cosφ sinλ, Z = (N(1 − e²) + h) sinφ.
Eigen::Vector3d ecef(double lat_deg, double lon_deg, double h) {
  const double e2 = kF * (2.0 - kF), p = lat_deg * kDeg, l = lon_deg * kDeg;
  const double n = kA / std::sqrt(1.0 - e2 * std::sin(p) * std::sin(p));
  return {(n + h) * std::cos(p) * std::cos(l), (n + h) * std::cos(p) * std::sin(l), (n * (1.0 - e2) + h) * std::sin(p)};
}

// The input before the STAR*NET file that gives the frame (and ellipsoid).
const std::string kFrameJson = R"({"schema": "geoanchor.network/1", "frame": "ITRF2014@2020.0", "stations": [
    {"id": "Q", "lat_deg": 45, "lon_deg": -120, "h_m": 100, "constraint": "CCC"}], "measurements": []})";
const std::string kHead = ".3D\n.UNITS Meters DMS\n.ORDER NE AtFromTo\n.DELTA OFF\n.LONGITUDE PositiveWest\n.GPS WEIGHT Covariance\n";

Network read(const std::string& dat, const NetworkReadOptions& options = {}) {
  Network net;
  read_network_text(kFrameJson, "f.json", net);
  read_network_text(dat, "n.dat", net, options);
  return net;
}

std::string refusal(const std::string& dat, bool with_frame = true) {
  try {
    Network net;
    if (with_frame) read_network_text(kFrameJson, "f.json", net);
    read_network_text(dat, "n.dat", net);
  } catch (const Error& e) {
    return e.code() + ": " + e.what();
  }
  ADD_FAILURE() << "read without refusal:\n" << dat;
  return "";
}

void expect_refused(const std::string& dat, const std::vector<std::string>& pieces, bool with_frame = true) {
  const std::string m = refusal(dat, with_frame);
  for (const auto& p : pieces) EXPECT_NE(m.find(p), std::string::npos) << "'" << p << "' in: " << m;
}

const geodesy::NetworkStation& station(const Network& net, const std::string& id) { return net.stations.at(*net.find(id)); }

TEST(NetworkStarnetGeodetic, PositionsAreOnTheFramesEllipsoidInTheLongitudeConventionGiven) {
  NetworkReadOptions options;
  StationGeoidTable geoid;
  geoid.by_station["E1"].n_m = -20.5;  // N at E1: its elevation 300 is h = 300 − 20.5
  options.station_geoid = &geoid;
  const Network net = read(kHead +
                               "PH P1 45-30-00 120-15-00 150.25 ! ! !\n"     // positive west: λ = −120.25°
                               ".LONGITUDE NegativeWest\n"
                               "PH P2 -33-52-30 151-12-36 20 0.01 0.02 *\n"  // negative west: λ = +151.21°
                               ".ELEVATION Ellipsoidal\nP P3 10-00-00 -5-00-00 7\n.ELEVATION Orthometric\n"
                               ".2D\nP E1 46-00-00 -119-00-00 * *\nE E1 300 0.05\n"
                               "P H1 46-10-00 -119-10-00\nEH H1 250\n",
                           options);
  EXPECT_EQ(net.space, geodesy::NetworkSpace::ellipsoidal);
  const auto expect_at = [&](const std::string& id, Eigen::Vector3d want) {
    const auto& s = station(net, id);
    for (int k = 0; k < 3; ++k) EXPECT_NEAR(s.position(k), want(k), kEcef_m) << id << " axis " << k;
  };
  expect_at("P1", ecef(45.5, -120.25, 150.25));
  expect_at("P2", ecef(-(33.0 + 52.5 / 60.0), 151.21, 20.0));
  expect_at("P3", ecef(10.0, -5.0, 7.0));  // .ELEVATION Ellipsoidal: P's elevation is h
  expect_at("E1", ecef(46.0, -119.0, 300.0 - 20.5));
  expect_at("H1", ecef(46.0 + 10.0 / 60.0, -(119.0 + 10.0 / 60.0), 250.0));
  // Fixity per latitude, longitude, height: '!' fixed, a number held, '*' free.
  EXPECT_EQ(station(net, "P1").constraint.text(), "CCC");
  EXPECT_EQ(station(net, "P2").constraint.text(), "CCF");
  EXPECT_EQ(station(net, "P2").constraint.sigma_m[1], 0.02);
  EXPECT_EQ(station(net, "E1").constraint.text(), "FFC");
  EXPECT_EQ(station(net, "E1").constraint.sigma_m[2], 0.05);
}

TEST(NetworkStarnetGeodetic, PositionsAreRefusedWithoutFrameConventionOrGeoid) {
  expect_refused(kHead + "P A 45-00-00 120-00-00 100\n", {"n.dat:7", "names no datum", "no input before it names a frame"}, false);
  expect_refused(".3D\n.UNITS Meters DMS\nP A 45-00-00 120-00-00 100\n",
                 {"n.dat:3", "longitude 120-00-00 before any .LONGITUDE PositiveWest|NegativeWest"});
  expect_refused(".3D\n.UNITS Meters GONS\n.LONG PositiveWest\nP A 50.0 133.3 100\n", {"n.dat:4", "latitude 50.0", "not gons"});
  expect_refused(kHead + "P A 95-00-00 120-00-00 100\n", {"E_ANGLE", "n.dat:7: latitude=95-00-00", "[-90-00-00, 90-00-00]"});
  expect_refused(kHead + "P A 45.5 120-00-00 100\n", {"latitude '45.5'", "DDD-MM-SS.s"});
  expect_refused(kHead + ".2D\nPH A 45-00-00 120-00-00\n", {"n.dat:8", "PH A in 2D data"});
  expect_refused(kHead + "P A 45-00-00 120-00-00\n", {"n.dat:7", "2 values; expected latitude, longitude, elevation"});
  expect_refused(kHead + "P A 45-00-00 120-00-00 100\n", {"n.dat:7", "elevation 100 m is orthometric", "--geoid"});
  expect_refused(kHead + ".2D\nP A 45-00-00 120-00-00\n", {"P A has no elevation"});
  expect_refused(kHead + "EH A 100\n", {"A: an elevation for a station without a P or PH line"});
  expect_refused(kHead + "PH A 45-00-00 120-00-00 1\nPH A 45-00-00 120-00-00 1\n", {"n.dat:8", "PH A is given again"});
  expect_refused(kHead + "PH A 45-00-00 120-00-00 1\nC B 1 2 3\n", {"n.dat:8", "C (grid coordinates) with the geodetic positions"});
  expect_refused(kHead + "C B 1 2 3\nPH A 45-00-00 120-00-00 1\n", {"n.dat:8", "with the C (grid) coordinates of n.dat:7"});
  expect_refused(kHead + "CH B 1 2 3\n", {"n.dat:7", "CH (grid coordinates with an ellipsoid height)"});
  expect_refused(kHead + ".ELEV Ellipsoidal\nC B 1 2 3\n", {"n.dat:8", "under .ELEVATION Ellipsoidal"});
  expect_refused(kHead + "PH A 45-00-00 120-00-00 1 ! !\n", {"n.dat:7", "PH A: 5 values"});
  expect_refused(kHead + "PH A 45-00-00 120-00-00 1 ! ! !\nPH B 45-01-00 120-00-00 1\nB A-B 0-00-00 2\n",
                 {"n.dat:9", "a bearing (B, BM) with the geodetic positions"});
  expect_refused(".LONGITUDE East\n", {".LONGITUDE East", "expected one of PositiveWest, NegativeWest"});
  // A local network before it: not merged.
  Network local;
  read_network_text(".2D\n.UNITS Meters\n.ORDER NE\nC A 1 2 ! !\n", "l.dat", local);
  try {
    read_network_text(kHead + "PH B 45-00-00 120-00-00 1\n", "n.dat", local);
    ADD_FAILURE() << "merged";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("the inputs before it make a local network"), std::string::npos) << e.what();
  }
}

TEST(NetworkStarnetGeodetic, GpsVectorsCarryTheirCovarianceAsGpsWeightSays) {
  const Network net = read(kHead +
                           "PH A 45-00-00 120-00-00 100 ! ! !\nPH B 45-01-00 120-00-00 100\n"
                           "G0 'vector one\nG1 A-B 1852.1 -10.5 1309.25\nG2 1e-6 4e-6 9e-6\nG3 1e-7 -2e-7 3e-7\n"
                           ".GPS WEIGHT StdErrCorr\nG1 B-Q 3.5 4.5 5.5\nG2 0.001 0.002 0.003\nG3 0.5 -0.25 0.1\n");
  ASSERT_EQ(net.measurements.size(), 2u);
  const auto& v = net.measurements[0];
  EXPECT_EQ(v.kind, MeasurementKind::gnss_baselines);
  EXPECT_EQ(station(net, "A").id, net.stations[v.stations[0]].id);
  EXPECT_EQ(net.stations[v.stations[1]].id, "B");
  EXPECT_EQ(v.value(0), 1852.1);
  EXPECT_EQ(v.value(1), -10.5);
  EXPECT_EQ(v.value(2), 1309.25);
  EXPECT_FALSE(v.frame.has_value());  // the network's frame
  EXPECT_EQ(v.source, "n.dat:10");
  ASSERT_EQ(v.metadata.size(), 1u);
  EXPECT_EQ(v.metadata[0].second, "vector one");  // G0's text (its descriptor quote starts it)
  // Covariance: G2 the diagonal, G3 XY, XZ, YZ.
  const double want0[3][3] = {{1e-6, 1e-7, -2e-7}, {1e-7, 4e-6, 3e-7}, {-2e-7, 3e-7, 9e-6}};
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) EXPECT_EQ(v.covariance(i, j), want0[i][j]) << i << j;
  }
  // StdErrCorrelation: σ 1, 2, 3 mm; Σxy = 0.5·1·2 mm², Σxz = −0.25·1·3 mm², Σyz = 0.1·2·3 mm².
  const auto& w = net.measurements[1];
  const double want1[3][3] = {{1e-6, 1e-6, -7.5e-7}, {1e-6, 4e-6, 6e-7}, {-7.5e-7, 6e-7, 9e-6}};
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) EXPECT_NEAR(w.covariance(i, j), want1[i][j], kExact * 1e-5) << i << j;
  }
}

TEST(NetworkStarnetGeodetic, GpsVectorsAreRefusedByLineAndValue) {
  const std::string ab = kHead + "PH A 45-00-00 120-00-00 100 ! ! !\nPH B 45-01-00 120-00-00 100\n";  // lines 7, 8
  expect_refused(kHead + "G1 A-B 1 2 3\n", {"n.dat:7", "names no datum"}, false);
  expect_refused(ab + "G1 A-B 1 2 3\nD A-B 5 0.003\n", {"n.dat:10", "D after the G1 of n.dat:9 without its G2 and G3"});
  expect_refused(ab + "G1 A-B 1 2 3\n", {"n.dat:9", "G1 without its G2 and G3 lines (the file ends)"});
  expect_refused(ab + "G1 A-B 1 2 3\nG2 1 1 1\n", {"n.dat:9", "without its G3"});
  expect_refused(ab + "G2 1 1 1\n", {"n.dat:9", "G2 without its G1"});
  expect_refused(ab + "G1 A-B 1 2 3\nG3 0 0 0\n", {"n.dat:10", "G3 before the G2"});
  expect_refused(ab + "G1 A-B 1 2 3\nG2 1 1 1\nG2 1 1 1\n", {"n.dat:11", "G2 given twice"});
  expect_refused(ab + "G1 A-B 1 2\n", {"n.dat:9", "expected From-To ΔX ΔY ΔZ"});
  expect_refused(ab + ".UNITS FeetUS\nG1 A-B 1 2 3\n", {"n.dat:10", "GPS vectors are read in metres", "FeetUS"});
  expect_refused(ab + "G1 A-B 1 2 x\n", {"n.dat:9", "G1 ΔZ 'x' is not a number"});
  expect_refused(ab + "G1 A-B 1 2 3\nG2 1e-6 0 1e-6\nG3 0 0 0\n", {"n.dat:10", "G2 Y '0'", "variance > 0"});
  expect_refused(ab + "G1 A-B 1 2 3\nG2 1e-6 1e-6 1e-6\nG3 2e-6 0 0\n", {"n.dat:11", "not positive definite", "n.dat:10"});
  expect_refused(ab + ".GPS W StdErrCorr\nG1 A-B 1 2 3\nG2 0.001 0.001 0.001\nG3 1.5 0 0\n",
                 {"n.dat:12", "G3 XY '1.5'", "correlation in [-1, 1]"});
  expect_refused(ab + "G1 A-B 1 2 3\nG2 1e-6 1e-6\nG3 0 0 0\n", {"n.dat:10", "expected the three variances"});
  expect_refused(".3D\n.UNITS Meters DMS\n.LONG PositiveWest\nPH A 45-00-00 120-00-00 1\nPH B 45-01-00 120-00-00 1\n"
                 "G1 A-B 1 2 3\nG2 1 1 1\nG3 0 0 0\n",
                 {"n.dat:7", "G2 before any .GPS WEIGHT Covariance|StdErrCorrelation"});
  expect_refused(ab + "G4 0.001 0.002\n", {"n.dat:9", "G4: not a GPS vector line geoanchor reads"});
  expect_refused(".GPS FACTOR 2\n", {".GPS FACTOR", "expected one of WEIGHT"});
  expect_refused(".GPS WEIGHT Diagonal\n", {".GPS WEIGHT Diagonal", "expected one of Covariance, StdErrCorrelation"});
}

TEST(NetworkStarnetGeodetic, RefractionIsTheNetworksOneCoefficient) {
  const Network net = read(kHead + "PH A 45-00-00 120-00-00 100 ! ! !\nPH B 45-01-00 120-00-00 100\n.REFR 0.07\n"
                                   "V A-B 89-59-00 3\n.REFRACTION 0.07\nV B-A 90-01-00 3\n");
  ASSERT_TRUE(net.refraction_k.has_value());
  EXPECT_EQ(*net.refraction_k, 0.07);
  EXPECT_EQ(net.refraction_source, "n.dat:9");
  const std::string ab = kHead + "PH A 45-00-00 120-00-00 100 ! ! !\nPH B 45-01-00 120-00-00 100\n";
  expect_refused(ab + ".REFRACTION 0.07\n.REFRACTION 0.13\n", {"n.dat:10", ".REFRACTION 0.13 differs from the 0.07 of n.dat:9"});
  expect_refused(ab + "V A-B 89-59-00 3\n.REFRACTION 0.07\n", {"n.dat:10", "after the zenith angle of n.dat:9"});
  expect_refused(ab + ".REFRACTION 2\n", {"n.dat:9", ".REFRACTION '2'", "[-1, 1]"});
  // A second file's zenith angles before its own .REFRACTION were read
  // with the project's coefficient too.
  Network two;
  read_network_text(kFrameJson, "f.json", two);
  read_network_text(ab + ".REFRACTION 0.07\n", "one.dat", two);
  try {
    read_network_text(".3D\n.UNITS Meters DMS\n.DELTA OFF\nV A-B 89-59-00 3\n", "two.dat", two);
    ADD_FAILURE() << "read";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("two.dat:4: a zenith angle before any .REFRACTION"), std::string::npos) << e.what();
  }
  // A local network is a plane: a non-zero coefficient is refused, 0 read.
  Network local;
  read_network_text(".3D\n.UNITS Meters DMS\n.ORDER NE\n.REFRACTION 0\nC A 1 2 3 ! ! !\n", "l.dat", local);
  EXPECT_EQ(local.refraction_k, 0.0);
  Network plane;
  try {
    read_network_text(".3D\n.UNITS Meters DMS\n.ORDER NE\n.REFRACTION 0.07\nC A 1 2 3 ! ! !\n", "p.dat", plane);
    ADD_FAILURE() << "read";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("p.dat:4: .REFRACTION 0.07 in a local network"), std::string::npos) << e.what();
  }
}

TEST(NetworkStarnetGeodetic, AFreeObservationIsReadAndIgnored) {
  Network net;
  read_network_text(".2D\n.UNITS Meters DMS\n.ORDER NE AtFromTo\nC A 0 0 ! !\nC B 10 0\nD A-B 10.002 *\nD A-B 10.001 0.003\n"
                    "M B-A-C 90-00-00 5 2 *\n",
                    "n.dat", net);
  ASSERT_EQ(net.measurements.size(), 4u);
  EXPECT_TRUE(net.measurements[0].ignore);
  EXPECT_EQ(net.measurements[0].value(0), 10.002);
  EXPECT_FALSE(net.measurements[1].ignore);
  EXPECT_FALSE(net.measurements[2].ignore);  // the angle, 2″
  EXPECT_TRUE(net.measurements[3].ignore);   // its distance is free
  EXPECT_EQ(net.measurements[3].kind, MeasurementKind::horizontal_distance);
  Network fixed;
  try {
    read_network_text(".2D\n.UNITS Meters DMS\nD A-B 10 !\n", "n.dat", fixed);
    ADD_FAILURE() << "read";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("n.dat:3: standard error '!' (a fixed observation)"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace geoanchor::io
