// A DynaML measurement into the network: its frame, its GNSS covariance and
// scaling, and each type (A … Z) as geoanchor's measurement kinds.

#include <Eigen/Core>

#include <cmath>
#include <optional>
#include <string>
#include <utility>

#include "geoanchor/geodesy/frame.hpp"
#include "geoanchor/geodesy/local_frame.hpp"
#include "network/network_dynaml_reader.hpp"

namespace geoanchor::io::detail::dynaml {

using geodesy::MeasurementKind;

// A GNSS measurement's frame: its own ReferenceFrame/Epoch, else the file's.
// The last one read is kept: a file's measurements mostly share theirs.
geodesy::Frame Reader::measurement_frame(const Measurement& m) const {
  const std::string& f = text(m.fields, Tag::ReferenceFrame);
  const std::string& e = text(m.fields, Tag::Epoch);
  if (f.empty() && e.empty()) return *root_frame_;
  if (last_frame_ && f == last_frame_name_ && e == last_frame_epoch_) return *last_frame_;
  const geodesy::Frame frame = frame_of(f.empty() ? root_frame_->name() : f,
                                        e.empty() ? (epoch_text_.empty() ? "01.01.2020" : epoch_text_) : e, m.line, "measurement");
  last_frame_name_ = f;
  last_frame_epoch_ = e;
  last_frame_ = frame;
  return frame;
}

// The covariance of n GNSS items: diagonal blocks from Sigma*, cross blocks from the items' blocks.
Eigen::MatrixXd Reader::gnss_covariance(const Measurement& m, const std::string& what) const {
  const std::size_t n = m.items.size();
  Eigen::MatrixXd v = Eigen::MatrixXd::Zero(static_cast<Eigen::Index>(3 * n), static_cast<Eigen::Index>(3 * n));
  using enum Tag;
  const Tag sig[3][3] = {{SigmaXX, SigmaXY, SigmaXZ}, {SigmaXY, SigmaYY, SigmaYZ}, {SigmaXZ, SigmaYZ, SigmaZZ}};
  for (std::size_t i = 0; i < n; ++i) {
    const Item& it = m.items[i];
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) v(static_cast<Eigen::Index>(3 * i) + r, static_cast<Eigen::Index>(3 * i) + c) = number(it.fields, sig[r][c], it.line, what);
    }
    if (it.blocks.size() != n - 1 - i) {
      fail(it.line, what + ": item " + std::to_string(i + 1) + " of " + std::to_string(n) + " carries " +
                        std::to_string(it.blocks.size()) + " covariance blocks; expected " + std::to_string(n - 1 - i) +
                        " (one with each later item)");
    }
    for (std::size_t k = 0; k < it.blocks.size(); ++k) {
      const std::size_t j = i + 1 + k;
      for (int r = 0; r < 3; ++r) {
        for (int c = 0; c < 3; ++c) {
          static constexpr Tag kBlock[3][3] = {{m11, m12, m13}, {m21, m22, m23}, {m31, m32, m33}};
          const double x = number(it.blocks[k], kBlock[r][c], it.line, what);
          v(static_cast<Eigen::Index>(3 * i) + r, static_cast<Eigen::Index>(3 * j) + c) = x;
          v(static_cast<Eigen::Index>(3 * j) + c, static_cast<Eigen::Index>(3 * i) + r) = x;
        }
      }
    }
  }
  return v;
}

// A station a measurement names (<First>, <Second>, …), referenced by name.
std::size_t Reader::station(const Finishing& fin, const std::string& id, const char* role) {
  if (id.empty()) fail(fin.m.line, fin.what + ": <" + std::string(role) + "> missing");
  return builder_.reference(id, fin.x.source);
}

// One value and its standard deviation.
void Reader::scalar(const Finishing& fin, MeasurementKind kind, double value, double sigma) {
  geodesy::NetworkMeasurement& x = fin.x;
  x.kind = kind;
  x.value = Eigen::VectorXd::Constant(1, value);
  x.covariance = Eigen::MatrixXd::Constant(1, 1, sigma * sigma);
}

// A packed sexagesimal <Value> of `kind`, within its range.
double Reader::angle(const Finishing& fin, MeasurementKind kind, const Fields& f, std::size_t at) const {
  const std::string& written = text(f, Tag::Value);
  const std::string at_value = where(at) + ": " + fin.what + " " + field(Tag::Value);
  const double v = packed_dms_to_rad(written, at_value, net_.warnings);
  check_angle_range(kind, v, written, AngleUnit::packed_dms, at_value);
  return v;
}

double Reader::angle_sigma(const Finishing& fin, const Fields& f, std::size_t at) const {
  return positive_sigma(number(f, Tag::StdDev, at, fin.what), at, fin.what) * kArcsec;
}

double Reader::linear_sigma(const Finishing& fin) const {
  return positive_sigma(number(fin.m.fields, Tag::StdDev, fin.m.line, fin.what), fin.m.line, fin.what);
}

// The instrument and target heights, when given.
void Reader::heights(const Finishing& fin) const {
  const Measurement& m = fin.m;
  const std::string& what = fin.what;
  geodesy::NetworkMeasurement& x = fin.x;
  if (m.fields.count(Tag::InstHeight) && !text(m.fields, Tag::InstHeight).empty()) x.instrument_height_m = number(m.fields, Tag::InstHeight, m.line, what);
  if (m.fields.count(Tag::TargHeight) && !text(m.fields, Tag::TargHeight).empty()) x.target_height_m = number(m.fields, Tag::TargHeight, m.line, what);
}

void Reader::finish_measurement() {
  const Measurement& m = measurement_;
  const std::string type = text(m.fields, Tag::Type);
  const std::string what = "measurement " + type;
  geodesy::NetworkMeasurement x;
  x.source = where(m.line);
  x.ignore = !text(m.fields, Tag::Ignore).empty();
  const std::string first = m.firsts.empty() ? "" : m.firsts.front();
  const std::string second = m.seconds.empty() ? "" : m.seconds.front();
  const Finishing fin{m, type, what, x, first, second};
  if (type.size() != 1) fail(m.line, field(Tag::Type) + " '" + type + "': expected one letter (A, B, C, D, E, G, H, I, J, K, L, M, P, Q, R, S, V, X, Y, Z)");
  switch (type[0]) {
    case 'G':
    case 'X':
      gnss_baselines(fin);
      break;
    case 'Y':
      gnss_points(fin);
      break;
    case 'S':
    case 'E':
    case 'M':
    case 'C': {
      const bool slope = type[0] == 'S';
      scalar(fin, slope ? MeasurementKind::slope_distance : type[0] == 'E' ? MeasurementKind::ellipsoid_arc
                                                           : type[0] == 'M' ? MeasurementKind::msl_arc
                                                                            : MeasurementKind::chord_distance,
             number(m.fields, Tag::Value, m.line, what), linear_sigma(fin));
      x.stations = {station(fin, first, "First"), station(fin, second, "Second")};
      if (slope) heights(fin);
      break;
    }
    case 'A': {
      scalar(fin, MeasurementKind::horizontal_angle, angle(fin, MeasurementKind::horizontal_angle, m.fields, m.line),
             angle_sigma(fin, m.fields, m.line));
      x.stations = {station(fin, first, "First"), station(fin, second, "Second"), station(fin, text(m.fields, Tag::Third), "Third")};
      break;
    }
    case 'B':
    case 'K': {
      // K, an astronomic azimuth: in the plumb line's horizon (the
      // station's deflection of the vertical, docs/network-format.md).
      const MeasurementKind kind = type[0] == 'B' ? MeasurementKind::azimuth : MeasurementKind::astronomic_azimuth;
      scalar(fin, kind, angle(fin, kind, m.fields, m.line), angle_sigma(fin, m.fields, m.line));
      x.stations = {station(fin, first, "First"), station(fin, second, "Second")};
      break;
    }
    case 'V':
    case 'Z': {
      const MeasurementKind kind = type[0] == 'V' ? MeasurementKind::zenith_angle : MeasurementKind::vertical_angle;
      scalar(fin, kind, angle(fin, kind, m.fields, m.line), angle_sigma(fin, m.fields, m.line));
      x.stations = {station(fin, first, "First"), station(fin, second, "Second")};
      heights(fin);
      break;
    }
    case 'H':
    case 'R': {
      scalar(fin, type[0] == 'H' ? MeasurementKind::orthometric_height : MeasurementKind::ellipsoidal_height,
             number(m.fields, Tag::Value, m.line, what), linear_sigma(fin));
      x.stations = {station(fin, first, "First")};
      break;
    }
    case 'L': {
      scalar(fin, MeasurementKind::height_difference, number(m.fields, Tag::Value, m.line, what), linear_sigma(fin));
      x.stations = {station(fin, first, "First"), station(fin, second, "Second")};
      break;
    }
    case 'P':
    case 'Q':
    case 'I':
    case 'J': {
      // I and J, astronomic: of the plumb line (the station's deflection).
      const MeasurementKind kind = type[0] == 'P'   ? MeasurementKind::geodetic_latitude
                                   : type[0] == 'Q' ? MeasurementKind::geodetic_longitude
                                   : type[0] == 'I' ? MeasurementKind::astronomic_latitude
                                                    : MeasurementKind::astronomic_longitude;
      scalar(fin, kind, angle(fin, kind, m.fields, m.line), angle_sigma(fin, m.fields, m.line));
      x.stations = {station(fin, first, "First")};
      break;
    }
    case 'D':
      direction_set(fin);
      return;
    default:
      fail(m.line, field(Tag::Type) + " '" + type + "': expected one of A, B, C, D, E, G, H, I, J, K, L, M, P, Q, R, S, V, X, Y, Z");
  }
  net_.measurements.push_back(std::move(x));
}

// G (one baseline) and X (a cluster of baselines): ECEF differences with
// their covariance.
void Reader::gnss_baselines(const Finishing& fin) {
  const Measurement& m = fin.m;
  const std::string& type = fin.type;
  const std::string& what = fin.what;
  geodesy::NetworkMeasurement& x = fin.x;
  const std::string& first = fin.first;
  const std::string& second = fin.second;
  if (m.items.empty()) fail(m.line, what + ": no " + field(Tag::GPSBaseline));
  if (type[0] == 'X' && !text(m.fields, Tag::Total).empty() &&
      number(m.fields, Tag::Total, m.line, what) != static_cast<double>(m.items.size())) {
    fail(m.line, what + ": " + field(Tag::Total) + " " + text(m.fields, Tag::Total) + " but " + std::to_string(m.items.size()) + " " + field(Tag::GPSBaseline));
  }
  x.kind = MeasurementKind::gnss_baselines;
  x.value.resize(static_cast<Eigen::Index>(3 * m.items.size()));
  for (std::size_t i = 0; i < m.items.size(); ++i) {
    const Item& it = m.items[i];
    const std::string a = type[0] == 'G' ? first : it.first, b = type[0] == 'G' ? second : it.second;
    x.stations.push_back(station(fin, a, "First"));
    x.stations.push_back(station(fin, b, "Second"));
    x.value.segment<3>(static_cast<Eigen::Index>(3 * i)) =
        Eigen::Vector3d(number(it.fields, Tag::X, it.line, what), number(it.fields, Tag::Y, it.line, what), number(it.fields, Tag::Z, it.line, what));
  }
  x.covariance = gnss_covariance(m, what);
  x.frame = measurement_frame(m);
  scale(x, m, what);
}

// Y, a cluster of GNSS points: ECEF (Coords XYZ) or latitude, longitude
// and orthometric height (Coords LLH), with their covariance.
void Reader::gnss_points(const Finishing& fin) {
  const Measurement& m = fin.m;
  const std::string& what = fin.what;
  geodesy::NetworkMeasurement& x = fin.x;
  if (m.items.empty()) fail(m.line, what + ": no " + field(Tag::Clusterpoint));
  if (!text(m.fields, Tag::Total).empty() && number(m.fields, Tag::Total, m.line, what) != static_cast<double>(m.items.size())) {
    fail(m.line, what + ": " + field(Tag::Total) + " " + text(m.fields, Tag::Total) + " but " + std::to_string(m.items.size()) + " " + field(Tag::Clusterpoint));
  }
  const std::string coords = text(m.fields, Tag::Coords);
  if (coords != "XYZ" && coords != "LLH") fail(m.line, what + ": " + field(Tag::Coords) + " '" + coords + "': expected XYZ or LLH");
  x.kind = MeasurementKind::gnss_points;
  const std::size_t n = m.items.size();
  x.value.resize(static_cast<Eigen::Index>(3 * n));
  Eigen::MatrixXd v = gnss_covariance(m, what);
  Eigen::MatrixXd j = Eigen::MatrixXd::Identity(v.rows(), v.cols());
  for (std::size_t i = 0; i < n; ++i) {
    const Item& it = m.items[i];
    x.stations.push_back(station(fin, it.first, "First"));
    if (coords == "XYZ") {
      x.value.segment<3>(static_cast<Eigen::Index>(3 * i)) =
          Eigen::Vector3d(number(it.fields, Tag::X, it.line, what), number(it.fields, Tag::Y, it.line, what), number(it.fields, Tag::Z, it.line, what));
      continue;
    }
    // LLH: latitude and longitude (packed), orthometric height; the
    // covariance in (latitude rad, longitude rad, height m).
    const std::string at_lat = where(it.line) + ": " + what + " " + field(Tag::X) + " (latitude)";
    const std::string at_lon = where(it.line) + ": " + what + " " + field(Tag::Y) + " (longitude)";
    const double lat = packed_dms_to_rad(text(it.fields, Tag::X), at_lat, net_.warnings);
    const double lon = packed_dms_to_rad(text(it.fields, Tag::Y), at_lon, net_.warnings);
    check_angle_range(MeasurementKind::geodetic_latitude, lat, text(it.fields, Tag::X), AngleUnit::packed_dms, at_lat);
    check_angle_range(MeasurementKind::geodetic_longitude, lon, text(it.fields, Tag::Y), AngleUnit::packed_dms, at_lon);
    const auto n_m = undulation(it.first, lat, lon, it.line);
    if (!n_m) fail(it.line, what + ": a point cluster of orthometric heights (Coords LLH) needs the geoid: give --geoid");
    const double h = number(it.fields, Tag::Z, it.line, what) + *n_m;
    const geodesy::GeodeticPosition g{geodesy::Angle::radians(lat), geodesy::Angle::radians(lon), geodesy::EllipsoidalHeight{h}};
    x.value.segment<3>(static_cast<Eigen::Index>(3 * i)) = geocentric_.ecef_from_geodetic(g).m;
    // ∂(X, Y, Z) / ∂(φ, λ, h): north·(M + h), east·(N + h)·cos φ, up.
    const double e2 = net_.ellipsoid.e2(), a = net_.ellipsoid.a_m();
    const double w = std::sqrt(1.0 - e2 * std::sin(lat) * std::sin(lat));
    const double meridian = a * (1.0 - e2) / (w * w * w), prime = a / w;
    const Eigen::Matrix3d r = geodesy::enu_from_ecef_rotation(g.lat, g.lon);
    Eigen::Matrix3d jac;
    jac.col(0) = r.row(1).transpose() * (meridian + h);
    jac.col(1) = r.row(0).transpose() * (prime + h) * std::cos(lat);
    jac.col(2) = r.row(2).transpose();
    j.block<3, 3>(static_cast<Eigen::Index>(3 * i), static_cast<Eigen::Index>(3 * i)) = jac;
  }
  x.covariance = j * v * j.transpose();
  x.frame = measurement_frame(m);
  scale(x, m, what);
}

// D, a direction set: the reference object, then the other targets, each a
// measurement of the set.
void Reader::direction_set(const Finishing& fin) {
  const Measurement& m = fin.m;
  const std::string& what = fin.what;
  geodesy::NetworkMeasurement& x = fin.x;
  const std::string& first = fin.first;
  const std::string& second = fin.second;
  const std::size_t at = station(fin, first, "First");
  const std::size_t set = net_.direction_sets.size();
  net_.direction_sets.push_back({at, where(m.line)});
  const bool ignored = x.ignore;
  // The reference object, then the other targets.
  geodesy::NetworkMeasurement ro;
  ro.source = where(m.line);
  ro.kind = MeasurementKind::direction;
  ro.stations = {at, station(fin, second, "Second")};
  const double s = angle_sigma(fin, m.fields, m.line);
  ro.value = Eigen::VectorXd::Constant(1, angle(fin, MeasurementKind::direction, m.fields, m.line));
  ro.covariance = Eigen::MatrixXd::Constant(1, 1, s * s);
  ro.set = set;
  ro.ignore = ignored;
  net_.measurements.push_back(ro);
  if (!text(m.fields, Tag::Total).empty() &&
      number(m.fields, Tag::Total, m.line, what) != static_cast<double>(m.directions.size())) {
    fail(m.line, what + ": " + field(Tag::Total) + " " + text(m.fields, Tag::Total) + " but " + std::to_string(m.directions.size()) + " " + field(Tag::Directions));
  }
  for (const auto& d : m.directions) {
    geodesy::NetworkMeasurement dir = ro;
    dir.source = where(d.line);
    dir.stations = {at, station(fin, text(d.fields, Tag::Target), "Target")};
    const double sd = angle_sigma(fin, d.fields, d.line);
    dir.value = Eigen::VectorXd::Constant(1, angle(fin, MeasurementKind::direction, d.fields, d.line));
    dir.covariance = Eigen::MatrixXd::Constant(1, 1, sd * sd);
    dir.ignore = ignored || !text(d.fields, Tag::Ignore).empty();
    net_.measurements.push_back(dir);
  }
}

// Vscale multiplies the whole covariance; Pscale, Lscale, Hscale the
// variances along latitude (north), longitude (east) and height (up),
// applied when the stations are known (Network measurement's
// local_variance_scale).
void Reader::scale(geodesy::NetworkMeasurement& x, const Measurement& m, const std::string& what) const {
  auto factor = [&](Tag key) {
    const std::string& t = text(m.fields, key);
    if (t.empty()) return 1.0;
    const auto v = parse_finite_double(t);
    if (!v || !(*v > 0.0)) fail(m.line, what + ": " + field(key) + " '" + t + "': expected a factor > 0");
    return *v;
  };
  x.covariance *= factor(Tag::Vscale);
  x.local_variance_scale = Eigen::Vector3d(factor(Tag::Pscale), factor(Tag::Lscale), factor(Tag::Hscale));
}

}  // namespace geoanchor::io::detail::dynaml
