// DynAdjust's DNA text (io/src/network/network_dna.cpp) against DynaML: the
// published sample networks of DynAdjust (icsm-au/DynAdjust sampleData,
// fixtures/networks/README.md) in both forms read into the same network;
// each refusal names the line, the field and its columns; and DynAdjust's
// per-station geoid file (station_geoid.hpp).

#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "geoanchor/base/error.hpp"
#include "geoanchor/io/network/network_input.hpp"
#include "geoanchor/io/network/station_geoid.hpp"

namespace geoanchor::io {
namespace {

const std::string kDir = std::string(GEOANCHOR_FIXTURES_DIR) + "/networks/dynadjust/";

// The same measurements whatever the form: kinds, stations, values,
// covariances, heights, sets, ignore flags and scalars; only the sources
// differ. Stations by name and constraint, and their positions within
// `position_tol_m` (DynAdjust's two exports of a sample write coordinates
// to different digits, or in different frames).
void expect_same_network(const geodesy::Network& a, const geodesy::Network& b, double position_tol_m) {
  ASSERT_EQ(a.stations.size(), b.stations.size());
  for (std::size_t i = 0; i < a.stations.size(); ++i) {
    EXPECT_EQ(a.stations[i].id, b.stations[i].id) << i;
    EXPECT_LE((a.stations[i].position - b.stations[i].position).norm(), position_tol_m) << a.stations[i].id;
    EXPECT_EQ(a.stations[i].constraint.text(), b.stations[i].constraint.text()) << a.stations[i].id;
  }
  ASSERT_EQ(a.measurements.size(), b.measurements.size());
  for (std::size_t i = 0; i < a.measurements.size(); ++i) {
    const auto& x = a.measurements[i];
    const auto& y = b.measurements[i];
    EXPECT_EQ(x.kind, y.kind) << x.source << " / " << y.source;
    EXPECT_EQ(x.stations, y.stations) << x.source;
    EXPECT_EQ(x.value, y.value) << x.source;
    EXPECT_EQ(x.covariance, y.covariance) << x.source;
    EXPECT_EQ(x.instrument_height_m, y.instrument_height_m) << x.source;
    EXPECT_EQ(x.target_height_m, y.target_height_m) << x.source;
    EXPECT_EQ(x.set, y.set) << x.source;
    EXPECT_EQ(x.ignore, y.ignore) << x.source;
    EXPECT_EQ(x.local_variance_scale, y.local_variance_scale) << x.source;
    ASSERT_EQ(x.frame.has_value(), y.frame.has_value()) << x.source;
    if (x.frame) {
      EXPECT_EQ(x.frame->to_string(), y.frame->to_string()) << x.source;
    }
  }
  EXPECT_EQ(a.direction_sets.size(), b.direction_sets.size());
}

// gnss-networkstn.xml holds the coordinates of a DynAdjust adjustment as
// its a-priori values (its header comment says so), gnss-network.stn the
// survey's own: the free stations' starting points are up to 10.7 m apart
// (their adjusted coordinates do not depend on them): only the
// measurements are compared for the GNSS pair.
constexpr double kGnssAprioriApart_m = 11.0;
// urban-network.stn is in GDA94, urban-networkstn.xml in GDA2020 (the same
// marks 1.8 m apart): only the measurements are compared for the urban pair.
constexpr double kGda94ToGda2020_m = 2.0;

TEST(NetworkDna, GnssSampleReadsAsItsDynaMLTwin) {
  const auto dna = read_network({kDir + "gnss-network.stn", kDir + "gnss-network.msr"});
  const auto xml = read_network({kDir + "gnss-networkstn.xml", kDir + "gnss-networkmsr.xml"});
  expect_same_network(dna, xml, kGnssAprioriApart_m);
  EXPECT_EQ(dna.frame->to_string(), xml.frame->to_string());
  EXPECT_EQ(dna.measurements.size(), 131u);
}

TEST(NetworkDna, UrbanSampleReadsAsItsDynaMLTwin) {
  // Every terrestrial type of the sample (A, B, K, V, Z, S, L, H, M, G, Y of
  // LLH points) with the per-station geoid making its heights ellipsoidal.
  const StationGeoidTable geo = load_dna_geoid(kDir + "urban-network.geo");
  NetworkReadOptions o;
  o.station_geoid = &geo;
  const auto dna = read_network({kDir + "urban-network.stn", kDir + "urban-network.msr"}, o);
  const auto xml = read_network({kDir + "urban-networkstn.xml", kDir + "urban-networkmsr.xml"}, o);
  expect_same_network(dna, xml, kGda94ToGda2020_m);
  EXPECT_EQ(dna.frame->to_string(), "GDA94@1994.0");  // the DNA header's frame and epoch
  std::size_t msl = 0, astro = 0;
  for (const auto& m : dna.measurements) {
    msl += m.kind == geodesy::MeasurementKind::msl_arc;
    astro += m.kind == geodesy::MeasurementKind::astronomic_azimuth;
  }
  EXPECT_EQ(msl, 1u);    // urban-network.msr's one M record
  EXPECT_EQ(astro, 1u);  // and its one K record
  for (const auto& s : dna.stations) EXPECT_TRUE(s.geoid.has_value()) << s.id;  // the .geo file covers all 149
}

std::string header(const std::string& type) { return "!#=DNA 3.01 " + type + "    12.12.2018         GDA94    01.01.1994         1\n"; }

void expect_refused(const std::string& text, const std::string& needle) {
  geodesy::Network net;
  try {
    read_network_text(text, "t.msr", net);
    ADD_FAILURE() << "accepted: " << text;
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
    EXPECT_EQ(e.code(), "E_DNA") << e.what();
  }
}

TEST(NetworkDna, RefusesWhatItDoesNotRead) {
  const std::string s = "1                   CCC UTM         320236.2750        5813988.8399             31.4770 55 1\n";
  // A version of the header geoanchor has no column table for.
  expect_refused("!#=DNA 2.00 STN    12.12.2018         GDA94    01.01.1994         1\n" + s, "DNA version '2.00'");
  // A geoid file given as a network input.
  expect_refused(header("GEO") + "1   4.7 -7.1 -4.1\n", "give it with --geoid");
  // A value one column to the left of its field: text between fields.
  expect_refused(header("MSR") + "H 1042                                                   43.0859                         0.065000\n",
                 "'43.08' in columns 58-62 is in no field of a H record");
  // A station record whose name is not in columns 1-20.
  expect_refused(header("STN") + "                    CCC UTM         320236.2750        5813988.8399             31.4770 55 1\n",
                 "a station record without a station name (columns 1-20)");
  // A tab in a fixed-column record.
  expect_refused(header("MSR") + "H 1042\t43.0859\n", "tab character");
  // An unknown measurement type, and an ignore flag that is not '*'.
  expect_refused(header("MSR") + "W 1042                                                               43.0859               0.065000\n",
                 "measurement type 'W'");
  expect_refused(header("MSR") + "HX1042                                                               43.0859               0.065000\n",
                 "column 2");
  // A direction set whose count runs past the file.
  expect_refused(header("MSR") +
                     "D 212000820           269100210           3                                 247 55 04.2736   0.0009\n"
                     "D                                         409700110                         334 55 50.4714   0.0009\n",
                 "the file ends inside");
  // An angle whose minutes are not whole.
  expect_refused(header("MSR") + "B 1046                4010                                                   91 2x 31.0000   20.000\n",
                 "expected whole degrees");
}

TEST(NetworkDna, StationGeoidFileIsReadByColumn) {
  // DynAdjust's own sample: station 1 carries N 4.780 m, xi -7.168", eta -4.144".
  const StationGeoidTable t = load_dna_geoid(kDir + "urban-network.geo");
  ASSERT_TRUE(t.by_station.count("1"));
  const auto& g = t.by_station.at("1");
  constexpr double kArcsec = 3.14159265358979323846 / 648000.0;
  EXPECT_DOUBLE_EQ(g.n_m, 4.780);
  EXPECT_DOUBLE_EQ(g.deflection.xi_rad, -7.168 * kArcsec);
  EXPECT_DOUBLE_EQ(g.deflection.eta_rad, -4.144 * kArcsec);
  EXPECT_EQ(t.by_station.size(), 149u);
  EXPECT_THROW(read_dna_geoid("# DNA geoid file.\n1  4.7\n", "x.geo"), Error);  // no deflections
  try {
    read_dna_geoid("# DNA geoid file.\n1                                            4.780             -7.168    -4.144\n"
                   "1                                            4.780             -7.168    -4.144\n",
                   "x.geo");
    ADD_FAILURE();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("x.geo:3: station 1 is given again (first at x.geo:2)"), std::string::npos) << e.what();
  }
}


TEST(NetworkDna, HeightsAreTheTwoNumbersAfterTheStandardDeviation) {
  // As DynAdjust's own writer put them in its dsg.msr sample: a column to
  // the right of the columns its reader cuts (which would read 1.65 and 1).
  const std::string stn = header("STN") +
                          "A                   CCC LLh      -37.4752000000      144.5737000000             43.1640\n"
                          "B                   FFF LLh      -37.4753000000      144.5738000000             44.1640\n";
  const std::string msr = header("MSR") +
                          "S A                   B                                          200.0000                 0.0159   1.650  1.651\n";
  geodesy::Network net;
  read_network_text(stn, "t.stn", net);
  read_network_text(msr, "t.msr", net);
  ASSERT_EQ(net.measurements.size(), 1u);
  EXPECT_EQ(net.measurements[0].instrument_height_m, 1.650);
  EXPECT_EQ(net.measurements[0].target_height_m, 1.651);
  expect_refused(header("MSR") + "S A                   B                                          200.0000                 0.0159   1.650  1.651  2\n",
                 "expected the instrument and the target height");
}

}  // namespace
}  // namespace geoanchor::io
