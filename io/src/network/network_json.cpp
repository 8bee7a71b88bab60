// geoanchor's own network input, JSON (schema geoanchor.network/1,
// docs/network-format.md). Every key is known or refused; units are in the
// key names.

#include <algorithm>
#include <array>
#include <cmath>
#include <nlohmann/json.hpp>
#include <numbers>
#include <set>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "geoanchor/base/error.hpp"
#include "geoanchor/crs/crs.hpp"
#include "geoanchor/crs/frame_ellipsoid.hpp"
#include "geoanchor/geodesy/geocentric.hpp"
#include "geoanchor/base/number_text.hpp"
#include "geoanchor/geodesy/physical_range.hpp"
#include "geoanchor/io/json_input.hpp"
#include "json_fields.hpp"
#include "network/network_builder.hpp"
#include "network/network_readers.hpp"

namespace geoanchor::io::detail {
namespace {

using nlohmann::json;
using geodesy::MeasurementKind;

constexpr double kArcsec = std::numbers::pi / 648000.0;
constexpr double kGon = std::numbers::pi / 200.0;

[[noreturn]] void fail(const std::string& where, const std::string& what) {
  throw Error(ErrorKind::input, "E_NETWORK", where + ": " + what);
}

void only_keys(const json& obj, const std::string& where, const std::set<std::string>& allowed) {
  if (!obj.is_object()) fail(where, "expected an object");
  if (const auto key = first_unknown_key(obj, allowed)) fail(where + "." + *key, "unknown key; expected " + key_list(allowed));
}

double number(const json& obj, const std::string& key, const std::string& where) {
  return finite_json_number(obj, key, where, "E_NETWORK");
}

// A measured value that may be null: a planned measurement (its value is
// not known yet; only a pre-analysis takes it). Sets `planned` and returns 0.
double value_or_planned(const json& obj, const std::string& key, const std::string& where, bool& planned) {
  if (obj.contains(key) && obj.at(key).is_null()) {
    planned = true;
    return 0.0;
  }
  return number(obj, key, where);
}

std::string text(const json& obj, const std::string& key, const std::string& where) {
  if (!obj.contains(key)) fail(where + "." + key, "missing");
  if (!obj.at(key).is_string()) fail(where + "." + key, "value " + obj.at(key).dump() + " is not a string");
  return obj.at(key).get<std::string>();
}

double positive(double v, const std::string& where) {
  if (!(v > 0.0)) fail(where, "value " + format_shortest(v) + " must be > 0");
  return v;
}

// An angle of `kind`: exactly one of value_deg, value_gon, value_rad,
// value_dms, within the kind's range (check_angle_range); a value_dms with
// seconds of 60 adds a warning to `warnings`.
double angle_value(const json& m, MeasurementKind kind, const std::string& where, std::vector<std::string>& warnings,
                   bool& planned) {
  constexpr std::array<std::pair<const char*, AngleUnit>, 4> kKeys{{{"value_deg", AngleUnit::degrees},
                                                                    {"value_gon", AngleUnit::gon},
                                                                    {"value_rad", AngleUnit::radians},
                                                                    {"value_dms", AngleUnit::dms_text}}};
  const char* key = nullptr;
  AngleUnit unit = AngleUnit::degrees;
  int given = 0;
  for (const auto& [k, u] : kKeys) {
    if (m.contains(k)) key = k, unit = u, ++given;
  }
  if (given != 1) fail(where, "expected one of value_deg, value_gon, value_rad, value_dms (\"ddd-mm-ss.s\")");
  if (m.at(key).is_null()) {  // a planned measurement
    planned = true;
    return 0.0;
  }
  double v = 0.0;
  switch (unit) {
    case AngleUnit::degrees: v = number(m, key, where) * std::numbers::pi / 180.0; break;
    case AngleUnit::gon: v = number(m, key, where) * kGon; break;
    case AngleUnit::radians: v = number(m, key, where); break;
    case AngleUnit::dms_text:
    case AngleUnit::packed_dms: v = dms_text_to_rad(text(m, key, where), where + "." + key, warnings); break;
  }
  const json& written = m.at(key);
  check_angle_range(kind, v, written.is_string() ? written.get<std::string>() : written.dump(), unit, where + "." + key);
  return v;
}

// An angle's standard deviation: exactly one of sigma_arcsec, sigma_deg,
// sigma_cc, sigma_mgon, sigma_rad; or none when an error model gives it (0).
double angle_sigma(const json& m, const std::string& where, bool modelled = false) {
  int given = 0;
  double v = 0.0;
  if (m.contains("sigma_arcsec")) v = number(m, "sigma_arcsec", where) * kArcsec, ++given;
  if (m.contains("sigma_deg")) v = number(m, "sigma_deg", where) * std::numbers::pi / 180.0, ++given;
  if (m.contains("sigma_cc")) v = number(m, "sigma_cc", where) * kGon / 10000.0, ++given;
  if (m.contains("sigma_mgon")) v = number(m, "sigma_mgon", where) * kGon / 1000.0, ++given;
  if (m.contains("sigma_rad")) v = number(m, "sigma_rad", where), ++given;
  if (given == 0 && modelled) return 0.0;
  if (given != 1) {
    fail(where, std::string("expected one of sigma_arcsec, sigma_deg, sigma_cc, sigma_mgon, sigma_rad") +
                    (given == 0 ? " (or an error_model that gives it)" : ""));
  }
  return positive(v, where + ".sigma");
}

const std::set<std::string> kAngleKeys = {"value_deg", "value_gon", "value_rad", "value_dms",
                                          "sigma_arcsec", "sigma_deg", "sigma_cc", "sigma_mgon", "sigma_rad"};

// A square matrix of numbers, symmetric.
Eigen::MatrixXd matrix(const json& m, Eigen::Index n, const std::string& where) {
  if (!m.is_array() || static_cast<Eigen::Index>(m.size()) != n) {
    fail(where, "expected a " + std::to_string(n) + "×" + std::to_string(n) + " array of arrays (SI units squared)");
  }
  Eigen::MatrixXd out(n, n);
  for (Eigen::Index i = 0; i < n; ++i) {
    const json& row = m[static_cast<std::size_t>(i)];
    if (!row.is_array() || static_cast<Eigen::Index>(row.size()) != n) {
      fail(where + "[" + std::to_string(i) + "]", "expected " + std::to_string(n) + " numbers");
    }
    for (Eigen::Index j = 0; j < n; ++j) {
      const json& v = row[static_cast<std::size_t>(j)];
      if (!v.is_number() || !std::isfinite(v.get<double>())) {
        fail(where + "[" + std::to_string(i) + "][" + std::to_string(j) + "]", "entry " + v.dump() + " is not a finite number");
      }
      out(i, j) = v.get<double>();
    }
  }
  for (Eigen::Index i = 0; i < n; ++i) {
    for (Eigen::Index j = 0; j < i; ++j) {
      if (std::fabs(out(i, j) - out(j, i)) > 1e-12 * std::max(std::fabs(out(i, j)), std::fabs(out(j, i)))) {
        fail(where, "not symmetric at [" + std::to_string(i) + "][" + std::to_string(j) + "]");
      }
    }
  }
  return out;
}

// A station's position: ECEF x_m, y_m, z_m or lat_deg, lon_deg, h_m
// (ellipsoidal networks, on the network's ellipsoid); local x_m, y_m, z_m.
Eigen::Vector3d position(const json& s, const geodesy::Network& net, const std::string& where) {
  const bool xyz = s.contains("x_m") || s.contains("y_m") || s.contains("z_m");
  const bool geodetic = s.contains("lat_deg") || s.contains("lon_deg") || s.contains("h_m");
  if (xyz && geodetic) fail(where, "both x_m/y_m/z_m and lat_deg/lon_deg/h_m; give one");
  if (net.space == geodesy::NetworkSpace::local) {
    if (geodetic) fail(where, "lat_deg/lon_deg/h_m in a local network; expected x_m, y_m, z_m");
    Eigen::Vector3d p = Eigen::Vector3d::Zero();
    if (net.local_dimensions >= 2) p.x() = number(s, "x_m", where), p.y() = number(s, "y_m", where);
    if (net.local_dimensions != 2) p.z() = number(s, "z_m", where);
    return p;
  }
  if (xyz) return {number(s, "x_m", where), number(s, "y_m", where), number(s, "z_m", where)};
  if (!net.ellipsoid_stated) {
    fail(where, net.frame ? "latitude and longitude in the frame " + net.frame->to_string() +
                                ", which neither geoanchor's frame catalog nor PROJ's database knows: give the input's "
                                "\"ellipsoid\" (or its \"crs\", e.g. EPSG:4272)"
                          : std::string("latitude and longitude without an ellipsoid: give the input's \"frame\", \"crs\" "
                                        "or \"ellipsoid\""));
  }
  const double lat = number(s, "lat_deg", where), lon = number(s, "lon_deg", where), h = number(s, "h_m", where);
  if (!(std::fabs(lat) <= 90.0)) fail(where + ".lat_deg", "latitude " + format_shortest(lat) + " not in [-90, 90]");
  if (!(std::fabs(lon) <= 180.0)) fail(where + ".lon_deg", "longitude " + format_shortest(lon) + " not in [-180, 180]");
  if (!geodesy::is_physical_height(h)) {
    fail(where + ".h_m", "ellipsoidal height " + format_shortest(h) + " m is not a height on the Earth: expected " +
                             geodesy::physical_height_range_text());
  }
  return geodesy::ecef_from_geodetic(net.ellipsoid, {geodesy::Angle::degrees(lat), geodesy::Angle::degrees(lon),
                                                     geodesy::EllipsoidalHeight{h}})
      .m;
}

geodesy::StationConstraint constraint_of(const json& s, const std::string& where) {
  geodesy::StationConstraint c;
  if (!s.contains("constraint")) {
    if (s.contains("constraint_sigma_m")) fail(where + ".constraint_sigma_m", "without a constraint");
    return c;
  }
  const std::string code = text(s, "constraint", where);
  if (code.size() != 3 || code.find_first_not_of("CF") != std::string::npos) {
    fail(where + ".constraint", "'" + code + "': expected three letters C (constrained) or F (free), e.g. CCF");
  }
  for (std::size_t k = 0; k < 3; ++k) c.code[k] = code[k];
  if (s.contains("constraint_sigma_m")) {
    const json& sig = s.at("constraint_sigma_m");
    if (!sig.is_array() || sig.size() != 3) fail(where + ".constraint_sigma_m", "expected three numbers (m; 0 = fixed)");
    for (std::size_t k = 0; k < 3; ++k) {
      if (!sig[k].is_number() || !(sig[k].get<double>() >= 0.0) || !std::isfinite(sig[k].get<double>())) {
        fail(where + ".constraint_sigma_m[" + std::to_string(k) + "]", "expected a number >= 0 (m; 0 = fixed)");
      }
      c.sigma_m[k] = sig[k].get<double>();
      if (c.code[k] == 'F' && c.sigma_m[k] != 0.0) {
        fail(where + ".constraint_sigma_m[" + std::to_string(k) + "]", "a sigma for a free component (F)");
      }
    }
  }
  return c;
}

// The ellipsoid the input's frame or CRS puts its coordinates on, and
// where that came from ("the frame NZGD1949 (PROJ: EPSG:4272 'NZGD49')").
struct ImpliedEllipsoid {
  geodesy::Ellipsoid ellipsoid;
  std::string by;
};

// The input's "ellipsoid", which must agree with the frame's or CRS's when
// they imply one.
void read_ellipsoid(const json& doc, const std::string& source, const std::optional<ImpliedEllipsoid>& implied,
                    geodesy::Network& net) {
  // By its EPSG name, or {"a_m", "rf", "name"}.
  const json& ej = doc.at("ellipsoid");
  std::optional<geodesy::Ellipsoid> named;
  std::string e;
  if (ej.is_object()) {
    const std::string where = source + ".ellipsoid";
    only_keys(ej, where, {"a_m", "rf", "name"});
    if (!ej.contains("a_m") || !ej.contains("rf")) fail(where, "an ellipsoid given by its parameters needs a_m and rf");
    try {
      named = geodesy::Ellipsoid::custom(number(ej, "a_m", where), number(ej, "rf", where),
                                         ej.contains("name") ? text(ej, "name", where) : "custom");
    } catch (const Error& x) {
      fail(where, x.what());
    }
    e = named->name() + " (a " + format_shortest(named->a_m()) + " m, 1/f " + format_shortest(named->rf()) + ")";
  } else {
    e = text(doc, "ellipsoid", source);
    named = geodesy::named_ellipsoid(e);
    if (!named) fail(source + ".ellipsoid", "'" + e + "': expected one of " + geodesy::named_ellipsoid_list() + ", or {\"a_m\", \"rf\"}");
  }
  const geodesy::Ellipsoid given = *named;
  if (implied && !same_ellipsoid(implied->ellipsoid, given)) {
    fail(source + ".ellipsoid",
         e + " contradicts " + implied->by + ", which is on " + implied->ellipsoid.name() + " (a " +
             format_shortest(implied->ellipsoid.a_m()) + " m, 1/f " + format_shortest(implied->ellipsoid.rf()) +
             "); give one of them, or both agreeing");
  }
  net.ellipsoid = implied ? implied->ellipsoid : given;
  net.ellipsoid_stated = true;
}

// The ellipsoid of the network's frame: the catalog's, else PROJ's.
std::optional<ImpliedEllipsoid> frame_implied(const geodesy::Frame& f, const std::string& where) {
  const auto e = frame_ellipsoid(f, where);
  if (!e) return std::nullopt;
  return ImpliedEllipsoid{e->ellipsoid, "the frame " + f.to_string() + " (" + e->source + ")"};
}

// The input's "crs": a geographic or geocentric CRS PROJ knows (EPSG:4272,
// WKT, PROJJSON) whose datum the coordinates are on. It gives the ellipsoid,
// and the frame when the input names none: the catalog's frame of its datum,
// else the CRS's name as a frame name ("NZGD49").
void read_crs(const json& doc, const std::string& source, std::optional<ImpliedEllipsoid>& implied, geodesy::Network& net) {
  const std::string where = source + ".crs";
  const Crs crs = Crs::parse(text(doc, "crs", source), where);
  const CrsDescription& d = crs.description();
  if (d.type != "geographic 2D" && d.type != "geographic 3D" && d.type != "geocentric") {
    fail(where, crs.display_name() + " is a " + d.type +
                    " CRS; expected a geographic or geocentric one (the stations are latitude, longitude and "
                    "ellipsoidal height, or ECEF)");
  }
  geodesy::Ellipsoid e = geodesy::Ellipsoid::grs80();
  try {
    e = crs_ellipsoid(crs);
  } catch (const Error& x) {
    fail(where, crs.display_name() + ": " + x.what());
  }
  if (implied && !same_ellipsoid(implied->ellipsoid, e)) {
    fail(where, crs.display_name() + " is on " + e.name() + ", which contradicts " + implied->by + ", which is on " +
                    implied->ellipsoid.name());
  }
  // A frame of the catalog and a CRS on another datum contradict each other
  // even on one ellipsoid (GDA2020 and EPSG:4283, GDA94).
  if (net.frame && (!d.catalog_frame.empty() || geodesy::implied_ellipsoid(*net.frame)) && d.catalog_frame != net.frame->name()) {
    fail(where, crs.display_name() + " is on the datum '" + d.datum + "'" +
                    (d.catalog_frame.empty() ? std::string() : " (frame " + d.catalog_frame + ")") + ", not the frame " +
                    net.frame->to_string());
  }
  if (!net.frame) {
    std::string name;  // a frame name has no spaces: "Pulkovo 1942" is Pulkovo1942
    for (char ch : !d.catalog_frame.empty() ? d.catalog_frame : d.name) {
      if (ch != ' ') name += ch;
    }
    if (crs.epoch()) name += "@" + geodesy::format_decimal_year(*crs.epoch());
    try {
      net.frame = geodesy::Frame::parse(name, where);
    } catch (const Error&) {
      // A CRS whose name is no frame name: the network has no frame (adjust asks for --frame).
    }
  }
  implied = ImpliedEllipsoid{e, "the CRS " + crs.display_name()};
}

// A local network's "local": its axes, angle sense and dimensions.
void read_local(const json& doc, const std::string& source, geodesy::NetworkSpace this_space, geodesy::Network& net) {
  if (this_space == geodesy::NetworkSpace::local) {
    if (!doc.contains("local")) fail(source + ".local", "missing: a local network states its axes, angle sense and dimensions");
    const json& l = doc.at("local");
    const std::string at = source + ".local";
    only_keys(l, at, {"axes", "angles", "dimensions"});
    const std::string axes = text(l, "axes", at);
    constexpr std::array<std::string_view, 8> kAxes{"ne", "en", "nw", "wn", "se", "es", "sw", "ws"};
    if (std::find(kAxes.begin(), kAxes.end(), axes) == kAxes.end()) {
      fail(at + ".axes", "'" + axes + "': expected one of ne en nw wn se es sw ws");
    }
    net.axes.x = axes[0];
    net.axes.y = axes[1];
    const std::string angles = text(l, "angles", at);
    if (angles != "clockwise" && angles != "counterclockwise") fail(at + ".angles", "'" + angles + "': expected clockwise or counterclockwise");
    net.axes.angles_clockwise = angles == "clockwise";
    const double dims = number(l, "dimensions", at);
    if (dims != 1.0 && dims != 2.0 && dims != 3.0) fail(at + ".dimensions", "expected 1 (heights), 2 (x, y) or 3");
    net.local_dimensions = static_cast<int>(dims);
  } else if (doc.contains("local")) {
    fail(source + ".local", "given for a network on the ellipsoid (space \"ellipsoidal\")");
  }
}

// The stations: each defined at its position, with its constraint.
void read_stations(const json& doc, const std::string& source, geodesy::Network& net, NetworkBuilder& b) {
  if (doc.contains("stations")) {
    const json& stations = doc.at("stations");
    if (!stations.is_array()) fail(source + ".stations", "expected an array");
    for (std::size_t i = 0; i < stations.size(); ++i) {
      const std::string at = source + ": stations[" + std::to_string(i) + "]";
      const json& s = stations[i];
      only_keys(s, at, {"id", "x_m", "y_m", "z_m", "lat_deg", "lon_deg", "h_m", "constraint", "constraint_sigma_m", "description"});
      b.define(text(s, "id", at), position(s, net, at), constraint_of(s, at), at);
    }
  }
}

// One element of "measurements" as it is read: its stations by key, what
// every kind may state (ignore, group), and the keys of its kind.
struct MeasurementInput {
  const json& m;
  const std::string& at;
  NetworkBuilder& b;
  const geodesy::Network& net;

  // An error model named: its standard deviations may stand for the
  // measurement's own.
  bool modelled() const { return m.contains("error_model"); }
  // A length's standard deviation: sigma_m, or none under an error model (0).
  double sigma_m() const {
    if (!m.contains("sigma_m") && modelled()) return 0.0;
    if (!m.contains("sigma_m")) fail(at + ".sigma_m", "missing (or give an error_model that gives it)");
    return positive(number(m, "sigma_m", at), at + ".sigma_m");
  }

  std::size_t station(const char* key) const { return b.reference(text(m, key, at), at + "." + key); }
  void common(geodesy::NetworkMeasurement& x) const {
    x.source = at;
    if (m.contains("ignore")) {
      if (!m.at("ignore").is_boolean()) fail(at + ".ignore", "expected true or false");
      x.ignore = m.at("ignore").get<bool>();
    }
    if (m.contains("group")) x.group = text(m, "group", at);
    if (modelled()) {
      const std::string name = text(m, "error_model", at);
      std::string names;
      for (std::size_t k = 0; k < net.error_models.size(); ++k) {
        if (net.error_models[k].name == name) x.error_model = k;
        names += (names.empty() ? "" : ", ") + net.error_models[k].name;
      }
      if (!x.error_model) {
        fail(at + ".error_model", "'" + name + "' names no error model of the file" +
                                      (names.empty() ? std::string(" (it has no error_models)") : "; expected one of " + names));
      }
    }
  }
  std::set<std::string> with(std::set<std::string> keys) const {
    const std::set<std::string> base = {"kind", "ignore", "group", "description", "error_model"};
    keys.insert(base.begin(), base.end());
    return keys;
  }
};

// A GNSS baseline, baseline cluster or point cluster: its vectors and their
// covariance (joint, per item, or an isotropic sigma).
void read_gnss(const MeasurementInput& in, const std::string& kind, geodesy::NetworkMeasurement& x) {
  const json& m = in.m;
  const std::string& at = in.at;
  NetworkBuilder& b = in.b;
  const bool points = kind == "gnss_point_cluster";
  const bool single = kind == "gnss_baseline";
  only_keys(m, at, single ? in.with({"from", "to", "dx_m", "dy_m", "dz_m", "cov_m2", "sigma_m", "frame", "solution"})
                          : in.with({points ? "points" : "baselines", "cov_m2", "frame", "solution"}));
  if (m.contains("solution")) {
    const json& sv = m.at("solution");
    if (sv.is_string()) x.solution = geodesy::parse_gnss_solution(sv.get<std::string>());
    if (!x.solution) {
      fail(at + ".solution", "value " + sv.dump() + " is not a GNSS solution type; expected one of " +
                                 geodesy::gnss_solution_names() + " (lower case)");
    }
  }
  x.kind = points ? MeasurementKind::gnss_points : MeasurementKind::gnss_baselines;
  std::vector<Eigen::Vector3d> values;
  // A planned vector (pre-analysis): its three components null; a
  // measurement's vectors all planned or none.
  std::size_t planned = 0;
  auto read_vector = [&](const json& v, const std::string& w, const char* a, const char* bb, const char* c) {
    bool nulls[3] = {false, false, false};
    const double va = value_or_planned(v, a, w, nulls[0]), vb = value_or_planned(v, bb, w, nulls[1]), vc = value_or_planned(v, c, w, nulls[2]);
    if (nulls[0] != nulls[1] || nulls[1] != nulls[2]) {
      fail(w, std::string("some of ") + a + ", " + bb + ", " + c + " are null: a planned vector has all three null, a measured one none");
    }
    planned += nulls[0] ? 1u : 0u;
    values.emplace_back(va, vb, vc);
  };
  std::vector<Eigen::Matrix3d> blocks;  // per-item 3×3 when the joint covariance is not given
  if (single) {
    x.stations = {in.station("from"), in.station("to")};
    read_vector(m, at, "dx_m", "dy_m", "dz_m");
  } else {
    const char* list = points ? "points" : "baselines";
    if (!m.contains(list) || !m.at(list).is_array() || m.at(list).empty()) fail(at + "." + list, "expected a non-empty array");
    for (std::size_t k = 0; k < m.at(list).size(); ++k) {
      const json& item = m.at(list)[k];
      const std::string w = at + "." + list + "[" + std::to_string(k) + "]";
      if (points) {
        only_keys(item, w, {"id", "x_m", "y_m", "z_m", "cov_m2", "sigma_m"});
        x.stations.push_back(b.reference(text(item, "id", w), w + ".id"));
        read_vector(item, w, "x_m", "y_m", "z_m");
      } else {
        only_keys(item, w, {"from", "to", "dx_m", "dy_m", "dz_m", "cov_m2", "sigma_m"});
        x.stations.push_back(b.reference(text(item, "from", w), w + ".from"));
        x.stations.push_back(b.reference(text(item, "to", w), w + ".to"));
        read_vector(item, w, "dx_m", "dy_m", "dz_m");
      }
      if (item.contains("cov_m2") && item.contains("sigma_m")) fail(w, "both cov_m2 and sigma_m; give one");
      if (item.contains("cov_m2")) blocks.push_back(matrix(item.at("cov_m2"), 3, w + ".cov_m2"));
      if (item.contains("sigma_m")) {
        const double sg = positive(number(item, "sigma_m", w), w + ".sigma_m");
        blocks.push_back(Eigen::Matrix3d::Identity() * sg * sg);
      }
    }
    if (!blocks.empty() && blocks.size() != values.size()) fail(at, "some items have a covariance and some not");
    if (!blocks.empty() && m.contains("cov_m2")) fail(at, "a joint cov_m2 and per-item covariances; give one");
  }
  if (planned > 0 && planned != values.size()) fail(at, "some vectors are planned (null) and some measured: give all or none");
  x.value_known = planned == 0;
  const Eigen::Index n = static_cast<Eigen::Index>(3 * values.size());
  x.value.resize(n);
  for (std::size_t k = 0; k < values.size(); ++k) x.value.segment<3>(static_cast<Eigen::Index>(3 * k)) = values[k];
  if (m.contains("cov_m2")) {
    if (single && m.contains("sigma_m")) fail(at, "both cov_m2 and sigma_m; give one");
    x.covariance = matrix(m.at("cov_m2"), n, at + ".cov_m2");
  } else if (single && m.contains("sigma_m")) {
    const double sg = positive(number(m, "sigma_m", at), at + ".sigma_m");
    x.covariance = Eigen::Matrix3d::Identity() * sg * sg;
  } else if (!blocks.empty()) {
    x.covariance = Eigen::MatrixXd::Zero(n, n);
    for (std::size_t k = 0; k < blocks.size(); ++k) {
      x.covariance.block<3, 3>(static_cast<Eigen::Index>(3 * k), static_cast<Eigen::Index>(3 * k)) = blocks[k];
    }
  } else if (in.modelled()) {
    x.covariance = Eigen::MatrixXd::Zero(n, n);  // the error model's alone
  } else {
    fail(at, "no covariance: give cov_m2 (" + std::to_string(n) + "×" + std::to_string(n) + ", m²), sigma_m or an error_model");
  }
  if (m.contains("frame")) x.frame = geodesy::Frame::parse(text(m, "frame", at), at + ".frame");
}

// A direction set: one measurement per direction, each of the set.
void read_direction_set(const MeasurementInput& in, geodesy::Network& net) {
  const json& m = in.m;
  const std::string& at = in.at;
  NetworkBuilder& b = in.b;
  only_keys(m, at, in.with({"at", "directions", "instrument_height_m"}));
  const std::size_t from = in.station("at");
  const std::size_t set = net.direction_sets.size();
  net.direction_sets.push_back({from, at});
  if (!m.contains("directions") || !m.at("directions").is_array() || m.at("directions").empty()) {
    fail(at + ".directions", "expected a non-empty array");
  }
  for (std::size_t k = 0; k < m.at("directions").size(); ++k) {
    const json& d = m.at("directions")[k];
    const std::string w = at + ".directions[" + std::to_string(k) + "]";
    std::set<std::string> keys = kAngleKeys;
    keys.insert({"to", "target_height_m", "ignore"});
    only_keys(d, w, keys);
    geodesy::NetworkMeasurement dir;
    bool planned = false;
    in.common(dir);
    dir.source = w;
    if (d.contains("ignore")) dir.ignore = d.at("ignore").is_boolean() && d.at("ignore").get<bool>();
    dir.kind = MeasurementKind::direction;
    dir.stations = {from, b.reference(text(d, "to", w), w + ".to")};
    dir.value = Eigen::VectorXd::Constant(1, angle_value(d, MeasurementKind::direction, w, net.warnings, planned));
    dir.value_known = !planned;
    const double sg = angle_sigma(d, w, in.modelled());
    dir.covariance = Eigen::MatrixXd::Constant(1, 1, sg * sg);
    dir.set = set;
    if (m.contains("instrument_height_m")) dir.instrument_height_m = number(m, "instrument_height_m", at);
    if (d.contains("target_height_m")) dir.target_height_m = number(d, "target_height_m", w);
    net.measurements.push_back(dir);
  }
}

// "error_models": {NAME: {TERM: value, …}, …}: each term a standard
// deviation >= 0 in the unit its key names, at least one > 0
// (geodesy::ErrorModel), held in the order of their names. A name another
// input already defined is refused.
void read_error_models(const json& doc, const std::string& source, geodesy::Network& net) {
  if (!doc.contains("error_models")) return;
  const json& models = doc.at("error_models");
  if (!models.is_object() || models.empty()) fail(source + ".error_models", "expected an object of named error models");
  constexpr double kMm = 1e-3, kPpm = 1.0;
  struct Term {
    const char* key;
    double geodesy::ErrorModel::*field;
    double scale;
  };
  const std::array<Term, 14> terms{{{"distance_constant_mm", &geodesy::ErrorModel::distance_constant_m, kMm},
                                    {"distance_ppm", &geodesy::ErrorModel::distance_ppm, kPpm},
                                    {"direction_pointing_arcsec", &geodesy::ErrorModel::direction_pointing_rad, kArcsec},
                                    {"direction_reading_arcsec", &geodesy::ErrorModel::direction_reading_rad, kArcsec},
                                    {"zenith_pointing_arcsec", &geodesy::ErrorModel::zenith_pointing_rad, kArcsec},
                                    {"zenith_reading_arcsec", &geodesy::ErrorModel::zenith_reading_rad, kArcsec},
                                    {"instrument_centring_mm", &geodesy::ErrorModel::instrument_centring_m, kMm},
                                    {"target_centring_mm", &geodesy::ErrorModel::target_centring_m, kMm},
                                    {"instrument_height_mm", &geodesy::ErrorModel::instrument_height_m, kMm},
                                    {"target_height_mm", &geodesy::ErrorModel::target_height_m, kMm},
                                    {"gnss_horizontal_mm", &geodesy::ErrorModel::gnss_horizontal_m, kMm},
                                    {"gnss_horizontal_ppm", &geodesy::ErrorModel::gnss_horizontal_ppm, kPpm},
                                    {"gnss_vertical_mm", &geodesy::ErrorModel::gnss_vertical_m, kMm},
                                    {"gnss_vertical_ppm", &geodesy::ErrorModel::gnss_vertical_ppm, kPpm}}};
  std::set<std::string> keys = {"description"};
  for (const auto& t : terms) keys.insert(t.key);
  for (const auto& [name, model] : models.items()) {
    const std::string at = source + ".error_models." + name;
    if (name.empty()) fail(source + ".error_models", "an error model with an empty name");
    for (const auto& e : net.error_models) {
      if (e.name == name) fail(at, "defined twice (first at " + e.source + ")");
    }
    only_keys(model, at, keys);
    geodesy::ErrorModel e;
    e.name = name;
    e.source = at;
    bool any = false;
    for (const auto& t : terms) {
      if (!model.contains(t.key)) continue;
      const double v = number(model, t.key, at);
      if (!(v >= 0.0)) fail(at + "." + t.key, "value " + format_shortest(v) + " must be >= 0");
      e.*(t.field) = v * t.scale;
      any = any || v > 0.0;
    }
    if (!any) fail(at, "no term above 0; expected at least one of " + key_list(keys));
    net.error_models.push_back(std::move(e));
  }
}

// The measurements, each as its kind says.
void read_measurements(const json& doc, const std::string& source, geodesy::Network& net, NetworkBuilder& b) {
  if (!doc.contains("measurements")) return;
  const json& ms = doc.at("measurements");
  if (!ms.is_array()) fail(source + ".measurements", "expected an array");
  for (std::size_t i = 0; i < ms.size(); ++i) {
    const std::string at = source + ": measurements[" + std::to_string(i) + "]";
    const json& m = ms[i];
    if (!m.is_object()) fail(at, "expected an object");
    const std::string kind = text(m, "kind", at);
    const MeasurementInput in{m, at, b, net};
    geodesy::NetworkMeasurement x;
    bool planned = false;  // "value_m": null, … (pre-analysis)
    in.common(x);
    if (kind == "gnss_baseline" || kind == "gnss_baseline_cluster" || kind == "gnss_point_cluster") {
      read_gnss(in, kind, x);
    } else if (kind == "slope_distance" || kind == "horizontal_distance" || kind == "ellipsoid_arc") {
      only_keys(m, at, in.with({"from", "to", "value_m", "sigma_m", "instrument_height_m", "target_height_m"}));
      x.kind = kind == "slope_distance" ? MeasurementKind::slope_distance
               : kind == "horizontal_distance" ? MeasurementKind::horizontal_distance
                                               : MeasurementKind::ellipsoid_arc;
      x.stations = {in.station("from"), in.station("to")};
      const double value = value_or_planned(m, "value_m", at, planned);
      x.value = Eigen::VectorXd::Constant(1, planned ? value : positive(value, at + ".value_m"));
      const double sg = in.sigma_m();
      x.covariance = Eigen::MatrixXd::Constant(1, 1, sg * sg);
      if (m.contains("instrument_height_m")) x.instrument_height_m = number(m, "instrument_height_m", at);
      if (m.contains("target_height_m")) x.target_height_m = number(m, "target_height_m", at);
      if (x.kind == MeasurementKind::ellipsoid_arc && (m.contains("instrument_height_m") || m.contains("target_height_m"))) {
        fail(at, "an ellipsoid arc is between footpoints: no instrument or target height");
      }
    } else if (kind == "direction_set") {
      read_direction_set(in, net);
      continue;
    } else if (kind == "horizontal_angle") {
      std::set<std::string> keys = in.with({"at", "from", "to", "instrument_height_m"});
      keys.insert(kAngleKeys.begin(), kAngleKeys.end());
      only_keys(m, at, keys);
      x.kind = MeasurementKind::horizontal_angle;
      x.stations = {in.station("at"), in.station("from"), in.station("to")};
      x.value = Eigen::VectorXd::Constant(1, angle_value(m, x.kind, at, net.warnings, planned));
      const double sg = angle_sigma(m, at, in.modelled());
      x.covariance = Eigen::MatrixXd::Constant(1, 1, sg * sg);
      if (m.contains("instrument_height_m")) x.instrument_height_m = number(m, "instrument_height_m", at);
    } else if (kind == "zenith_angle" || kind == "vertical_angle" || kind == "azimuth") {
      std::set<std::string> keys = in.with({"from", "to", "instrument_height_m", "target_height_m"});
      keys.insert(kAngleKeys.begin(), kAngleKeys.end());
      only_keys(m, at, keys);
      x.kind = kind == "zenith_angle" ? MeasurementKind::zenith_angle
               : kind == "vertical_angle" ? MeasurementKind::vertical_angle
                                          : MeasurementKind::azimuth;
      x.stations = {in.station("from"), in.station("to")};
      x.value = Eigen::VectorXd::Constant(1, angle_value(m, x.kind, at, net.warnings, planned));
      const double sg = angle_sigma(m, at, in.modelled());
      x.covariance = Eigen::MatrixXd::Constant(1, 1, sg * sg);
      if (m.contains("instrument_height_m")) x.instrument_height_m = number(m, "instrument_height_m", at);
      if (m.contains("target_height_m")) x.target_height_m = number(m, "target_height_m", at);
    } else if (kind == "height_difference") {
      only_keys(m, at, in.with({"from", "to", "value_m", "sigma_m", "sigma_mm_per_sqrt_km", "length_km"}));
      x.kind = MeasurementKind::height_difference;
      x.stations = {in.station("from"), in.station("to")};
      x.value = Eigen::VectorXd::Constant(1, value_or_planned(m, "value_m", at, planned));
      double sg = 0.0;
      if (m.contains("sigma_m") == m.contains("sigma_mm_per_sqrt_km")) {
        fail(at, "expected sigma_m, or sigma_mm_per_sqrt_km with length_km");
      }
      if (m.contains("sigma_m")) {
        if (m.contains("length_km")) fail(at + ".length_km", "only with sigma_mm_per_sqrt_km");
        sg = positive(number(m, "sigma_m", at), at + ".sigma_m");
      } else {
        sg = 1e-3 * positive(number(m, "sigma_mm_per_sqrt_km", at), at + ".sigma_mm_per_sqrt_km") *
             std::sqrt(positive(number(m, "length_km", at), at + ".length_km"));
      }
      x.covariance = Eigen::MatrixXd::Constant(1, 1, sg * sg);
    } else if (kind == "ellipsoidal_height" || kind == "orthometric_height") {
      only_keys(m, at, in.with({"at", "value_m", "sigma_m"}));
      x.kind = kind == "ellipsoidal_height" ? MeasurementKind::ellipsoidal_height : MeasurementKind::orthometric_height;
      x.stations = {in.station("at")};
      x.value = Eigen::VectorXd::Constant(1, value_or_planned(m, "value_m", at, planned));
      const double sg = positive(number(m, "sigma_m", at), at + ".sigma_m");
      x.covariance = Eigen::MatrixXd::Constant(1, 1, sg * sg);
    } else {
      fail(at + ".kind", "'" + kind + "': expected gnss_baseline, gnss_baseline_cluster, gnss_point_cluster, slope_distance, "
                                      "horizontal_distance, ellipsoid_arc, direction_set, horizontal_angle, zenith_angle, "
                                      "vertical_angle, azimuth, height_difference, ellipsoidal_height or orthometric_height");
    }
    if (planned) x.value_known = false;
    // A local network's azimuth is a bearing from +x turning as its angles
    // do (GNU Gama's and STAR*NET's grid bearing); an ellipsoid arc has no
    // meaning there.
    if (net.space == geodesy::NetworkSpace::local && (x.kind == MeasurementKind::ellipsoid_arc || x.frame)) {
      fail(at, std::string(geodesy::to_string(x.kind)) + (x.frame ? " with a frame" : "") + " in a local network");
    }
    net.measurements.push_back(std::move(x));
  }
}

}  // namespace

void read_network_json(std::string_view text_in, std::string_view source_in, geodesy::Network& into) {
  const std::string source(source_in);
  const json doc = parse_json_strict<json>(text_in, source);
  only_keys(doc, source,
            {"schema", "space", "frame", "crs", "ellipsoid", "local", "stations", "measurements", "error_models", "description"});
  if (text(doc, "schema", source) != "geoanchor.network/1") {
    fail(source + ".schema", "'" + doc.at("schema").get<std::string>() + "': expected geoanchor.network/1");
  }
  geodesy::Network& net = into;
  const std::string space = doc.contains("space") ? text(doc, "space", source) : "ellipsoidal";
  if (space != "ellipsoidal" && space != "local") fail(source + ".space", "'" + space + "': expected ellipsoidal or local");
  const geodesy::NetworkSpace this_space = space == "local" ? geodesy::NetworkSpace::local : geodesy::NetworkSpace::ellipsoidal;
  const bool first = net.stations.empty() && net.measurements.empty();
  if (!first && net.space != this_space) fail(source + ".space", "'" + space + "' but the other inputs are another space");
  net.space = this_space;
  if (doc.contains("frame")) {
    if (this_space == geodesy::NetworkSpace::local) fail(source + ".frame", "a local network has no frame");
    const auto f = geodesy::Frame::parse(text(doc, "frame", source), source + ".frame");
    if (net.frame && !(*net.frame == f)) {
      fail(source + ".frame", f.to_string() + " but another input is in " + net.frame->to_string());
    }
    net.frame = f;
  }
  if (doc.contains("crs")) {
    if (this_space == geodesy::NetworkSpace::local) fail(source + ".crs", "a local network has no CRS");
  }
  // The ellipsoid: the frame's (catalog, else PROJ), the CRS's, the input's
  // "ellipsoid"; where several are given they agree.
  std::optional<ImpliedEllipsoid> implied;
  if (net.frame) implied = frame_implied(*net.frame, source + (doc.contains("frame") ? ".frame" : ""));
  if (doc.contains("crs")) read_crs(doc, source, implied, net);
  if (implied) net.ellipsoid = implied->ellipsoid, net.ellipsoid_stated = true;
  if (doc.contains("ellipsoid")) read_ellipsoid(doc, source, implied, net);
  read_local(doc, source, this_space, net);

  NetworkBuilder b(net);
  read_stations(doc, source, net, b);
  read_error_models(doc, source, net);
  read_measurements(doc, source, net, b);
}

}  // namespace geoanchor::io::detail
