// DynaML read in parts on threads (io/src/network/network_dynaml.cpp,
// NetworkReadOptions::dynaml_part_bytes) against the same file read in one
// piece: the same stations in the same order, the same measurements,
// direction sets, sources (file:line) and warnings; and where a part cannot
// stand on its own (a cut inside a comment) or the file is wrong, the same
// result or the same error as one reading.

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "geoanchor/base/error.hpp"
#include "geoanchor/io/network/network_input.hpp"
#include "temp_folder.hpp"

namespace geoanchor::io {
namespace {

namespace fs = std::filesystem;

constexpr std::size_t kSmallParts = 64;  // bytes: cut wherever a top-level element starts

void expect_same(const geodesy::Network& a, const geodesy::Network& b) {
  ASSERT_EQ(a.stations.size(), b.stations.size());
  for (std::size_t i = 0; i < a.stations.size(); ++i) {
    EXPECT_EQ(a.stations[i].id, b.stations[i].id) << i;
    EXPECT_EQ(a.stations[i].position, b.stations[i].position) << a.stations[i].id;
    EXPECT_EQ(a.stations[i].source, b.stations[i].source) << a.stations[i].id;
    EXPECT_EQ(a.stations[i].constraint.text(), b.stations[i].constraint.text()) << a.stations[i].id;
  }
  ASSERT_EQ(a.measurements.size(), b.measurements.size());
  for (std::size_t i = 0; i < a.measurements.size(); ++i) {
    const auto& x = a.measurements[i];
    const auto& y = b.measurements[i];
    EXPECT_EQ(x.source, y.source) << i;
    EXPECT_EQ(x.kind, y.kind) << x.source;
    EXPECT_EQ(x.stations, y.stations) << x.source;
    EXPECT_EQ(x.value, y.value) << x.source;
    EXPECT_EQ(x.covariance, y.covariance) << x.source;
    EXPECT_EQ(x.set, y.set) << x.source;
    EXPECT_EQ(x.ignore, y.ignore) << x.source;
    EXPECT_EQ(x.frame.has_value(), y.frame.has_value()) << x.source;
  }
  ASSERT_EQ(a.direction_sets.size(), b.direction_sets.size());
  for (std::size_t i = 0; i < a.direction_sets.size(); ++i) {
    EXPECT_EQ(a.direction_sets[i].station, b.direction_sets[i].station);
    EXPECT_EQ(a.direction_sets[i].source, b.direction_sets[i].source);
  }
  EXPECT_EQ(a.warnings, b.warnings);
  EXPECT_EQ(a.frame.has_value(), b.frame.has_value());
}

NetworkReadOptions whole() {
  NetworkReadOptions o;
  o.dynaml_part_bytes = 0;
  return o;
}

NetworkReadOptions in_parts() {
  NetworkReadOptions o;
  o.dynaml_part_bytes = kSmallParts;
  return o;
}

// Stations in LLh, measurements of several kinds (baselines, a direction
// set, distances, heights), a station measured before it is defined, a
// comment holding what looks like a cut, and no epoch on the root (a
// warning the first part alone gives).
std::string measurements_file() {
  std::string m = "<?xml version=\"1.0\"?>\n<DnaXmlFormat type=\"Measurement File\" referenceframe=\"GDA2020\">\n";
  const auto baseline = [&](const std::string& a, const std::string& b, double x) {
    m += "  <DnaMeasurement>\n    <Type>G</Type>\n    <Ignore/>\n    <First>" + a + "</First>\n    <Second>" + b +
         "</Second>\n    <GPSBaseline>\n      <X>" + std::to_string(x) +
         "</X>\n      <Y>12.5</Y>\n      <Z>-3.25</Z>\n      <SigmaXX>1e-5</SigmaXX>\n      <SigmaXY>1e-7</SigmaXY>\n"
         "      <SigmaXZ>2e-7</SigmaXZ>\n      <SigmaYY>2e-5</SigmaYY>\n      <SigmaYZ>3e-7</SigmaYZ>\n      <SigmaZZ>3e-5</SigmaZZ>\n"
         "    </GPSBaseline>\n  </DnaMeasurement>\n";
  };
  baseline("A", "B", 100.0);
  baseline("B", "C", 50.0);
  m += "  <!-- a comment that holds a cut: <DnaMeasurement> and <DnaStation> -->\n";
  m += "  <DnaMeasurement>\n    <Type>D</Type>\n    <Ignore/>\n    <First>A</First>\n    <Second>B</Second>\n    <Total>2</Total>\n"
       "    <Value>0.000000</Value>\n    <StdDev>1.0</StdDev>\n"
       "    <Directions>\n      <Ignore/>\n      <Target>C</Target>\n      <Value>45.1230</Value>\n      <StdDev>1.0</StdDev>\n    </Directions>\n"
       "    <Directions>\n      <Ignore/>\n      <Target>D</Target>\n      <Value>90.0000</Value>\n      <StdDev>1.5</StdDev>\n    </Directions>\n"
       "  </DnaMeasurement>\n";
  m += "  <DnaMeasurement>\n    <Type>S</Type>\n    <Ignore/>\n    <First>C</First>\n    <Second>D</Second>\n    <Value>141.421</Value>\n"
       "    <StdDev>0.003</StdDev>\n    <InstHeight>1.5</InstHeight>\n    <TargHeight>1.6</TargHeight>\n  </DnaMeasurement>\n";
  baseline("C", "D", 75.0);
  m += "  <DnaMeasurement>\n    <Type>R</Type>\n    <Ignore/>\n    <First>D</First>\n    <Value>120.5</Value>\n    <StdDev>0.02</StdDev>\n"
       "  </DnaMeasurement>\n";
  baseline("D", "A", -225.0);
  m += "  <DnaMeasurement>\n    <Type>D</Type>\n    <Ignore/>\n    <First>C</First>\n    <Second>A</Second>\n    <Total>1</Total>\n"
       "    <Value>0.000000</Value>\n    <StdDev>1.0</StdDev>\n"
       "    <Directions>\n      <Ignore/>\n      <Target>B</Target>\n      <Value>30.0000</Value>\n      <StdDev>1.0</StdDev>\n    </Directions>\n"
       "  </DnaMeasurement>\n";
  m += "</DnaXmlFormat>\n";
  return m;
}

std::string stations_file() {
  std::string s = "<?xml version=\"1.0\"?>\n<DnaXmlFormat type=\"Station File\" referenceframe=\"GDA2020\" epoch=\"01.01.2020\">\n";
  const char* names[] = {"A", "B", "C", "D"};
  for (int k = 0; k < 4; ++k) {
    s += std::string("  <DnaStation>\n    <Name>") + names[k] + "</Name>\n    <Constraints>" + (k == 0 ? "CCC" : "FFF") +
         "</Constraints>\n    <Type>LLh</Type>\n    <StationCoord>\n      <Name>" + names[k] + "</Name>\n      <XAxis>-37.48" +
         std::to_string(k) + "1234</XAxis>\n      <YAxis>144.58" + std::to_string(k) + "0000</YAxis>\n      <Height>" +
         std::to_string(100 + k) + ".5</Height>\n    </StationCoord>\n  </DnaStation>\n";
  }
  s += "</DnaXmlFormat>\n";
  return s;
}

class DynamlParts : public ::testing::Test {
 protected:
  testing::TempFolder dir;
  std::string write(const std::string& name, const std::string& text) {
    const fs::path p = dir.path() / name;
    std::ofstream(p, std::ios::binary) << text;
    return p.string();
  }
};

TEST_F(DynamlParts, Issue17_AFileReadInPartsIsTheFileReadWhole) {
  // Measurements before the stations that define them, and after.
  const std::string msr = write("net.msr.xml", measurements_file()), stn = write("net.stn.xml", stations_file());
  for (const auto& inputs : {std::vector<std::string>{msr, stn}, std::vector<std::string>{stn, msr}}) {
    SCOPED_TRACE(inputs.front());
    const geodesy::Network a = read_network(inputs, whole());
    const geodesy::Network b = read_network(inputs, in_parts());
    ASSERT_EQ(a.measurements.size(), 11u);  // 4 baselines, direction sets of 3 and 2, a distance, a height
    ASSERT_EQ(a.direction_sets.size(), 2u);
    EXPECT_FALSE(a.warnings.empty());  // the root names no epoch: said once
    expect_same(a, b);
  }
  // DynAdjust's own sample, its comments and clusters included.
  const std::vector<std::string> sample = {std::string(GEOANCHOR_FIXTURES_DIR) + "/networks/dynadjust/gnss-networkstn.xml",
                                           std::string(GEOANCHOR_FIXTURES_DIR) + "/networks/dynadjust/gnss-networkmsr.xml"};
  expect_same(read_network(sample, whole()), read_network(sample, in_parts()));
}

// Issue 40 point 7 (found by fuzz/dynaml_fuzz.cpp): expat counts a CR
// alone as a line break (XML's end-of-line rule), as it counts LF and CR LF;
// the parts' line offsets counted LFs alone, so after lone CRs (legal
// white space inside a tag) every later part named other lines than one
// reading does.
TEST_F(DynamlParts, Issue40_LoneCarriageReturnsMoveLaterLinesAsInOneReading) {
  std::string msr = measurements_file(), stn = stations_file();
  msr.replace(msr.find("<First>A</First>"), 16, "<First\r\r\r>A</First\r>");
  stn.replace(stn.find("<Type>LLh</Type>"), 16, "<Type\r\r>LLh</Type>");
  // CR LF line ends (one break each), and a lone CR as the last byte before
  // each later <DnaStation> (where a part may start).
  for (auto at = stn.find("</DnaStation>\n  <DnaStation>"); at != std::string::npos;
       at = stn.find("</DnaStation>\n  <DnaStation>", at + 1)) {
    stn.replace(at, 28, "</DnaStation>\r\n  \r<DnaStation>");
  }
  const std::string a = write("cr.msr.xml", msr), b = write("cr.stn.xml", stn);
  for (const auto& inputs : {std::vector<std::string>{a, b}, std::vector<std::string>{b, a}}) {
    SCOPED_TRACE(inputs.front());
    const geodesy::Network whole_read = read_network(inputs, whole());
    expect_same(whole_read, read_network(inputs, in_parts()));
    // Station D's <DnaStation> is on line 3 + 3 × 11 of the stations file,
    // and 5 lines further on for the lone CRs before it (two in station A's
    // <Type>, one before each of B, C and D).
    const auto d = whole_read.find("D");
    ASSERT_TRUE(d.has_value());
    EXPECT_EQ(whole_read.stations[*d].source, b + ":41");
  }
}

TEST_F(DynamlParts, Issue17_AnErrorInALaterPartIsReportedAsByOneReading) {
  const std::string stn = write("net.stn.xml", stations_file());
  std::string text = measurements_file();
  const std::vector<std::pair<std::string, std::string>> faults = {
      {"<Value>120.5</Value>", "<Value>12O.5</Value>"},         // not a number, in the last part
      {"<Target>D</Target>", "<Target></Target>"},              // a missing target, mid-file
      {"  <!-- a comment", "  <Extra/>\n  <!-- a comment"},    // an element DynaML has not there
      {"</Directions>\n  </DnaMeasurement>\n</DnaXmlFormat>", "</Directions>\n</DnaXmlFormat>"},  // not well-formed at the end
  };
  for (const auto& [from, to] : faults) {
    SCOPED_TRACE(to);
    std::string bad = text;
    const auto at = bad.rfind(from);
    ASSERT_NE(at, std::string::npos);
    bad.replace(at, from.size(), to);
    const std::string msr = write("bad.msr.xml", bad);
    std::string one, parts;
    try {
      read_network({stn, msr}, whole());
    } catch (const Error& e) {
      one = e.code() + ": " + e.what();
    }
    try {
      read_network({stn, msr}, in_parts());
    } catch (const Error& e) {
      parts = e.code() + ": " + e.what();
    }
    EXPECT_FALSE(one.empty());
    EXPECT_EQ(parts, one);
  }
  // A station defined twice, differently, in two parts: the same message.
  std::string twice = stations_file();
  const std::string again = "  <DnaStation>\n    <Name>B</Name>\n    <Constraints>FFF</Constraints>\n    <Type>LLh</Type>\n"
                            "    <StationCoord>\n      <Name>B</Name>\n      <XAxis>-37.4811234</XAxis>\n      <YAxis>144.5810000</YAxis>\n"
                            "      <Height>150.5</Height>\n    </StationCoord>\n  </DnaStation>\n</DnaXmlFormat>";
  twice.replace(twice.rfind("</DnaXmlFormat>"), 15, again);
  const std::string stn2 = write("twice.stn.xml", twice);
  std::string one, parts;
  try {
    read_network({stn2}, whole());
  } catch (const Error& e) {
    one = e.code() + ": " + e.what();
  }
  try {
    read_network({stn2}, in_parts());
  } catch (const Error& e) {
    parts = e.code() + ": " + e.what();
  }
  EXPECT_NE(one.find("E_STATION_DUPLICATE"), std::string::npos) << one;
  EXPECT_EQ(parts, one);
}

}  // namespace
}  // namespace geoanchor::io
