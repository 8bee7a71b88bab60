// GNU Gama's local-network input (gama-local XML), read with expat.
//
// The format as GNU Gama's manual defines it ("gama-local input data
// format", doc/gama-local-input.texi; docs/network-format.md lists what is
// read and how):
//  - <gama-local> holds one <network axes-xy="ne" angles="left-handed">
//    with <description>, <parameters> and <points-observations>;
//  - axes-xy names the directions of +x and +y; angles are clockwise
//    ("left-handed") or counter-clockwise; bearings run from +x;
//  - <point id x y z fix adj>: fix (any case) holds a component fixed;
//    adj in lower case makes it an unknown, in upper case a constrained
//    unknown that holds whatever datum defect the fixed components leave
//    (the minimum-norm solution over those); a given component neither
//    fixed nor adjusted is held fixed;
//  - <obs from>: directions (one orientation unknown per <obs>),
//    distances (horizontal), angles, s-distances, z-angles (zenith),
//    azimuths (bearings from +x); <height-differences> (dh), <vectors>
//    (vec dx dy dz) and <coordinates> (observed points), each group with an
//    optional <cov-mat dim band> (upper band by rows, in the group's order;
//    mm², cc² or ″² and their products): a cov-mat that correlates two
//    terrestrial observations makes the group one observation set;
//  - lengths in metres, their standard deviations in millimetres; angles
//    in gon (400 a circle) with standard deviations in cc (1e-4 gon), or
//    as d-m-s text "57-32-28.428" with standard deviations in arc-seconds;
//  - distance-stdev="a b c" is σ = a + b·D_km^c mm; a dh without stdev has
//    σ = sigma-apr·√dist_km mm;
//  - `extern` attributes (an observation's or point's outside identifier)
//    are accepted and not used;
//  - tol-abs (mm): measurements whose misclosure at the a-priori
//    coordinates is larger are set aside (with a warning).

#include <algorithm>
#include <cctype>
#include <cmath>
#include <map>
#include <memory>
#include <numbers>
#include <optional>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "geoanchor/base/error.hpp"
#include "geoanchor/base/number_text.hpp"
#include "network/network_builder.hpp"
#include "network/network_readers.hpp"
#include "xml_stream.hpp"

namespace geoanchor::io::detail {
namespace {

using geodesy::MeasurementKind;

constexpr double kMm = 1e-3;
constexpr double kGon = std::numbers::pi / 200.0;
constexpr double kCc = kGon * 1e-4;
constexpr double kArcsec = std::numbers::pi / 648000.0;

using Attributes = std::map<std::string, std::string>;

// One observation of a group, before its covariance is known.
struct Pending {
  geodesy::NetworkMeasurement m;
  double sigma_unit = 1.0;        // the SI value of one unit of the group's cov-mat (mm or cc or ″)
  std::optional<double> sigma;    // from the element or the defaults (SI)
  std::size_t line = 0;
  std::string element;
};

// A <point> as the file gives it; later elements for the same id add to it.
struct PointText {
  std::optional<double> x, y, z;
  std::string fix, adj;
  std::size_t line = 0;
};

class Reader final : public XmlHandler {
 public:
  Reader(std::string_view source, geodesy::Network& net) : source_(source), net_(net), builder_(net) {}

  void parse(std::string_view text) {
    xml_.parse(text, source_, "E_GAMA");
    if (!network_seen_) fail(1, "no <network> in <gama-local>");
    finish();
  }

  void start_element(const std::string& name, const XML_Char** attributes) override {
    Attributes a;
    for (const XML_Char** p = attributes; *p; p += 2) a[p[0]] = p[1];
    start(name, a);
  }
  void end_element(const std::string& name) override { end(name); }
  void character_data(const char* s, std::size_t n) override { text_.append(s, n); }

 private:
  [[noreturn]] void fail(std::size_t line, const std::string& what) const {
    throw Error(ErrorKind::input, "E_GAMA", source_ + ":" + std::to_string(line) + ": " + what);
  }
  std::size_t line() const { return xml_.line(); }
  std::string where(std::size_t at) const { return source_ + ":" + std::to_string(at); }

  void only(const std::string& element, const Attributes& a, const std::set<std::string>& allowed) const {
    for (const auto& [key, value] : a) {
      if (allowed.count(key)) continue;
      std::string list;
      for (const auto& k : allowed) list += (list.empty() ? "" : ", ") + k;
      fail(line(), "<" + element + "> attribute " + key + "=\"" + value + "\" is not read by geoanchor" +
                       (list.empty() ? "" : "; expected " + list));
    }
  }
  double number(const std::string& element, const std::string& key, const std::string& text) const {
    const auto v = parse_finite_double(trim(text));
    if (!v) fail(line(), "<" + element + "> " + key + "=\"" + text + "\" is not a number");
    return *v;
  }
  std::optional<double> optional_number(const std::string& element, const Attributes& a, const std::string& key) const {
    const auto it = a.find(key);
    if (it == a.end() || trim(it->second).empty()) return std::nullopt;
    return number(element, key, it->second);
  }
  double required_number(const std::string& element, const Attributes& a, const std::string& key) const {
    const auto v = optional_number(element, a, key);
    if (!v) fail(line(), "<" + element + "> has no " + key);
    return *v;
  }
  static std::string trim(const std::string& s) {
    const auto b = s.find_first_not_of(" \t\r\n");
    if (b == std::string::npos) return "";
    return s.substr(b, s.find_last_not_of(" \t\r\n") - b + 1);
  }
  std::string required_text(const std::string& element, const Attributes& a, const std::string& key) const {
    const auto it = a.find(key);
    if (it == a.end() || trim(it->second).empty()) fail(line(), "<" + element + "> has no " + key);
    return trim(it->second);
  }

  // An angle of `kind` in radians, within the kind's range, and the SI size
  // of one unit of its standard deviation: gon and cc, or d-m-s text and
  // arc-seconds (seconds of 60 add a warning).
  std::pair<double, double> angle(const std::string& element, MeasurementKind kind, const std::string& text) const {
    const std::string t = trim(text);
    const std::string at = where(line()) + ": <" + element + "> val";
    // d-m-s text: a '-' between digits past the sign (not an exponent's).
    bool dms = false;
    for (std::size_t i = 1; i + 1 < t.size(); ++i) {
      dms = dms || (t[i] == '-' && std::isdigit(static_cast<unsigned char>(t[i - 1])) && std::isdigit(static_cast<unsigned char>(t[i + 1])));
    }
    const double value = dms ? dms_text_to_rad(t, at, net_.warnings) : number(element, "val", t) * kGon;
    check_angle_range(kind, value, t, dms ? AngleUnit::dms_text : AngleUnit::gon, at);
    return {value, dms ? kArcsec : kCc};
  }

  // The standard deviation from `stdev` or the group's default, in units of `unit`.
  std::optional<double> stdev(const std::string& element, const Attributes& a, const std::optional<double>& fallback,
                              double unit) const {
    if (const auto s = optional_number(element, a, "stdev")) {
      if (!(*s > 0.0)) fail(line(), "<" + element + "> stdev=\"" + a.at("stdev") + "\" must be > 0");
      return *s * unit;
    }
    if (fallback) return *fallback * unit;
    return std::nullopt;
  }

  std::size_t station(const std::string& id) {
    const std::size_t s = builder_.reference(id, where(line()));
    return s;
  }

  void start(const std::string& name, const Attributes& a) {
    text_.clear();
    const std::string parent = path_.empty() ? "" : path_.back();
    path_.push_back(name);
    if (path_.size() == 1) {
      if (name != "gama-local") fail(line(), "root element <" + name + ">; expected <gama-local>");
      only(name, a, {"xmlns", "version"});
      return;
    }
    if (name == "network" && parent == "gama-local") {
      network(name, a);
      return;
    }
    if (!network_seen_) fail(line(), "<" + name + "> outside <network>");
    if (name == "description" && parent == "network") return;
    if (name == "parameters" && parent == "network") {
      parameters(name, a);
      return;
    }
    if (name == "points-observations" && parent == "network") {
      points_observations(name, a);
      return;
    }
    if (parent == "points-observations") {
      if (name == "point") return point(a);
      if (name == "obs") {
        only(name, a, {"from", "orientation", "from_dh", "extern"});
        group_ = {};
        group_line_ = line();
        obs_from_ = required_text(name, a, "from");
        obs_from_dh_ = optional_number(name, a, "from_dh").value_or(0.0);
        set_.reset();
        return;
      }
      if (name == "height-differences" || name == "vectors" || name == "coordinates") {
        only(name, a, {});
        group_ = {};
        group_line_ = line();
        return;
      }
      fail(line(), "element <" + name + "> in <points-observations>; expected point, obs, height-differences, vectors or coordinates");
    }
    if (name == "cov-mat" && (parent == "obs" || parent == "height-differences" || parent == "vectors" || parent == "coordinates")) {
      cov_mat(name, a);
      return;
    }
    if (parent == "obs") return observation(name, a);
    if (parent == "height-differences") return height_difference(name, a);
    if (parent == "vectors") return gnss_vector(name, a);
    if (parent == "coordinates") return observed_point(name, a);
    fail(line(), "element <" + name + "> in <" + parent + "> is not read by geoanchor");
  }

  // <network>: its axes and angles, the same as the other inputs'.
  void network(const std::string& name, const Attributes& a) {
    if (network_seen_) fail(line(), "a second <network>; geoanchor reads one network per file");
    network_seen_ = true;
    only(name, a, {"axes-xy", "angles"});
    const std::string axes = a.count("axes-xy") ? trim(a.at("axes-xy")) : "ne";
    const std::string valid = "ne sw es wn en nw se ws";
    if (axes.size() != 2 || valid.find(axes) == std::string::npos) {
      fail(line(), "<network> axes-xy=\"" + axes + "\"; expected one of ne, sw, es, wn, en, nw, se, ws");
    }
    const std::string angles = a.count("angles") ? trim(a.at("angles")) : "left-handed";
    if (angles != "left-handed" && angles != "right-handed") {
      fail(line(), "<network> angles=\"" + angles + "\"; expected left-handed (clockwise) or right-handed");
    }
    const bool first = net_.stations.empty() && net_.measurements.empty();
    first_network_ = first;
    if (!first && net_.space != geodesy::NetworkSpace::local) {
      fail(line(), "a local network, but the other inputs are on the ellipsoid");
    }
    geodesy::LocalAxes axes_here;
    axes_here.x = axes[0];
    axes_here.y = axes[1];
    axes_here.angles_clockwise = angles == "left-handed";
    if (!first && (net_.axes.x != axes_here.x || net_.axes.y != axes_here.y ||
                   net_.axes.angles_clockwise != axes_here.angles_clockwise)) {
      fail(line(), "axes-xy=\"" + axes + "\" angles=\"" + angles + "\" differ from another input's (" + net_.axes.name() + ")");
    }
    net_.space = geodesy::NetworkSpace::local;
    net_.axes = axes_here;
  }

  // <parameters>: sigma-apr and tol-abs; conf-pr noted.
  void parameters(const std::string& name, const Attributes& a) {
    only(name, a, {"sigma-apr", "conf-pr", "tol-abs", "sigma-act", "update-constrained-coordinates", "algorithm",
                   "cov-band", "angles", "language", "encoding"});
    if (const auto s = optional_number(name, a, "sigma-apr")) {
      if (!(*s > 0.0)) fail(line(), "<parameters> sigma-apr must be > 0");
      sigma_apr_mm_ = *s;
    }
    if (const auto t = optional_number(name, a, "tol-abs")) {
      if (!(*t > 0.0)) fail(line(), "<parameters> tol-abs must be > 0");
      tol_abs_mm_ = *t;
    }
    if (a.count("conf-pr")) {
      net_.warnings.push_back(where(line()) + ": conf-pr=\"" + a.at("conf-pr") +
                              "\": geoanchor's --confidence and --alpha set the tests' levels");
    }
  }

  // <points-observations>: the group's default standard deviations.
  void points_observations(const std::string& name, const Attributes& a) {
    only(name, a, {"distance-stdev", "direction-stdev", "angle-stdev", "zenith-angle-stdev", "azimuth-stdev"});
    defaults_ = {};
    distance_abc_.clear();
    if (a.count("distance-stdev")) {
      std::istringstream in(a.at("distance-stdev"));
      std::string word;
      std::vector<double> abc;
      while (in >> word) abc.push_back(number(name, "distance-stdev", word));
      if (abc.empty() || abc.size() > 3) fail(line(), "distance-stdev=\"" + a.at("distance-stdev") + "\"; expected a [b [c]]");
      distance_abc_ = {abc[0], abc.size() > 1 ? abc[1] : 0.0, abc.size() > 2 ? abc[2] : 1.0};
      if (!(distance_abc_[0] > 0.0) || distance_abc_[1] < 0.0 || distance_abc_[2] < 0.0) {
        fail(line(), "distance-stdev=\"" + a.at("distance-stdev") + "\": a must be > 0 and b, c >= 0 (σ = a + b·D_km^c mm)");
      }
    }
    defaults_.direction = optional_number(name, a, "direction-stdev");
    defaults_.angle = optional_number(name, a, "angle-stdev");
    defaults_.zenith = optional_number(name, a, "zenith-angle-stdev");
    defaults_.azimuth = optional_number(name, a, "azimuth-stdev");
    for (const char* key : {"direction-stdev", "angle-stdev", "zenith-angle-stdev", "azimuth-stdev"}) {
      if (const auto v = optional_number(name, a, key); v && !(*v > 0.0)) {
        fail(line(), std::string(key) + "=\"" + a.at(key) + "\" must be > 0");
      }
    }
  }

  // <cov-mat>: the dimension and band of the group's covariance (its text follows).
  void cov_mat(const std::string& name, const Attributes& a) {
    only(name, a, {"dim", "band"});
    const double dim = required_number(name, a, "dim"), band = required_number(name, a, "band");
    if (!(dim >= 0.0 && dim <= 1e6 && dim == std::floor(dim)) || !(band >= 0.0 && band <= 1e6 && band == std::floor(band))) {
      fail(line(), "<cov-mat dim=\"" + a.at("dim") + "\" band=\"" + a.at("band") + "\">: expected whole numbers >= 0");
    }
    cov_dim_ = static_cast<long>(dim);
    cov_band_ = std::min(static_cast<long>(band), std::max(cov_dim_ - 1, 0L));  // a band past the last column is the full matrix
    cov_line_ = line();
  }

  // <dh> in <height-differences>.
  void height_difference(const std::string& name, const Attributes& a) {
    if (name != "dh") fail(line(), "element <" + name + "> in <height-differences>; expected dh or cov-mat");
    only(name, a, {"from", "to", "val", "stdev", "dist", "extern"});
    Pending p;
    p.line = line();
    p.element = name;
    p.m.kind = MeasurementKind::height_difference;
    p.m.stations = {station(required_text(name, a, "from")), station(required_text(name, a, "to"))};
    p.m.value = Eigen::VectorXd::Constant(1, required_number(name, a, "val"));
    p.sigma_unit = kMm;
    p.sigma = stdev(name, a, std::nullopt, kMm);
    // Neither: its group's cov-mat must give it (close_group).
    if (const auto dist = optional_number(name, a, "dist"); !p.sigma && dist) {
      if (!(*dist > 0.0)) fail(line(), "<dh> dist=\"" + a.at("dist") + "\" must be > 0 (km)");
      p.sigma = sigma_apr_mm_ * std::sqrt(*dist) * kMm;
    }
    three_d_.push_back({p.m.stations, line()});
    group_.push_back(std::move(p));
  }

  // <vec> in <vectors>.
  void gnss_vector(const std::string& name, const Attributes& a) {
    if (name != "vec") fail(line(), "element <" + name + "> in <vectors>; expected vec or cov-mat");
    only(name, a, {"from", "to", "dx", "dy", "dz", "from_dh", "to_dh", "extern"});
    Pending p;
    p.line = line();
    p.element = name;
    p.m.kind = MeasurementKind::gnss_baselines;
    p.m.stations = {station(required_text(name, a, "from")), station(required_text(name, a, "to"))};
    // Between the instrument points: the marks differ by dz + from_dh − to_dh.
    const double from_dh = optional_number(name, a, "from_dh").value_or(0.0);
    const double to_dh = optional_number(name, a, "to_dh").value_or(0.0);
    p.m.value = Eigen::Vector3d(required_number(name, a, "dx"), required_number(name, a, "dy"),
                                required_number(name, a, "dz") + from_dh - to_dh);
    p.sigma_unit = kMm;
    three_d_.push_back({p.m.stations, line()});
    group_.push_back(std::move(p));
  }

  // <point> in <coordinates>: an observed point.
  void observed_point(const std::string& name, const Attributes& a) {
    if (name != "point") fail(line(), "element <" + name + "> in <coordinates>; expected point or cov-mat");
    only(name, a, {"id", "x", "y", "z", "extern"});
    Pending p;
    p.line = line();
    p.element = "coordinates point";
    p.m.kind = MeasurementKind::gnss_points;
    p.m.stations = {station(required_text(name, a, "id"))};
    const auto x = optional_number(name, a, "x"), y = optional_number(name, a, "y"), z = optional_number(name, a, "z");
    if (!x || !y || !z) {
      fail(line(), "an observed point with only some of x, y, z: geoanchor reads observed coordinates with all three");
    }
    p.m.value = Eigen::Vector3d(*x, *y, *z);
    p.sigma_unit = kMm;
    three_d_.push_back({p.m.stations, line()});
    group_.push_back(std::move(p));
  }

  void point(const Attributes& a) {
    only("point", a, {"id", "x", "y", "z", "fix", "adj"});
    const std::string id = required_text("point", a, "id");
    PointText& p = points_[id];
    if (!p.line) {
      p.line = line();
      point_order_.push_back(id);
    }
    // A point named again may add to it; its coordinates must not change.
    auto coordinate = [&](const char* key, std::optional<double>& into) {
      const auto v = optional_number("point", a, key);
      if (!v) return;
      if (into && *into != *v) {
        fail(line(), "point " + id + ": " + key + "=\"" + a.at(key) + "\" differs from " + format_shortest(*into) +
                         " given at line " + std::to_string(p.line) + "; give one value");
      }
      into = v;
    };
    coordinate("x", p.x);
    coordinate("y", p.y);
    coordinate("z", p.z);
    if ((a.count("x") != 0) != (a.count("y") != 0)) fail(line(), "point " + id + ": x without y or y without x");
    auto flags = [&](const std::string& key) {
      if (!a.count(key)) return std::optional<std::string>();
      const std::string v = trim(a.at(key));
      static const std::set<std::string> valid = {"xy", "XY", "xY", "Xy", "z", "Z", "xyz", "XYZ", "xyZ", "XYz", "xYz",
                                                  "XyZ", "Xyz", "xYZ", ""};
      if (!valid.count(v)) fail(line(), "point " + id + ": " + key + "=\"" + v + "\"; expected xy, z or xyz (upper case: constrained)");
      return std::optional<std::string>(v);
    };
    if (const auto f = flags("fix")) p.fix = *f;
    if (const auto f = flags("adj")) p.adj = *f;
    builder_.reference(id, where(line()));
  }

  void observation(const std::string& name, const Attributes& a) {
    Pending p;
    p.line = line();
    p.element = name;
    const std::string from = a.count("from") ? trim(a.at("from")) : obs_from_;
    if (a.count("from") && from != obs_from_) {
      fail(line(), "<" + name + "> from=\"" + from + "\" in <obs from=\"" + obs_from_ + "\">: one instrument station per <obs>");
    }
    const double from_dh = optional_number(name, a, "from_dh").value_or(obs_from_dh_);
    if (name == "direction" || name == "distance" || name == "s-distance" || name == "z-angle" || name == "azimuth") {
      only(name, a, {"from", "to", "val", "stdev", "from_dh", "to_dh", "extern"});
      p.m.stations = {station(from), station(required_text(name, a, "to"))};
      p.m.instrument_height_m = from_dh;
      p.m.target_height_m = optional_number(name, a, "to_dh").value_or(0.0);
    } else if (name == "angle") {
      only(name, a, {"from", "bs", "fs", "val", "stdev", "from_dh", "bs_dh", "fs_dh", "extern"});
      p.m.stations = {station(from), station(required_text(name, a, "bs")), station(required_text(name, a, "fs"))};
    } else {
      fail(line(), "element <" + name + "> in <obs>; expected direction, distance, angle, s-distance, z-angle, azimuth or cov-mat");
    }
    if (!a.count("val")) fail(line(), "<" + name + "> has no val");
    if (name == "distance" || name == "s-distance") {
      const double d = required_number(name, a, "val");
      if (!(d > 0.0)) fail(line(), "<" + name + "> val=\"" + a.at("val") + "\" must be > 0 (metres)");
      p.m.kind = name == "distance" ? MeasurementKind::horizontal_distance : MeasurementKind::slope_distance;
      p.m.value = Eigen::VectorXd::Constant(1, d);
      p.sigma_unit = kMm;
      std::optional<double> fallback;
      if (!distance_abc_.empty()) fallback = distance_abc_[0] + distance_abc_[1] * std::pow(d / 1000.0, distance_abc_[2]);
      p.sigma = stdev(name, a, fallback, kMm);
      if (name == "s-distance") three_d_.push_back({p.m.stations, line()});
    } else {
      p.m.kind = name == "direction" ? MeasurementKind::direction
                 : name == "angle"   ? MeasurementKind::horizontal_angle
                 : name == "z-angle" ? MeasurementKind::zenith_angle
                                     : MeasurementKind::azimuth;
      const auto [value, unit] = angle(name, p.m.kind, a.at("val"));
      p.m.value = Eigen::VectorXd::Constant(1, value);
      p.sigma_unit = unit;
      std::optional<double> fallback;
      if (name == "direction") {
        fallback = defaults_.direction;
        if (!set_) {
          set_ = net_.direction_sets.size();
          net_.direction_sets.push_back({p.m.stations[0], where(group_line_)});
        }
        p.m.set = set_;
      } else if (name == "angle") {
        fallback = defaults_.angle;
      } else if (name == "z-angle") {
        fallback = defaults_.zenith;
        three_d_.push_back({p.m.stations, line()});
      } else {
        fallback = defaults_.azimuth;
      }
      p.sigma = stdev(name, a, fallback, unit);
    }
    group_.push_back(std::move(p));
  }

  void end(const std::string& name) {
    const std::string body = text_;
    text_.clear();
    path_.pop_back();
    if (name == "cov-mat") {
      cov_values_.clear();
      std::istringstream in(body);
      std::string word;
      while (in >> word) cov_values_.push_back(number("cov-mat", "value", word));
      cov_given_ = true;
      return;
    }
    if (name == "obs" || name == "height-differences" || name == "vectors" || name == "coordinates") {
      close_group(name);
      return;
    }
  }

  // The group's covariance (its cov-mat, or each observation's stdev) and
  // its measurements into the network.
  void close_group(const std::string& element) {
    const bool vectors = element == "vectors" || element == "coordinates";
    std::size_t dim = 0;
    for (const auto& p : group_) dim += static_cast<std::size_t>(p.m.value.size());
    Eigen::MatrixXd cov = Eigen::MatrixXd::Zero(static_cast<Eigen::Index>(dim), static_cast<Eigen::Index>(dim));
    if (cov_given_) {
      if (static_cast<std::size_t>(cov_dim_) != dim) {
        fail(cov_line_, "<cov-mat dim=\"" + std::to_string(cov_dim_) + "\"> in a group of " + std::to_string(dim) +
                            " observed values; the dimension must match");
      }
      // Upper band by rows: row i holds (i, i) … (i, min(i + band, dim − 1)).
      std::size_t expected = 0;
      for (std::size_t i = 0; i < dim; ++i) expected += std::min<std::size_t>(static_cast<std::size_t>(cov_band_), dim - 1 - i) + 1;
      if (cov_values_.size() != expected) {
        fail(cov_line_, "<cov-mat dim=\"" + std::to_string(cov_dim_) + "\" band=\"" + std::to_string(cov_band_) + "\"> holds " +
                            std::to_string(cov_values_.size()) + " values; expected " + std::to_string(expected) +
                            " (the upper band by rows)");
      }
      std::vector<double> unit;
      for (const auto& p : group_) {
        for (Eigen::Index k = 0; k < p.m.value.size(); ++k) unit.push_back(p.sigma_unit);
      }
      std::size_t at = 0;
      for (std::size_t i = 0; i < dim; ++i) {
        for (std::size_t j = i; j <= std::min(i + static_cast<std::size_t>(cov_band_), dim - 1); ++j) {
          const double v = cov_values_[at++] * unit[i] * unit[j];
          cov(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(j)) = v;
          cov(static_cast<Eigen::Index>(j), static_cast<Eigen::Index>(i)) = v;
        }
      }
    } else {
      if (vectors) {
        fail(group_line_, "<" + element + "> without a <cov-mat>: observed vectors and coordinates need their covariance");
      }
      std::size_t at = 0;
      for (const auto& p : group_) {
        if (!p.sigma && p.element == "dh") {
          fail(p.line, "<dh> has neither stdev (mm) nor dist (km) for its standard deviation, and its "
                       "<height-differences> no <cov-mat>");
        }
        if (!p.sigma) {
          fail(p.line, "<" + p.element + "> has no stdev and <points-observations> gives no default for it");
        }
        cov(static_cast<Eigen::Index>(at), static_cast<Eigen::Index>(at)) = *p.sigma * *p.sigma;
        ++at;
      }
    }
    if (vectors) {
      // One measurement: every vector or point with the joint covariance.
      geodesy::NetworkMeasurement m;
      m.kind = group_.empty() ? MeasurementKind::gnss_baselines : group_.front().m.kind;
      m.value.resize(static_cast<Eigen::Index>(dim));
      std::size_t at = 0;
      for (const auto& p : group_) {
        m.stations.insert(m.stations.end(), p.m.stations.begin(), p.m.stations.end());
        m.value.segment(static_cast<Eigen::Index>(at), 3) = p.m.value;
        at += 3;
      }
      m.covariance = cov;
      m.source = where(group_line_) + " <" + element + ">";
      if (dim > 0) net_.measurements.push_back(std::move(m));
    } else {
      // Terrestrial observations: each a measurement of its own, or, when
      // the cov-mat correlates any two, one observation set of them all.
      bool correlated = false;
      for (Eigen::Index i = 0; i < cov.rows(); ++i) {
        for (Eigen::Index j = 0; j < i; ++j) correlated = correlated || cov(i, j) != 0.0;
      }
      std::vector<geodesy::NetworkMeasurement> parts;
      Eigen::Index at = 0;
      for (auto& p : group_) {
        p.m.covariance = Eigen::MatrixXd::Constant(1, 1, cov(at, at));
        ++at;
        p.m.source = where(p.line) + " <" + p.element + ">";
        if (correlated) parts.push_back(std::move(p.m));
        else net_.measurements.push_back(std::move(p.m));
      }
      if (correlated) {
        net_.measurements.push_back(geodesy::make_observation_set(std::move(parts), cov, where(group_line_) + " <" + element + ">"));
      }
    }
    group_.clear();
    cov_given_ = false;
    cov_values_.clear();
  }

  // The points into the network, once every element is read.
  void finish() {
    // The dimension: heights only, plane only, or both.
    bool horizontal = false, vertical = !three_d_.empty();
    for (const auto& set : net_.measurements) {
      for (const auto& m : geodesy::parts_of(set)) {
        switch (m.kind) {
          case MeasurementKind::height_difference: break;
          case MeasurementKind::slope_distance:
          case MeasurementKind::zenith_angle:
          case MeasurementKind::gnss_baselines:
          case MeasurementKind::gnss_points: horizontal = vertical = true; break;
          default: horizontal = true; break;
        }
      }
    }
    for (const auto& [id, p] : points_) {
      auto has = [](const std::string& s, char c) { return s.find(c) != std::string::npos || s.find(static_cast<char>(std::toupper(c))) != std::string::npos; };
      horizontal = horizontal || has(p.adj, 'x') || has(p.adj, 'y');
      vertical = vertical || has(p.adj, 'z');
    }
    int dims = horizontal && vertical ? 3 : horizontal ? 2 : 1;
    if (!first_network_ && net_.local_dimensions != dims) dims = 3;  // another input's part
    net_.local_dimensions = dims;
    if (tol_abs_mm_ > 0.0) {
      net_.gross_misclosure_m = net_.gross_misclosure_m > 0.0 ? std::min(net_.gross_misclosure_m, tol_abs_mm_ * kMm)
                                                              : tol_abs_mm_ * kMm;
    }

    std::set<std::size_t> no_height;
    for (const auto& id : point_order_) {
      const PointText& p = points_.at(id);
      const std::string at = where(p.line);
      geodesy::StationConstraint con;
      bool datum = false;
      const char letters[3] = {'x', 'y', 'z'};
      const std::optional<double> value[3] = {p.x, p.y, p.z};
      for (int k = 0; k < 3; ++k) {
        const char lo = letters[k], up = static_cast<char>(std::toupper(lo));
        const bool fixed = p.fix.find(lo) != std::string::npos || p.fix.find(up) != std::string::npos;
        const bool adjusted = p.adj.find(lo) != std::string::npos;
        const bool constrained = p.adj.find(up) != std::string::npos;
        const bool used = k == 2 ? dims != 2 : dims != 1;
        if (!used) continue;
        if (fixed) {
          if (!value[k]) fail(p.line, "point " + id + " fixes " + std::string(1, lo) + " but gives no value for it");
          con.code[static_cast<std::size_t>(k)] = 'C';
        } else if (adjusted || constrained) {
          datum = datum || constrained;
        } else if (value[k]) {
          con.code[static_cast<std::size_t>(k)] = 'C';  // given, neither fixed nor adjusted: held
        } else {
          con.code[static_cast<std::size_t>(k)] = 'C';  // not part of the network: checked against the measurements below
          if (k == 2) no_height.insert(*net_.find(id));
        }
      }
      const bool horizontal_given = p.x && p.y;
      if (dims != 1 && !horizontal_given && con.code[0] == 'C') {
        fail(p.line, "point " + id + ": x and y are neither given nor adjusted");
      }
      const Eigen::Vector3d position(p.x.value_or(0.0), p.y.value_or(0.0), p.z.value_or(0.0));
      const std::size_t s = builder_.define(id, position, con, at);
      const bool known = dims == 1 ? p.z.has_value() : horizontal_given;
      net_.stations[s].position_known = known;
      if (datum) {
        geodesy::DatumStation d;
        d.station = s;
        for (int k = 0; k < 3; ++k) {
          d.components[static_cast<std::size_t>(k)] =
              p.adj.find(static_cast<char>(std::toupper(letters[k]))) != std::string::npos;
        }
        net_.datum_stations.push_back(d);
      }
    }
    for (const auto& [stations, at] : three_d_) {
      for (std::size_t s : stations) {
        if (no_height.count(s)) {
          fail(at, "point " + net_.stations[s].id + " has no z (neither given nor adjusted) but a height, slope distance, "
                   "zenith angle, vector or observed coordinate needs it");
        }
      }
    }
  }

  std::string source_;
  geodesy::Network& net_;
  NetworkBuilder builder_;
  XmlStream xml_{*this};
  std::vector<std::string> path_;
  std::string text_;
  bool network_seen_ = false;
  bool first_network_ = true;

  double sigma_apr_mm_ = 10.0;
  double tol_abs_mm_ = 1000.0;
  struct Defaults {
    std::optional<double> direction, angle, zenith, azimuth;
  } defaults_;
  std::vector<double> distance_abc_;

  std::map<std::string, PointText> points_;
  std::vector<std::string> point_order_;

  std::vector<Pending> group_;
  std::size_t group_line_ = 0;
  std::string obs_from_;
  double obs_from_dh_ = 0.0;
  std::optional<std::size_t> set_;
  bool cov_given_ = false;
  long cov_dim_ = 0, cov_band_ = 0;
  std::size_t cov_line_ = 0;
  std::vector<double> cov_values_;
  std::vector<std::pair<std::vector<std::size_t>, std::size_t>> three_d_;  // stations that need a height, and the line
};

}  // namespace

void read_gama_local(std::string_view text, std::string_view source, geodesy::Network& into) {
  Reader(source, into).parse(text);
}

}  // namespace geoanchor::io::detail
