// GNU Gama's <cov-mat> on terrestrial observations (issue 42, point 5): a
// cov-mat that correlates two observations of an <obs> or a
// <height-differences> makes the group one observation set
// (geodesy::MeasurementKind::observation_set) with the joint covariance; one
// whose band holds only zeros leaves them measurements of their own.
//
// The layout as GNU Gama's manual gives it (doc/gama-local-input.texi,
// "Covariance matrix"; its test tests/gama-local/input/scale-cov-gon.gkf):
// the upper band of the symmetric matrix, listed by rows (row i holds
// (i, i) … (i, i + band)), in the order of the group's observations, in
// the units of their standard deviations: mm for lengths, cc for angles in
// gon (″ for d-m-s angles), their products off the diagonal.

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <numbers>
#include <string>

#include "geoanchor/base/error.hpp"
#include "geoanchor/io/network/network_input.hpp"
#include "temp_folder.hpp"

namespace geoanchor::io {
namespace {

namespace fs = std::filesystem;
using geodesy::MeasurementKind;
using ::testing::HasSubstr;

constexpr double kMm = 1e-3;
constexpr double kCc = std::numbers::pi / 200.0 * 1e-4;
constexpr double kArcsec = std::numbers::pi / 648000.0;
// A cov-mat value times its units, against the same product by hand.
constexpr double kCovarianceRelative = 1e-15;

// Three points (lines 5–7), then `groups` from line 8.
std::string gama(const std::string& groups, const std::string& fix = "xy", const std::string& adj = "xy") {
  return "<?xml version=\"1.0\" ?>\n<gama-local xmlns=\"http://www.gnu.org/software/gama/gama-local\">\n"
         "<network axes-xy=\"ne\" angles=\"left-handed\">\n<points-observations>\n"
         "<point id=\"1\" x=\"0\" y=\"0\" z=\"10\" fix=\"" + fix + "\"/>\n"
         "<point id=\"2\" x=\"100\" y=\"0\" z=\"10\" fix=\"" + fix + "\"/>\n"
         "<point id=\"3\" x=\"0\" y=\"100\" z=\"11\" adj=\"" + adj + "\"/>\n" +
         groups + "</points-observations>\n</network>\n</gama-local>\n";
}

class NetworkGamaSets : public ::testing::Test {
 protected:
  geoanchor::testing::TempFolder dir;

  std::string write(const std::string& name, const std::string& text) {
    const fs::path p = dir.path() / name;
    std::ofstream(p, std::ios::binary) << text;
    return p.string();
  }
  static void expect_near(double got, double want) { EXPECT_NEAR(got, want, std::abs(want) * kCovarianceRelative); }
};

TEST_F(NetworkGamaSets, ACorrelatingCovMatMakesTheObsOneObservationSet) {
  const std::string file = write("set.gkf", gama("<obs from=\"1\">\n"                                     // line 8
                                                 "  <direction to=\"2\" val=\"0.0000\"/>\n"               // 9
                                                 "  <distance to=\"3\" val=\"100.004\"/>\n"               // 10
                                                 "  <direction to=\"3\" val=\"100.0012\"/>\n"             // 11
                                                 "  <cov-mat dim=\"3\" band=\"1\">\n"                     // 12
                                                 "    4.0  1.5\n"
                                                 "         9.0 -2.0\n"
                                                 "              5.0\n"
                                                 "  </cov-mat>\n"
                                                 "</obs>\n"));
  const geodesy::Network net = read_network({file});
  ASSERT_EQ(net.measurements.size(), 1u);
  const auto& m = net.measurements.front();
  EXPECT_EQ(m.kind, MeasurementKind::observation_set);
  EXPECT_EQ(m.source, file + ":8 <obs>");
  ASSERT_EQ(m.parts.size(), 3u);
  EXPECT_EQ(m.parts[0].kind, MeasurementKind::direction);
  EXPECT_EQ(m.parts[1].kind, MeasurementKind::horizontal_distance);
  EXPECT_EQ(m.parts[2].kind, MeasurementKind::direction);
  EXPECT_EQ(m.parts[0].source, file + ":9 <direction>");
  EXPECT_EQ(m.parts[2].source, file + ":11 <direction>");
  // One direction set: both directions in it, the distance in none.
  ASSERT_EQ(net.direction_sets.size(), 1u);
  EXPECT_EQ(m.parts[0].set, std::optional<std::size_t>(0));
  EXPECT_EQ(m.parts[2].set, std::optional<std::size_t>(0));
  EXPECT_FALSE(m.parts[1].set.has_value());
  // The set's stations and value are its parts' in order.
  const std::size_t s1 = *net.find("1"), s2 = *net.find("2"), s3 = *net.find("3");
  EXPECT_EQ(m.stations, (std::vector<std::size_t>{s1, s2, s1, s3, s1, s3}));
  ASSERT_EQ(m.value.size(), 3);
  EXPECT_EQ(m.value(1), 100.004);
  EXPECT_NEAR(m.value(2), 100.0012 * std::numbers::pi / 200.0, 1e-15);
  // cc², mm·cc, mm², mm·cc, cc²; outside the band zero.
  ASSERT_EQ(m.covariance.rows(), 3);
  expect_near(m.covariance(0, 0), 4.0 * kCc * kCc);
  expect_near(m.covariance(0, 1), 1.5 * kCc * kMm);
  expect_near(m.covariance(1, 0), 1.5 * kCc * kMm);
  expect_near(m.covariance(1, 1), 9.0 * kMm * kMm);
  expect_near(m.covariance(1, 2), -2.0 * kMm * kCc);
  expect_near(m.covariance(2, 2), 5.0 * kCc * kCc);
  EXPECT_EQ(m.covariance(0, 2), 0.0);
  EXPECT_EQ(m.covariance(2, 0), 0.0);
  // Each part's covariance is its variance in the set.
  expect_near(m.parts[1].covariance(0, 0), 9.0 * kMm * kMm);
}

TEST_F(NetworkGamaSets, DmsAnglesAndHeightDifferencesFormSetsInTheirUnits) {
  // d-m-s angles: the cov-mat in arc-seconds; height differences in mm.
  const std::string file =
      write("dms.gkf", gama("<obs from=\"1\">\n"
                            "  <angle bs=\"2\" fs=\"3\" val=\"90-00-01.5\"/>\n"
                            "  <angle bs=\"3\" fs=\"2\" val=\"269-59-58.5\"/>\n"
                            "  <cov-mat dim=\"2\" band=\"1\"> 18.0 -9.0 18.0 </cov-mat>\n"
                            "</obs>\n"
                            "<height-differences>\n"
                            "  <dh from=\"1\" to=\"3\" val=\"1.250\"/>\n"
                            "  <dh from=\"2\" to=\"3\" val=\"1.248\"/>\n"
                            "  <cov-mat dim=\"2\" band=\"1\"> 4.0 1.0 4.0 </cov-mat>\n"
                            "</height-differences>\n",
                            "xyz", "xyz"));
  const geodesy::Network net = read_network({file});
  ASSERT_EQ(net.measurements.size(), 2u);
  const auto& angles = net.measurements[0];
  ASSERT_EQ(angles.kind, MeasurementKind::observation_set);
  EXPECT_EQ(angles.parts[1].kind, MeasurementKind::horizontal_angle);
  expect_near(angles.covariance(0, 1), -9.0 * kArcsec * kArcsec);
  expect_near(angles.covariance(1, 1), 18.0 * kArcsec * kArcsec);
  const auto& dh = net.measurements[1];
  ASSERT_EQ(dh.kind, MeasurementKind::observation_set);
  EXPECT_EQ(dh.parts[0].kind, MeasurementKind::height_difference);
  expect_near(dh.covariance(0, 1), 1.0 * kMm * kMm);
  EXPECT_EQ(net.local_dimensions, 3);  // heights and the plane: the set's parts count
}

TEST_F(NetworkGamaSets, ABandOfZerosLeavesTheObservationsMeasurementsOfTheirOwn) {
  // As GNU Gama's stroner-levelling-b.gkf gives its variances.
  const std::string file = write("zeros.gkf", gama("<obs from=\"1\">\n"
                                                   "  <direction to=\"2\" val=\"0.0000\"/>\n"
                                                   "  <direction to=\"3\" val=\"100.0012\"/>\n"
                                                   "  <cov-mat dim=\"2\" band=\"1\"> 4.0 0 5.0 </cov-mat>\n"
                                                   "</obs>\n"));
  const geodesy::Network net = read_network({file});
  ASSERT_EQ(net.measurements.size(), 2u);
  for (const auto& m : net.measurements) EXPECT_EQ(m.kind, MeasurementKind::direction);
  expect_near(net.measurements[1].covariance(0, 0), 5.0 * kCc * kCc);
}

TEST_F(NetworkGamaSets, ACovMatOfTheWrongSizeIsRefusedAtItsLine) {
  struct Case {
    std::string name, cov, message;
  };
  const std::vector<Case> cases = {
      {"dim past the group", "<cov-mat dim=\"3\" band=\"1\"> 4 1 4 1 4 </cov-mat>",
       ":11: <cov-mat dim=\"3\"> in a group of 2 observed values; the dimension must match"},
      {"a value short", "<cov-mat dim=\"2\" band=\"1\"> 4 1 </cov-mat>",
       ":11: <cov-mat dim=\"2\" band=\"1\"> holds 2 values; expected 3 (the upper band by rows)"},
      {"a value over", "<cov-mat dim=\"2\" band=\"0\"> 4 1 4 </cov-mat>",
       ":11: <cov-mat dim=\"2\" band=\"0\"> holds 3 values; expected 2 (the upper band by rows)"},
      {"a band that is no count", "<cov-mat dim=\"2\" band=\"1.5\"> 4 1 4 </cov-mat>", ":11: <cov-mat dim=\"2\" band=\"1.5\">: expected whole numbers"},
      {"a value that is no number", "<cov-mat dim=\"2\" band=\"1\"> 4 1,0 4 </cov-mat>", "<cov-mat> value=\"1,0\" is not a number"},
  };
  for (const auto& c : cases) {
    SCOPED_TRACE(c.name);
    const std::string file = write("bad.gkf", gama("<obs from=\"1\">\n"
                                                   "  <direction to=\"2\" val=\"0.0000\"/>\n"
                                                   "  <direction to=\"3\" val=\"100.0012\"/>\n"
                                                   "  " + c.cov + "\n"
                                                   "</obs>\n"));
    try {
      read_network({file});
      ADD_FAILURE() << "read";
    } catch (const Error& e) {
      EXPECT_EQ(e.code(), "E_GAMA");
      EXPECT_THAT(e.what(), HasSubstr(c.message));
    }
  }
}

// A <dh> needs no stdev or dist where its group's cov-mat gives its
// variance (GNU Gama's stroner-levelling-b.gkf); without one it is refused
// at its line.
TEST_F(NetworkGamaSets, AHeightDifferenceWithoutStdevNeedsItsGroupsCovMat) {
  const std::string file = write("dh.gkf", gama("<height-differences>\n"
                                                "  <dh from=\"1\" to=\"3\" val=\"1.250\" stdev=\"2\"/>\n"
                                                "  <dh from=\"2\" to=\"3\" val=\"1.248\"/>\n"
                                                "</height-differences>\n",
                                                "xyz", "xyz"));
  try {
    read_network({file});
    ADD_FAILURE() << "read";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), "E_GAMA");
    EXPECT_THAT(e.what(), HasSubstr(file + ":10: <dh> has neither stdev (mm) nor dist (km) for its standard deviation, and its "
                                           "<height-differences> no <cov-mat>"));
  }
}

}  // namespace
}  // namespace geoanchor::io
