// A network's ellipsoid from its frame or CRS (issue 42 point 4): a frame of
// geoanchor's catalog implies its own; any other name is looked up in PROJ's
// database (the EPSG dataset); a CRS given as EPSG:n gives its datum's; a
// stated ellipsoid that contradicts the frame's is refused naming both, and
// a frame nobody knows never falls back to GRS 80.
//
// Expected a and 1/f are the EPSG dataset's published definitions (EPSG
// registry, ellipsoid codes in each row), and the datum each frame name is
// on is EPSG's (geodetic CRS codes in each row): independent of the code
// under test, which reads PROJ's copy of that dataset.

#include <gtest/gtest.h>

#include <GeographicLib/Geocentric.hpp>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "geoanchor/base/error.hpp"
#include "geoanchor/crs/frame_ellipsoid.hpp"
#include "geoanchor/io/network/network_input.hpp"
#include "proj_reference.hpp"

namespace geoanchor::io {
namespace {

constexpr double kSameA_m = 1e-9;         // a is given to the millimetre or exactly; a double holds it exactly
constexpr double kSameRf = 1e-9;          // 1/f, relative: EPSG gives 7 to 10 significant digits
constexpr double kSamePosition_m = 1e-6;  // a station read from lat/lon against GeographicLib on the expected ellipsoid

struct Expected {
  const char* frame;      // as a network names it
  const char* ellipsoid;  // EPSG's name
  double a_m, rf;
  const char* why;        // the EPSG datum and ellipsoid codes
};

const std::vector<Expected> kFrames = {
    {"NZGD1949", "International 1924", 6378388.0, 297.0, "EPSG:4272 NZGD49, ellipsoid EPSG:7022 (year written in four digits)"},
    {"ED50", "International 1924", 6378388.0, 297.0, "EPSG:4230 ED50, EPSG:7022"},
    {"DHDN", "Bessel 1841", 6377397.155, 299.1528128, "EPSG:4314 DHDN, EPSG:7004"},
    {"Tokyo", "Bessel 1841", 6377397.155, 299.1528128, "EPSG:4301 Tokyo, EPSG:7004"},
    {"NAD27", "Clarke 1866", 6378206.4, 6378206.4 / (6378206.4 - 6356583.8), "EPSG:4267 NAD27, EPSG:7008 (a and b = 6356583.8 m)"},
    {"Arc1960", "Clarke 1880 (RGS)", 6378249.145, 293.465, "EPSG:4210 Arc 1960, EPSG:7012 (a frame name has no spaces)"},
    {"OSGB36", "Airy 1830", 6377563.396, 299.3249646, "EPSG:4277 OSGB36, EPSG:7001"},
    {"Pulkovo1942", "Krassowsky 1940", 6378245.0, 298.3, "EPSG:4284 Pulkovo 1942, EPSG:7024 (a frame name has no spaces)"},
    {"HD72", "GRS 1967", 6378160.0, 298.247167427, "EPSG:4237 HD72, EPSG:7036"},
    {"AGD66", "Australian National Spheroid", 6378160.0, 298.25, "EPSG:4202 AGD66, EPSG:7003"},
    {"NZGD2000", "GRS 1980", 6378137.0, 298.257222101, "EPSG:4167 NZGD2000, EPSG:7019"},
    {"GDA2020", "GRS 1980", 6378137.0, 298.257222101, "geoanchor's catalog (EPSG:7844, EPSG:7019)"},
};

void expect_ellipsoid(const geodesy::Ellipsoid& e, const Expected& x) {
  EXPECT_EQ(e.name(), x.ellipsoid == std::string("GRS 1980") ? "GRS80" : x.ellipsoid) << x.why;
  EXPECT_NEAR(e.a_m(), x.a_m, kSameA_m) << x.why;
  EXPECT_NEAR(e.rf(), x.rf, kSameRf * x.rf) << x.why;
}

std::string error_of(const std::string& text, const std::string& source = "net.json") {
  geodesy::Network net;
  try {
    read_network_text(text, source, net);
  } catch (const Error& e) {
    return e.code() + ": " + e.what();
  }
  return "no error";
}

const char* kStation = R"("stations": [{"id": "A", "lat_deg": -41.013, "lon_deg": 173.321, "h_m": 150.0}], "measurements": [])";

TEST(NetworkEllipsoid, Issue42_EachFrameNameGivesTheEllipsoidOfItsEpsgDatum) {
  for (const Expected& x : kFrames) {
    SCOPED_TRACE(x.frame);
    const auto found = frame_ellipsoid(geodesy::Frame::parse(x.frame, "test"), "test");
    ASSERT_TRUE(found.has_value()) << x.why;
    expect_ellipsoid(found->ellipsoid, x);
  }
}

// A network JSON's "frame" alone puts its latitudes and longitudes on the
// frame's ellipsoid: the station is where GeographicLib puts it on that one.
TEST(NetworkEllipsoid, Issue42_ANetworkJsonFrameOutsideTheCatalogReadsItsStationsOnThatEllipsoid) {
  for (const Expected& x : kFrames) {
    SCOPED_TRACE(x.frame);
    geodesy::Network net;
    read_network_text(R"({"schema": "geoanchor.network/1", "frame": ")" + std::string(x.frame) + "\", " + kStation + "}",
                      "net.json", net);
    ASSERT_TRUE(net.ellipsoid_stated);
    expect_ellipsoid(net.ellipsoid, x);
    double ex = 0, ey = 0, ez = 0;
    GeographicLib::Geocentric(x.a_m, 1.0 / x.rf).Forward(-41.013, 173.321, 150.0, ex, ey, ez);
    EXPECT_LT((net.stations[0].position - Eigen::Vector3d(ex, ey, ez)).norm(), kSamePosition_m);
  }
}

// "crs": a geographic or geocentric CRS by its code gives its datum's
// ellipsoid, and the frame when the input names none.
TEST(NetworkEllipsoid, Issue42_ANetworkJsonCrsGivesItsDatumsEllipsoid) {
  const std::vector<std::pair<std::string, Expected>> cases = {
      {"EPSG:4272", kFrames[0]}, {"EPSG:4277", kFrames[6]}, {"EPSG:4284", kFrames[7]}, {"EPSG:4267", kFrames[4]},
      {"EPSG:4301", kFrames[3]}};
  for (const auto& [crs, x] : cases) {
    SCOPED_TRACE(crs);
    geodesy::Network net;
    read_network_text(R"({"schema": "geoanchor.network/1", "crs": ")" + crs + "\", " + kStation + "}", "net.json", net);
    expect_ellipsoid(net.ellipsoid, x);
    ASSERT_TRUE(net.frame.has_value());
  }
  geodesy::Network net;
  read_network_text(R"({"schema": "geoanchor.network/1", "crs": "EPSG:4272", "frame": "NZGD1949", "ellipsoid": "International 1924", )" +
                        std::string(kStation) + "}",
                    "net.json", net);
  EXPECT_EQ(net.frame->name(), "NZGD1949");
  expect_ellipsoid(net.ellipsoid, kFrames[0]);
}

// A stated ellipsoid, a frame and a CRS that disagree are refused, naming
// both; a frame nobody knows is never put on GRS 80.
TEST(NetworkEllipsoid, Issue42_ContradictionsAndUnknownFramesAreRefusedByName) {
  const std::string head = R"({"schema": "geoanchor.network/1", )";
  struct Case {
    std::string json;
    std::vector<std::string> pieces;
  };
  const std::vector<Case> cases = {
      {head + R"("frame": "NZGD1949", "ellipsoid": "GRS80", )" + kStation + "}",
       {"E_NETWORK", "net.json.ellipsoid", "GRS80 contradicts the frame NZGD1949 (PROJ: EPSG:4272 'NZGD49')",
        "which is on International 1924"}},
      {head + R"("frame": "OSGB36", "ellipsoid": {"a_m": 6378388, "rf": 297}, )" + kStation + "}",
       {"net.json.ellipsoid", "custom (a 6378388 m, 1/f 297) contradicts the frame OSGB36", "Airy 1830"}},
      {head + R"("frame": "ED50", "crs": "EPSG:4277", )" + kStation + "}",
       {"net.json.crs", "EPSG:4277 (OSGB36) is on Airy 1830, which contradicts the frame ED50", "International 1924"}},
      {head + R"("frame": "GDA2020", "crs": "EPSG:4283", )" + kStation + "}",
       {"net.json.crs", "EPSG:4283 (GDA94) is on the datum 'Geocentric Datum of Australia 1994' (frame GDA94), not the frame GDA2020"}},
      {head + R"("crs": "EPSG:27700", )" + kStation + "}",
       {"net.json.crs", "is a projected CRS; expected a geographic or geocentric one"}},
      {head + R"("frame": "SITEGRID", )" + kStation + "}",
       {"net.json: stations[0]", "frame SITEGRID, which neither geoanchor's frame catalog nor PROJ's database knows",
        "give the input's \"ellipsoid\""}},
      {head + R"("crs": "EPSG:999999", )" + kStation + "}", {"E_CRS", "net.json.crs", "EPSG:999999"}},
  };
  for (const Case& c : cases) {
    const std::string e = error_of(c.json);
    for (const std::string& piece : c.pieces) EXPECT_NE(e.find(piece), std::string::npos) << piece << " in: " << e;
  }
  // An unknown frame with its ellipsoid stated is read on that ellipsoid.
  geodesy::Network net;
  read_network_text(head + R"("frame": "SITEGRID", "ellipsoid": "Bessel 1841", )" + kStation + "}", "net.json", net);
  expect_ellipsoid(net.ellipsoid, kFrames[2]);
}

// DynaML's (and DNA's) root frame: AGD66 stations on the Australian
// National Spheroid, from PROJ; latitudes and longitudes in a frame nobody
// knows are refused.
TEST(NetworkEllipsoid, Issue42_ADynamlFrameOutsideTheCatalogTakesProjsEllipsoid) {
  const auto file = [](const std::string& frame) {
    return "<?xml version=\"1.0\"?>\n<DnaXmlFormat type=\"Station File\" referenceframe=\"" + frame +
           "\" epoch=\"01.01.1970\">\n  <DnaStation>\n    <Name>A</Name>\n    <Constraints>CCC</Constraints>\n"
           "    <Type>LLh</Type>\n    <StationCoord>\n      <Name>A</Name>\n      <XAxis>-37.300000</XAxis>\n"
           "      <YAxis>144.300000</YAxis>\n      <Height>100.0</Height>\n    </StationCoord>\n  </DnaStation>\n"
           "</DnaXmlFormat>\n";
  };
  geodesy::Network net;
  read_network_text(file("AGD66"), "st.xml", net);
  ASSERT_TRUE(net.ellipsoid_stated);
  expect_ellipsoid(net.ellipsoid, kFrames[9]);
  double ex = 0, ey = 0, ez = 0;
  GeographicLib::Geocentric(6378160.0, 1.0 / 298.25).Forward(-37.5, 144.5, 100.0, ex, ey, ez);  // 37°30′ S 144°30′ E (packed DMS)
  EXPECT_LT((net.stations[0].position - Eigen::Vector3d(ex, ey, ez)).norm(), kSamePosition_m);
  const std::string e = error_of(file("SITEGRID"), "st.xml");
  for (const char* piece : {"st.xml:3", "station A", "LLh in the frame SITEGRID@1970.0",
                            "neither geoanchor's frame catalog nor PROJ's database knows"}) {
    EXPECT_NE(e.find(piece), std::string::npos) << piece << " in: " << e;
  }
}

// A DNA header's frame: DynAdjust's urban sample (149 UTM zone 55
// stations, fixtures/networks/dynadjust/urban-network.stn) with its header
// saying AGD66 instead of GDA94 is read on the Australian National Spheroid:
// each station where PROJ puts its easting, northing and height through UTM
// zone 55 S and geocentric on that ellipsoid (heights orthometric, no geoid:
// taken as they are, as the reader does without one; every station left
// free, since a held one would need the geoid).
TEST(NetworkEllipsoid, Issue42_ADnaHeadersFrameOutsideTheCatalogTakesProjsEllipsoid) {
  std::ifstream in(std::string(GEOANCHOR_FIXTURES_DIR) + "/networks/dynadjust/urban-network.stn", std::ios::binary);
  std::ostringstream content;
  content << in.rdbuf();
  std::string text = content.str();
  const auto at = text.find("GDA94   ");
  ASSERT_NE(at, std::string::npos);
  text.replace(at, 5, "AGD66");  // the same columns
  // Every station free: a held orthometric height needs a geoid, which is not the point here.
  for (std::size_t from = 0; from < text.size();) {
    const std::size_t end = std::min(text.find('\n', from), text.size());
    if (end - from >= 87 && text.compare(from + 24, 3, "UTM") == 0) text.replace(from + 20, 3, "FFF");
    from = end + 1;
  }
  geodesy::Network net;
  read_network_text(text, "urban-agd66.stn", net);
  expect_ellipsoid(net.ellipsoid, kFrames[9]);
  ASSERT_EQ(net.stations.size(), 149u);
  const testing::ProjPipeline utm(
      "+proj=pipeline +step +inv +proj=utm +zone=55 +south +a=6378160 +rf=298.25 +step +proj=cart +a=6378160 +rf=298.25");
  std::istringstream lines(text);
  std::string line;
  std::size_t checked = 0;
  while (std::getline(lines, line)) {
    // DNA 3.01 station records: name 0-19, constraints 20-22, type 24-26,
    // easting 27-46, northing 47-66, height 67-86 (network_dna.cpp).
    if (line.size() < 87 || line[0] == '*' || line[0] == '!' || line.compare(24, 3, "UTM") != 0) continue;
    const std::string id = line.substr(0, line.find(' '));
    const auto s = net.find(id);
    ASSERT_TRUE(s.has_value()) << id;
    const Eigen::Vector3d e_n_h(std::stod(line.substr(27, 20)), std::stod(line.substr(47, 20)), std::stod(line.substr(67, 20)));
    EXPECT_LT((net.stations[*s].position - utm.forward(e_n_h)).norm(), kSamePosition_m) << id;
    ++checked;
  }
  EXPECT_EQ(checked, 149u);
}

}  // namespace
}  // namespace geoanchor::io
