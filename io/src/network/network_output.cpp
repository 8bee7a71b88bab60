// DynaML and network JSON out (network_output.hpp).

#include "geoanchor/io/network/network_output.hpp"

#include <cmath>
#include <cstdio>
#include <string>

#include "geoanchor/base/error.hpp"
#include "geoanchor/base/number_text.hpp"

namespace geoanchor::io {

namespace {

using geodesy::MeasurementKind;

[[noreturn]] void refuse(const std::string& what) {
  throw Error(ErrorKind::usage, "E_NETWORK_WRITE", what);
}

// The day (dd.mm.yyyy) whose decimal year is the frame's epoch, as the
// DynaML reader turns it back.
std::string dynaml_date(const geodesy::Frame& frame) {
  const double year = frame.epoch()->year;
  const int y = static_cast<int>(std::floor(year));
  for (int month = 1; month <= 12; ++month) {
    for (int day = 1; day <= 31; ++day) {
      const auto d = geodesy::decimal_year_from_date(y, month, day);
      if (d && d->year == year) {
        char text[40];  // room for any int the compiler cannot rule out (-Wformat-truncation)
        std::snprintf(text, sizeof text, "%02d.%02d.%04d", day, month, y);
        return text;
      }
    }
  }
  refuse("the frame " + frame.to_string() + ": DynaML states an epoch as a day (dd.mm.yyyy) and " +
         format_decimal_year(*frame.epoch()) + " is not the start of one");
}

std::string escaped(const std::string& s) {
  std::string out;
  for (char c : s) {
    switch (c) {
      case '&': out += "&amp;"; break;
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '"': out += "&quot;"; break;
      default: out += c;
    }
  }
  return out;
}

std::string json_string(const std::string& s) {
  std::string out = "\"";
  for (char c : s) {
    if (c == '"' || c == '\\') {
      out += '\\';
      out += c;
    } else if (static_cast<unsigned char>(c) < 0x20) {
      char u[8];
      std::snprintf(u, sizeof u, "\\u%04x", static_cast<unsigned>(static_cast<unsigned char>(c)));
      out += u;
    } else {
      out += c;
    }
  }
  return out + "\"";
}

const std::string& n(double v, std::string& buffer) {
  buffer = format_shortest(v);
  return buffer;
}

const geodesy::Frame& measurement_frame(const geodesy::Network& net, const geodesy::NetworkMeasurement& m) {
  return m.frame ? *m.frame : *net.frame;
}

}  // namespace

void check_writable_network(const geodesy::Network& net) {
  const std::string where = net.source_name.empty() ? "the network" : net.source_name;
  if (net.space != geodesy::NetworkSpace::ellipsoidal) refuse(where + ": a local network; these writers hold networks on the ellipsoid");
  if (!net.frame || !net.frame->epoch()) refuse(where + ": the network's frame and its epoch are needed (DynaML states both)");
  dynaml_date(*net.frame);
  for (const auto& s : net.stations) {
    const std::string code = s.constraint.text();
    if (code != "CCC" && code != "FFF") {
      refuse("station " + s.id + ": constraint " + code + "; stations in XYZ are written free (FFF) or held (CCC)");
    }
    if (s.constraint.any() && (s.constraint.sigma_m[0] > 0.0 || s.constraint.sigma_m[1] > 0.0 || s.constraint.sigma_m[2] > 0.0)) {
      refuse("station " + s.id + ": held with a standard deviation, which DynaML's station file cannot state");
    }
    if (!s.position_known) refuse("station " + s.id + ": no a-priori position to write");
    if (!s.position.allFinite()) refuse("station " + s.id + ": its position is not finite");
  }
  for (const auto& m : net.measurements) {
    if (m.kind != MeasurementKind::gnss_baselines || m.stations.size() != 2) {
      refuse(m.source + ": " + geodesy::to_string(m.kind) + (m.kind == MeasurementKind::gnss_baselines ? " cluster" : "") +
             ": these writers hold single GNSS baselines only");
    }
    if (!m.group.empty()) refuse(m.source + ": its group '" + m.group + "' has no place in DynaML");
    if (m.local_variance_scale != Eigen::Vector3d::Ones()) refuse(m.source + ": local variance scales are not written");
    if (!m.value_known) refuse(m.source + ": a planned measurement (no value): these writers hold measured ones");
    if (!m.value.allFinite() || !m.covariance.allFinite()) refuse(m.source + ": its value or covariance is not finite");
    if (m.covariance != m.covariance.transpose()) refuse(m.source + ": its covariance is not symmetric (only one triangle is written)");
    const auto& f = measurement_frame(net, m);
    if (!f.epoch()) refuse(m.source + ": frame " + f.to_string() + " without an epoch");
    dynaml_date(f);
  }
}

void write_dynaml_stations(const geodesy::Network& net, std::ostream& out) {
  check_writable_network(net);
  std::string a, b, c;
  out << "<?xml version=\"1.0\"?>\n<DnaXmlFormat type=\"Station File\" referenceframe=\"" << escaped(net.frame->name())
      << "\" epoch=\"" << dynaml_date(*net.frame) << "\">\n";
  for (const auto& s : net.stations) {
    const std::string id = escaped(s.id);
    out << "  <DnaStation>\n    <Name>" << id << "</Name>\n    <Constraints>" << s.constraint.text()
        << "</Constraints>\n    <Type>XYZ</Type>\n    <StationCoord>\n      <Name>" << id << "</Name>\n      <XAxis>"
        << n(s.position.x(), a) << "</XAxis>\n      <YAxis>" << n(s.position.y(), b) << "</YAxis>\n      <Height>"
        << n(s.position.z(), c) << "</Height>\n    </StationCoord>\n  </DnaStation>\n";
  }
  out << "</DnaXmlFormat>\n";
}

void write_dynaml_measurements(const geodesy::Network& net, std::ostream& out) {
  check_writable_network(net);
  std::string t[9];
  out << "<?xml version=\"1.0\"?>\n<DnaXmlFormat type=\"Measurement File\" referenceframe=\"" << escaped(net.frame->name())
      << "\" epoch=\"" << dynaml_date(*net.frame) << "\">\n";
  for (const auto& m : net.measurements) {
    const auto& f = measurement_frame(net, m);
    const auto& v = m.value;
    const auto& cv = m.covariance;
    out << "  <DnaMeasurement>\n    <Type>G</Type>\n    <Ignore>" << (m.ignore ? "*" : "") << "</Ignore>\n    <ReferenceFrame>"
        << escaped(f.name()) << "</ReferenceFrame>\n    <Epoch>" << dynaml_date(f) << "</Epoch>\n    <First>"
        << escaped(net.stations[m.stations[0]].id) << "</First>\n    <Second>" << escaped(net.stations[m.stations[1]].id)
        << "</Second>\n    <GPSBaseline>\n      <X>" << n(v(0), t[0]) << "</X>\n      <Y>" << n(v(1), t[1]) << "</Y>\n      <Z>"
        << n(v(2), t[2]) << "</Z>\n      <SigmaXX>" << n(cv(0, 0), t[3]) << "</SigmaXX>\n      <SigmaXY>" << n(cv(0, 1), t[4])
        << "</SigmaXY>\n      <SigmaXZ>" << n(cv(0, 2), t[5]) << "</SigmaXZ>\n      <SigmaYY>" << n(cv(1, 1), t[6])
        << "</SigmaYY>\n      <SigmaYZ>" << n(cv(1, 2), t[7]) << "</SigmaYZ>\n      <SigmaZZ>" << n(cv(2, 2), t[8])
        << "</SigmaZZ>\n    </GPSBaseline>\n  </DnaMeasurement>\n";
  }
  out << "</DnaXmlFormat>\n";
}

void write_network_json(const geodesy::Network& net, std::ostream& out) {
  check_writable_network(net);
  std::string t[9];
  out << "{\n\"schema\": \"geoanchor.network/1\",\n\"space\": \"ellipsoidal\",\n\"frame\": " << json_string(net.frame->to_string())
      << ",\n\"stations\": [\n";
  for (std::size_t k = 0; k < net.stations.size(); ++k) {
    const auto& s = net.stations[k];
    out << (k ? ",\n" : "") << "{\"id\": " << json_string(s.id) << ", \"x_m\": " << n(s.position.x(), t[0])
        << ", \"y_m\": " << n(s.position.y(), t[1]) << ", \"z_m\": " << n(s.position.z(), t[2])
        << (s.constraint.any() ? ", \"constraint\": \"CCC\"" : "") << "}";
  }
  out << "\n],\n\"measurements\": [\n";
  for (std::size_t k = 0; k < net.measurements.size(); ++k) {
    const auto& m = net.measurements[k];
    const auto& v = m.value;
    const auto& cv = m.covariance;
    out << (k ? ",\n" : "") << "{\"kind\": \"gnss_baseline\", \"from\": " << json_string(net.stations[m.stations[0]].id)
        << ", \"to\": " << json_string(net.stations[m.stations[1]].id) << ", \"dx_m\": " << n(v(0), t[0])
        << ", \"dy_m\": " << n(v(1), t[1]) << ", \"dz_m\": " << n(v(2), t[2]) << ", \"cov_m2\": [[" << n(cv(0, 0), t[3]) << ", "
        << n(cv(0, 1), t[4]) << ", " << n(cv(0, 2), t[5]) << "], [" << t[4] << ", " << n(cv(1, 1), t[6]) << ", "
        << n(cv(1, 2), t[7]) << "], [" << t[5] << ", " << t[7] << ", " << n(cv(2, 2), t[8]) << "]], \"frame\": "
        << json_string(measurement_frame(net, m).to_string()) << (m.ignore ? ", \"ignore\": true" : "") << "}";
  }
  out << "\n]\n}\n";
}

}  // namespace geoanchor::io
