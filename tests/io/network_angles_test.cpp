// Angles checked where they are read (issue 39, point 6): every network
// reader (geoanchor JSON, DynaML, GNU Gama) refuses an angle outside the
// range of its kind at the element that holds it — E_ANGLE, naming the
// file, the line or path, the value as written and the range in the unit
// it is written in — and reads sexagesimal seconds of exactly 60 as the
// carried minute, with a warning in the network's warnings; seconds above
// 60 and minutes of 60 stay refused. Ranges: directions, horizontal angles
// and azimuths [0, 360°]; zenith angles [0, 180°]; vertical angles
// [−90°, 90°] (io/src/network/network_builder.hpp, check_angle_range).

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <string>
#include <vector>

#include "geoanchor/base/error.hpp"
#include "geoanchor/io/network/network_input.hpp"
#include "temp_folder.hpp"

namespace geoanchor::io {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;

constexpr double kPi = std::numbers::pi;
// An angle read from text against the same angle computed by hand: the
// reading sums degrees, minutes/60 and seconds/3600 in float64 (a few
// 1e-16 rad of rounding on angles up to 2π); 1e-12 rad is 2e-7″.
constexpr double kAngleTol_rad = 1e-12;
constexpr std::size_t kSmallParts = 64;  // bytes: a DynaML file cut wherever a top-level element starts

// The line (1-based) where `needle` last starts in `text`.
std::size_t line_of_last(const std::string& text, const std::string& needle) {
  const auto at = text.rfind(needle);
  EXPECT_NE(at, std::string::npos) << needle;
  return 1 + static_cast<std::size_t>(std::count(text.begin(), text.begin() + static_cast<std::ptrdiff_t>(at), '\n'));
}

struct Refusal {
  std::string code, message;
};

class NetworkAngles : public ::testing::Test {
 protected:
  geoanchor::testing::TempFolder dir;

  std::string write(const std::string& name, const std::string& text) {
    const fs::path p = dir.path() / name;
    std::ofstream(p, std::ios::binary) << text;
    return p.string();
  }
  // The error reading `file` throws; an empty code when it reads.
  static Refusal refusal(const std::string& file, const NetworkReadOptions& options = {}) {
    try {
      read_network({file}, options);
    } catch (const Error& e) {
      return {e.code(), e.what()};
    }
    return {};
  }
};

// --- geoanchor network JSON -------------------------------------------------

// Three stations on GRS80; a distance first, so that the angle under test
// is measurements[1].
std::string json_network(const std::string& measurement) {
  return R"({"schema": "geoanchor.network/1", "ellipsoid": "GRS80",
  "stations": [{"id": "A", "lat_deg": 47.0, "lon_deg": 8.0, "h_m": 400.0, "constraint": "CCC"},
               {"id": "B", "lat_deg": 47.001, "lon_deg": 8.0, "h_m": 410.0},
               {"id": "C", "lat_deg": 47.0, "lon_deg": 8.001, "h_m": 420.0}],
  "measurements": [
    {"kind": "slope_distance", "from": "A", "to": "B", "value_m": 111.3, "sigma_m": 0.002},
    )" + measurement + R"(
  ]})";
}

std::string json_direction_set(const std::string& second_value) {
  return R"({"kind": "direction_set", "at": "A", "directions": [
      {"to": "B", "value_deg": 0.0, "sigma_arcsec": 1.0},
      {"to": "C", )" + second_value + R"(, "sigma_arcsec": 1.0}]})";
}

std::string json_angle(const std::string& kind, const std::string& value) {
  const std::string stations = kind == "horizontal_angle" ? R"("at": "A", "from": "B", "to": "C")" : R"("from": "A", "to": "B")";
  return R"({"kind": ")" + kind + R"(", )" + stations + ", " + value + R"(, "sigma_arcsec": 2.0})";
}

TEST_F(NetworkAngles, Issue39_JsonRefusesAnAngleOutOfRangeAtItsKey) {
  struct Case {
    std::string name, measurement, at, range;
  };
  const std::vector<Case> cases = {
      {"a direction of 400°", json_direction_set(R"("value_deg": 400)"), "measurements[1].directions[1].value_deg=400",
       "a direction lies in [0, 360] degrees"},
      {"a negative direction", json_direction_set(R"("value_gon": -0.5)"), "measurements[1].directions[1].value_gon=-0.5",
       "a direction lies in [0, 400] gon"},
      {"a zenith angle of 181°", json_angle("zenith_angle", R"("value_deg": 181)"), "measurements[1].value_deg=181",
       "a zenith angle lies in [0, 180] degrees"},
      {"a vertical angle of 91°", json_angle("vertical_angle", R"("value_dms": "91-00-00")"), "measurements[1].value_dms=91-00-00",
       "a vertical angle lies in [-90-00-00, 90-00-00] degrees-minutes-seconds"},
      {"a vertical angle of −91°", json_angle("vertical_angle", R"("value_deg": -91)"), "measurements[1].value_deg=-91",
       "a vertical angle lies in [-90, 90] degrees"},
      {"a negative horizontal angle", json_angle("horizontal_angle", R"("value_deg": -1.5)"), "measurements[1].value_deg=-1.5",
       "a horizontal angle lies in [0, 360] degrees"},
      // 7 rad > 2π = 6.283185307179586 rad.
      {"an azimuth of 7 rad", json_angle("azimuth", R"("value_rad": 7.0)"), "measurements[1].value_rad=7.0",
       "an azimuth lies in [0, 6.283185307179586] radians ([0, 2π])"},
  };
  for (const auto& c : cases) {
    SCOPED_TRACE(c.name);
    const std::string file = write("net.json", json_network(c.measurement));
    const Refusal r = refusal(file);
    EXPECT_EQ(r.code, "E_ANGLE") << r.message;
    EXPECT_THAT(r.message, HasSubstr(file + ": " + c.at + ": " + c.range));
  }
}

TEST_F(NetworkAngles, Issue39_JsonReadsTheBoundsOfEachRange) {
  // 360° is the full circle; 180° the nadir; ±90° the vertical; 400 gon and
  // 2π rad (the float64 nearest, 6.283185307179586) are 360°.
  const std::vector<std::string> inside = {
      json_direction_set(R"("value_deg": 360)"),       json_direction_set(R"("value_gon": 400)"),
      json_direction_set(R"("value_rad": 6.283185307179586)"), json_direction_set(R"("value_dms": "360-00-00")"),
      json_angle("zenith_angle", R"("value_deg": 180)"), json_angle("zenith_angle", R"("value_deg": 0)"),
      json_angle("vertical_angle", R"("value_deg": -90)"), json_angle("vertical_angle", R"("value_gon": 100)"),
      json_angle("horizontal_angle", R"("value_deg": 0)"), json_angle("azimuth", R"("value_deg": 359.999999)"),
  };
  for (const auto& m : inside) {
    SCOPED_TRACE(m);
    const std::string file = write("net.json", json_network(m));
    EXPECT_NO_THROW(read_network({file}));
  }
}

TEST_F(NetworkAngles, Issue39_JsonDmsSecondsOf60AreTheNextMinuteWithAWarning) {
  // "91-41-60.00" is 91°41′60″ = 91°42′00″ = (91 + 42/60)° = 91.7°.
  const std::string file = write("net.json", json_network(json_angle("zenith_angle", R"("value_dms": "91-41-60.00")")));
  const geodesy::Network net = read_network({file});
  ASSERT_EQ(net.measurements.size(), 2u);
  EXPECT_NEAR(net.measurements[1].value(0), (91.0 + 42.0 / 60.0) * kPi / 180.0, kAngleTol_rad);
  ASSERT_EQ(net.warnings.size(), 1u);
  EXPECT_THAT(net.warnings[0], HasSubstr(file + ": measurements[1].value_dms: '91-41-60.00': seconds 60 read as 91°42'00\""));

  // Carried into the degrees, with a sign: "-0-59-60" is −(0°59′60″) = −1°00′00″ = −π/180 rad.
  const std::string minus = write("minus.json", json_network(json_angle("vertical_angle", R"("value_dms": "-0-59-60")")));
  const geodesy::Network m = read_network({minus});
  EXPECT_NEAR(m.measurements[1].value(0), -kPi / 180.0, kAngleTol_rad);
  ASSERT_EQ(m.warnings.size(), 1u);
  EXPECT_THAT(m.warnings[0], HasSubstr("'-0-59-60': seconds 60 read as -1°00'00\""));

  // 359°59′60″ is 360°00′00″, the full circle: a direction in range (2π rad).
  const std::string full = write("full.json", json_network(json_direction_set(R"("value_dms": "359-59-60.0")")));
  const geodesy::Network f = read_network({full});
  EXPECT_NEAR(f.measurements[2].value(0), 2.0 * kPi, kAngleTol_rad);
  ASSERT_EQ(f.warnings.size(), 1u);
  EXPECT_THAT(f.warnings[0], HasSubstr("directions[1].value_dms: '359-59-60.0': seconds 60 read as 360°00'00\""));
}

TEST_F(NetworkAngles, Issue39_JsonDmsSecondsAbove60AndMinutesOf60AreRefused) {
  struct Case {
    std::string value, message;
  };
  const std::vector<Case> cases = {
      {"91-41-60.01", "measurements[1].value_dms: '91-41-60.01': seconds 60.01 must be below 60"},
      {"91-41-60.0001", "measurements[1].value_dms: '91-41-60.0001': seconds 60.0001 must be below 60"},
      {"91-60-00", "measurements[1].value_dms: '91-60-00': minutes 60 must be below 60"},
  };
  for (const auto& c : cases) {
    SCOPED_TRACE(c.value);
    const std::string file = write("net.json", json_network(json_angle("zenith_angle", R"("value_dms": ")" + c.value + "\"")));
    const Refusal r = refusal(file);
    EXPECT_EQ(r.code, "E_ANGLE") << r.message;
    EXPECT_THAT(r.message, HasSubstr(file + ": " + c.message));
  }
}

// --- DynaML -----------------------------------------------------------------

std::string dynaml(const std::string& measurements) {
  std::string s = "<?xml version=\"1.0\"?>\n<DnaXmlFormat type=\"Measurement File\" referenceframe=\"GDA2020\" epoch=\"01.01.2020\">\n";
  const char* names[] = {"A", "B", "C"};
  const char* lats[] = {"-37.4800000", "-37.4805000", "-37.4800000"};
  const char* lons[] = {"144.5800000", "144.5800000", "144.5805000"};
  for (int k = 0; k < 3; ++k) {
    s += std::string("  <DnaStation>\n    <Name>") + names[k] + "</Name>\n    <Constraints>" + (k == 0 ? "CCC" : "FFF") +
         "</Constraints>\n    <Type>LLh</Type>\n    <StationCoord>\n      <Name>" + names[k] + "</Name>\n      <XAxis>" + lats[k] +
         "</XAxis>\n      <YAxis>" + lons[k] + "</YAxis>\n      <Height>100.0</Height>\n    </StationCoord>\n  </DnaStation>\n";
  }
  return s + measurements + "</DnaXmlFormat>\n";
}

// A measurement of one value: A (at First, Second to Third), B, V, Z, P, Q.
std::string dyna_measurement(char type, const std::string& value) {
  std::string m = std::string("  <DnaMeasurement>\n    <Type>") + type + "</Type>\n    <Ignore/>\n    <First>A</First>\n";
  if (type != 'P' && type != 'Q') m += "    <Second>B</Second>\n";
  if (type == 'A') m += "    <Third>C</Third>\n";
  return m + "    <Value>" + value + "</Value>\n    <StdDev>1.0</StdDev>\n  </DnaMeasurement>\n";
}

// A direction set at A: the reference object B, then C.
std::string dyna_directions(const std::string& reference, const std::string& to_c) {
  return "  <DnaMeasurement>\n    <Type>D</Type>\n    <Ignore/>\n    <First>A</First>\n    <Second>B</Second>\n    <Total>1</Total>\n"
         "    <Value>" + reference + "</Value>\n    <StdDev>1.0</StdDev>\n"
         "    <Directions>\n      <Ignore/>\n      <Target>C</Target>\n      <Value>" + to_c + "</Value>\n      <StdDev>1.0</StdDev>\n"
         "    </Directions>\n  </DnaMeasurement>\n";
}

TEST_F(NetworkAngles, Issue39_DynamlRefusesAnAngleOutOfRangeAtItsElement) {
  struct Case {
    std::string name, measurements, line_of, at, range;
  };
  const std::vector<Case> cases = {
      {"a direction of 400° (a target of a set)", dyna_directions("0.0000", "400.0000"), "<Directions>",
       "measurement D <Value>=400.0000", "a direction lies in [0.0000, 360.0000] degrees (packed DDD.MMSS)"},
      {"a negative direction (the reference object)", dyna_directions("-10.0000", "45.0000"), "<DnaMeasurement>",
       "measurement D <Value>=-10.0000", "a direction lies in [0.0000, 360.0000] degrees"},
      {"a zenith angle of 181°", dyna_measurement('V', "181.0000"), "<DnaMeasurement>", "measurement V <Value>=181.0000",
       "a zenith angle lies in [0.0000, 180.0000] degrees"},
      {"a vertical angle of 91°", dyna_measurement('Z', "91.0000"), "<DnaMeasurement>", "measurement Z <Value>=91.0000",
       "a vertical angle lies in [-90.0000, 90.0000] degrees"},
      {"a horizontal angle of 360°00′01″", dyna_measurement('A', "360.0001"), "<DnaMeasurement>", "measurement A <Value>=360.0001",
       "a horizontal angle lies in [0.0000, 360.0000] degrees"},
      {"a negative azimuth", dyna_measurement('B', "-0.0001"), "<DnaMeasurement>", "measurement B <Value>=-0.0001",
       "an azimuth lies in [0.0000, 360.0000] degrees"},
      {"a geodetic latitude of −90°00′01″", dyna_measurement('P', "-90.0001"), "<DnaMeasurement>", "measurement P <Value>=-90.0001",
       "a geodetic latitude lies in [-90.0000, 90.0000] degrees"},
      {"a geodetic longitude of 360°", dyna_measurement('Q', "360.0000"), "<DnaMeasurement>", "measurement Q <Value>=360.0000",
       "a geodetic longitude lies in [-180.0000, 360.0000) degrees"},
  };
  for (const auto& c : cases) {
    SCOPED_TRACE(c.name);
    const std::string text = dynaml(dyna_measurement('S', "111.3") + c.measurements);  // a distance, then the angle
    const std::string file = write("net.xml", text);
    for (const auto& options : {NetworkReadOptions{}, [] {
                                  NetworkReadOptions o;
                                  o.dynaml_part_bytes = kSmallParts;
                                  return o;
                                }()}) {
      const Refusal r = refusal(file, options);
      EXPECT_EQ(r.code, "E_ANGLE") << r.message;
      EXPECT_THAT(r.message, HasSubstr(file + ":" + std::to_string(line_of_last(text, c.line_of)) + ": " + c.at + ": " + c.range));
    }
  }
}

TEST_F(NetworkAngles, Issue39_DynamlPackedSecondsOf60AreTheNextMinuteWithAWarning) {
  // 91.416000 is 91°41′60.00″ = 91°42′00″ = (91 + 42/60)° = 91.7°;
  // 359.5960 is 359°59′60″ = 360°00′00″ = 2π rad (the full circle);
  // 45.0060 is 45°00′60″ = 45°01′00″ = (45 + 1/60)°.
  const std::string text = dynaml(dyna_measurement('V', "91.416000") + dyna_directions("359.5960", "45.0060"));
  const std::string file = write("net.xml", text);
  const geodesy::Network net = read_network({file});
  ASSERT_EQ(net.measurements.size(), 3u);
  EXPECT_NEAR(net.measurements[0].value(0), (91.0 + 42.0 / 60.0) * kPi / 180.0, kAngleTol_rad);
  EXPECT_NEAR(net.measurements[1].value(0), 2.0 * kPi, kAngleTol_rad);
  EXPECT_NEAR(net.measurements[2].value(0), (45.0 + 1.0 / 60.0) * kPi / 180.0, kAngleTol_rad);
  ASSERT_EQ(net.warnings.size(), 3u);
  const std::string v = file + ":" + std::to_string(line_of_last(text, "<Type>V</Type>") - 1);
  const std::string d = file + ":" + std::to_string(line_of_last(text, "<Type>D</Type>") - 1);
  const std::string c = file + ":" + std::to_string(line_of_last(text, "<Directions>"));
  EXPECT_THAT(net.warnings[0], HasSubstr(v + ": measurement V <Value>: '91.416000': seconds 60 read as 91°42'00\""));
  EXPECT_THAT(net.warnings[1], HasSubstr(d + ": measurement D <Value>: '359.5960': seconds 60 read as 360°00'00\""));
  EXPECT_THAT(net.warnings[2], HasSubstr(c + ": measurement D <Value>: '45.0060': seconds 60 read as 45°01'00\""));
}

TEST_F(NetworkAngles, Issue39_DynamlPackedSecondsAbove60AndMinutesOf60AreRefused) {
  struct Case {
    std::string value, message;
  };
  const std::vector<Case> cases = {
      {"91.416001", "'91.416001': seconds 60.01 must be below 60"},     // 91°41′60.01″
      {"91.41600001", "'91.41600001': seconds 60.0001 must be below 60"},  // 91°41′60.0001″
      {"91.6000", "'91.6000': minutes 60 must be below 60"},            // 91°60′00″
  };
  for (const auto& c : cases) {
    SCOPED_TRACE(c.value);
    const std::string text = dynaml(dyna_measurement('V', c.value));
    const std::string file = write("net.xml", text);
    const Refusal r = refusal(file);
    EXPECT_EQ(r.code, "E_ANGLE") << r.message;
    EXPECT_THAT(r.message, HasSubstr(file + ":" + std::to_string(line_of_last(text, "<DnaMeasurement>")) +
                                         ": measurement V <Value>: " + c.message));
  }
}

TEST_F(NetworkAngles, Issue39_DynamlWarningsOfEveryPartArriveInFileOrder) {
  // Twelve zenith angles with seconds of 60 (90°MM′60″, MM = 0 … 11), read
  // whole and in parts on threads: the same twelve warnings, in the order
  // of their lines.
  std::string body;
  for (int k = 0; k < 12; ++k) body += dyna_measurement('V', "90." + std::string(k < 10 ? "0" : "") + std::to_string(k) + "60");
  const std::string file = write("net.xml", dynaml(body));
  NetworkReadOptions whole, parts;
  whole.dynaml_part_bytes = 0;
  parts.dynaml_part_bytes = kSmallParts;
  const geodesy::Network one = read_network({file}, whole);
  const geodesy::Network many = read_network({file}, parts);
  ASSERT_EQ(one.warnings.size(), 12u);
  EXPECT_EQ(many.warnings, one.warnings);
  for (int k = 0; k < 12; ++k) {
    // 90°k′60″ is 90°(k+1)′00″.
    const std::string minutes = (k + 1 < 10 ? "0" : "") + std::to_string(k + 1);
    EXPECT_THAT(one.warnings[static_cast<std::size_t>(k)], HasSubstr("seconds 60 read as 90°" + minutes + "'00\"")) << k;
    EXPECT_NEAR(many.measurements[static_cast<std::size_t>(k)].value(0), (90.0 + (k + 1) / 60.0) * kPi / 180.0, kAngleTol_rad);
  }
}

// --- GNU Gama ---------------------------------------------------------------

std::string gama(const std::string& observations) {
  return "<?xml version=\"1.0\" ?>\n<gama-local xmlns=\"http://www.gnu.org/software/gama/gama-local\">\n"
         "<network axes-xy=\"ne\" angles=\"left-handed\">\n<points-observations>\n"
         "<point id=\"1\" x=\"0\" y=\"0\" z=\"0\" fix=\"xyz\"/>\n"
         "<point id=\"2\" x=\"100\" y=\"0\" z=\"0\" adj=\"xyz\"/>\n"
         "<point id=\"3\" x=\"0\" y=\"100\" z=\"0\" adj=\"xyz\"/>\n"
         "<obs from=\"1\">\n"
         "  <distance to=\"2\" val=\"100.001\" stdev=\"2\"/>\n" +
         observations +
         "</obs>\n</points-observations>\n</network>\n</gama-local>\n";
}

TEST_F(NetworkAngles, Issue39_GamaRefusesAnAngleOutOfRangeAtItsElement) {
  struct Case {
    std::string name, observation, at, range;
  };
  const std::vector<Case> cases = {
      {"a direction of 400.5 gon", "  <direction to=\"2\" val=\"400.5\" stdev=\"5\"/>\n", "<direction> val=400.5",
       "a direction lies in [0, 400] gon"},
      {"a negative direction", "  <direction to=\"2\" val=\"-0.0010\" stdev=\"5\"/>\n", "<direction> val=-0.0010",
       "a direction lies in [0, 400] gon"},
      {"a zenith angle of 181° (d-m-s)", "  <z-angle to=\"2\" val=\"181-00-00\" stdev=\"5\"/>\n", "<z-angle> val=181-00-00",
       "a zenith angle lies in [0-00-00, 180-00-00] degrees-minutes-seconds"},
      {"a zenith angle of 201.2 gon", "  <z-angle to=\"2\" val=\" 201.2\" stdev=\"5\"/>\n", "<z-angle> val=201.2",
       "a zenith angle lies in [0, 200] gon"},
      {"a negative horizontal angle", "  <angle bs=\"2\" fs=\"3\" val=\"-100\" stdev=\"5\"/>\n", "<angle> val=-100",
       "a horizontal angle lies in [0, 400] gon"},
      {"an azimuth of 400.0001 gon", "  <azimuth to=\"2\" val=\"400.0001\" stdev=\"5\"/>\n", "<azimuth> val=400.0001",
       "an azimuth lies in [0, 400] gon"},
  };
  for (const auto& c : cases) {
    SCOPED_TRACE(c.name);
    const std::string text = gama(c.observation);
    const std::string file = write("net.gkf", text);
    const std::string element = c.at.substr(0, c.at.find('>'));  // "<direction", "<z-angle", …
    const Refusal r = refusal(file);
    EXPECT_EQ(r.code, "E_ANGLE") << r.message;
    EXPECT_THAT(r.message, HasSubstr(file + ":" + std::to_string(line_of_last(text, element + " ")) + ": " + c.at + ": " + c.range));
  }
}

TEST_F(NetworkAngles, Issue39_GamaDmsSecondsOf60AreTheNextMinuteWithAWarning) {
  // "57-32-60.000" is 57°32′60″ = 57°33′00″ = (57 + 33/60)° = 57.55°; 400 gon
  // and "200" gon, the bounds, are read (2π and π rad).
  const std::string text = gama("  <direction to=\"2\" val=\"57-32-60.000\" stdev=\"5\"/>\n"
                                "  <direction to=\"3\" val=\"400\" stdev=\"5\"/>\n"
                                "  <z-angle to=\"2\" val=\"200\" stdev=\"5\"/>\n");
  const std::string file = write("net.gkf", text);
  const geodesy::Network net = read_network({file});
  ASSERT_EQ(net.measurements.size(), 4u);
  EXPECT_NEAR(net.measurements[1].value(0), (57.0 + 33.0 / 60.0) * kPi / 180.0, kAngleTol_rad);
  EXPECT_NEAR(net.measurements[2].value(0), 2.0 * kPi, kAngleTol_rad);
  EXPECT_NEAR(net.measurements[3].value(0), kPi, kAngleTol_rad);
  ASSERT_EQ(net.warnings.size(), 1u);
  EXPECT_THAT(net.warnings[0], HasSubstr(file + ":" + std::to_string(line_of_last(text, "<direction to=\"2\"")) +
                                         ": <direction> val: '57-32-60.000': seconds 60 read as 57°33'00\""));

  // 60.01″ and 60′ stay refused.
  for (const std::string value : {"57-32-60.01", "57-60-00"}) {
    SCOPED_TRACE(value);
    const std::string bad = write("bad.gkf", gama("  <direction to=\"2\" val=\"" + value + "\" stdev=\"5\"/>\n"));
    const Refusal r = refusal(bad);
    EXPECT_EQ(r.code, "E_ANGLE") << r.message;
    EXPECT_THAT(r.message, HasSubstr("<direction> val: '" + value + "': " +
                                     (value == "57-60-00" ? "minutes 60 must be below 60" : "seconds 60.01 must be below 60")));
  }
}

// --- The bundled samples ----------------------------------------------------

TEST_F(NetworkAngles, Issue39_TheBundledSampleNetworksStillRead) {
  const std::string f = GEOANCHOR_FIXTURES_DIR;
  const std::vector<std::vector<std::string>> inputs = {
      {f + "/networks/dynadjust/gnss-networkstn.xml", f + "/networks/dynadjust/gnss-networkmsr.xml"},
      {f + "/networks/gama/stroner-levelling-a.gkf"},
      {f + "/networks/gama/tst-tetrahedron-1.gkf"},
      {f + "/airport_network/lszh_network.json"},
      {f + "/airport_network/lszh_site1998.json"},
  };
  for (const auto& files : inputs) {
    SCOPED_TRACE(files.back());
    geodesy::Network net;
    ASSERT_NO_THROW(net = read_network(files));
    EXPECT_FALSE(net.measurements.empty());
    for (const auto& w : net.warnings) EXPECT_THAT(w, ::testing::Not(HasSubstr("seconds 60"))) << w;
  }
}

}  // namespace
}  // namespace geoanchor::io
