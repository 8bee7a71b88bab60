// What adjust writes besides its report: the stations as SINEX and CSV, the
// measurements as CSV, the stations' sidecar and the record of GNSS
// solution types; and the naming and units these share with the report.
#include "adjust_outputs.hpp"

#include "geoanchor/base/parallel.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <filesystem>
#include <limits>
#include <sstream>
#include <stdexcept>

#include "geoanchor/base/error.hpp"
#include "geoanchor/geodesy/geocentric.hpp"
#include "geoanchor/base/number_text.hpp"
#include "geoanchor/base/hash.hpp"
#include "geoanchor/io/network/sinex.hpp"

namespace geoanchor::workflow {

namespace adjust_detail {

using geodesy::MeasurementKind;

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
    case MeasurementKind::astronomic_latitude: return "astronomic_latitude";
    case MeasurementKind::astronomic_longitude: return "astronomic_longitude";
    case MeasurementKind::astronomic_azimuth: return "astronomic_azimuth";
    case MeasurementKind::msl_arc: return "msl_arc";
    case MeasurementKind::observation_set: return "observation_set";
  }
  return "measurement";
}

bool angular(MeasurementKind k) {
  return k == MeasurementKind::direction || k == MeasurementKind::horizontal_angle || k == MeasurementKind::zenith_angle ||
         k == MeasurementKind::vertical_angle || k == MeasurementKind::azimuth || k == MeasurementKind::geodetic_latitude ||
         k == MeasurementKind::geodetic_longitude || k == MeasurementKind::astronomic_latitude ||
         k == MeasurementKind::astronomic_longitude || k == MeasurementKind::astronomic_azimuth;
}

std::string stations_of(const geodesy::Network& net, const geodesy::NetworkMeasurement& m) {
  std::string s;
  const bool pairs = m.kind == MeasurementKind::gnss_baselines;
  if (m.kind == MeasurementKind::observation_set) {
    std::vector<std::size_t> seen;
    for (std::size_t st : m.stations) {
      if (std::find(seen.begin(), seen.end(), st) != seen.end()) continue;
      s += (seen.empty() ? "" : " ") + net.stations[st].id;
      seen.push_back(st);
    }
    return s;
  }
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

std::string metadata_text(const geodesy::NetworkMeasurement& m) {
  std::string out;
  const auto put = [&out](const std::string& s) {
    for (const char ch : s) {
      switch (ch) {
        case '%': out += "%25"; break;
        case ';': out += "%3B"; break;
        case '=': out += "%3D"; break;
        case '\n': out += "%0A"; break;
        case '\r': out += "%0D"; break;
        default: out += ch;
      }
    }
  };
  for (std::size_t k = 0; k < m.metadata.size(); ++k) {
    if (k > 0) out += ';';
    put(m.metadata[k].first);
    out += '=';
    put(m.metadata[k].second);
  }
  return out;
}

double correlation(const Eigen::Matrix3d& c, int a, int b) {
  const double d = std::sqrt(c(a, a) * c(b, b));
  if (!(d > 0.0) || !std::isfinite(c(a, b))) return 0.0;
  return std::clamp(c(a, b) / d, -1.0, 1.0);
}

}  // namespace adjust_detail

using namespace adjust_detail;
using geodesy::MeasurementKind;
using geodesy::NetworkSpace;

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
      const char* status = am ? solver::to_string(am->status(r.alpha_point)) : "ignored";
      const std::string rank = am && am->snooping_rank > 0 ? std::to_string(am->snooping_rank) : std::string();
      // An observation set: a row per observation, named by its own source,
      // kind and stations, with the set's source in `set`.
      const bool set = m.kind == MeasurementKind::observation_set;
      const std::string source = csv_field(m.source), stations = csv_field(stations_of(net, m));
      const std::string metadata = csv_field(metadata_text(m));
      const auto at = [&](const Eigen::VectorXd* v, Eigen::Index k) {
        return v && k < v->size() ? (*v)(k) : std::numeric_limits<double>::quiet_NaN();
      };
      for (Eigen::Index k = 0; k < m.value.size(); ++k) {
        static constexpr const char* kAxis[] = {"x", "y", "z"};
        const geodesy::NetworkMeasurement& part = set ? m.parts[static_cast<std::size_t>(k)] : m;
        const bool ang = angular(part.kind);
        const double value_scale = ang ? kRadToDeg : 1.0, small_scale = ang ? kRadToArcsec : 1.0;
        out += set ? csv_field(part.source) : source;
        out += ',';
        out += kind_key(part.kind);
        out += ',';
        out += set ? csv_field(stations_of(net, part)) : stations;
        out += ',';
        if (m.value.size() != 1 && !set) {
          if (m.kind == MeasurementKind::gnss_points) out += net.stations[m.stations[static_cast<std::size_t>(k / 3)]].id;
          else out += std::to_string(k / 3);
          out += '.';
          out += kAxis[k % 3];
        }
        out += ',';
        if (m.value_known) number(out, m.value(k) * value_scale);  // a planned measurement (pre-analysis): empty
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
        // External reliability: the largest effect of a blunder of its MDB
        // on any station (3-D, horizontal, vertical; metres) and where.
        const solver::ExternalReliability* e =
            am && static_cast<std::size_t>(k) < am->external.size() ? &am->external[static_cast<std::size_t>(k)] : nullptr;
        const bool has_e = e && std::isfinite(e->effect_m);
        number(out, has_e ? e->effect_m : std::numeric_limits<double>::quiet_NaN());
        out += ',';
        if (has_e) out += csv_field(r.stations[e->station].id);
        out += ',';
        number(out, has_e ? e->horizontal_m : std::numeric_limits<double>::quiet_NaN());
        out += ',';
        if (has_e) out += csv_field(r.stations[e->horizontal_station].id);
        out += ',';
        number(out, has_e ? e->vertical_m : std::numeric_limits<double>::quiet_NaN());
        out += ',';
        if (has_e) out += csv_field(r.stations[e->vertical_station].id);
        out += ',';
        out += status;
        out += ',';
        out += rank;
        out += ',';
        if (set) out += source;
        out += ',';
        out += metadata;
        out += '\n';
      }
    }
  });
  std::string out = "source,kind,stations,component,observed,adjusted,value_unit,residual,sigma,residual_sigma,residual_unit,redundancy,w,"
                    "mdb,external_m,external_station,external_horizontal_m,external_horizontal_station,external_vertical_m,"
                    "external_vertical_station,status,snooping_rank,set,metadata\n";
  std::size_t size = out.size();
  for (const auto& part : parts) size += part.size();
  out.reserve(size);
  for (auto& part : parts) {
    out += part;
    std::string().swap(part);
  }
  return out;
}

std::string candidate_criterion_name(const solver::AdjustOptions& o) {
  if (o.candidate_criterion) return "custom";
  if (o.candidate_ranking == solver::CandidateRanking::sigma_up) return "sigma_up";
  return "semi_major_" + format_shortest(100.0 * o.confidence);
}

std::string candidates_csv(const PreparedNetwork& prepared, const solver::AdjustmentResult& r, const solver::AdjustOptions& o) {
  const auto& net = prepared.network;
  const std::string criterion = candidate_criterion_name(o);
  std::string out = "rank,source,kind,stations,measurements,criterion,worst_m,worst_station,improvement_m\n";
  const auto number = [&out](double v) {
    if (std::isfinite(v)) out += format_shortest(v);  // else empty
  };
  for (std::size_t k = 0; k < r.candidates.size(); ++k) {
    const auto& c = r.candidates[k];
    const auto& first = prepared.candidates[c.measurements.front()];
    out += std::to_string(k + 1) + ',' + csv_field(first.source) + ',' +
           (first.set && c.measurements.size() > 1 ? std::string("direction_set") : std::string(kind_key(first.kind))) + ',';
    std::string stations;
    for (std::size_t mi : c.measurements) stations += (stations.empty() ? "" : " ") + stations_of(net, prepared.candidates[mi]);
    out += csv_field(stations) + ',' + std::to_string(c.measurements.size()) + ',' + criterion + ',';
    number(c.worst.value);
    out += ',' + csv_field(r.stations[c.worst.station].id) + ',';
    number(c.improvement);
    out += '\n';
  }
  return out;
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
