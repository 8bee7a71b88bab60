// Issue 42 point 6: STAR*NET data files read into a local network. Each
// record and inline option is tested for its meaning (values worked by hand
// from the STAR*NET V6 reference manual's definitions, chapter 5: the
// clockwise angle At-From-To, quadrant bearings, the face-II zenith, the
// US survey foot of 1200/3937 m) and for its refusal by name.

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <string>

#include "geoanchor/base/error.hpp"
#include "geoanchor/io/network/network_input.hpp"
#include "temp_folder.hpp"

namespace geoanchor::io {
namespace {

using geodesy::MeasurementKind;
using geodesy::Network;

constexpr double kDeg = std::numbers::pi / 180.0;
constexpr double kArcsec = kDeg / 3600.0;
// Values parsed from decimal text and converted once: a few ulp.
constexpr double kExact_m = 1e-12;
constexpr double kExact_rad = 1e-14;

// Every file states what STAR*NET keeps in its project options.
const std::string k2d = ".2D\n.UNITS Meters DMS\n.ORDER NE AtFromTo\n";
const std::string k3d = ".3D\n.UNITS Meters DMS\n.ORDER NE AtFromTo\n.DELTA OFF\n";

Network read(const std::string& text) {
  Network net;
  read_network_text(text, "n.dat", net);
  return net;
}

// The message of the refusal, or "" (a test failure) when it is read.
std::string refusal(const std::string& text) {
  try {
    read(text);
  } catch (const Error& e) {
    return e.code() + ": " + e.what();
  }
  ADD_FAILURE() << "read without refusal:\n" << text;
  return "";
}

void expect_refused(const std::string& text, const std::vector<std::string>& pieces) {
  const std::string m = refusal(text);
  for (const auto& p : pieces) EXPECT_NE(m.find(p), std::string::npos) << "'" << p << "' in: " << m;
}

const geodesy::NetworkMeasurement& only(const Network& net, MeasurementKind kind) {
  for (const auto& m : net.measurements) {
    if (m.kind == kind) return m;
  }
  ADD_FAILURE() << geodesy::to_string(kind) << " not read";
  return net.measurements.front();
}

double sigma(const geodesy::NetworkMeasurement& m) { return std::sqrt(m.covariance(0, 0)); }

TEST(NetworkStarnet, DetectionIsByContentAndNeverCapturesTheOtherFormats) {
  EXPECT_EQ(detect_network_format("# job 12\n\n  # crew B\n.2D\nC A 1 2\n", "x.json"), NetworkFormat::starnet);
  EXPECT_EQ(detect_network_format("C A 1 2 ! !\n", "x"), NetworkFormat::starnet);
  EXPECT_EQ(detect_network_format("\xEF\xBB\xBF" "m 1-2-3 10-00-00 5\n", "x"), NetworkFormat::starnet);
  EXPECT_EQ(detect_network_format("{\"schema\": \"geoanchor.network/1\"}", "x.dat"), NetworkFormat::json);
  EXPECT_EQ(detect_network_format("%=SNX 2.02 XXX\n", "x.dat"), NetworkFormat::sinex);
  EXPECT_EQ(detect_network_format("!#=DNA 3.01 STN 01.01.2020 GDA2020 01.01.2020 2\n", "x.dat"), NetworkFormat::dna);
  for (const std::string other : {"# c\n{}", "Cx A 1 2\n", "hello world\n",
                                  "# only comments\n", ".\n", "C\n", "<?xml version=\"1.0\"?>\n<root/>"}) {
    EXPECT_THROW(detect_network_format(other, "x.dat"), Error) << other;
  }
}

TEST(NetworkStarnet, CoordinatesFollowOrderUnitsAndFixity) {
  Network net = read(k2d + "C A 1000.5 2000.25 ! !\nC B 10 20 0.01 *\n.ORDER EN\nC C 30 40\n");
  EXPECT_EQ(net.space, geodesy::NetworkSpace::local);
  EXPECT_EQ(net.axes.name(), "ne");
  EXPECT_TRUE(net.axes.angles_clockwise);
  EXPECT_EQ(net.local_dimensions, 2);
  const auto& a = net.stations[*net.find("A")];
  EXPECT_EQ(a.position.x(), 1000.5);  // x is north
  EXPECT_EQ(a.position.y(), 2000.25);
  EXPECT_EQ(a.constraint.text(), "CCF");
  const auto& b = net.stations[*net.find("B")];
  EXPECT_EQ(b.constraint.text(), "CFF");
  EXPECT_EQ(b.constraint.sigma_m[0], 0.01);
  const auto& c = net.stations[*net.find("C")];  // .ORDER EN: east first
  EXPECT_EQ(c.position.x(), 40.0);
  EXPECT_EQ(c.position.y(), 30.0);
  EXPECT_EQ(c.constraint.text(), "FFF");
  // 3D, US survey feet: 1000 ft = 1 200 000 / 3937 m = 304.800 609 601 219 2 m.
  net = read(".3D\n.UNITS FeetUS\n.ORDER NE\nC A 1000 0 100 ! * 0.5\n");
  EXPECT_EQ(net.local_dimensions, 3);
  const auto& f = net.stations[0];
  EXPECT_NEAR(f.position.x(), 304.8006096012192, kExact_m);
  EXPECT_NEAR(f.position.z(), 30.48006096012192, kExact_m);
  EXPECT_EQ(f.constraint.text(), "CFC");
  EXPECT_NEAR(f.constraint.sigma_m[2], 0.5 * 1200.0 / 3937.0, kExact_m);
  net = read(".2D\n.UNITS FeetIntl\n.ORDER NE\nC A 1000 0\n");
  EXPECT_NEAR(net.stations[0].position.x(), 304.8, kExact_m);
}

TEST(NetworkStarnet, CoordinateRefusals) {
  expect_refused(".UNITS Meters\n.ORDER NE\nC A 1 2\n", {"E_STARNET", "n.dat:3", "before any .2D or .3D"});
  expect_refused(".2D\n.UNITS Meters\nC A 1 2\n", {"n.dat:3", "before any .ORDER NE|EN"});
  expect_refused(".2D\n.ORDER NE\nC A 1 2\n", {"before any .UNITS", "linear unit"});
  expect_refused(k2d + "C A 1 2 & &\n", {"'&'", "default standard error"});
  expect_refused(k2d + "C A 1 2 3\n", {"C A: 3 values", "expected 2 coordinates"});
  expect_refused(k2d + "C A 1 2 -0.1 !\n", {"coordinate standard error '-0.1'", "> 0"});
  expect_refused(k2d + "C A 1 2\nC A 1 2\n", {"n.dat:5", "C A is given again", "n.dat:4"});
  expect_refused(k2d + "C A 1,5 2\n", {"north '1,5' is not a number"});
  expect_refused(k3d + ".2D\nC A 1 2\n.3D\nC B 1 2 3\n", {"C A has no elevation", "3D network"});
}

TEST(NetworkStarnet, ElevationsAndLevellingMakeALevellingNetwork) {
  const Network net = read(".UNITS Meters\nE BM1 100.25 !\nE BM2 101 0.002\nL BM1-P 1.5 200 0.0015\nL P-BM2 -0.7 150 0.0012\n");
  EXPECT_EQ(net.local_dimensions, 1);
  const auto& bm1 = net.stations[*net.find("BM1")];
  EXPECT_EQ(bm1.position.z(), 100.25);
  EXPECT_EQ(bm1.constraint.text(), "FFC");
  EXPECT_EQ(net.stations[*net.find("BM2")].constraint.sigma_m[2], 0.002);
  EXPECT_FALSE(net.stations[*net.find("P")].position_known);  // placed by the adjustment
  ASSERT_EQ(net.measurements.size(), 2u);
  EXPECT_EQ(net.measurements[0].kind, MeasurementKind::height_difference);
  EXPECT_EQ(net.measurements[0].value(0), 1.5);
  EXPECT_EQ(sigma(net.measurements[0]), 0.0015);
  EXPECT_EQ(net.measurements[0].source, "n.dat:4");
  expect_refused(".UNITS Meters\nE A 1 2 3\n", {"E A: expected an elevation"});
  expect_refused(".UNITS Meters\nE A 1\nE A 2\n", {"n.dat:3", "its elevation is given already"});
  expect_refused(k2d + "C A 1 2\nE A 5\n", {"n.dat:5", "E A: an elevation in a 2D network"});
  expect_refused(".UNITS Meters\nL A-B 1.5 0 0.001\n", {"levelled length '0' must be > 0"});
  expect_refused(".UNITS Meters\nL A-B 1.5 100\n", {"0 standard error(s) for 1 observation", "project options"});
}

TEST(NetworkStarnet, AnglesAreClockwiseAtFromTo) {
  Network net = read(k2d + "A 2-1-3 90-00-00 2.5\n");
  const auto& a = only(net, MeasurementKind::horizontal_angle);
  EXPECT_EQ(net.stations[a.stations[0]].id, "2");  // at
  EXPECT_EQ(net.stations[a.stations[1]].id, "1");  // from (backsight)
  EXPECT_EQ(net.stations[a.stations[2]].id, "3");  // to
  EXPECT_NEAR(a.value(0), 90.0 * kDeg, kExact_rad);
  EXPECT_NEAR(sigma(a), 2.5 * kArcsec, kExact_rad);
  // Counter-clockwise 102°34′12.5″ is clockwise 257°25′47.5″.
  net = read(k2d + "A 2-1-3 -102-34-12.5 3\n");
  EXPECT_NEAR(net.measurements[0].value(0), (257.0 + 25.0 / 60 + 47.5 / 3600) * kDeg, 1e-12);
  net = read(".2D\n.UNITS Meters DMS\n.ORDER FromAtTo\nA 1-2-3 45-00-00 1\n");
  EXPECT_EQ(net.stations[net.measurements[0].stations[0]].id, "2");
  net = read(".2D\n.UNITS Meters GONS\n.ORDER AtFromTo\nA 2-1-3 100.5 3\n");  // gons, sigma in milligons
  EXPECT_NEAR(net.measurements[0].value(0), 100.5 * std::numbers::pi / 200.0, kExact_rad);
  EXPECT_NEAR(sigma(net.measurements[0]), 3e-3 * std::numbers::pi / 200.0, kExact_rad);
  expect_refused(".2D\n.UNITS Meters DMS\nA 2-1-3 90-00-00 2\n", {"before any .ORDER AtFromTo|FromAtTo"});
  expect_refused(".2D\n.UNITS Meters\n.ORDER AtFromTo\nA 2-1-3 90-00-00 2\n", {"before any .UNITS DMS|GONS"});
  expect_refused(k2d + "A 2-1-3 90.5 2\n", {"'90.5'", "DDD-MM-SS.s"});
  expect_refused(k2d + "A 2-1-3 400-00-00 2\n", {"E_ANGLE", "=400-00-00", "360-00-00"});
  expect_refused(k2d + "A 2-1 90-00-00 2\n", {"expected 3 station name(s) joined by '-'"});
  expect_refused(k2d + "A 2-1-3 90-00-00\n", {"0 standard error(s) for 1 observation"});
  expect_refused(k2d + "A 2-1-3 90-00-00 !\n", {"'!' (a fixed observation)"});
  // '*' (a free observation) is read, ignored: network_starnet_geodetic_test.cpp.
  expect_refused(k2d + "A 2-1-3 90-00-00 &\n", {"'&' (the project's default)"});
  expect_refused(k2d + "A 2-1-3 90-00-00 0\n", {"standard error '0'", "> 0"});
  expect_refused(k2d + "A 2-1-3 90-00-00 2 1.5/1.6\n", {"HI/HT '1.5/1.6'", "without a 3D distance"});
}

TEST(NetworkStarnet, DistancesAndVerticalsFollowDelta) {
  Network net = read(k2d + "D A-B 100.5 0.003\n");
  EXPECT_EQ(net.measurements[0].kind, MeasurementKind::horizontal_distance);
  EXPECT_EQ(net.measurements[0].value(0), 100.5);
  EXPECT_EQ(sigma(net.measurements[0]), 0.003);
  net = read(k3d + "D A-B 100.5 0.003 1.5/1.6\nV A-B 95-00-00 5 1.5/1.6\nV A-B 265-00-00 5\n");
  const auto& s = only(net, MeasurementKind::slope_distance);
  EXPECT_EQ(s.value(0), 100.5);
  EXPECT_EQ(s.instrument_height_m, 1.5);
  EXPECT_EQ(s.target_height_m, 1.6);
  ASSERT_EQ(net.measurements.size(), 3u);
  EXPECT_NEAR(net.measurements[1].value(0), 95.0 * kDeg, kExact_rad);
  EXPECT_EQ(net.measurements[1].instrument_height_m, 1.5);
  EXPECT_NEAR(net.measurements[2].value(0), 95.0 * kDeg, kExact_rad);  // face II: 360° − 265°
  EXPECT_EQ(net.local_dimensions, 3);
  // .DELTA ON: horizontal distance, elevation difference instrument to
  // target: 2.5 + HI 1.5 − HT 1.6 = 2.4 mark to mark.
  net = read(".3D\n.UNITS Meters DMS\n.DELTA ON\nD A-B 100.5 0.003\nV A-B 2.5 0.004 1.5/1.6\nDV A-C 50 -1 0.002 0.003\n");
  EXPECT_EQ(net.measurements[0].kind, MeasurementKind::horizontal_distance);
  EXPECT_EQ(net.measurements[1].kind, MeasurementKind::height_difference);
  EXPECT_NEAR(net.measurements[1].value(0), 2.4, kExact_m);
  EXPECT_EQ(sigma(net.measurements[1]), 0.004);
  EXPECT_EQ(net.measurements[2].kind, MeasurementKind::horizontal_distance);
  EXPECT_EQ(net.measurements[3].value(0), -1.0);
  expect_refused(".3D\n.UNITS Meters DMS\nD A-B 100 0.003\n", {"D in 3D data before any .DELTA ON|OFF"});
  expect_refused(k2d + "V A-B 90-00-00 5\n", {"V: a vertical observation is 3D data"});
  expect_refused(k2d + "DV A-B 100 90-00-00 0.003 5\n", {"DV: a vertical observation is 3D data"});
  expect_refused(k2d + "D A-B -3 0.003\n", {"distance '-3' must be > 0"});
  expect_refused(k3d + "V A-B 185-00-00x 5\n", {"185-00-00x"});
  expect_refused(k3d + "D A-B 100 0.003 1.5/x\n", {"HT 'x' is not a number"});
}

TEST(NetworkStarnet, BearingsAreClockwiseFromNorth) {
  const Network net = read(k2d + "B A-B N45-00-00W 3\nB A-B S10-00-00E 3\nB A-B S10-00-00W 3\nB A-B 123-30-00 3\n");
  EXPECT_NEAR(net.measurements[0].value(0), 315.0 * kDeg, kExact_rad);
  EXPECT_NEAR(net.measurements[1].value(0), 170.0 * kDeg, kExact_rad);
  EXPECT_NEAR(net.measurements[2].value(0), 190.0 * kDeg, kExact_rad);
  EXPECT_NEAR(net.measurements[3].value(0), 123.5 * kDeg, kExact_rad);
  EXPECT_EQ(net.measurements[3].kind, MeasurementKind::azimuth);
  expect_refused(k2d + "B A-B N95-00-00E 3\n", {"a quadrant bearing lies in [0, 90]"});
  expect_refused(k2d + "B A-B N45-00-00 3\n", {"expected N|S DDD-MM-SS.s E|W"});
  expect_refused(".2D\n.UNITS Meters GONS\nB A-B N45E 3\n", {"quadrant bearings are written in DMS"});
}

TEST(NetworkStarnet, MeasureLinesCarryEveryObservation) {
  Network net = read(k2d + "M 2-1-3 90-00-00 100.5 2 0.003\nBM 2-3 N90-00-00E 50 2 0.003\n");
  ASSERT_EQ(net.measurements.size(), 4u);
  EXPECT_EQ(net.measurements[0].kind, MeasurementKind::horizontal_angle);
  EXPECT_EQ(net.measurements[1].kind, MeasurementKind::horizontal_distance);
  EXPECT_EQ(net.stations[net.measurements[1].stations[0]].id, "2");  // from the instrument
  EXPECT_EQ(net.stations[net.measurements[1].stations[1]].id, "3");
  EXPECT_NEAR(net.measurements[2].value(0), 90.0 * kDeg, kExact_rad);
  net = read(k3d + "M 2-1-3 90-00-00 100.5 91-00-00 2 0.003 4 1.5/1.6\n");
  ASSERT_EQ(net.measurements.size(), 3u);
  EXPECT_EQ(net.measurements[1].kind, MeasurementKind::slope_distance);
  EXPECT_EQ(net.measurements[2].kind, MeasurementKind::zenith_angle);
  EXPECT_NEAR(sigma(net.measurements[2]), 4 * kArcsec, kExact_rad);
  EXPECT_EQ(net.measurements[2].target_height_m, 1.6);
  EXPECT_EQ(net.measurements[0].instrument_height_m, 0.0);  // a horizontal angle takes no height
  expect_refused(k3d + "M 2-1-3 90-00-00 100.5 2 0.003\n", {"'2'", "DDD-MM-SS.s"});  // its zenith is missing
  expect_refused(k3d + "M 2-1-3 90-00-00 100.5\n", {"M: expected its distance and vertical observation"});
  expect_refused(k3d + "M 2-1-3 90-00-00 100.5 91-00-00 2 0.003\n", {"2 standard error(s) for 3 observation(s)"});
}

TEST(NetworkStarnet, DirectionSetsHaveOneOrientationEach) {
  const Network net = read(k2d + "DB 1\nDN 2 0-00-00 2\nDM 3 45-00-00 100 2 0.003\nDE\nDB 2\nDN 1 10-00-00 2\nDE\n");
  ASSERT_EQ(net.direction_sets.size(), 2u);
  EXPECT_EQ(net.stations[net.direction_sets[0].station].id, "1");
  ASSERT_EQ(net.measurements.size(), 4u);
  EXPECT_EQ(net.measurements[0].kind, MeasurementKind::direction);
  EXPECT_EQ(net.measurements[0].set, 0u);
  EXPECT_EQ(net.stations[net.measurements[1].stations[1]].id, "3");
  EXPECT_NEAR(net.measurements[1].value(0), 45.0 * kDeg, kExact_rad);
  EXPECT_EQ(net.measurements[2].kind, MeasurementKind::horizontal_distance);
  EXPECT_FALSE(net.measurements[2].set.has_value());
  EXPECT_EQ(net.measurements[3].set, 1u);
  expect_refused(k2d + "DN 2 0-00-00 2\n", {"DN outside a direction set"});
  expect_refused(k2d + "DB 1\nDN 2 0-00-00 2\n", {"n.dat:4", "DB) without its DE"});
  expect_refused(k2d + "DB 1\nDB 2\n", {"DB while the set of n.dat:4 is open"});
  expect_refused(k2d + "DB 1\nDE 3\n", {"DE: expected nothing after it"});
  expect_refused(k2d + "DB 1-2\n", {"expected 1 station name(s)"});
}

TEST(NetworkStarnet, InlineOptionsAndTheirRefusals) {
  // Abbreviations (manual 5.9 rule 2) and the separator.
  Network net = read(".2d\n.U Meters DMS\n.OR NE AtFromTo\n.SEP :\nA S-1:S-2:S-3 10-00-00 2\n.ELEV Orthometric\n");
  EXPECT_EQ(net.stations[net.measurements[0].stations[0]].id, "S-1");
  expect_refused(".2D\n.UNITS Feet\n", {".UNITS Feet", "ambiguous between FeetUS, FeetIntl"});
  expect_refused(".2D\n.UNITS Yards\n", {"expected one of Meters, FeetUS, FeetIntl, DMS, GONS"});
  expect_refused(".D ON\n", {"inline option .D is ambiguous"});
  expect_refused(".FOO\n", {"inline option .FOO is not a STAR*NET inline option"});
  expect_refused(".DELTA MAYBE\n", {".DELTA MAYBE", "expected one of ON, OFF"});
  expect_refused(".2D 3\n", {"with 1 argument(s); expected 0"});
  expect_refused(".SEPARATOR ab\n", {"expected one character"});
  expect_refused(".2D\n.UNITS Meters\n.ELEVATION Ellipsoidal\nE A 3\n", {"n.dat:4", "E under .ELEVATION Ellipsoidal", "names no datum"});
  expect_refused(".REFRACTION 0.07\n", {"n.dat:1", ".REFRACTION 0.07 in a local network"});
  expect_refused(".SCALE 0.9996\n", {".SCALE", "scale factor"});
  expect_refused(".INSTRUMENT TS1\n", {".INSTRUMENT", "library of standard errors"});
  expect_refused(".PRISM 0.03\n", {".PRISM", "prism constant"});
  expect_refused(".MULT 3.28083333\n", {".MULTIPLIER", "use .UNITS"});
  expect_refused(".LEVEL\n", {".LEVEL", "E and L lines"});
  // .UNITS alone returns to the project's units, which the file does not hold.
  expect_refused(k2d + ".UNITS\nD A-B 10 0.003\n", {"before any .UNITS"});
}

TEST(NetworkStarnet, RecordsGeoanchorDoesNotModelAreRefusedByName) {
  // Geodetic data need the frame of an input before (network_starnet_geodetic_test.cpp).
  expect_refused(k3d + "P A 45-00-00 -120-00-00 100\n", {"n.dat:5", "P: a STAR*NET data file names no datum"});
  expect_refused(k3d + "PH A 45-00-00 -120-00-00 100\n", {"n.dat:5", "PH: a STAR*NET data file names no datum"});
  expect_refused(k3d + "CH A 1 2 3\n", {"CH (grid coordinates with an ellipsoid height)"});
  expect_refused(".UNITS Meters\nEH A 3\n", {"EH: a STAR*NET data file names no datum"});
  expect_refused(k3d + "G0 'V1\nG1 A-B 1 2 3\n", {"n.dat:5", "G0: a STAR*NET data file names no datum"});
  expect_refused(k2d + "TB N45-00-00E\n", {"TB (traverse or sideshot data)"});
  expect_refused(k2d + "X A 1\n", {"record 'X' is not a STAR*NET data code"});
}

TEST(NetworkStarnet, IncludeReadsRelativeToTheIncludingFileAndRefusesCycles) {
  testing::TempFolder dir;
  std::filesystem::create_directories(dir / "sub");
  std::ofstream(dir / "main.dat") << k2d << "C A 0 0 ! !\n.INCLUDE sub/obs.dat\nD A-B 10 0.003\n";
  std::ofstream(dir / "sub" / "obs.dat") << "# settings carry into the included file\nD A-C 20 0.003\n";
  const Network net = read_network({(dir / "main.dat").string()});
  ASSERT_EQ(net.measurements.size(), 2u);
  EXPECT_EQ(net.measurements[0].value(0), 20.0);
  EXPECT_EQ(net.measurements[0].source, (dir / "sub" / "obs.dat").string() + ":2");
  std::ofstream(dir / "loop.dat") << ".INCLUDE loop2.dat\n";
  std::ofstream(dir / "loop2.dat") << ".INCLUDE loop.dat\n";
  try {
    read_network({(dir / "loop.dat").string()});
    ADD_FAILURE() << "an include cycle was read";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("includes itself"), std::string::npos) << e.what();
  }
  std::ofstream(dir / "missing.dat") << ".INCLUDE nowhere.dat\n";
  EXPECT_THROW(read_network({(dir / "missing.dat").string()}), Error);
  Network none;
  try {
    read_network_text(".INCLUDE x.dat\n", "standard input", none);
    ADD_FAILURE() << "an include from standard input was read";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("give the data file by its path"), std::string::npos) << e.what();
  }
}

TEST(NetworkStarnet, ALocalNetworkIsNotMergedWithOneOnTheEllipsoid) {
  Network net;
  read_network_text(R"({"schema": "geoanchor.network/1", "frame": "ITRF2014@2020.0", "stations": [
      {"id": "Q", "lat_deg": 47, "lon_deg": 8, "h_m": 400, "constraint": "CCC"}], "measurements": []})",
                    "e.json", net);
  try {
    read_network_text(k2d + "C A 1 2 ! !\n", "n.dat", net);
    ADD_FAILURE() << "merged";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("other inputs are on the ellipsoid"), std::string::npos) << e.what();
  }
}

// 10⁵ stations, each with a C line and a distance, read from the one
// string read_network holds (the reader walks it line by line).
TEST(NetworkStarnet, AHundredThousandStationsAreRead) {
  constexpr int kStations = 100000;
  std::string text = k2d + "C S0 0 0 ! !\n";
  text.reserve(static_cast<std::size_t>(kStations) * 48);
  for (int i = 1; i < kStations; ++i) {
    text += "C S" + std::to_string(i) + " " + std::to_string(i) + ".5 7\nD S" + std::to_string(i - 1) + "-S" + std::to_string(i) +
            " 1 0.003\n";
  }
  const Network net = read(text);
  EXPECT_EQ(net.stations.size(), static_cast<std::size_t>(kStations));
  EXPECT_EQ(net.measurements.size(), static_cast<std::size_t>(kStations - 1));
  EXPECT_EQ(net.stations.back().position.x(), kStations - 1 + 0.5);
}

}  // namespace
}  // namespace geoanchor::io
