// NGS GNSS Vector Exchange (GVX 1.0) read into a network
// (io/src/network/network_gvx*.cpp): what each record means, against the
// schema's own words ("GVX Schema.xml", github.com/noaa-ngs/ngs_xml) and
// values computed here independently (GeographicLib for the points'
// geocentric coordinates, the covariance from its standard deviations and
// correlations by hand, the epoch by counting days); and the refusal of
// each element, attribute or value geoanchor does not understand, by its
// message.

#include <gtest/gtest.h>

#include <GeographicLib/Geocentric.hpp>

#include <algorithm>
#include <string>
#include <vector>

#include "geoanchor/base/error.hpp"
#include "geoanchor/geodesy/frame_catalog.hpp"
#include "geoanchor/io/network/network_input.hpp"
#include "accuracy.hpp"
#include "gvx_text.hpp"

namespace geoanchor::io {
namespace {

using testing::GvxPoint;
using testing::GvxVector;

// float64 spacing at ECEF magnitude is 9.3e-10 m: two implementations of
// the geodetic-to-geocentric formula agree to a few of those.
constexpr double kEcef_m = 1e-8;
// The decimal year of a GPS second, to 3e-11 yr (1 ms).
constexpr double kEpoch_yr = 3e-11;

Eigen::Vector3d truth(const GvxPoint& p) { return testing::gvx_ecef(p); }

const std::vector<GvxPoint> kPoints = {
    {"P1", "BASE1", 40.0, -105.25, 1650.0, "Keyed-in", "E1"},
    {"P2", "ROV1", 40.01, -105.24, 1660.1234, "Fixed", "E2"},
    {"P3", "ROV2", 39.995, -105.26, 1645.5, "Float", "E2"},
};

std::vector<GvxVector> vectors() {
  GvxVector v1{"V1", "P1", "P2"}, v2{"V2", "P1", "P3"}, v3{"V3", "P2", "P3", "S2"};
  v1.d_m = truth(kPoints[1]) - truth(kPoints[0]);
  v2.d_m = truth(kPoints[2]) - truth(kPoints[0]);
  v3.d_m = truth(kPoints[2]) - truth(kPoints[1]);
  return {v1, v2, v3};
}

std::string base() { return testing::gvx_document(kPoints, vectors()); }

geodesy::Network read(const std::string& text) {
  geodesy::Network net;
  read_network_text(text, "net.gvx", net);
  return net;
}

// `text` with `from` (which must occur) replaced by `to`.
std::string with(std::string text, const std::string& from, const std::string& to) {
  const auto at = text.find(from);
  if (at == std::string::npos) throw std::runtime_error("test text has no " + from);
  return text.replace(at, from.size(), to);
}

std::string meta(const geodesy::NetworkMeasurement& m, const std::string& key) {
  for (const auto& [k, v] : m.metadata) {
    if (k == key) return v;
  }
  return "(none)";
}

TEST(NetworkGvx, DetectedByItsRootElement) {
  EXPECT_EQ(detect_network_format(base(), "x.xml"), NetworkFormat::gvx);
  EXPECT_EQ(detect_network_format("<!-- c --><GVX VERSION=\"1.0\"/>", "x.xml"), NetworkFormat::gvx);
  EXPECT_THROW(detect_network_format("<GVXX/>", "x.xml"), Error);
}

// POINT: the station NAME at its geodetic coordinates on GRS 80 (NAD 83's
// ellipsoid), free; the network's frame the first point's, at its EPOCH.
TEST(NetworkGvx, PointsAreFreeStationsAtTheirCoordinates) {
  const geodesy::Network net = read(base());
  ASSERT_EQ(net.stations.size(), 3u);
  for (std::size_t i = 0; i < 3; ++i) {
    EXPECT_EQ(net.stations[i].id, kPoints[i].name);
    EXPECT_LT((net.stations[i].position - truth(kPoints[i])).norm(), kEcef_m) << kPoints[i].name;
    EXPECT_EQ(net.stations[i].constraint.text(), "FFF");
  }
  ASSERT_TRUE(net.frame);
  EXPECT_EQ(net.frame->to_string(), "NAD83(2011)@2010.0");
  EXPECT_EQ(net.ellipsoid.name(), geodesy::Ellipsoid::grs80().name());
  EXPECT_TRUE(net.warnings.empty()) << net.warnings.front();
}

// GNSS_VECTOR: ECEF_DELTAS from the initial to the terminal point, the
// covariance from SDX..SDZ (m) and the correlations PXY, PXZ, PYZ.
TEST(NetworkGvx, VectorIsABaselineWithItsCovariance) {
  const geodesy::Network net = read(base());
  ASSERT_EQ(net.measurements.size(), 3u);
  const auto& m = net.measurements[0];
  EXPECT_EQ(m.kind, geodesy::MeasurementKind::gnss_baselines);
  EXPECT_EQ(net.stations[m.stations[0]].id, "BASE1");
  EXPECT_EQ(net.stations[m.stations[1]].id, "ROV1");
  // to − from, as the truth says (the deltas are written with 17 digits).
  EXPECT_LT((Eigen::Vector3d(m.value) - (truth(kPoints[1]) - truth(kPoints[0]))).norm(), kEcef_m);
  // By hand: σx σy ρxy = 0.002·0.003·0.5 = 3e-6; σx σz ρxz = 0.002·0.004·(−0.25) = −2e-6; σy σz ρyz = 0.003·0.004·0.1 = 1.2e-6.
  Eigen::Matrix3d expected;
  expected << 4e-6, 3e-6, -2e-6, 3e-6, 9e-6, 1.2e-6, -2e-6, 1.2e-6, 16e-6;
  constexpr double kCov_m2 = 1e-18;  // the products above are exact to a few ulps of 1e-6
  EXPECT_LT(testing::max_abs_component(m.covariance - expected), kCov_m2) << m.covariance;  // NaN fails
  const std::string t = base();
  const auto line = std::count(t.begin(), t.begin() + static_cast<std::ptrdiff_t>(t.find("<GNSS_VECTOR>")), '\n') + 1;
  EXPECT_EQ(m.source, "net.gvx:" + std::to_string(line));
}

// The vector's frame: its ORBIT's REFERENCE_SYSTEM (ISO 131 = WGS 84
// (G1762)) at the middle of OBSERVATION_TIME. 2021-03-07T06:00 is 65 days
// and 6 hours into 2021 (31 + 28 + 6 days): 2021 + 65.25/365.
TEST(NetworkGvx, VectorFrameIsItsOrbitsAtTheMiddleOfItsObservation) {
  const geodesy::Network net = read(base());
  const auto& f = net.measurements[0].frame;
  ASSERT_TRUE(f);
  EXPECT_EQ(f->name(), "WGS84(G1762)");
  ASSERT_TRUE(f->epoch());
  EXPECT_NEAR(f->epoch()->year, 2021.0 + 65.25 / 365.0, kEpoch_yr);
  // With one REFERENCE_SYSTEM in the file, an ORBIT naming none is in it.
  std::string one = base();
  one = with(one, "<REFERENCE_SYSTEM>\n    <ID>131</ID>", "<REMARK>x</REMARK><!--");
  one = with(one, "<REMARK>broadcast orbits</REMARK>\n  </REFERENCE_SYSTEM>", "-->");
  for (int k = 0; k < 3; ++k) one = with(one, "<REFERENCE_SYSTEM_ID>131</REFERENCE_SYSTEM_ID>", "");
  const geodesy::Network single = read(one);
  EXPECT_EQ(single.measurements[0].frame->name(), "NAD83(2011)");
}

// SOLUTION_TYPE with the terminal point's POINT_TYPE: RTK + Fixed is
// fixed, post-processed + Float (V3 ends at ROV2, a Float point) float;
// RTK + Float float; Code dgps; Keyed-in states nothing.
TEST(NetworkGvx, SolutionTypeFromTheSetupAndTheTerminalPoint) {
  const geodesy::Network net = read(base());
  EXPECT_EQ(net.measurements[0].solution, geodesy::GnssSolution::fixed);
  EXPECT_EQ(net.measurements[1].solution, geodesy::GnssSolution::floating);
  EXPECT_EQ(net.measurements[2].solution, geodesy::GnssSolution::floating);
  std::vector<GvxPoint> points = kPoints;
  points[2].point_type = "Fixed";
  EXPECT_EQ(read(testing::gvx_document(points, vectors())).measurements[2].solution, geodesy::GnssSolution::ppk);
  points[2].point_type = "Code";
  EXPECT_EQ(read(testing::gvx_document(points, vectors())).measurements[1].solution, geodesy::GnssSolution::dgps);
  points[2].point_type = "Keyed-in";
  EXPECT_FALSE(read(testing::gvx_document(points, vectors())).measurements[1].solution);
  points[2].point_type = "PartialFixed";
  EXPECT_EQ(read(testing::gvx_document(points, vectors())).measurements[1].solution, geodesy::GnssSolution::floating);
}

// The metadata a user wants back: receiver, antenna, PDOP, solution type,
// occupation times, the setup, the file's source and project.
TEST(NetworkGvx, MetadataKeepsWhatIsNotMapped) {
  const geodesy::Network net = read(base());
  const auto& m = net.measurements[0];
  EXPECT_EQ(meta(m, "GNSS_VECTOR/ID"), "V1");
  EXPECT_EQ(meta(m, "GNSS_VECTOR/OBSERVATION_TIME/START"), "2021-03-07T00:00:00.00");
  EXPECT_EQ(meta(m, "GNSS_VECTOR/OBSERVATION_TIME/END"), "2021-03-07T12:00:00.00");
  EXPECT_EQ(meta(m, "GNSS_VECTOR/QUALITY_CONTROL/DILUTION_PRECISION/PDOP"), "1.6");
  EXPECT_EQ(meta(m, "GNSS_VECTOR/QUALITY_CONTROL/SATELLITE_USED/TOTAL"), "17");
  EXPECT_EQ(meta(m, "GNSS_VECTOR/QUALITY_CONTROL/ORBIT/TYPE"), "Broadcast");
  EXPECT_EQ(meta(m, "SURVEY_SETUP/SOLUTION_TYPE"), "NetworkRTK");
  EXPECT_EQ(meta(m, "SURVEY_SETUP/NETWORKRTK/MOUNT_POINT"), "VRS_RTCM3");
  EXPECT_EQ(meta(m, "INITIAL_POINT/EQUIPMENT/RECEIVER/TYPE"), "TRIMBLE R10");
  EXPECT_EQ(meta(m, "TERMINAL_POINT/EQUIPMENT/RECEIVER/TYPE"), "LEICA GS18");
  EXPECT_EQ(meta(m, "TERMINAL_POINT/EQUIPMENT/ANTENNA/TYPE"), "LEIGS18         NONE");
  EXPECT_EQ(meta(m, "TERMINAL_POINT/POINT_TYPE"), "Fixed");
  EXPECT_EQ(meta(m, "TERMINAL_POINT/ARP_HEIGHT"), "1.8000");
  EXPECT_EQ(meta(m, "TERMINAL_POINT/COORDINATES/CORRELATION_MATRIX_LOCAL/SDU"), "0.0200");
  EXPECT_EQ(meta(m, "REFERENCE_SYSTEM/NAME"), "WGS 84 (G1762)");
  EXPECT_EQ(meta(m, "SOURCE_DATA/APPLICATION/NAME"), "Field App");
  EXPECT_EQ(meta(m, "PROJECT_INFORMATION/PARTY_CHIEF"), "A. Chief");
  EXPECT_EQ(meta(m, "REMARK"), "end of file");
  // Mapped, so not repeated: the deltas, the covariance, the references, the points' coordinates.
  for (const auto& [k, v] : m.metadata) {
    EXPECT_EQ(k.find("ECEF_DELTAS"), std::string::npos) << k;
    EXPECT_EQ(k.find("CORRELATION_MATRIX/"), std::string::npos) << k;
    EXPECT_EQ(k.find("_POINT_ID"), std::string::npos) << k;
    EXPECT_EQ(k.find("GEODETIC_COORDINATES"), std::string::npos) << k;
  }
}

// NGS's own writer (ngs_xml_writer.py) writes every optional element,
// empty when unset, and the deltas and correlations inside QUALITY_CONTROL:
// read as the schema's layout.
TEST(NetworkGvx, NgsWritersLayoutReadsTheSame) {
  std::string t = base();
  t = with(t, "<CODE>MON</CODE>", "<CODE/>");
  t = with(t, "<REMARK>written by geoanchor's tests</REMARK>", "<REMARK></REMARK>");
  t = with(t, "<CORRECTOR_AGE>1</CORRECTOR_AGE>\n    </QUALITY_CONTROL>\n    <ECEF_DELTAS>",
           "<CORRECTOR_AGE>1</CORRECTOR_AGE>\n    <ECEF_DELTAS>");
  t = with(t, "</CORRELATION_MATRIX>\n  </GNSS_VECTOR>", "</CORRELATION_MATRIX>\n    </QUALITY_CONTROL>\n  </GNSS_VECTOR>");
  const geodesy::Network a = read(base()), b = read(t);
  ASSERT_EQ(a.measurements.size(), b.measurements.size());
  EXPECT_EQ(a.measurements[0].value, b.measurements[0].value);
  EXPECT_EQ(a.measurements[0].covariance, b.measurements[0].covariance);
  EXPECT_EQ(meta(b.measurements[0], "INITIAL_POINT/CODE"), "(none)");
  EXPECT_EQ(meta(a.measurements[0], "INITIAL_POINT/CODE"), "MON");
}

// Several POINT records of one mark are one station (the first record's
// coordinates); one more than 1 mm away is named in a warning, and so is a
// point no vector uses.
TEST(NetworkGvx, RecordsOfOneMarkAreOneStation) {
  std::vector<GvxPoint> points = kPoints;
  GvxPoint again = points[1];
  again.id = "P2B";
  again.h_m += 0.02;
  points.push_back(again);
  points.push_back({"P9", "LONELY", 40.1, -105.1, 1500.0, "Keyed-in", "E1"});
  std::vector<GvxVector> v = vectors();
  v[2].from = "P2B";
  const geodesy::Network net = read(testing::gvx_document(points, v));
  ASSERT_EQ(net.stations.size(), 3u);
  EXPECT_LT((net.stations[1].position - truth(kPoints[1])).norm(), kEcef_m);
  EXPECT_EQ(net.measurements[2].stations[0], net.measurements[0].stations[1]);
  ASSERT_EQ(net.warnings.size(), 2u);
  EXPECT_NE(net.warnings[0].find("1 POINT record(s) no GNSS_VECTOR uses are no stations (POINT P9 (LONELY"), std::string::npos)
      << net.warnings[0];
  EXPECT_NE(net.warnings[1].find("POINT P2B (net.gvx:"), std::string::npos) << net.warnings[1];
  EXPECT_NE(net.warnings[1].find("0.0200 m from POINT P2 of ROV1"), std::string::npos) << net.warnings[1];
}

// A station another input defines elsewhere (more than 1 mm away) is
// refused naming both, as for every input (NetworkBuilder).
TEST(NetworkGvx, AStationDefinedElsewhereMustAgree) {
  geodesy::Network net;
  const Eigen::Vector3d p = truth(kPoints[0]) + Eigen::Vector3d(0.0, 0.0, 0.05);
  read_network_text(R"({"schema": "geoanchor.network/1", "frame": "NAD83(2011)@2010.0", "stations": [{"id": "BASE1", "x_m": )" +
                        testing::gvx_number(p.x()) + ", \"y_m\": " + testing::gvx_number(p.y()) + ", \"z_m\": " +
                        testing::gvx_number(p.z()) + R"(, "constraint": "FFF"}], "measurements": []})",
                    "s.json", net);
  try {
    read_network_text(base(), "net.gvx", net);
    FAIL() << "accepted";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), "E_STATION_DUPLICATE");
    EXPECT_NE(std::string(e.what()).find("station BASE1 is defined again, differently from s.json"), std::string::npos) << e.what();
  }
}

struct Refusal {
  const char* what;
  const char* from;  // text of the base file (an opening tag when `whole`)
  const char* to;
  const char* message;
  bool whole = false;  // `from` through its closing tag is replaced
};

// Each element, attribute or value refused, by its message (E_GVX unless
// said). `from` → `to` in the base file.
const Refusal kRefusals[] = {
    {"no VERSION", "<GVX VERSION=\"1.0\">", "<GVX>", "<GVX> has no VERSION; expected VERSION=\"1.0\""},
    {"another VERSION", "VERSION=\"1.0\"", "VERSION=\"2.0\"", "<GVX> VERSION=\"2.0\"; geoanchor reads GVX 1.0"},
    {"a namespace", "VERSION=\"1.0\"", "VERSION=\"1.0\" xmlns=\"urn:x\"", "<GVX> attribute xmlns=\"urn:x\" is not read"},
    {"an unknown record", "<SOURCE_DATA>", "<FOO/><SOURCE_DATA>", "<FOO> in <GVX> is not an element of GVX 1.0; expected SOURCE_DATA"},
    {"SESSION", "<REMARK>end of file</REMARK>", "<SESSION ID=\"S\" TOTAL_VECTORS=\"2\"/>", "<SESSION> (the cross-correlations"},
    {"an unknown element", "<PDOP>1.6</PDOP>", "<PDOPX>1.6</PDOPX>",
     "<PDOPX> in <DILUTION_PRECISION> (GNSS_VECTOR at line"},
    {"an attribute on an element", "<DX>", "<DX unit=\"mm\">", "<DX> has the attribute unit=\"mm\""},
    {"text in a container", "<ECEF_DELTAS>", "<ECEF_DELTAS>12", "text '12' in <ECEF_DELTAS>, which holds elements"},
    {"an element twice", "<RMS>0.012</RMS>", "<RMS>0.012</RMS><RMS>0.013</RMS>", "GNSS_VECTOR/QUALITY_CONTROL/RMS is given twice"},
    {"deltas in both places", "<CORRECTOR_AGE>1</CORRECTOR_AGE>", "<CORRECTOR_AGE>1</CORRECTOR_AGE><ECEF_DELTAS><DX>1</DX></ECEF_DELTAS>",
     "GNSS_VECTOR/ECEF_DELTAS/DX is given twice"},
    {"a decimal comma", "<RMS>0.012</RMS>", "<RMS>0,012</RMS>", "GNSS_VECTOR/QUALITY_CONTROL/RMS='0,012' is not a finite number"},
    {"NaN", "<SDX>0.002</SDX>", "<SDX>NaN</SDX>", "GNSS_VECTOR/CORRELATION_MATRIX/SDX='NaN' is not a finite number"},
    {"INF", "<DX>", "<DX>INF</DX>", "GNSS_VECTOR/ECEF_DELTAS/DX='INF' is not a finite number", true},
    {"a solution type", "<SOLUTION_TYPE>NetworkRTK</SOLUTION_TYPE>", "<SOLUTION_TYPE>RTK</SOLUTION_TYPE>",
     "SURVEY_SETUP/SOLUTION_TYPE='RTK' is not one of Single-baseRTK, NetworkRTK, Post-processed"},
    {"feet", "<NAME>meters</NAME>", "<NAME>US survey feet</NAME>", "REFERENCE_SYSTEM/LINEAR_UNIT/NAME='US survey feet' is not one of meters, metres"},
    {"radians", "<NAME>decimal degrees</NAME>", "<NAME>radians</NAME>", "REFERENCE_SYSTEM/ANGULAR_UNIT/NAME='radians' is not one of decimal degrees"},
    {"a point type", "<POINT_TYPE>Fixed</POINT_TYPE>", "<POINT_TYPE>fixed</POINT_TYPE>", "POINT/POINT_TYPE='fixed' is not one of Keyed-in"},
    {"an orbit type", "<TYPE>Broadcast</TYPE>", "<TYPE>Precise</TYPE>", "GNSS_VECTOR/QUALITY_CONTROL/ORBIT/TYPE='Precise' is not one of"},
    {"a network RTK type", "<TYPE>VRS</TYPE>", "<TYPE>PRS</TYPE>", "SURVEY_SETUP/NETWORKRTK/TYPE='PRS' is not one of VRS"},
    {"a calibration type", "<CALIBRATION_TYPE>Absolute</CALIBRATION_TYPE>", "<CALIBRATION_TYPE>abs</CALIBRATION_TYPE>",
     "EQUIPMENT/ANTENNA/CALIBRATION_TYPE='abs' is not one of Absolute, Relative, Unknown"},
    {"a network location", "<NETWORK_LOCATION>Inside</NETWORK_LOCATION>", "<NETWORK_LOCATION>In</NETWORK_LOCATION>",
     "POINT/NETWORK_LOCATION='In' is not one of Inside, Outside, Unknown"},
    {"a day that does not exist", "<START>2021-03-07T00:00:00.00</START>", "<START>2021-02-29T00:00:00.00</START>",
     "GNSS_VECTOR/OBSERVATION_TIME/START='2021-02-29T00:00:00.00' is not a date and time"},
    {"a time zone", "<START>2021-03-07T00:00:00.00</START>", "<START>2021-03-07T00:00:00.00+01:00</START>", "is not a date and time"},
    {"a leap second", "<END>2021-03-07T12:00:00.00</END>", "<END>2021-03-07T12:00:60.00</END>", "is not a date and time"},
    {"an integer", "<EPOCHS_USED>180</EPOCHS_USED>", "<EPOCHS_USED>180.5</EPOCHS_USED>", "QUALITY_CONTROL/EPOCHS_USED='180.5' is not an integer"},
    {"a port", "<IP_PORT>2101</IP_PORT>", "<IP_PORT>-1</IP_PORT>", "SURVEY_SETUP/NETWORKRTK/IP_PORT='-1' is not a whole number"},
    {"a boolean", "<TILT_COMPENSATOR>0</TILT_COMPENSATOR>", "<TILT_COMPENSATOR>no</TILT_COMPENSATOR>", "POINT/TILT_COMPENSATOR='no' is not a boolean"},
    {"an identifier", "<ID>V1</ID>", "<ID>V-1</ID>", "GNSS_VECTOR/ID='V-1' is not an identifier"},
    {"a second SOURCE_DATA", "<PROJECT_INFORMATION>", "<SOURCE_DATA/><PROJECT_INFORMATION>", "a second <SOURCE_DATA> (the first at line 3)"},
    {"END before START", "<END>2021-03-07T12:00:00.00</END>", "<END>2021-03-06T12:00:00.00</END>",
     "GNSS_VECTOR V1: OBSERVATION_TIME END 2021-03-06T12:00:00.00 is before its START"},
    {"no DX", "<DX>", "", "GNSS_VECTOR V1 has no ECEF_DELTAS/DX (or it is empty); GVX 1.0 requires it", true},
    {"an empty DZ", "<DZ>", "<DZ></DZ>", "GNSS_VECTOR V1 has no ECEF_DELTAS/DZ (or it is empty); GVX 1.0 requires it", true},
    {"no SDZ", "<SDZ>0.004</SDZ>", "", "GNSS_VECTOR V1 has no CORRELATION_MATRIX/SDZ"},
    {"no OBSERVATION_TIME", "<START>2021-03-07T00:00:00.00</START>", "", "GNSS_VECTOR V1 has no OBSERVATION_TIME/START"},
    {"no LINEAR_UNIT", "<LINEAR_UNIT><NAME>meters</NAME><SIGNIFICANT_DIGITS>4</SIGNIFICANT_DIGITS></LINEAR_UNIT>", "",
     "REFERENCE_SYSTEM 126 has no LINEAR_UNIT/NAME"},
    {"no EPOCH", "<EPOCH>2010.0000</EPOCH>", "", "POINT P1 has no COORDINATES/EPOCH"},
    {"a zero SD", "<SDX>0.002</SDX>", "<SDX>0</SDX>", "GNSS_VECTOR V1: CORRELATION_MATRIX SDX=0 m must be > 0"},
    {"a negative SD", "<SDY>0.003</SDY>", "<SDY>-0.003</SDY>", "CORRELATION_MATRIX SDY=-0.003 m must be > 0"},
    {"a correlation above 1", "<PXY>0.5</PXY>", "<PXY>1.5</PXY>", "CORRELATION_MATRIX PXY=1.5 is a correlation coefficient: expected one in [-1, 1]"},
    {"correlations not positive definite", "", "", "(set in refusal_text)"},
    {"an ISO number geoanchor does not know", "<ID>126</ID>", "<ID>216</ID>", "REFERENCE_SYSTEM ID 216 (NAME 'NAD 83(2011)') is not a geodetic datum"},
    {"a frame the catalog cannot reach", "<ID>131</ID>\n    <NAME>WGS 84 (G1762)</NAME>", "<ID>724</ID>\n    <NAME>IGb14</NAME>",
     "REFERENCE_SYSTEM ID 724 is IGb14, a frame geoanchor's catalog does not reach"},
    {"a NAME contradicting the ID", "<NAME>NAD 83(2011)</NAME>", "<NAME>ITRF2014</NAME>",
     "REFERENCE_SYSTEM ID 126 is NAD83(2011) but its NAME 'ITRF2014' is ITRF2014"},
    {"an unknown point", "<INITIAL_POINT_ID>P1</INITIAL_POINT_ID>", "<INITIAL_POINT_ID>P7</INITIAL_POINT_ID>",
     "GNSS_VECTOR V1: INITIAL_POINT_ID 'P7' names no POINT of the file"},
    {"an unknown setup", "<SURVEY_SETUP_ID>S1</SURVEY_SETUP_ID>", "<SURVEY_SETUP_ID>S7</SURVEY_SETUP_ID>",
     "SURVEY_SETUP_ID 'S7' names no SURVEY_SETUP of the file"},
    {"an unknown equipment", "<EQUIPMENT_ID>E2</EQUIPMENT_ID>", "<EQUIPMENT_ID>E7</EQUIPMENT_ID>",
     "POINT P2: EQUIPMENT_ID 'E7' names no EQUIPMENT of the file"},
    {"a setup named as a point", "<TERMINAL_POINT_ID>P2</TERMINAL_POINT_ID>", "<TERMINAL_POINT_ID>S1</TERMINAL_POINT_ID>",
     "TERMINAL_POINT_ID 'S1' names no POINT of the file"},
    {"an orbit frame unknown", "<REFERENCE_SYSTEM_ID>131</REFERENCE_SYSTEM_ID>", "<REFERENCE_SYSTEM_ID>132</REFERENCE_SYSTEM_ID>",
     "GNSS_VECTOR V1: QUALITY_CONTROL/ORBIT/REFERENCE_SYSTEM_ID '132' names no REFERENCE_SYSTEM"},
    {"no orbit frame among two", "<REFERENCE_SYSTEM_ID>131</REFERENCE_SYSTEM_ID>", "",
     "GNSS_VECTOR V1: its ORBIT names no REFERENCE_SYSTEM_ID and the file has 2 REFERENCE_SYSTEMs"},
    {"a duplicate ID", "<ID>E2</ID>", "<ID>E1</ID>", "EQUIPMENT ID E1 is the ID of the EQUIPMENT at line"},
    {"an ID shared across records", "<ID>S2</ID>", "<ID>P1</ID>", "is the ID of the SURVEY_SETUP at line"},
    {"a vector to itself", "<TERMINAL_POINT_ID>P2</TERMINAL_POINT_ID>", "<TERMINAL_POINT_ID>P1</TERMINAL_POINT_ID>",
     "GNSS_VECTOR V1 runs from point BASE1 to itself"},
    {"a latitude", "<LATITUDE>40</LATITUDE>", "<LATITUDE>91</LATITUDE>", "POINT P1: LATITUDE 91 not in [-90, 90] degrees"},
    {"a longitude", "<LONGITUDE>-105.25</LONGITUDE>", "<LONGITUDE>-400</LONGITUDE>", "POINT P1: LONGITUDE -400 not in [-360, 360] degrees"},
    {"a height", "<ELLIPSOIDAL_HEIGHT>1650</ELLIPSOIDAL_HEIGHT>", "<ELLIPSOIDAL_HEIGHT>1e9</ELLIPSOIDAL_HEIGHT>",
     "POINT P1: ELLIPSOIDAL_HEIGHT 1e+09 m is not a height on the Earth"},
    {"geocentric off the geodetic", "</GEODETIC_COORDINATES>",
     "</GEODETIC_COORDINATES><GEOCENTRIC_COORDINATES><X>-1281000</X><Y>-4712000</Y><Z>4078000</Z></GEOCENTRIC_COORDINATES>",
     "m from its GEODETIC_COORDINATES on "},
    {"geocentric in part", "</GEODETIC_COORDINATES>", "</GEODETIC_COORDINATES><GEOCENTRIC_COORDINATES><X>1</X></GEOCENTRIC_COORDINATES>",
     "POINT P1 has no COORDINATES/GEOCENTRIC_COORDINATES/Y"},
    {"not XML", "</GVX>", "</GVY>", "not well-formed"},
};

std::string refusal_text(const Refusal& r) {
  if (std::string(r.what) == "correlations not positive definite") {
    // ρxy = ρxz = 0.9, ρyz = −0.9: the correlation matrix times (1, −1, −1)
    // is −0.8 times it, a negative eigenvalue (by hand).
    std::string t = with(base(), "<PXY>0.5</PXY>", "<PXY>0.9</PXY>");
    t = with(t, "<PXZ>-0.25</PXZ>", "<PXZ>0.9</PXZ>");
    return with(t, "<PYZ>0.1</PYZ>", "<PYZ>-0.9</PYZ>");
  }
  if (r.whole) {
    std::string t = base();
    const std::string open = r.from, close = "</" + open.substr(1);
    const auto at = t.find(open);
    const auto end = t.find(close, at);
    if (at == std::string::npos || end == std::string::npos) throw std::runtime_error("test text has no " + open);
    return t.replace(at, end + close.size() - at, r.to);
  }
  return with(base(), r.from, r.to);
}

TEST(NetworkGvx, EachRefusalNamesWhatAndWhere) {
  for (const Refusal& r : kRefusals) {
    SCOPED_TRACE(r.what);
    const std::string text = refusal_text(r);
    try {
      (void)read(text);
      ADD_FAILURE() << "accepted";
    } catch (const Error& e) {
      EXPECT_EQ(e.kind(), ErrorKind::input);
      const std::string msg = e.what();
      EXPECT_EQ(msg.rfind("net.gvx:", 0), 0u) << msg;
      if (std::string(r.what) == "correlations not positive definite") {
        EXPECT_NE(msg.find("GNSS_VECTOR V1: CORRELATION_MATRIX is not positive definite: smallest eigenvalue -"), std::string::npos) << msg;
      } else {
        EXPECT_NE(msg.find(r.message), std::string::npos) << msg;
      }
    }
  }
}

// The fuzz corpus's seeds in both layouts are read (the same first
// vector), and its SESSION seed is refused.
TEST(NetworkGvx, TheFuzzSeedsOfBothLayoutsAreRead) {
  const std::string dir = std::string(GEOANCHOR_SOURCE_DIR) + "/fuzz/corpus/gvx/";
  const geodesy::Network a = read_network({dir + "schema_layout.gvx"});
  const geodesy::Network b = read_network({dir + "ngs_writer_layout.gvx"});
  ASSERT_EQ(a.measurements.size(), 2u);
  ASSERT_EQ(b.measurements.size(), 2u);
  EXPECT_EQ(a.measurements[0].value, b.measurements[0].value);
  EXPECT_EQ(a.measurements[0].covariance, b.measurements[0].covariance);
  EXPECT_THROW((void)read_network({dir + "session_refused.gvx"}), Error);
}

TEST(NetworkGvx, RefusesALocalNetworkAndAFileWithoutVectors) {
  geodesy::Network net;
  net.space = geodesy::NetworkSpace::local;
  net.stations.push_back({});
  try {
    read_network_text(base(), "net.gvx", net);
    FAIL() << "accepted";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("net.gvx:1: GNSS vectors in ECEF, but the other inputs are a local network"), std::string::npos)
        << e.what();
  }
  try {
    (void)read(testing::gvx_document(kPoints, {}));
    FAIL() << "accepted";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("no GNSS_VECTOR: nothing to adjust"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace geoanchor::io
