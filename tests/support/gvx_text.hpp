#pragma once
// NGS GVX 1.0 files written by the tests from a truth (points and vectors),
// as the schema lays them out ("GVX Schema.xml" of github.com/noaa-ngs/ngs_xml):
// SOURCE_DATA, PROJECT_INFORMATION, two REFERENCE_SYSTEMs (ISO Geodetic
// Register 126 NAD 83(2011) for the points, 131 WGS 84 (G1762) for the
// orbits), two EQUIPMENT pairs, two SURVEY_SETUPs (S1 network RTK, S2
// post-processed), the POINTs and the GNSS_VECTORs. Numbers are written
// with 17 significant digits, so that a JSON file written from the same
// doubles holds the same values.

#include <Eigen/Core>

#include <GeographicLib/Geocentric.hpp>

#include <cstdio>
#include <string>
#include <vector>

namespace geoanchor::testing {

struct GvxPoint {
  std::string id, name;
  double lat_deg = 0.0, lon_deg = 0.0, h_m = 0.0;
  std::string point_type = "Fixed";
  std::string equipment = "E1";
};

struct GvxVector {
  std::string id, from, to;  // POINT IDs
  std::string setup = "S1";
  Eigen::Vector3d d_m = Eigen::Vector3d::Zero();
  double sdx_m = 0.002, sdy_m = 0.003, sdz_m = 0.004, pxy = 0.5, pxz = -0.25, pyz = 0.1;
  std::string start = "2021-03-07T00:00:00.00", end = "2021-03-07T12:00:00.00";
  std::string orbit_reference_system = "131";
};

inline std::string gvx_number(double v) {
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.17g", v);
  return buf;
}

// Standard deviations and correlations: short decimals, written so (15
// digits read back to the same double).
inline std::string gvx_short(double v) {
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.15g", v);
  return buf;
}

inline std::string gvx_point(const GvxPoint& p) {
  return "  <POINT>\n    <ID>" + p.id + "</ID>\n    <NAME>" + p.name + "</NAME>\n    <CODE>MON</CODE>\n    <EQUIPMENT_ID>" +
         p.equipment + "</EQUIPMENT_ID>\n    <ARP_HEIGHT>1.8000</ARP_HEIGHT>\n    <POINT_TYPE>" + p.point_type +
         "</POINT_TYPE>\n    <NETWORK_LOCATION>Inside</NETWORK_LOCATION>\n    <TILT_COMPENSATOR>0</TILT_COMPENSATOR>\n"
         "    <COORDINATES>\n      <REFERENCE_SYSTEM_ID>126</REFERENCE_SYSTEM_ID>\n      <EPOCH>2010.0000</EPOCH>\n"
         "      <GEODETIC_COORDINATES>\n        <LATITUDE>" + gvx_number(p.lat_deg) + "</LATITUDE>\n        <LONGITUDE>" +
         gvx_number(p.lon_deg) + "</LONGITUDE>\n        <ELLIPSOIDAL_HEIGHT>" + gvx_number(p.h_m) +
         "</ELLIPSOIDAL_HEIGHT>\n      </GEODETIC_COORDINATES>\n      <CORRELATION_MATRIX_LOCAL>\n"
         "        <SDN>0.0100</SDN><SDE>0.0100</SDE><SDU>0.0200</SDU><PNE>0.000000</PNE><PNU>0.000000</PNU><PEU>0.000000</PEU>\n"
         "      </CORRELATION_MATRIX_LOCAL>\n    </COORDINATES>\n  </POINT>\n";
}

inline std::string gvx_vector(const GvxVector& v) {
  return "  <GNSS_VECTOR>\n    <ID>" + v.id + "</ID>\n    <INITIAL_POINT_ID>" + v.from + "</INITIAL_POINT_ID>\n    <TERMINAL_POINT_ID>" +
         v.to + "</TERMINAL_POINT_ID>\n    <SURVEY_SETUP_ID>" + v.setup +
         "</SURVEY_SETUP_ID>\n    <OBSERVATION_TIME>\n      <START>" + v.start + "</START>\n      <END>" + v.end +
         "</END>\n      <UTC_OFFSET>-7</UTC_OFFSET>\n      <LEAP_SECONDS>18</LEAP_SECONDS>\n    </OBSERVATION_TIME>\n"
         "    <QUALITY_CONTROL>\n      <EPOCHS_USED>180</EPOCHS_USED>\n      <MASK><ELEVATION>10</ELEVATION><PDOP_MASK>6</PDOP_MASK></MASK>\n"
         "      <RMS>0.012</RMS>\n      <DILUTION_PRECISION><GDOP>1.9</GDOP><HDOP>0.9</HDOP><PDOP>1.6</PDOP><TDOP>1.0</TDOP><VDOP>1.3</VDOP></DILUTION_PRECISION>\n"
         "      <SATELLITE_USED><TOTAL>17</TOTAL><GPS>9</GPS><GLONASS>6</GLONASS><GALILEO>2</GALILEO><QZSS>0</QZSS><BEIDOU>0</BEIDOU></SATELLITE_USED>\n"
         "      <ORBIT><TYPE>Broadcast</TYPE><SOURCE>Broadcast</SOURCE><REFERENCE_SYSTEM_ID>" + v.orbit_reference_system +
         "</REFERENCE_SYSTEM_ID></ORBIT>\n      <CORRECTOR_AGE>1</CORRECTOR_AGE>\n    </QUALITY_CONTROL>\n"
         "    <ECEF_DELTAS>\n      <DX>" + gvx_number(v.d_m.x()) + "</DX>\n      <DY>" + gvx_number(v.d_m.y()) + "</DY>\n      <DZ>" +
         gvx_number(v.d_m.z()) + "</DZ>\n    </ECEF_DELTAS>\n    <CORRELATION_MATRIX>\n      <SDX>" + gvx_short(v.sdx_m) +
         "</SDX>\n      <SDY>" + gvx_short(v.sdy_m) + "</SDY>\n      <SDZ>" + gvx_short(v.sdz_m) + "</SDZ>\n      <PXY>" +
         gvx_short(v.pxy) + "</PXY>\n      <PXZ>" + gvx_short(v.pxz) + "</PXZ>\n      <PYZ>" + gvx_short(v.pyz) +
         "</PYZ>\n    </CORRELATION_MATRIX>\n  </GNSS_VECTOR>\n";
}

inline std::string gvx_document(const std::vector<GvxPoint>& points, const std::vector<GvxVector>& vectors) {
  std::string out = R"(<?xml version="1.0" encoding="UTF-8"?>
<GVX VERSION="1.0">
  <SOURCE_DATA>
    <NAME>job_066.job</NAME>
    <CREATED_DATE>2021-03-07T18:00:00.00</CREATED_DATE>
    <APPLICATION><NAME>Field App</NAME><VERSION>5.2</VERSION><MANUFACTURER>Maker</MANUFACTURER><MANUFACTURER_URL>https://example.com</MANUFACTURER_URL></APPLICATION>
    <CONVERTED_BY><SOFTWARE_NAME>Converter</SOFTWARE_NAME><VERSION>1.0</VERSION><SOFTWARE_URL>https://example.com/c</SOFTWARE_URL><CONVERTED_DATE>2021-03-08T09:00:00.00</CONVERTED_DATE></CONVERTED_BY>
  </SOURCE_DATA>
  <PROJECT_INFORMATION>
    <TITLE>Test network</TITLE>
    <EMAIL_ADDRESS>chief@example.com</EMAIL_ADDRESS>
    <PARTY_CHIEF>A. Chief</PARTY_CHIEF>
    <AGENCY>Survey Co</AGENCY>
    <START_DATE>2021-03-07T00:00:00.00</START_DATE>
    <END_DATE>2021-03-07T12:00:00.00</END_DATE>
    <REMARK>written by geoanchor's tests</REMARK>
  </PROJECT_INFORMATION>
  <REFERENCE_SYSTEM>
    <ID>126</ID>
    <CODE>EPSG:6319</CODE>
    <NAME>NAD 83(2011)</NAME>
    <LINEAR_UNIT><NAME>meters</NAME><SIGNIFICANT_DIGITS>4</SIGNIFICANT_DIGITS></LINEAR_UNIT>
    <ANGULAR_UNIT><NAME>decimal degrees</NAME><SIGNIFICANT_DIGITS>10</SIGNIFICANT_DIGITS></ANGULAR_UNIT>
  </REFERENCE_SYSTEM>
  <REFERENCE_SYSTEM>
    <ID>131</ID>
    <NAME>WGS 84 (G1762)</NAME>
    <LINEAR_UNIT><NAME>metres</NAME></LINEAR_UNIT>
    <ANGULAR_UNIT><NAME>decimal degrees</NAME></ANGULAR_UNIT>
    <REMARK>broadcast orbits</REMARK>
  </REFERENCE_SYSTEM>
  <EQUIPMENT>
    <ID>E1</ID>
    <RECEIVER><TYPE>TRIMBLE R10</TYPE><SERIAL_NUMBER>5432</SERIAL_NUMBER><FIRMWARE_VERSION>5.45</FIRMWARE_VERSION></RECEIVER>
    <ANTENNA><TYPE>TRMR10          NONE</TYPE><CALIBRATION_TYPE>Absolute</CALIBRATION_TYPE><CALIBRATION_SOURCE>NGS</CALIBRATION_SOURCE><SERIAL_NUMBER>5432</SERIAL_NUMBER></ANTENNA>
  </EQUIPMENT>
  <EQUIPMENT>
    <ID>E2</ID>
    <RECEIVER><TYPE>LEICA GS18</TYPE><SERIAL_NUMBER>99</SERIAL_NUMBER><FIRMWARE_VERSION>7.0</FIRMWARE_VERSION></RECEIVER>
    <ANTENNA><TYPE>LEIGS18         NONE</TYPE><SERIAL_NUMBER>99</SERIAL_NUMBER></ANTENNA>
  </EQUIPMENT>
  <SURVEY_SETUP>
    <ID>S1</ID>
    <SOLUTION_TYPE>NetworkRTK</SOLUTION_TYPE>
    <OPERATOR>B. Operator</OPERATOR>
    <PROCESSING_SOFTWARE><NAME>Field App</NAME><VERSION>5.2</VERSION></PROCESSING_SOFTWARE>
    <CORRECTOR_FORMAT>RTCM v3</CORRECTOR_FORMAT>
    <NETWORKRTK><NAME>State RTN</NAME><MOUNT_POINT>VRS_RTCM3</MOUNT_POINT><TYPE>VRS</TYPE><IP_ADDRESS>rtn.example.com</IP_ADDRESS><IP_PORT>2101</IP_PORT></NETWORKRTK>
  </SURVEY_SETUP>
  <SURVEY_SETUP>
    <ID>S2</ID>
    <SOLUTION_TYPE>Post-processed</SOLUTION_TYPE>
    <OPERATOR>C. Office</OPERATOR>
    <PROCESSING_SOFTWARE><NAME>PAGES</NAME><VERSION>PAGE5 V1603.24</VERSION></PROCESSING_SOFTWARE>
  </SURVEY_SETUP>
)";
  for (const auto& p : points) out += gvx_point(p);
  for (const auto& v : vectors) out += gvx_vector(v);
  return out + "  <REMARK>end of file</REMARK>\n</GVX>\n";
}

// A point's geocentric position on GRS 1980 (NAD 83's ellipsoid), by
// GeographicLib: the truth both GVX tests compare with.
inline Eigen::Vector3d gvx_ecef(const GvxPoint& p) {
  static const GeographicLib::Geocentric grs80(6378137.0, 1.0 / 298.257222101);
  Eigen::Vector3d x;
  grs80.Forward(p.lat_deg, p.lon_deg, p.h_m, x.x(), x.y(), x.z());
  return x;
}

}  // namespace geoanchor::testing
