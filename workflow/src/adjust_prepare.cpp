// `geoanchor adjust` as a library (adjust.hpp): the network prepared for
// the solver (inputs read, GNSS solution types, variance scales, frames,
// error models, the Helmert group, constraints). Its outputs, report and Helmert transform
// file are in adjust_outputs.cpp, adjust_report.cpp, adjust_helmert_file.cpp.

#include "geoanchor/workflow/adjust.hpp"

#include <Eigen/SVD>

#include <algorithm>
#include <array>
#include <cmath>

#include "geoanchor/base/error.hpp"
#include "geoanchor/crs/frame_ellipsoid.hpp"
#include "geoanchor/geodesy/frame_catalog.hpp"
#include "geoanchor/geodesy/geocentric.hpp"
#include "geoanchor/geodesy/local_frame.hpp"
#include "geoanchor/base/number_text.hpp"
#include "geoanchor/io/network/network_input.hpp"
#include "geoanchor/solver/error_models.hpp"

namespace geoanchor::workflow {
namespace {

using geodesy::Frame;
using geodesy::MeasurementKind;
using geodesy::NetworkSpace;

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

// The group's stations must span what seven parameters need (fit's
// rules, RELIABILITY 1, 3, 4): three or more, not on one line, not in one place.
void require_helmert_geometry(const std::string& flag, const geodesy::Network& net, const solver::HelmertGroup& g) {
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
  require_helmert_geometry(flag, net, g);
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

// The inputs read into one network (--sinex-frame: a frame of the catalog).
geodesy::Network read_inputs(const AdjustRequest& request) {
  io::NetworkReadOptions read_options;
  read_options.geoid = request.options.geoid;
  read_options.station_geoid = request.station_geoid.get();
  if (request.sinex_frame) {
    read_options.sinex_frame = geodesy::Frame::parse(*request.sinex_frame, "--sinex-frame");
    const auto known = geodesy::catalog_frame_names();
    if (std::find(known.begin(), known.end(), read_options.sinex_frame->name()) == known.end()) {
      std::string list;
      for (const auto& k : known) list += (list.empty() ? "" : ", ") + k;
      throw Error(ErrorKind::usage, "E_OPTION", "--sinex-frame " + *request.sinex_frame + ": not a frame of the catalog (" + list + ")");
    }
  }
  return io::read_network(request.inputs, read_options);
}

// GNSS solution types: float and worse left out, or weighted on request.
void apply_solution_types(const AdjustRequest& request, PreparedNetwork& p) {
  geodesy::Network& net = p.network;
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
void apply_variance_scales(geodesy::Network& net) {
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

// The frame the network is adjusted in (--frame, else the stations'), and
// the network's ellipsoid from it.
Frame adjustment_frame(const AdjustRequest& request, geodesy::Network& net) {
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
  // adjustment frame's own ellipsoid: the catalog's, else PROJ's.
  const std::string where = request.frame ? "--frame" : net.source_name + ": the stations' frame";
  if (const auto e = io::frame_ellipsoid(*target, where)) {
    if (net.ellipsoid_stated && !io::same_ellipsoid(net.ellipsoid, e->ellipsoid)) {
      throw Error(ErrorKind::input, "E_ELLIPSOID",
                  net.source_name + ": the network states the ellipsoid " + net.ellipsoid.name() + ", but its frame " +
                      target->to_string() + " is on " + e->ellipsoid.name() + " (" + e->source + ")");
    }
    net.ellipsoid = e->ellipsoid;
  } else if (!net.ellipsoid_stated) {
    // Never a default ellipsoid for a frame nobody knows: the terrestrial
    // models, the local axes and the stations' heights are on it.
    throw Error(ErrorKind::input, "E_ELLIPSOID",
                net.source_name + ": the frame " + target->to_string() +
                    " is in neither geoanchor's frame catalog nor PROJ's database, so its ellipsoid is unknown: give "
                    "the network's \"ellipsoid\" (" +
                    geodesy::named_ellipsoid_list() + ", or {\"a_m\", \"rf\"}) or its \"crs\" (e.g. EPSG:4272)");
  }
  return *target;
}

// The network into the adjustment frame `target`, and the Helmert group
// resolved (its GNSS measurements stay in their own datum).
void bring_to_frame(const AdjustRequest& request, const Frame& target, PreparedNetwork& p) {
  geodesy::Network& net = p.network;
  // The stations' a-priori positions and each GNSS measurement into the target.
  if (net.frame && !(*net.frame == target)) {
    const FrameChange c = frame_change(*net.frame, target, net.source_name + ": the stations");
    for (auto& s : net.stations) s.position = c.map.apply(s.position);
    p.notes.push_back("stations' a-priori positions: " + c.description);
  }
  if (request.estimate_helmert) resolve_helmert_group(request, net, target, p);
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
    Frame from = m.frame ? *m.frame : net.frame ? *net.frame : target;
    if (geodesy::is_dynamic(from) && !from.epoch()) {
      // A dynamic frame names no epoch: refused, unless --frame gives the
      // epoch to assume (said in the notes and on standard error).
      if (!request.frame || !target.epoch()) {
        throw Error(ErrorKind::input, "E_EPOCH_MISSING",
                    m.source + ": " + geodesy::to_string(m.kind) + " in " + from.to_string() +
                        ", a dynamic frame, with no coordinate epoch: give it (\"" + from.name() +
                        "@YYYY.Y\"), or --frame NAME@EPOCH to take such measurements at that epoch");
      }
      from = Frame::parse(from.name() + "@" + geodesy::format_decimal_year(*target.epoch()), m.source);
      if (assumed++ == 0) assumed_first = m.source;
      assumed_frame = from.to_string();
    }
    if (from == target) continue;
    const FrameChange c = frame_change(from, target, m.source);
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
  if (moved > 0) p.notes.push_back(std::to_string(moved) + " GNSS measurement(s) brought to " + target.to_string() + "; the first " + first);
}

// --constrain ID=CCC[,SIGMA_M]: each station's constraint.
void apply_constraints(const AdjustRequest& request, PreparedNetwork& p) {
  geodesy::Network& net = p.network;
  for (const auto& text : request.constrain) {
    std::string id;
    const geodesy::StationConstraint c = parse_constraint(text, id);
    const auto s = net.find(id);
    if (!s) throw Error(ErrorKind::usage, "E_OPTION", "--constrain " + text + ": no station " + id + " in " + net.source_name);
    net.stations[*s].constraint = c;
    p.notes.push_back("station " + id + " constrained " + c.text() + " by --constrain");
  }
}

}  // namespace

// --candidates FILE: its measurements (those whose source is the file's)
// taken out of the network; each station of a candidate must be one the
// design's measurements reach.
void take_candidates(const AdjustRequest& request, PreparedNetwork& p) {
  if (!request.candidates) return;
  geodesy::Network& net = p.network;
  const std::string prefix = *request.candidates + ":";
  std::vector<geodesy::NetworkMeasurement> design;
  for (auto& m : net.measurements) {
    (m.source.rfind(prefix, 0) == 0 ? p.candidates : design).push_back(std::move(m));
  }
  net.measurements = std::move(design);
  if (p.candidates.empty()) {
    throw Error(ErrorKind::input, "E_CANDIDATES", "--candidates " + *request.candidates + ": no measurement read from it");
  }
  std::vector<bool> reached(net.stations.size(), false);
  for (const auto& m : net.measurements) {
    if (m.ignore) continue;
    for (std::size_t s : m.stations) reached[s] = true;
  }
  for (const auto& m : p.candidates) {
    for (std::size_t s : m.stations) {
      if (!reached[s]) {
        throw Error(ErrorKind::input, "E_CANDIDATE_STATION",
                    m.source + ": candidate " + geodesy::to_string(m.kind) + " at station " + net.stations[s].id +
                        ", which no measurement of the network reaches (" + (net.stations[s].position_known ? "not in the design" : "an unknown station") +
                        "): a candidate joins stations of the design");
      }
    }
  }
}

PreparedNetwork prepare_network(const AdjustRequest& request) {
  PreparedNetwork p;
  // The standard first: a name that is not shipped fails before the inputs are read.
  if (request.standard) p.standard = std::make_shared<const AccuracyStandard>(load_standard(*request.standard));
  if (request.candidates) {
    AdjustRequest with = request;
    with.inputs.push_back(*request.candidates);
    with.candidates.reset();
    p.network = read_inputs(with);
  } else {
    p.network = read_inputs(request);
  }
  take_candidates(request, p);
  geodesy::Network& net = p.network;
  for (const auto& w : net.warnings) p.notes.push_back("warning: " + w);
  // Which geoid, and what it gives (N, the deflections): the report says so.
  if (request.station_geoid) {
    std::size_t named = 0;
    for (const auto& s : net.stations) named += s.geoid ? 1u : 0u;
    p.notes.push_back("geoid: " + request.station_geoid->path.string() + " (DynAdjust per-station file): N and deflections of the "
                      "vertical (xi, eta) of " + std::to_string(named) + " of " + std::to_string(net.stations.size()) + " stations");
  } else if (request.options.geoid && net.space == NetworkSpace::ellipsoidal) {
    const auto& g = *request.options.geoid;
    p.notes.push_back("geoid: " + g.model_name() +
                      (g.has_deflections() ? ": N and the deflections of the vertical" : ": N; deflections of the vertical zero"));
  }
  // Astronomic measurements where nothing gives the deflection of the
  // vertical: adjusted with it zero, said once.
  if (net.space == NetworkSpace::ellipsoidal && !(request.options.geoid && request.options.geoid->has_deflections())) {
    std::size_t astronomic = 0;
    for (const auto& m : net.measurements) {
      const bool astro = m.kind == geodesy::MeasurementKind::astronomic_azimuth || m.kind == geodesy::MeasurementKind::astronomic_latitude ||
                         m.kind == geodesy::MeasurementKind::astronomic_longitude;
      if (astro && !m.ignore && !net.stations[m.stations[0]].geoid) ++astronomic;
    }
    if (astronomic > 0) {
      const std::string w = std::to_string(astronomic) + " astronomic measurement(s) (azimuth, latitude, longitude) at stations without a "
                            "deflection of the vertical: adjusted with it zero (--geoid a grid with deflections or a per-station .geo file gives it)";
      net.warnings.push_back(w);
      p.notes.push_back("warning: " + w);
    }
  }
  apply_solution_types(request, p);
  apply_variance_scales(net);
  if (net.space == NetworkSpace::ellipsoidal) {
    const Frame target = adjustment_frame(request, net);
    bring_to_frame(request, target, p);
    net.frame = target;
  } else if (request.frame) {
    throw Error(ErrorKind::usage, "E_OPTION", "--frame " + *request.frame + ": the network is local (" + net.source_name + "): it has no frame");
  } else if (request.estimate_helmert) {
    throw Error(ErrorKind::usage, "E_OPTION", "--estimate-helmert: the network is local (" + net.source_name + "): it has no frame to relate a datum to");
  }
  if (!net.error_models.empty()) {
    // The instruments' error models, from the geometry in the network's
    // frame (solver/error_models.hpp).
    solver::apply_error_models(net);
    std::size_t modelled = 0;
    for (const auto& m : net.measurements) modelled += m.error_model ? 1u : 0u;
    std::string names;
    for (const auto& e : net.error_models) names += (names.empty() ? "" : ", ") + e.name;
    p.notes.push_back("error models " + names + " added to the covariances of " + std::to_string(modelled) + " measurement(s)");
  }
  apply_constraints(request, p);
  p.refraction_k = request.options.refraction_k;
  if (net.refraction_k) {
    if (request.refraction_given && request.options.refraction_k != *net.refraction_k) {
      throw Error(ErrorKind::usage, "E_OPTION", "--refraction " + format_shortest(request.options.refraction_k) + " differs from the " +
                                                    format_shortest(*net.refraction_k) + " of " + net.refraction_source +
                                                    ": give one coefficient of refraction");
    }
    p.refraction_k = *net.refraction_k;
    p.notes.push_back("coefficient of refraction " + format_shortest(p.refraction_k) + " from " + net.refraction_source);
  }
  p.relative = relative_options(request.relative, net);
  p.relative_spec = request.relative;
  return p;
}

}  // namespace geoanchor::workflow
