// `geoanchor adjust` as a library (adjust.hpp).

#include "geoanchor/workflow/adjust.hpp"

#include "geoanchor/base/parallel.hpp"

#include <Eigen/SVD>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <filesystem>
#include <cstdio>
#include <limits>
#include <numbers>
#include <sstream>
#include <stdexcept>

#include "geoanchor/base/error.hpp"
#include "geoanchor/geodesy/frame_catalog.hpp"
#include "geoanchor/geodesy/geocentric.hpp"
#include "geoanchor/geodesy/local_frame.hpp"
#include "geoanchor/base/number_text.hpp"
#include "geoanchor/base/hash.hpp"
#include "geoanchor/io/network/network_input.hpp"
#include "geoanchor/io/network/sinex.hpp"
#include "geoanchor/workflow/fit_export.hpp"

namespace geoanchor::workflow {
namespace {

using geodesy::Frame;
using geodesy::MeasurementKind;
using geodesy::NetworkSpace;

constexpr double kRadToDeg = 180.0 / std::numbers::pi;
constexpr double kRadToArcsec = 648000.0 / std::numbers::pi;

// The change from frame `from` to frame `to` as one affine map, following
// the catalog's rule for static and dynamic frames (the time-dependent sets
// evaluated at the dynamic side's epoch); throws naming `where` for a change
// of epoch within a dynamic frame (that needs velocities) or a missing epoch.
struct FrameChange {
  geodesy::AffineMap map = geodesy::AffineMap::identity();
  std::string description;
};

FrameChange frame_change(const Frame& from, const Frame& to, const std::string& where) {
  FrameChange c;
  const bool from_dynamic = geodesy::is_dynamic(from), to_dynamic = geodesy::is_dynamic(to);
  if (from_dynamic && to_dynamic && from.epoch() && to.epoch() && from.epoch()->year != to.epoch()->year) {
    throw Error(ErrorKind::input, "E_EPOCH_PROPAGATION",
                where + ": in " + from.to_string() + ", the adjustment is in " + to.to_string() +
                    ": moving measurements between epochs needs the stations' velocities; bring them to " +
                    geodesy::format_decimal_year(*to.epoch()) + " first (geoanchor transform with velocities or --plate), "
                    "or adjust at " + geodesy::format_decimal_year(*from.epoch()));
  }
  if (from.name() == to.name()) {
    // The same frame: a dynamic one at the same epoch (checked above), or a
    // static one, whose epoch records when it was observed.
    c.description = from.to_string() + " -> " + to.to_string() + " (the same frame)";
    return c;
  }
  const geodesy::FramePath path = geodesy::find_frame_path(from.name(), to.name(), where);
  std::optional<geodesy::DecimalYear> t = from_dynamic ? from.epoch() : to_dynamic ? to.epoch() : from.epoch() ? from.epoch() : to.epoch();
  if ((from_dynamic && !from.epoch()) || (to_dynamic && !to.epoch()) || (path.time_dependent() && !t)) {
    throw Error(ErrorKind::input, "E_EPOCH_MISSING",
                where + ": " + from.to_string() + " -> " + to.to_string() +
                    " needs the coordinate epoch of the dynamic frame (NAME@YYYY.Y)");
  }
  c.map = path.at(t.value_or(geodesy::DecimalYear{2000.0}));
  c.description = from.to_string() + " -> " + to.to_string() + (t ? " at " + geodesy::format_decimal_year(*t) : "") +
                  " (" + std::to_string(path.steps.size()) + " step" + (path.steps.size() == 1 ? "" : "s") + ", ±" +
                  format_fixed(path.accuracy_m(), 3) + " m)";
  return c;
}

geodesy::StationConstraint parse_constraint(const std::string& text, std::string& id) {
  const auto eq = text.find('=');
  if (eq == std::string::npos || eq == 0) {
    throw Error(ErrorKind::usage, "E_OPTION", "--constrain " + text + ": expected ID=CCC[,SIGMA_M] (e.g. A1=CCC, B7=CCF,0.005)");
  }
  id = text.substr(0, eq);
  const std::string rest = text.substr(eq + 1);
  const auto comma = rest.find(',');
  const std::string code = rest.substr(0, comma);
  if (code.size() != 3 || code.find_first_not_of("CF") != std::string::npos) {
    throw Error(ErrorKind::usage, "E_OPTION", "--constrain " + text + ": '" + code + "': expected three letters C or F (e.g. CCF)");
  }
  geodesy::StationConstraint c;
  for (std::size_t k = 0; k < 3; ++k) c.code[k] = code[k];
  if (comma != std::string::npos) {
    const auto sigma = parse_finite_double(rest.substr(comma + 1));
    if (!sigma || !(*sigma > 0.0)) {
      throw Error(ErrorKind::usage, "E_OPTION", "--constrain " + text + ": '" + rest.substr(comma + 1) + "': expected a standard deviation > 0 in metres");
    }
    for (std::size_t k = 0; k < 3; ++k) c.sigma_m[k] = c.code[k] == 'C' ? *sigma : 0.0;
  }
  return c;
}

std::string kind_key(MeasurementKind k) {
  switch (k) {
    case MeasurementKind::gnss_baselines: return "gnss_baselines";
    case MeasurementKind::gnss_points: return "gnss_point_cluster";
    case MeasurementKind::slope_distance: return "slope_distance";
    case MeasurementKind::horizontal_distance: return "horizontal_distance";
    case MeasurementKind::ellipsoid_arc: return "ellipsoid_arc";
    case MeasurementKind::chord_distance: return "chord_distance";
    case MeasurementKind::geodetic_latitude: return "geodetic_latitude";
    case MeasurementKind::geodetic_longitude: return "geodetic_longitude";
    case MeasurementKind::direction: return "direction";
    case MeasurementKind::horizontal_angle: return "horizontal_angle";
    case MeasurementKind::zenith_angle: return "zenith_angle";
    case MeasurementKind::vertical_angle: return "vertical_angle";
    case MeasurementKind::azimuth: return "azimuth";
    case MeasurementKind::height_difference: return "height_difference";
    case MeasurementKind::ellipsoidal_height: return "ellipsoidal_height";
    case MeasurementKind::orthometric_height: return "orthometric_height";
  }
  return "measurement";
}

bool angular(MeasurementKind k) {
  return k == MeasurementKind::direction || k == MeasurementKind::horizontal_angle || k == MeasurementKind::zenith_angle ||
         k == MeasurementKind::vertical_angle || k == MeasurementKind::azimuth || k == MeasurementKind::geodetic_latitude ||
         k == MeasurementKind::geodetic_longitude;
}

// The stations a measurement names: "A->B" (from, to), "A->B C->D" for
// baselines, "A B C" for a point cluster.
std::string stations_of(const geodesy::Network& net, const geodesy::NetworkMeasurement& m) {
  std::string s;
  const bool pairs = m.kind == MeasurementKind::gnss_baselines;
  for (std::size_t k = 0; k < m.stations.size(); ++k) {
    s += (k == 0 ? "" : pairs && k % 2 == 1 ? "->" : " ") + net.stations[m.stations[k]].id;
  }
  if (m.stations.size() == 2 && !pairs && m.kind != MeasurementKind::gnss_points) s = net.stations[m.stations[0]].id + "->" + net.stations[m.stations[1]].id;
  return s;
}

std::string csv_field(const std::string& v) {
  if (v.find_first_of(",\"\n\r") == std::string::npos) return v;
  std::string out = "\"";
  for (char c : v) out += c == '"' ? std::string("\"\"") : std::string(1, c);
  return out + "\"";
}

// Within [−1, 1] (rounding of a nearly dependent pair can put it a few
// parts in 10⁶ outside); 0 where a component is fixed (σ = 0).
double correlation(const Eigen::Matrix3d& c, int a, int b) {
  const double d = std::sqrt(c(a, a) * c(b, b));
  if (!(d > 0.0) || !std::isfinite(c(a, b))) return 0.0;
  return std::clamp(c(a, b) / d, -1.0, 1.0);
}


}  // namespace

namespace {

// --estimate-helmert GROUP[:MODEL]: the group's measurements, frame and
// epochs (AdjustRequest's rules), into `p`.
void resolve_helmert_group(const AdjustRequest& request, const geodesy::Network& net, const Frame& target, PreparedNetwork& p) {
  const std::string& text = *request.estimate_helmert;
  const std::string flag = "--estimate-helmert " + text;
  const auto colon = text.rfind(':');
  std::string group = text, model = "helmert7";
  if (colon != std::string::npos && (text.substr(colon + 1) == "helmert7" || text.substr(colon + 1) == "helmert14")) {
    group = text.substr(0, colon);
    model = text.substr(colon + 1);
  } else if (colon != std::string::npos && text.find_first_of("/\\.", colon) == std::string::npos) {
    throw Error(ErrorKind::usage, "E_OPTION", flag + ": the model after ':' is helmert7 or helmert14, not '" + text.substr(colon + 1) + "'");
  }
  if (group.empty()) throw Error(ErrorKind::usage, "E_OPTION", flag + ": name the group (a measurement 'group' or an input file)");
  if (!request.convention) {
    throw Error(ErrorKind::usage, "E_OPTION",
                flag + ": --convention position_vector|coordinate_frame is required: the transform file is written in it "
                       "(never assumed)");
  }
  if (*request.convention != "position_vector" && *request.convention != "coordinate_frame") {
    throw Error(ErrorKind::usage, "E_OPTION", "--convention " + *request.convention + ": expected position_vector or coordinate_frame");
  }
  solver::HelmertGroup g;
  g.name = group;
  g.rates = model == "helmert14";
  for (std::size_t mi = 0; mi < net.measurements.size(); ++mi) {
    if (net.measurements[mi].group == group && !net.measurements[mi].ignore) g.measurements.push_back(mi);
  }
  const bool by_file = g.measurements.empty();
  if (by_file) {
    for (std::size_t mi = 0; mi < net.measurements.size(); ++mi) {
      if (net.measurements[mi].source.rfind(group + ":", 0) == 0 && !net.measurements[mi].ignore) g.measurements.push_back(mi);
    }
  }
  if (g.measurements.empty()) {
    std::vector<std::string> groups;
    for (const auto& m : net.measurements) {
      if (!m.group.empty() && std::find(groups.begin(), groups.end(), m.group) == groups.end()) groups.push_back(m.group);
    }
    std::string list;
    for (const auto& n : groups) list += (list.empty() ? "" : ", ") + n;
    throw Error(ErrorKind::usage, "E_OPTION",
                flag + ": no measurement has group '" + group + "' and no input is that file (groups in the inputs: " +
                    (list.empty() ? "none" : list) + ")");
  }
  std::optional<Frame> frame;
  std::string frame_at;
  for (std::size_t mi : g.measurements) {
    const auto& m = net.measurements[mi];
    if (m.kind != MeasurementKind::gnss_baselines && m.kind != MeasurementKind::gnss_points) {
      throw Error(ErrorKind::input, "E_HELMERT_GROUP",
                  m.source + ": " + geodesy::to_string(m.kind) + " in Helmert group " + group +
                      ": a datum transformation relates GNSS positions and baselines only (give the terrestrial "
                      "measurements another group, or none)");
    }
    const Frame f = m.frame ? *m.frame : net.frame ? *net.frame : target;
    if (!frame) {
      frame = f;
      frame_at = m.source;
    } else if (frame->name() != f.name() || (!g.rates && !(*frame == f))) {
      throw Error(ErrorKind::input, "E_HELMERT_GROUP",
                  m.source + ": in " + f.to_string() + ", but Helmert group " + group + " is in " + frame->to_string() + " (" +
                      frame_at + "): one transformation relates one frame" +
                      (frame->name() == f.name() ? " at one epoch (helmert14 relates several epochs)" : ""));
    }
    if (g.rates) {
      if (!f.epoch()) {
        throw Error(ErrorKind::input, "E_EPOCH_MISSING",
                    m.source + ": Helmert group " + group + " with rates (helmert14): the measurement's epoch is needed (" +
                        f.to_string() + " names none)");
      }
      g.epochs.push_back(f.epoch()->year);
    }
  }
  // The group's stations must span what seven parameters need (fit's
  // rules, RELIABILITY 1, 3, 4): three or more, not on one line, not in one place.
  {
    std::vector<std::size_t> stations;
    for (std::size_t mi : g.measurements) {
      for (std::size_t s : net.measurements[mi].stations) {
        if (std::find(stations.begin(), stations.end(), s) == stations.end()) stations.push_back(s);
      }
    }
    if (stations.size() < 3) {
      throw Error(ErrorKind::input, "E_HELMERT_GROUP",
                  flag + ": the group reaches " + std::to_string(stations.size()) +
                      " station(s); a Helmert needs >= 3 non-collinear stations");
    }
    Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
    for (std::size_t s : stations) centroid += net.stations[s].position;
    centroid /= static_cast<double>(stations.size());
    Eigen::MatrixXd spread(static_cast<Eigen::Index>(stations.size()), 3);
    for (std::size_t k = 0; k < stations.size(); ++k) {
      spread.row(static_cast<Eigen::Index>(k)) = (net.stations[stations[k]].position - centroid).transpose();
    }
    const Eigen::JacobiSVD<Eigen::MatrixXd> svd(spread);
    const Eigen::Vector3d sv = svd.singularValues();
    constexpr double kCoincidentM = 1.0;  // RMS spread below which only a translation is observed
    constexpr double kCollinearRatio = 1e-3;
    const double rms = std::sqrt(sv.squaredNorm() / static_cast<double>(stations.size()));
    if (!(rms >= kCoincidentM)) {
      throw Error(ErrorKind::input, "E_HELMERT_GROUP",
                  flag + ": the group's " + std::to_string(stations.size()) + " stations lie within " + format_fixed(rms, 3) +
                      " m (RMS) of their centroid: only a translation is observable, not rotations and scale");
    }
    if (!(sv(1) >= kCollinearRatio * sv(0))) {
      throw Error(ErrorKind::input, "E_HELMERT_GROUP",
                  flag + ": the group's " + std::to_string(stations.size()) +
                      " stations lie on one line (singular values of their spread " + format_shortest(sv(0)) + ", " +
                      format_shortest(sv(1)) + " m; ratio " + format_shortest(sv(1) / sv(0)) + " < " +
                      format_shortest(kCollinearRatio) + "): the rotation about that line is not observable");
    }
  }
  if (g.rates) {
    const auto [lo, hi] = std::minmax_element(g.epochs.begin(), g.epochs.end());
    if (!(*hi > *lo)) {
      throw Error(ErrorKind::input, "E_HELMERT_GROUP",
                  flag + ": every measurement of the group is at " + format_shortest(*lo) +
                      ": rates need two epochs or more (estimate helmert7)");
    }
    double sum = 0.0;
    for (double e : g.epochs) sum += e;
    g.reference_epoch = sum / static_cast<double>(g.epochs.size());
  }
  p.notes.push_back(std::to_string(g.measurements.size()) + " GNSS measurement(s) of " + (by_file ? "input " : "group ") + group +
                    " in " + frame->to_string() + " related to " + target.to_string() + " by an estimated " + model +
                    (g.rates ? " (reference epoch " + format_fixed(g.reference_epoch, 4) + ")" : ""));
  p.helmert_frame = g.rates ? Frame::parse(frame->name(), flag) : *frame;
  p.helmert_position_vector = *request.convention == "position_vector";
  p.helmert = std::move(g);
}

}  // namespace

std::optional<io::GnssSolutionRecord> adjust_solution_record(const PreparedNetwork& p, const solver::AdjustmentResult& r,
                                                             const std::vector<std::size_t>* only) {
  if (!p.solution_policy) return std::nullopt;
  const auto& ms = p.network.measurements;
  std::vector<bool> in(ms.size(), only == nullptr);
  if (only) {
    for (const std::size_t mi : *only) in[mi] = true;
  }
  io::GnssSolutionRecord rec;
  rec.policy = *p.solution_policy;
  for (const auto s : geodesy::kGnssSolutions) {
    rec.classes[geodesy::solution_index(s)].sigma_factor = geodesy::sigma_factor_under(s, rec.policy);
  }
  for (std::size_t mi = 0; mi < ms.size(); ++mi) {
    if (in[mi] && ms[mi].solution) ++rec.classes[geodesy::solution_index(*ms[mi].solution)].marks;
  }
  for (const std::size_t mi : p.solution_excluded) {
    if (in[mi]) ++rec.classes[geodesy::solution_index(*ms[mi].solution)].excluded;
  }
  for (const auto& am : r.measurements) {
    if (am.index < ms.size() && in[am.index] && am.used && ms[am.index].solution) {
      ++rec.classes[geodesy::solution_index(*ms[am.index].solution)].used;
    }
  }
  return rec;
}

PreparedNetwork prepare_network(const AdjustRequest& request) {
  PreparedNetwork p;
  io::NetworkReadOptions read_options;
  read_options.geoid = request.options.geoid;
  if (request.sinex_frame) {
    read_options.sinex_frame = geodesy::Frame::parse(*request.sinex_frame, "--sinex-frame");
    const auto known = geodesy::catalog_frame_names();
    if (std::find(known.begin(), known.end(), read_options.sinex_frame->name()) == known.end()) {
      std::string list;
      for (const auto& k : known) list += (list.empty() ? "" : ", ") + k;
      throw Error(ErrorKind::usage, "E_OPTION", "--sinex-frame " + *request.sinex_frame + ": not a frame of the catalog (" + list + ")");
    }
  }
  p.network = io::read_network(request.inputs, read_options);
  geodesy::Network& net = p.network;
  for (const auto& w : net.warnings) p.notes.push_back("warning: " + w);
  // GNSS solution types: float and worse left out, or weighted on request.
  {
    std::array<std::size_t, geodesy::kGnssSolutionCount> seen{}, left_out{}, weighted{};
    for (std::size_t mi = 0; mi < net.measurements.size(); ++mi) {
      auto& m = net.measurements[mi];
      if (!m.solution) continue;
      p.solution_policy = request.solutions;
      const std::size_t k = geodesy::solution_index(*m.solution);
      ++seen[k];
      if (m.ignore) continue;  // its input ignores it already
      if (!geodesy::used_under(*m.solution, request.solutions)) {
        m.ignore = true;
        p.solution_excluded.push_back(mi);
        ++left_out[k];
      } else if (const double f = geodesy::sigma_factor_under(*m.solution, request.solutions); f != 1.0) {
        m.covariance *= f * f;
        ++weighted[k];
      }
    }
    if (p.solution_policy) {
      std::string line;
      for (const auto s : geodesy::kGnssSolutions) {
        const std::size_t k = geodesy::solution_index(s);
        if (!seen[k]) continue;
        line += (line.empty() ? "" : ", ") + std::to_string(seen[k]) + " " + std::string(geodesy::to_string(s));
        if (left_out[k]) line += " (" + std::to_string(left_out[k]) + " left out)";
        if (weighted[k]) line += " (σ × " + format_shortest(geodesy::sigma_factor_under(s, request.solutions)) + ")";
      }
      p.notes.push_back("GNSS solution types of the measurements: " + line +
                        (request.solutions == geodesy::SolutionPolicy::exclude
                             ? "; float and worse are left out (--solution-weighting weighs them)"
                             : "; float, dgps, sbas and standalone weighted, dead_reckoned left out"));
    }
  }
  // DynaML's Pscale, Lscale, Hscale: variances scaled along north, east and
  // up at each item's first station, now that its position is known.
  {
    const geodesy::GeocentricConverter geocentric(net.ellipsoid);
    for (auto& m : net.measurements) {
      if (m.local_variance_scale == Eigen::Vector3d::Ones()) continue;
      const bool pairs = m.kind == MeasurementKind::gnss_baselines;
      Eigen::MatrixXd s = Eigen::MatrixXd::Identity(m.covariance.rows(), m.covariance.cols());
      for (Eigen::Index k = 0; k < m.value.size() / 3; ++k) {
        const auto& x = net.stations[m.stations[static_cast<std::size_t>(pairs ? 2 * k : k)]].position;
        const auto g = geocentric.geodetic_from_ecef(geodesy::EcefPosition(x.x(), x.y(), x.z()));
        const Eigen::Matrix3d r = geodesy::enu_from_ecef_rotation(g.lat, g.lon);
        const Eigen::Vector3d enu_scale(std::sqrt(m.local_variance_scale(1)), std::sqrt(m.local_variance_scale(0)),
                                        std::sqrt(m.local_variance_scale(2)));  // east: L, north: P, up: H
        s.block<3, 3>(3 * k, 3 * k) = r.transpose() * enu_scale.asDiagonal() * r;
      }
      m.covariance = s * m.covariance * s.transpose();
      m.local_variance_scale = Eigen::Vector3d::Ones();
    }
  }
  if (net.space == NetworkSpace::ellipsoidal) {
    std::optional<Frame> target = net.frame;
    if (request.frame) target = Frame::parse(*request.frame, "--frame");
    if (!target) {
      throw Error(ErrorKind::usage, "E_FRAME_MISSING",
                  net.source_name + ": the inputs name no frame for the stations: give --frame NAME[@EPOCH] (e.g. GDA2020, "
                                    "ITRF2020@2024.5)");
    }
    geodesy::require_epoch_if_dynamic(*target, request.frame ? "--frame" : net.source_name + ": the stations' frame",
                                      ErrorKind::usage);
    // The stations are ECEF already; heights and terrestrial models use the
    // adjustment frame's own ellipsoid.
    if (const auto e = geodesy::implied_ellipsoid(*target)) {
      if (net.ellipsoid_stated && !(net.ellipsoid == *e)) {
        throw Error(ErrorKind::input, "E_ELLIPSOID",
                    net.source_name + ": the network states the ellipsoid " + net.ellipsoid.name() + ", but its frame " +
                        target->to_string() + " is on " + e->name());
      }
      net.ellipsoid = *e;
    } else if (!net.ellipsoid_stated) {
      // Never a default ellipsoid for a frame geoanchor does not know: the
      // terrestrial models, the local axes and the stations' heights are on it.
      throw Error(ErrorKind::input, "E_ELLIPSOID",
                  net.source_name + ": the frame " + target->to_string() +
                      " is not in geoanchor's catalog, so its ellipsoid is unknown: give the network's \"ellipsoid\" (" +
                      geodesy::named_ellipsoid_list() + ", or {\"a_m\", \"rf\"})");
    }
    // The stations' a-priori positions and each GNSS measurement into the target.
    if (net.frame && !(*net.frame == *target)) {
      const FrameChange c = frame_change(*net.frame, *target, net.source_name + ": the stations");
      for (auto& s : net.stations) s.position = c.map.apply(s.position);
      p.notes.push_back("stations' a-priori positions: " + c.description);
    }
    if (request.estimate_helmert) resolve_helmert_group(request, net, *target, p);
    std::vector<bool> in_group(net.measurements.size(), false);
    if (p.helmert) {
      for (std::size_t mi : p.helmert->measurements) in_group[mi] = true;
    }
    std::size_t moved = 0, assumed = 0;
    std::string first, assumed_first, assumed_frame;
    for (std::size_t mi = 0; mi < net.measurements.size(); ++mi) {
      auto& m = net.measurements[mi];
      if (m.kind != MeasurementKind::gnss_baselines && m.kind != MeasurementKind::gnss_points) continue;
      if (in_group[mi]) continue;  // in its own datum: the estimated Helmert relates it
      Frame from = m.frame ? *m.frame : net.frame ? *net.frame : *target;
      if (geodesy::is_dynamic(from) && !from.epoch()) {
        // A dynamic frame names no epoch: refused, unless --frame gives the
        // epoch to assume (said in the notes and on standard error).
        if (!request.frame || !target->epoch()) {
          throw Error(ErrorKind::input, "E_EPOCH_MISSING",
                      m.source + ": " + geodesy::to_string(m.kind) + " in " + from.to_string() +
                          ", a dynamic frame, with no coordinate epoch: give it (\"" + from.name() +
                          "@YYYY.Y\"), or --frame NAME@EPOCH to take such measurements at that epoch");
        }
        from = Frame::parse(from.name() + "@" + geodesy::format_decimal_year(*target->epoch()), m.source);
        if (assumed++ == 0) assumed_first = m.source;
        assumed_frame = from.to_string();
      }
      if (from == *target) continue;
      const FrameChange c = frame_change(from, *target, m.source);
      const Eigen::Matrix3d linear = c.map.linear();
      const Eigen::Index n = m.value.size() / 3;
      Eigen::MatrixXd j = Eigen::MatrixXd::Zero(m.value.size(), m.value.size());
      for (Eigen::Index k = 0; k < n; ++k) {
        j.block<3, 3>(3 * k, 3 * k) = linear;
        const Eigen::Vector3d v = m.value.segment<3>(3 * k);
        if (m.kind == MeasurementKind::gnss_points) {
          m.value.segment<3>(3 * k) = c.map.apply(v);
        } else {
          m.value.segment<3>(3 * k) = linear * v;  // a difference: the translation cancels
        }
      }
      m.covariance = j * m.covariance * j.transpose();
      m.frame_step = c.description;
      if (moved++ == 0) first = m.source + ": " + c.description;
    }
    if (assumed > 0) {
      p.notes.push_back("warning: " + std::to_string(assumed) + " GNSS measurement(s) in a dynamic frame name no coordinate epoch (" +
                        assumed_first + " the first): taken at --frame's epoch, as " + assumed_frame);
    }
    if (moved > 0) p.notes.push_back(std::to_string(moved) + " GNSS measurement(s) brought to " + target->to_string() + "; the first " + first);
    net.frame = target;
  } else if (request.frame) {
    throw Error(ErrorKind::usage, "E_OPTION", "--frame " + *request.frame + ": the network is local (" + net.source_name + "): it has no frame");
  } else if (request.estimate_helmert) {
    throw Error(ErrorKind::usage, "E_OPTION", "--estimate-helmert: the network is local (" + net.source_name + "): it has no frame to relate a datum to");
  }
  for (const auto& text : request.constrain) {
    std::string id;
    const geodesy::StationConstraint c = parse_constraint(text, id);
    const auto s = net.find(id);
    if (!s) throw Error(ErrorKind::usage, "E_OPTION", "--constrain " + text + ": no station " + id + " in " + net.source_name);
    net.stations[*s].constraint = c;
    p.notes.push_back("station " + id + " constrained " + c.text() + " by --constrain");
  }
  return p;
}

std::string stations_sinex(const PreparedNetwork& prepared, const solver::AdjustmentResult& r, const std::string& software) {
  const geodesy::Network& net = prepared.network;
  if (net.space != NetworkSpace::ellipsoidal) {
    throw Error(ErrorKind::usage, "E_OPTION", "--sinex: a local network has no geocentric coordinates to write as SINEX");
  }
  if (!net.frame) throw Error(ErrorKind::usage, "E_OPTION", "--sinex: the network has no frame; give --frame FRAME@EPOCH");
  if (r.station_covariance_m2.rows() != static_cast<Eigen::Index>(3 * r.covariance_stations.size())) {
    throw std::logic_error("stations_sinex: the adjustment was run without the joint covariance");
  }
  io::SinexSolution s(*net.frame);
  const geodesy::GeocentricConverter geocentric(net.ellipsoid);
  bool terrestrial = false;
  for (const auto& m : net.measurements) {
    terrestrial = terrestrial || (m.kind != MeasurementKind::gnss_baselines && m.kind != MeasurementKind::gnss_points);
  }
  s.technique = terrestrial ? 'C' : 'P';
  bool fixed = false, held = false;
  for (std::size_t i : r.covariance_stations) {
    const auto& st = r.stations[i];
    const auto g = geocentric.geodetic_from_ecef(geodesy::EcefPosition(st.position.x(), st.position.y(), st.position.z()));
    io::SinexSite site;
    site.id = st.id;
    site.ecef_m = st.position;
    site.lat_deg = g.lat.deg();
    site.lon_deg = g.lon.deg();
    site.h_m = g.h.m;
    s.sites.push_back(site);
    const auto& con = net.stations[i].constraint;
    for (int k = 0; k < 3; ++k) {
      if (st.constraint[static_cast<std::size_t>(k)] != 'C') continue;
      (con.sigma_m[static_cast<std::size_t>(k)] > 0.0 ? held : fixed) = true;
    }
  }
  s.constraint_code = fixed ? 0 : (held || r.datum_by_minimum_norm) ? 1 : 2;
  s.covariance_m2 = r.station_covariance_m2;
  s.observations = r.observations;
  s.unknowns = r.unknowns;
  s.dof = r.dof;
  s.vtpv = r.vtpv;
  s.variance_factor = r.variance_factor;
  s.description = "network adjustment by geoanchor adjust";
  s.software = software;
  s.input = net.source_name;
  s.comments.push_back("Datum: " + r.datum);
  s.comments.push_back("Covariance from the a-priori weights (sigma0 = 1); VARIANCE FACTOR is vtpv/dof.");
  return io::sinex_text(s);
}

std::string stations_csv(const geodesy::Network& net, const solver::AdjustmentResult& r, const solver::AdjustOptions& o) {
  std::ostringstream out;
  const bool ellipsoidal = net.space == NetworkSpace::ellipsoidal;
  if (ellipsoidal) {
    out << "# frame = " << (net.frame ? net.frame->to_string() : std::string("?")) << "\n";
    out << "# ellipsoid = " << net.ellipsoid.name() << "\n";
  } else {
    out << "# local network: axes " << net.axes.name() << ", " << net.local_dimensions << "-D\n";
  }
  out << "# sigmas from the a-priori weights (sigma0 = 1); ellipse_conf at " << format_shortest(100.0 * o.confidence) << " %\n";
  const geodesy::GeocentricConverter geocentric(net.ellipsoid);
  if (ellipsoidal) {
    out << "id,x_m,y_m,z_m,lat_deg,lon_deg,h_m,sigma_e_m,sigma_n_m,sigma_u_m,corr_en,corr_eu,corr_nu,ellipse_a_m,ellipse_b_m,"
           "ellipse_azimuth_deg,ellipse_conf_a_m,ellipse_conf_b_m,constraint\n";
  } else {
    std::vector<std::string> cols = {"id"};
    if (net.local_dimensions >= 2) cols.insert(cols.end(), {"x_m", "y_m"});
    if (net.local_dimensions != 2) cols.push_back("z_m");
    if (net.local_dimensions >= 2) cols.insert(cols.end(), {"sigma_x_m", "sigma_y_m"});
    if (net.local_dimensions != 2) cols.push_back("sigma_z_m");
    if (net.local_dimensions >= 2) cols.insert(cols.end(), {"corr_xy", "ellipse_a_m", "ellipse_b_m", "ellipse_azimuth_deg", "ellipse_conf_a_m", "ellipse_conf_b_m"});
    cols.push_back("constraint");
    for (std::size_t k = 0; k < cols.size(); ++k) out << (k ? "," : "") << cols[k];
    out << "\n";
  }
  for (const auto& s : r.stations) {
    if (!s.used) continue;
    const Eigen::Matrix3d& c = s.covariance_local_m2;
    out << csv_field(s.id);
    if (ellipsoidal) {
      const auto g = geocentric.geodetic_from_ecef(geodesy::EcefPosition(s.position.x(), s.position.y(), s.position.z()));
      out << ',' << format_fixed(s.position.x(), 5) << ',' << format_fixed(s.position.y(), 5) << ',' << format_fixed(s.position.z(), 5)
          << ',' << format_fixed(g.lat.deg(), 11) << ',' << format_fixed(g.lon.deg(), 11) << ',' << format_fixed(g.h.m, 5);
      for (int k = 0; k < 3; ++k) out << ',' << format_fixed(std::sqrt(std::max(0.0, c(k, k))), 6);
      out << ',' << format_fixed(correlation(c, 0, 1), 6) << ',' << format_fixed(correlation(c, 0, 2), 6) << ','
          << format_fixed(correlation(c, 1, 2), 6);
    } else {
      if (net.local_dimensions >= 2) out << ',' << format_fixed(s.position.x(), 5) << ',' << format_fixed(s.position.y(), 5);
      if (net.local_dimensions != 2) out << ',' << format_fixed(s.position.z(), 5);
      if (net.local_dimensions >= 2) out << ',' << format_fixed(std::sqrt(std::max(0.0, c(0, 0))), 6) << ',' << format_fixed(std::sqrt(std::max(0.0, c(1, 1))), 6);
      if (net.local_dimensions != 2) out << ',' << format_fixed(std::sqrt(std::max(0.0, c(2, 2))), 6);
      if (net.local_dimensions >= 2) out << ',' << format_fixed(correlation(c, 0, 1), 6);
    }
    if (ellipsoidal || net.local_dimensions >= 2) {
      out << ',' << format_fixed(s.ellipse.semi_major_m, 6) << ',' << format_fixed(s.ellipse.semi_minor_m, 6) << ','
          << format_fixed(s.ellipse.azimuth_rad * kRadToDeg, 3) << ',' << format_fixed(s.ellipse_confidence.semi_major_m, 6) << ','
          << format_fixed(s.ellipse_confidence.semi_minor_m, 6);
    }
    out << ',' << s.constraint << "\n";
  }
  return out.str();
}

std::string measurements_csv(const geodesy::Network& net, const solver::AdjustmentResult& r, int jobs) {
  // Rows of consecutive measurements formatted on threads into strings of
  // their own and joined in order: the same text for any number of threads
  // (10⁵ stations: 8·10⁵ rows, 200 MB). Every measurement of the network,
  // in its order: those its input ignores with their observed values only.
  constexpr std::size_t kMeasurementsPerChunk = 4096;
  constexpr std::size_t kNone = std::numeric_limits<std::size_t>::max();
  std::vector<std::size_t> slot_of(net.measurements.size(), kNone);
  for (std::size_t k = 0; k < r.measurements.size(); ++k) slot_of[r.measurements[k].index] = k;
  const std::size_t chunks = (net.measurements.size() + kMeasurementsPerChunk - 1) / kMeasurementsPerChunk;
  std::vector<std::string> parts(chunks);
  const auto number = [](std::string& out, double v) {
    if (!std::isfinite(v)) return;  // empty field
    char buf[32];
    const auto [ptr, ec] = std::to_chars(buf, buf + sizeof buf, v);
    out.append(buf, ec == std::errc() ? ptr : buf);
  };
  for_chunks(net.measurements.size(), kMeasurementsPerChunk, resolve_jobs(jobs), [&](std::size_t begin, std::size_t end) {
    std::string& out = parts[begin / kMeasurementsPerChunk];
    out.reserve((end - begin) * 3 * 240);
    for (std::size_t mi = begin; mi < end; ++mi) {
      const auto& m = net.measurements[mi];
      const solver::AdjustedMeasurement* am = slot_of[mi] == kNone ? nullptr : &r.measurements[slot_of[mi]];
      const bool ang = angular(m.kind);
      const double value_scale = ang ? kRadToDeg : 1.0, small_scale = ang ? kRadToArcsec : 1.0;
      const char* status = am ? solver::to_string(am->status(r.alpha_point)) : "ignored";
      const std::string rank = am && am->snooping_rank > 0 ? std::to_string(am->snooping_rank) : std::string();
      const std::string source = csv_field(m.source), stations = csv_field(stations_of(net, m));
      const auto at = [&](const Eigen::VectorXd* v, Eigen::Index k) {
        return v && k < v->size() ? (*v)(k) : std::numeric_limits<double>::quiet_NaN();
      };
      for (Eigen::Index k = 0; k < m.value.size(); ++k) {
        static constexpr const char* kAxis[] = {"x", "y", "z"};
        out += source;
        out += ',';
        out += kind_key(m.kind);
        out += ',';
        out += stations;
        out += ',';
        if (m.value.size() != 1) {
          if (m.kind == MeasurementKind::gnss_points) out += net.stations[m.stations[static_cast<std::size_t>(k / 3)]].id;
          else out += std::to_string(k / 3);
          out += '.';
          out += kAxis[k % 3];
        }
        out += ',';
        number(out, m.value(k) * value_scale);
        out += ',';
        number(out, at(am ? &am->adjusted : nullptr, k) * value_scale);
        out += ang ? ",deg," : ",m,";
        number(out, at(am ? &am->residual : nullptr, k) * small_scale);
        out += ',';
        number(out, std::sqrt(m.covariance(k, k)) * small_scale);
        out += ',';
        number(out, at(am ? &am->residual_sigma : nullptr, k) * small_scale);
        out += ang ? ",arcsec," : ",m,";
        number(out, at(am ? &am->redundancy : nullptr, k));
        out += ',';
        number(out, at(am ? &am->w : nullptr, k));
        out += ',';
        number(out, at(am ? &am->mdb : nullptr, k) * small_scale);
        out += ',';
        out += status;
        out += ',';
        out += rank;
        out += '\n';
      }
    }
  });
  std::string out = "source,kind,stations,component,observed,adjusted,value_unit,residual,sigma,residual_sigma,residual_unit,redundancy,w,"
                    "mdb,status,snooping_rank\n";
  std::size_t size = out.size();
  for (const auto& part : parts) size += part.size();
  out.reserve(size);
  for (auto& part : parts) {
    out += part;
    std::string().swap(part);
  }
  return out;
}

namespace {

// The estimated Helmert in the transform file's units (m, arcsec, ppm and
// per year) and convention (rotations negated for coordinate_frame).
struct HelmertInFileUnits {
  std::vector<std::string> names;
  Eigen::VectorXd value;
  Eigen::MatrixXd covariance;
};

HelmertInFileUnits helmert_in_file_units(const PreparedNetwork& prepared, const solver::AdjustmentResult& r) {
  static const char* const kNames[14] = {"tx_m",           "ty_m",           "tz_m",           "rx_arcsec",
                                         "ry_arcsec",      "rz_arcsec",      "ds_ppm",         "dtx_m_per_year",
                                         "dty_m_per_year", "dtz_m_per_year", "drx_arcsec_per_year",
                                         "dry_arcsec_per_year", "drz_arcsec_per_year", "dds_ppm_per_year"};
  constexpr double kArcsecPerRad = 180.0 / std::numbers::pi * 3600.0;
  const Eigen::Index n = r.helmert->parameters.size();
  Eigen::VectorXd factor(n);
  HelmertInFileUnits u;
  for (Eigen::Index k = 0; k < n; ++k) {
    const Eigen::Index j = k % 7;
    factor(k) = j < 3 ? 1.0 : j < 6 ? (prepared.helmert_position_vector ? 1.0 : -1.0) * kArcsecPerRad : 1e6;
    u.names.emplace_back(kNames[k]);
  }
  u.value = factor.cwiseProduct(r.helmert->parameters);
  u.covariance = factor.asDiagonal() * r.helmert->covariance * factor.asDiagonal();
  return u;
}

}  // namespace

std::string report_text(const PreparedNetwork& prepared, const solver::AdjustmentResult& r, const solver::AdjustOptions& o) {
  const auto& net = prepared.network;
  std::ostringstream out;
  out << "geoanchor adjust: " << net.source_name << "\n";
  out << "  network: " << (net.space == NetworkSpace::ellipsoidal ? "on the ellipsoid " + net.ellipsoid.name() + ", frame " +
                                                                         (net.frame ? net.frame->to_string() : std::string("?"))
                                                                   : "local, axes " + net.axes.name())
      << "; " << net.stations.size() << " stations, " << net.measurements.size() << " measurements\n";
  for (const auto& n : prepared.notes) out << "  " << n << "\n";
  out << "  datum: " << r.datum << "\n";
  out << "  solve: " << r.iterations << " iterations, last correction " << format_fixed(r.largest_correction_m, 6) << " m; "
      << r.unknowns << " unknowns, " << r.observations << " observations, factor " << r.factor_nonzeros << " nonzeros\n";
  if (!r.removed_per_pass.empty()) {
    std::string steps;
    for (std::size_t k : r.removed_per_pass) steps += (steps.empty() ? "" : ", ") + std::to_string(k);
    out << "  data snooping: " << r.passes << " adjustments, removing " << steps << " measurement(s) in turn";
    if (r.passes_downdated > 0) {
      out << "; " << r.passes_downdated << " of them by taking the removed measurements out of the last factor (a downdate)";
    }
    out << "\n";
  }
  out << "\n";
  out << "Statistics\n";
  out << "  vtpv = " << format_shortest(r.vtpv) << ", dof = " << r.dof;
  if (r.variance_factor) out << ", variance factor = " << format_fixed(*r.variance_factor, 4) << ", sigma0 = " << format_fixed(*r.sigma0, 4);
  out << "\n";
  const auto& g = r.global_test;
  if (r.dof > 0) {
    out << "  global test (chi-squared, " << format_shortest(100.0 * (1.0 - o.alpha)) << " %): " << format_fixed(g.statistic, 3)
        << " in [" << format_fixed(g.critical_lower, 3) << ", " << format_fixed(g.critical_upper, 3) << "]: "
        << (g.passed ? "PASSED" : g.failed_high() ? "FAILED (high)" : "FAILED (low)") << "\n";
  }
  out << "  w-tests: critical |w| = " << format_fixed(r.w_critical, 2) << " (alpha " << format_shortest(o.alpha_point) << ")\n\n";
  if (prepared.helmert && r.helmert) {
    const HelmertInFileUnits u = helmert_in_file_units(prepared, r);
    out << "Helmert of group " << prepared.helmert->name << ": " << prepared.helmert_frame->to_string() << " -> "
        << net.frame->to_string() << ", " << (prepared.helmert->rates ? "helmert14 at reference epoch " + format_fixed(prepared.helmert->reference_epoch, 4) : "helmert7")
        << ", " << (prepared.helmert_position_vector ? "position_vector" : "coordinate_frame")
        << " (sigmas from the a-priori weights)\n";
    for (std::size_t k = 0; k < u.names.size(); ++k) {
      const auto i = static_cast<Eigen::Index>(k);
      char line[160];
      std::snprintf(line, sizeof line, "  %-22s %14.6f  ± %.6f\n", u.names[k].c_str(), u.value(i), std::sqrt(std::max(0.0, u.covariance(i, i))));
      out << line;
    }
    out << "\n";
  }
  out << "Stations (sigmas from the a-priori weights; ellipse 1 sigma)\n";
  const bool ellipsoidal = net.space == NetworkSpace::ellipsoidal;
  out << "  id            " << (ellipsoidal ? "sigma_e  sigma_n  sigma_u" : "sigma_x  sigma_y  sigma_z") << "  (mm)   ellipse a/b (mm) az (deg)  constraint\n";
  for (const auto& s : r.stations) {
    if (!s.used) continue;
    const Eigen::Matrix3d& c = s.covariance_local_m2;
    char line[200];
    std::snprintf(line, sizeof line, "  %-12s %8.2f %8.2f %8.2f        %7.2f/%-7.2f %7.2f    %s\n", s.id.c_str(),
                  1e3 * std::sqrt(std::max(0.0, c(0, 0))), 1e3 * std::sqrt(std::max(0.0, c(1, 1))),
                  1e3 * std::sqrt(std::max(0.0, c(2, 2))), 1e3 * s.ellipse.semi_major_m, 1e3 * s.ellipse.semi_minor_m,
                  s.ellipse.azimuth_rad * kRadToDeg, s.constraint.c_str());
    out << line;
  }
  // The flagged measurements first, in the order data snooping removes them.
  const auto p_text = [](double p) {
    char b[32];
    std::snprintf(b, sizeof b, "%.3g", p);
    return std::string(b);
  };
  const auto mdb_text = [&](const solver::AdjustedMeasurement& am, const geodesy::NetworkMeasurement& m) {
    double largest = 0.0;
    for (Eigen::Index k = 0; k < am.mdb.size(); ++k) {
      if (!(am.mdb(k) <= largest)) largest = am.mdb(k);
    }
    if (!std::isfinite(largest)) return std::string("-");
    return angular(m.kind) ? format_fixed(largest * kRadToArcsec, 2) + "\"" : format_fixed(largest * 1e3, 1) + " mm";
  };
  const std::vector<std::size_t> failing = solver::failing_measurements(r);
  std::size_t flagged = 0, removed = 0;
  for (const auto& am : r.measurements) {
    const auto st = am.status(r.alpha_point);
    flagged += st == solver::TestStatus::flagged ? 1u : 0u;
    removed += st == solver::TestStatus::removed ? 1u : 0u;
  }
  if (flagged > 0) {
    out << "\nFlagged measurements: " << flagged << " fail their test at alpha " << format_shortest(o.alpha_point)
        << " and are kept (--remove-outliers removes them in the order of their snooping rank, strongest evidence first)\n";
    out << "  rank  measurement\n";
    for (const std::size_t k : failing) {
      const auto& am = r.measurements[k];
      if (am.status(r.alpha_point) != solver::TestStatus::flagged) continue;
      const auto& m = net.measurements[am.index];
      char rank[16];
      std::snprintf(rank, sizeof rank, "%4s", am.snooping_rank > 0 ? std::to_string(am.snooping_rank).c_str() : "-");
      out << "  " << rank << "  " << m.source << "  " << geodesy::to_string(m.kind) << " " << stations_of(net, m) << ": max |w| "
          << format_fixed(am.w_max, 2) << ", test " << format_fixed(am.statistic, 2) << " (chi-squared, " << am.test_dof
          << " dof), p " << p_text(am.p_value) << ", MDB " << mdb_text(am, m)
          << (am.passes_after_rank > 0 ? "; passes once rank " + std::to_string(am.passes_after_rank) + " is removed" : std::string())
          << "\n";
    }
  }
  // The measurements with the largest |w|.
  std::vector<const solver::AdjustedMeasurement*> by_w;
  for (const auto& am : r.measurements) {
    if (std::isfinite(am.w_max)) by_w.push_back(&am);
  }
  std::stable_sort(by_w.begin(), by_w.end(), [](auto* a, auto* b) { return a->w_max > b->w_max; });
  out << "\nMeasurements with the largest |w| (of " << r.measurements.size() << ")\n";
  for (std::size_t k = 0; k < by_w.size() && k < 20; ++k) {
    const auto& am = *by_w[k];
    const auto& m = net.measurements[am.index];
    out << "  " << m.source << "  " << geodesy::to_string(m.kind) << " " << stations_of(net, m) << ": max |w| "
        << format_fixed(am.w_max, 2) << ", p " << p_text(am.p_value) << ", " << solver::to_string(am.status(r.alpha_point))
        << (am.snooping_rank > 0 ? " (snooping rank " + std::to_string(am.snooping_rank) + ")" : std::string()) << "\n";
  }
  if (removed > 0) {
    out << "\nMeasurements removed (--remove-outliers, or a gross misclosure past the input's tolerance): " << removed << "\n";
    for (const auto& am : r.measurements) {
      if (am.outlier) out << "  " << net.measurements[am.index].source << ": " << am.removed_because << "\n";
    }
  }
  if (!r.warnings.empty()) {
    out << "\nWarnings\n";
    for (const auto& w : r.warnings) out << "  " << w << "\n";
  }
  return out.str();
}

nlohmann::ordered_json report_document(const PreparedNetwork& prepared, const solver::AdjustmentResult& r,
                                       const solver::AdjustOptions& o, ReportDetail detail) {
  const bool full = detail == ReportDetail::full;
  using nlohmann::ordered_json;
  const auto& net = prepared.network;
  auto num = [](double v) { return std::isfinite(v) ? ordered_json(v) : ordered_json(nullptr); };
  ordered_json j;
  j["schema"] = "geoanchor.adjust-report/1";
  j["inputs"] = net.source_name;
  j["space"] = net.space == NetworkSpace::ellipsoidal ? "ellipsoidal" : "local";
  if (net.frame) j["frame"] = net.frame->to_string();
  j["ellipsoid"] = net.ellipsoid.name();
  j["datum"] = r.datum;
  j["datum_defect"] = r.datum_defect;
  if (const auto rec = adjust_solution_record(prepared, r)) {
    ordered_json classes = ordered_json::object();
    for (const auto s : geodesy::kGnssSolutions) {
      const io::SolutionTally& c = rec->classes[geodesy::solution_index(s)];
      classes[std::string(geodesy::to_string(s))] = {
          {"measurements", c.marks}, {"used", c.used}, {"excluded", c.excluded}, {"sigma_factor", c.sigma_factor}};
    }
    j["gnss_solutions"] = {{"policy", std::string(geodesy::to_string(rec->policy))}, {"classes", classes}};
  }
  j["notes"] = prepared.notes;
  j["vtpv"] = r.vtpv;
  j["dof"] = r.dof;
  j["variance_factor"] = r.variance_factor ? ordered_json(*r.variance_factor) : ordered_json(nullptr);
  j["sigma0"] = r.sigma0 ? ordered_json(*r.sigma0) : ordered_json(nullptr);
  j["global_test"] = {{"statistic", r.global_test.statistic},
                      {"lower", r.global_test.critical_lower},
                      {"upper", r.global_test.critical_upper},
                      {"passed", r.global_test.passed},
                      {"verdict", r.global_test.verdict()},
                      {"confidence", 1.0 - o.alpha}};
  if (prepared.helmert && r.helmert) {
    const HelmertInFileUnits u = helmert_in_file_units(prepared, r);
    ordered_json values, sigmas;
    for (std::size_t k = 0; k < u.names.size(); ++k) {
      const auto i = static_cast<Eigen::Index>(k);
      values[u.names[k]] = num(u.value(i));
      sigmas[u.names[k]] = num(std::sqrt(std::max(0.0, u.covariance(i, i))));
    }
    j["helmert"] = {{"group", prepared.helmert->name},
                    {"model", prepared.helmert->rates ? "helmert14" : "helmert7"},
                    {"convention", prepared.helmert_position_vector ? "position_vector" : "coordinate_frame"},
                    {"source_frame", prepared.helmert_frame->to_string()},
                    {"target_frame", net.frame->to_string()},
                    {"reference_epoch", prepared.helmert->rates ? num(prepared.helmert->reference_epoch) : ordered_json(nullptr)},
                    {"measurements", prepared.helmert->measurements.size()},
                    {"parameters", values},
                    {"sigmas", sigmas}};
  }
  j["w_critical"] = r.w_critical;
  j["iterations"] = r.iterations;
  j["snooping"] = {{"adjustments", r.passes}, {"removed_per_step", r.removed_per_pass}, {"downdated", r.passes_downdated}};
  j["converged"] = r.converged;
  j["largest_correction_m"] = r.largest_correction_m;
  j["unknowns"] = r.unknowns;
  j["observations"] = r.observations;
  ordered_json stations = ordered_json::array();
  const double sigma_scale = r.sigma0.value_or(1.0);
  for (const auto& s : r.stations) {
    if (!s.used || !full) continue;
    const Eigen::Matrix3d& c = s.covariance_local_m2;
    ordered_json st = {{"id", s.id}, {"position_m", {s.position.x(), s.position.y(), s.position.z()}}};
    if (net.space == NetworkSpace::ellipsoidal) {
      const auto g = geodesy::geodetic_from_ecef(net.ellipsoid, geodesy::EcefPosition(s.position.x(), s.position.y(), s.position.z()));
      st["lat_deg"] = g.lat.deg();
      st["lon_deg"] = g.lon.deg();
      st["h_m"] = g.h.m;
      st["sigma_enu_m"] = {std::sqrt(std::max(0.0, c(0, 0))), std::sqrt(std::max(0.0, c(1, 1))), std::sqrt(std::max(0.0, c(2, 2)))};
      st["sigma_enu_scaled_m"] = {sigma_scale * std::sqrt(std::max(0.0, c(0, 0))), sigma_scale * std::sqrt(std::max(0.0, c(1, 1))),
                                  sigma_scale * std::sqrt(std::max(0.0, c(2, 2)))};
    } else {
      st["sigma_xyz_m"] = {std::sqrt(std::max(0.0, c(0, 0))), std::sqrt(std::max(0.0, c(1, 1))), std::sqrt(std::max(0.0, c(2, 2)))};
      st["sigma_xyz_scaled_m"] = {sigma_scale * std::sqrt(std::max(0.0, c(0, 0))), sigma_scale * std::sqrt(std::max(0.0, c(1, 1))),
                                  sigma_scale * std::sqrt(std::max(0.0, c(2, 2)))};
    }
    ordered_json cov = ordered_json::array();
    for (int a = 0; a < 3; ++a) cov.push_back({s.covariance_m2(a, 0), s.covariance_m2(a, 1), s.covariance_m2(a, 2)});
    st["covariance_m2"] = cov;
    st["ellipse"] = {{"a_m", s.ellipse.semi_major_m}, {"b_m", s.ellipse.semi_minor_m}, {"azimuth_deg", s.ellipse.azimuth_rad * kRadToDeg}};
    st["ellipse_confidence"] = {{"a_m", s.ellipse_confidence.semi_major_m}, {"b_m", s.ellipse_confidence.semi_minor_m},
                                {"confidence", o.confidence}};
    st["constraint"] = s.constraint;
    stations.push_back(st);
  }
  if (full) j["stations"] = std::move(stations);
  ordered_json measurements = ordered_json::array(), flagged = ordered_json::array(), removed = ordered_json::array();
  for (const std::size_t k : solver::failing_measurements(r)) {
    const auto& am = r.measurements[k];
    const auto& m = net.measurements[am.index];
    ordered_json x = {{"source", m.source},
                      {"kind", kind_key(m.kind)},
                      {"stations", stations_of(net, m)},
                      {"snooping_rank", am.snooping_rank > 0 ? ordered_json(am.snooping_rank) : ordered_json(nullptr)},
                      {"passes_after_rank", am.passes_after_rank > 0 ? ordered_json(am.passes_after_rank) : ordered_json(nullptr)},
                      {"w_max", num(am.w_max)},
                      {"test", {{"statistic", num(am.statistic)}, {"dof", am.test_dof}, {"p_value", num(am.p_value)}}}};
    ordered_json mdb = ordered_json::array();
    for (Eigen::Index c = 0; c < am.mdb.size(); ++c) mdb.push_back(num(am.mdb(c)));
    x["mdb"] = mdb;
    if (am.outlier) x["because"] = am.removed_because;
    (am.outlier ? removed : flagged).push_back(std::move(x));
  }
  for (const auto& am : r.measurements) {
    const auto& m = net.measurements[am.index];
    if (am.outlier && am.snooping_rank == 0) removed.push_back({{"source", m.source}, {"kind", kind_key(m.kind)},
                                                               {"stations", stations_of(net, m)}, {"because", am.removed_because}});
    if (!full) continue;
    ordered_json x = {{"source", m.source}, {"kind", kind_key(m.kind)}, {"stations", stations_of(net, m)},
                      {"unit", angular(m.kind) ? "rad" : "m"}};
    auto vec = [&](const Eigen::VectorXd& v) {
      ordered_json a = ordered_json::array();
      for (Eigen::Index k = 0; k < v.size(); ++k) a.push_back(num(v(k)));
      return a;
    };
    x["observed"] = vec(am.observed);
    x["adjusted"] = vec(am.adjusted);
    x["residual"] = vec(am.residual);
    x["sigma"] = vec(am.sigma);
    x["residual_sigma"] = vec(am.residual_sigma);
    x["redundancy"] = vec(am.redundancy);
    x["w"] = vec(am.w);
    x["mdb"] = vec(am.mdb);
    x["test"] = {{"statistic", am.statistic}, {"dof", am.test_dof}, {"p_value", am.p_value}};
    x["status"] = solver::to_string(am.status(r.alpha_point));
    x["snooping_rank"] = am.snooping_rank > 0 ? ordered_json(am.snooping_rank) : ordered_json(nullptr);
    if (!m.frame_step.empty()) x["frame_step"] = m.frame_step;
    measurements.push_back(std::move(x));
  }
  if (full) j["measurements"] = std::move(measurements);
  j["flagged"] = std::move(flagged);
  j["removed"] = std::move(removed);
  j["warnings"] = r.warnings;
  if (!r.refused_because.empty()) j["refused_because"] = r.refused_because;
  return j;
}

std::string stations_sidecar_text(const PreparedNetwork& prepared, const solver::AdjustmentResult& r, const solver::AdjustOptions& o,
                                  const std::vector<std::string>& argv, const std::vector<std::string>& inputs,
                                  const std::string& version) {
  nlohmann::ordered_json side = report_document(prepared, r, o, ReportDetail::summary);
  side["schema"] = "geoanchor.stations/2";
  side["report_schema"] = "geoanchor.adjust-report/1";
  side["stations"] = static_cast<std::size_t>(std::count_if(r.stations.begin(), r.stations.end(), [](const auto& s) { return s.used; }));
  side["geoanchor_version"] = version;
  side["command"] = argv;
  nlohmann::ordered_json listed = nlohmann::ordered_json::array();
  for (const auto& in : inputs) {
    std::error_code ec;
    const bool hashable = in != "-" && std::filesystem::is_regular_file(in, ec);
    listed.push_back({{"path", in == "-" ? nlohmann::ordered_json(nullptr) : nlohmann::ordered_json(in)},
                      {"sha256", hashable ? nlohmann::ordered_json(sha256_file_hex(in)) : nlohmann::ordered_json(nullptr)}});
  }
  side["inputs"] = listed;
  return side.dump(2);
}

}  // namespace geoanchor::workflow

namespace geoanchor::workflow {


io::TransformFile helmert_transform_file(const PreparedNetwork& prepared, const solver::AdjustmentResult& r,
                                         const solver::AdjustOptions& o, const std::string& generator) {
  if (!prepared.helmert || !r.helmert) throw std::logic_error("helmert_transform_file: no Helmert was estimated");
  const solver::HelmertGroup& g = *prepared.helmert;
  const bool pv = prepared.helmert_position_vector;
  const HelmertInFileUnits u = helmert_in_file_units(prepared, r);
  const Eigen::Index n = u.value.size();
  const Eigen::VectorXd& value = u.value;
  const Eigen::MatrixXd& cov = u.covariance;
  io::TransformFile t;
  t.model = g.rates ? io::TransformModel::helmert14 : io::TransformModel::helmert7;
  t.rotation_model = geodesy::RotationModel::small_angle;
  t.source_frame = prepared.helmert_frame;
  t.target_frame = prepared.network.frame;
  auto seven = [&](Eigen::Index at, auto h) {
    h.t_m = value.segment<3>(at);
    h.rx = geodesy::Angle::arcseconds(value(at + 3));
    h.ry = geodesy::Angle::arcseconds(value(at + 4));
    h.rz = geodesy::Angle::arcseconds(value(at + 5));
    h.ds = geodesy::ScaleDifference::ppm(value(at + 6));
    return h;
  };
  auto rates = [&](auto h) {
    h.dt_m_per_year = value.segment<3>(7);
    h.drx_per_year = geodesy::Angle::arcseconds(value(10));
    h.dry_per_year = geodesy::Angle::arcseconds(value(11));
    h.drz_per_year = geodesy::Angle::arcseconds(value(12));
    h.dds_per_year = geodesy::ScaleDifference::ppm(value(13));
    return h;
  };
  if (g.rates) {
    t.reference_epoch = geodesy::DecimalYear{g.reference_epoch};
    if (pv) {
      geodesy::Helmert14<geodesy::PositionVector> h;
      h.at_reference_epoch = seven(0, geodesy::Helmert7<geodesy::PositionVector>{});
      h.rates = rates(geodesy::Helmert7Rates<geodesy::PositionVector>{});
      h.reference_epoch = *t.reference_epoch;
      t.helmert = h;
    } else {
      geodesy::Helmert14<geodesy::CoordinateFrame> h;
      h.at_reference_epoch = seven(0, geodesy::Helmert7<geodesy::CoordinateFrame>{});
      h.rates = rates(geodesy::Helmert7Rates<geodesy::CoordinateFrame>{});
      h.reference_epoch = *t.reference_epoch;
      t.helmert = h;
    }
  } else if (pv) {
    t.helmert = seven(0, geodesy::Helmert7<geodesy::PositionVector>{});
  } else {
    t.helmert = seven(0, geodesy::Helmert7<geodesy::CoordinateFrame>{});
  }
  io::FitRecord f;
  for (Eigen::Index k = 0; k < n; ++k) {
    f.sigmas.emplace_back(u.names[static_cast<std::size_t>(k)], std::sqrt(std::max(0.0, cov(k, k))));
    f.correlation_names.push_back(u.names[static_cast<std::size_t>(k)]);
  }
  for (Eigen::Index i = 0; i < n; ++i) {
    std::vector<double> row;
    for (Eigen::Index j = 0; j < n; ++j) {
      const double d = std::sqrt(cov(i, i) * cov(j, j));
      row.push_back(i == j ? 1.0 : d > 0.0 ? std::clamp(cov(i, j) / d, -1.0, 1.0) : 0.0);
    }
    f.correlation.push_back(row);
  }
  f.sigmas_scaled_by_sigma0 = false;
  record_statistics(f, r.sigma0, r.dof, o.alpha, o.alpha_point, r.global_test);
  f.warnings = r.warnings;
  for (const auto& note : prepared.notes) {
    if (note.rfind("warning: ", 0) == 0) f.warnings.push_back(note.substr(9));
  }
  f.generator = generator;
  // The group's stations that the final adjustment used, in the group's
  // datum (taken back through the estimate, at the reference epoch): where
  // the transformation was observed, in its source frame.
  std::vector<bool> used(prepared.network.measurements.size(), false);
  for (const auto& am : r.measurements) used[am.index] = am.used;
  std::vector<geodesy::EcefPosition> marks;
  std::vector<bool> seen(r.stations.size(), false);
  const std::optional<geodesy::DecimalYear> at = t.reference_epoch;
  for (std::size_t mi : g.measurements) {
    if (!used[mi]) continue;
    for (std::size_t s : prepared.network.measurements[mi].stations) {
      if (seen[s]) continue;
      seen[s] = true;
      marks.push_back(t.apply(geodesy::EcefPosition(r.stations[s].position), at, true, "the group's stations"));
    }
  }
  if (!marks.empty()) f.extent = io::ControlExtent::of(marks);
  f.gnss_solutions = adjust_solution_record(prepared, r);
  t.fit = std::move(f);
  // The map metadata contract: the target side is the network's frame.
  using T = io::MapMetadataBuilder::Text;
  io::MapMetadataBuilder b("the transform file of adjust --estimate-helmert");
  const std::string derived = "the adjustment (the network's frame)";
  if (t.target_frame) {
    b.frame(t.target_frame->name(), derived);
    if (t.target_frame->epoch()) b.coordinate_epoch(t.target_frame->epoch()->year, derived);
  }
  const std::string& ellipsoid = prepared.network.ellipsoid.name();
  b.text(T::horizontal_crs,
         "geographic (latitude, longitude) on " + ellipsoid + (t.target_frame ? " in " + t.target_frame->to_string() : ""),
         derived);
  b.text(T::vertical_datum, "ellipsoid " + ellipsoid, derived);
  if (prepared.solution_policy) {
    geodesy::SolutionCounts c;
    for (const auto& m : prepared.network.measurements) {
      if (m.solution) ++c.count[geodesy::solution_index(*m.solution)];
    }
    b.gnss_solution_counts(c, "computed from the solution types of " + std::to_string(c.total()) + " GNSS measurements");
  }
  b.text(T::coordinate_storage, "float64 (JSON numbers at full precision)", "the transform file's format");
  t.metadata = b.metadata();
  return t;
}

}  // namespace geoanchor::workflow
