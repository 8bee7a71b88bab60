// Control sets in JSON (schema: docs/commands/fit.md).

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstring>
#include <fstream>
#include <nlohmann/json.hpp>
#include <set>
#include <span>
#include <sstream>
#include <string_view>
#include <vector>

#include "control/control_common.hpp"
#include "json_fields.hpp"
#include "geoanchor/base/error.hpp"
#include "geoanchor/base/number_text.hpp"
#include "geoanchor/io/control/control_csv.hpp"
#include "geoanchor/io/control/crs_columns.hpp"
#include "geoanchor/io/json_input.hpp"

namespace geoanchor::io {
namespace {

using nlohmann::json;

[[noreturn]] void fail(const std::string& where, const std::string& what) {
  throw Error(ErrorKind::input, "E_VALUE", where + ": " + what);
}

double number_at(const json& obj, const std::string& key, const std::string& where) {
  return detail::finite_json_number(obj, key, where, "E_VALUE");
}

// One frame of one point: {"x_m","y_m","z_m"} | {"lat_deg","lon_deg","h_m"} | {"e_m","n_m","u_m"}, with
// "H_m" (orthometric) in place of "h_m" when `geoid` reads it.
detail::RoleValues role_values(const json& point, const std::string& role, const std::string& where,
                               const geodesy::GeoidGrid* geoid) {
  const std::string frame = role == "src" ? "source" : "target";
  if (!point.contains(frame) || !point.at(frame).is_object()) fail(where + "." + frame, "missing; expected an object of coordinates");
  const json& c = point.at(frame);
  const std::string at = where + "." + frame;
  detail::RoleValues v;
  v.source = role == "src";
  const char* const kinds[3][3] = {{"x_m", "y_m", "z_m"}, {"lat_deg", "lon_deg", "h_m"}, {"e_m", "n_m", "u_m"}};
  const CoordinateKind kind_of[3] = {CoordinateKind::ecef, CoordinateKind::geodetic, CoordinateKind::enu};
  int found = -1;
  for (int k = 0; k < 3; ++k) {
    if (c.contains(kinds[k][0]) || c.contains(kinds[k][1])) {
      if (found >= 0) fail(at, "mixes coordinate kinds; expected one of x_m/y_m/z_m, lat_deg/lon_deg/h_m, e_m/n_m/u_m");
      found = k;
    }
  }
  if (found < 0) fail(at, "no coordinates; expected x_m,y_m,z_m | lat_deg,lon_deg,h_m | e_m,n_m,u_m");
  // Geodetic heights: h_m (ellipsoidal) or H_m (orthometric, h = H + N).
  const bool geodetic = found == 1;
  v.orthometric = geodetic && c.contains("H_m");
  if (v.orthometric && c.contains("h_m")) {
    fail(at + ".H_m", "an ellipsoidal (h_m) and an orthometric (H_m) height for one mark; give one");
  }
  if (v.orthometric && !geoid) detail::refuse_orthometric_without_geoid(at + ".H_m");
  const auto* row = kinds[found];
  const std::string_view keys[4] = {row[0], row[1], row[2], "H_m"};  // H_m only for orthometric heights
  if (const auto key = detail::first_unknown_key(c, std::span<const std::string_view>(keys, v.orthometric ? 4 : 3))) {
    fail(at + "." + *key, std::string("unknown key for these coordinates; expected ") + row[0] + ", " + row[1] + ", " + row[2] +
                              (geodetic ? " (h_m ellipsoidal, or H_m orthometric with --geoid; metres)"
                                        : " (heights ellipsoidal, in metres)"));
  }
  v.kind = kind_of[found];
  v.a = number_at(c, kinds[found][0], at);
  v.b = number_at(c, kinds[found][1], at);
  v.c = number_at(c, v.orthometric ? "H_m" : kinds[found][2], at);
  const std::string sigma_key = "sigma_" + role + "_m", cov_key = "cov_" + role + "_m2";
  if (point.contains(sigma_key)) v.sigma_m = number_at(point, sigma_key, where);
  if (point.contains(cov_key)) {
    if (v.sigma_m) fail(where, "both " + sigma_key + " and " + cov_key + "; give one");
    const json& m = point.at(cov_key);
    if (!m.is_array() || m.size() != 3) fail(where + "." + cov_key, "expected a 3×3 array of arrays (m²)");
    std::array<double, 9> full{};
    for (std::size_t i = 0; i < 3; ++i) {
      if (!m[i].is_array() || m[i].size() != 3) fail(where + "." + cov_key, "expected a 3×3 array of arrays (m²)");
      for (std::size_t j = 0; j < 3; ++j) {
        if (!m[i][j].is_number()) {
          fail(where + "." + cov_key + "[" + std::to_string(i) + "][" + std::to_string(j) + "]",
               "entry " + m[i][j].dump() + " is not a number");
        }
        full[3 * i + j] = m[i][j].get<double>();
      }
    }
    for (std::size_t i = 0; i < 3; ++i) {
      for (std::size_t j = 0; j < i; ++j) {
        if (full[3 * i + j] != full[3 * j + i]) fail(where + "." + cov_key, "not symmetric");
      }
    }
    v.cov_m2 = std::array<double, 6>{full[0], full[1], full[2], full[4], full[5], full[8]};
  }
  return v;
}

// One frame of one point in a CRS: exactly the CRS's keys (`columns`), in
// its units; read as three numbers that PROJ turns into ECEF once every
// point is read (positions_from_crs), with the point's sigma or covariance.
detail::RoleValues crs_role_values(const json& point, const std::string& role, const std::string& where,
                                   const CrsColumns& columns) {
  const std::string frame = role == "src" ? "source" : "target";
  if (!point.contains(frame) || !point.at(frame).is_object()) fail(where + "." + frame, "missing; expected an object of coordinates");
  const json& c = point.at(frame);
  const std::string at = where + "." + frame;
  if (const auto key = detail::first_unknown_key(c, columns.names)) {
    fail(at + "." + *key, "unknown key for the CRS " + columns.crs.display_name() + "; expected " + detail::key_list(columns.names));
  }
  // The sigma and covariance as role_values reads them, on a stand-in of
  // ECEF keys (the checks and messages are the same).
  json stand_in = point;
  stand_in[frame] = json{{"x_m", 0.0}, {"y_m", 0.0}, {"z_m", 0.0}};
  detail::RoleValues v = role_values(stand_in, role, where, nullptr);
  v.kind = CoordinateKind::ecef;  // as read; made ECEF through PROJ after the points are read
  v.a = number_at(c, columns.names[0], at);
  v.b = number_at(c, columns.names[1], at);
  v.c = number_at(c, columns.names[2], at);
  return v;
}

// The frames the file names ("source_frame", "target_frame"), and where.
void read_frames(const json& doc, const std::string& source_name, geodesy::ControlSet& set, std::string& source_frame_where,
                 std::string& target_frame_where) {
  for (const char* key : {"source_frame", "target_frame"}) {
    if (!doc.contains(key)) continue;
    if (!doc.at(key).is_string()) fail(source_name + ": " + key, "expected a string such as ITRF2014@2024.5");
    auto f = geodesy::Frame::parse(doc.at(key).get<std::string>(), source_name + ": " + key);
    const bool source = std::string_view(key) == "source_frame";
    (source ? set.source_frame : set.target_frame) = std::move(f);
    (source ? source_frame_where : target_frame_where) = source_name + ": " + key;
  }
}

const char* const kCrsFlags[2] = {"--src-crs", "--dst-crs"};

// Each frame's CRS: the option, or the file's "source_crs"/"target_crs";
// both must say the same. Its keys are the CRS's columns without the role
// (easting_ftus, northing_ftus, h_m; lat_deg, lon_deg, H_m for a compound
// CRS), the same in every point.
void read_crs_columns(const json& doc, const json& points, const ControlReadOptions& o, const std::string& source_name,
                      geodesy::ControlSet& set, std::optional<CrsColumns> (&crs_columns)[2]) {
  const char* crs_keys[2] = {"source_crs", "target_crs"};
  for (std::size_t k = 0; k < 2; ++k) {
    std::optional<Crs> crs = k == 0 ? o.src_crs : o.dst_crs;
    std::string where = kCrsFlags[k];
    if (doc.contains(crs_keys[k])) {
      const std::string at = source_name + ": " + crs_keys[k];
      if (!doc.at(crs_keys[k]).is_string()) fail(at, "expected a string such as \"EPSG:2236\"");
      const Crs stated = Crs::parse(doc.at(crs_keys[k]).get<std::string>(), at);
      if (crs && !crs->same_as(stated)) {
        throw Error(ErrorKind::input, "E_CRS_CONFLICT",
                    std::string(kCrsFlags[k]) + " " + crs->display_name() + " contradicts " + at + " (" +
                        stated.display_name() + "); drop the flag or fix the file");
      }
      if (!crs) crs = stated, where = crs_keys[k];
    }
    if (!crs) continue;
    const char* role = k == 0 ? "source" : "target";
    std::vector<std::string> keys;
    if (!points.empty() && points[0].is_object() && points[0].contains(role) && points[0].at(role).is_object()) {
      for (const auto& [key, value] : points[0].at(role).items()) keys.push_back(key);
    }
    crs_columns[k] = crs_input_columns(*crs, keys, source_name + ": points[0]." + role, where);
    if (!crs_columns[k]->has_height()) {
      fail(source_name + ": points[0]." + role,
           crs_columns[k]->names[0] + ", " + crs_columns[k]->names[1] +
               " but no height: a control point needs its height (h_<unit>, or H_<unit> with a compound CRS)");
    }
    detail::adopt_crs(set, k == 0, *crs_columns[k], where);
  }
}

// How each point's frames are read: the file, the options, each frame's CRS
// columns (when it is in a CRS), and the conversion to ECEF.
struct PointContext {
  const std::string& source_name;
  const ControlReadOptions& o;
  const std::optional<CrsColumns> (&crs_columns)[2];
  const detail::RoleConverter& converter;
  bool has_a_priori_sigmas;
};

// The forms of the first point; a set whose points use several forms is
// recorded as ECEF (as_read then holds the ECEF positions).
struct RoleForms {
  std::optional<CoordinateKind> src_kind, dst_kind;
  bool mixed_src = false, mixed_dst = false;
  // Each frame's height type, from its first geodetic point: one frame's
  // heights are all ellipsoidal or all orthometric.
  std::optional<bool> src_orthometric, dst_orthometric;
  std::string src_height_where, dst_height_where;
};

// One point's source and target: each frame's values to ECEF (with its
// covariance), as read kept in as_read.
void read_roles(const PointContext& c, const json& jp, const std::string& where, RoleForms& forms, geodesy::ControlPoint& p) {
  auto& src_kind = forms.src_kind;
  auto& dst_kind = forms.dst_kind;
  bool& mixed_src = forms.mixed_src;
  bool& mixed_dst = forms.mixed_dst;
  auto& src_orthometric = forms.src_orthometric;
  auto& dst_orthometric = forms.dst_orthometric;
  std::string& src_height_where = forms.src_height_where;
  std::string& dst_height_where = forms.dst_height_where;
  for (const char* role : {"src", "dst"}) {
    const bool src_role = std::string(role) == "src";
    const auto& in_crs = c.crs_columns[src_role ? 0 : 1];
    const detail::RoleValues v = in_crs ? crs_role_values(jp, role, where, *in_crs)
                                        : role_values(jp, role, where, src_role ? c.o.src_geoid : c.o.dst_geoid);
    if (v.kind == CoordinateKind::geodetic) {
      auto& ortho = src_role ? src_orthometric : dst_orthometric;
      auto& first = src_role ? src_height_where : dst_height_where;
      const std::string here = where + "." + (src_role ? "source" : "target") + (v.orthometric ? ".H_m" : ".h_m");
      if (!ortho) {
        ortho = v.orthometric;
        first = here.substr(c.source_name.size() + 2);  // the path alone, without "c.json: "
      } else if (*ortho != v.orthometric) {
        fail(here, std::string(v.orthometric ? "an orthometric" : "an ellipsoidal") + " height, but " + first + " is " +
                       (*ortho ? "orthometric" : "ellipsoidal") + "; one frame's heights are of one type");
      }
    }
    const std::string frame = std::string(role) == "src" ? "source" : "target";
    const auto on_fail = [&](detail::RoleField f, const std::string& message) {
      const char* field = f == detail::RoleField::sigma ? (std::string(role) == "src" ? "sigma_src_m" : "sigma_dst_m")
                          : f == detail::RoleField::covariance ? (std::string(role) == "src" ? "cov_src_m2" : "cov_dst_m2")
                                                               : nullptr;
      fail(where + "." + (field ? std::string(field) : frame), message);
    };
    const bool src = std::string(role) == "src";
    auto& kind = src ? src_kind : dst_kind;
    if (!kind) kind = v.kind;
    (src ? mixed_src : mixed_dst) |= *kind != v.kind;
    Eigen::Vector3d& as_read = src ? p.source_as_read : p.target_as_read;
    as_read = Eigen::Vector3d(v.a, v.b, v.c);
    if (src) {
      as_read.z() += c.converter.convert(v, c.has_a_priori_sigmas, on_fail, p.source, p.source_cov_m2);
    } else {
      as_read.z() += c.converter.convert(v, c.has_a_priori_sigmas, on_fail, p.target, p.target_cov_m2);
    }
  }
}

// A point's epoch, use and GNSS solution type.
void read_point_details(const json& jp, const std::string& where, geodesy::ControlPoint& p) {
  if (jp.contains("epoch")) {
    p.epoch = geodesy::parse_decimal_year(format_shortest(number_at(jp, "epoch", where)), where + ".epoch");
  }
  if (jp.contains("use")) {
    if (!jp.at("use").is_boolean()) fail(where + ".use", "expected true or false");
    p.use = jp.at("use").get<bool>();
  }
  // The GNSS solution type: every point states it or none does (a point
  // without it would be of unknown quality, used as if it were fixed).
  if (jp.contains("solution")) {
    const json& sv = jp.at("solution");
    if (sv.is_string()) p.solution = geodesy::parse_gnss_solution(sv.get<std::string>());
    if (!p.solution) {
      fail(where + ".solution", "value " + sv.dump() + " is not a GNSS solution type; expected one of " +
                                    geodesy::gnss_solution_names() + " (lower case)");
    }
  }
}

}  // namespace

geodesy::ControlSet read_control_json(std::istream& in, const std::string& source_name, const ControlReadOptions& o) {
  std::ostringstream text;
  text << in.rdbuf();
  const json doc = parse_json_strict<json>(text.str(), source_name);
  if (!doc.is_object()) fail(source_name, "expected a JSON object with \"points\"");
  static const char* const kKeys[] = {"points", "source_frame", "target_frame", "source_crs", "target_crs", "description"};
  if (const auto key = detail::first_unknown_key(doc, kKeys)) {
    fail(source_name + ": " + *key, "unknown key; expected points, source_frame, target_frame, source_crs, target_crs, description");
  }
  // Free text for people; typed so that a misplaced value is not kept as one.
  if (doc.contains("description") && !doc.at("description").is_string()) {
    fail(source_name + ": description", "value " + doc.at("description").dump() + " is not a string");
  }
  geodesy::ControlSet set;
  set.source_name = source_name;
  std::string source_frame_where, target_frame_where;
  read_frames(doc, source_name, set, source_frame_where, target_frame_where);
  if (!doc.contains("points") || !doc.at("points").is_array()) fail(source_name + ": points", "missing; expected an array");
  const json& points = doc.at("points");
  set.has_a_priori_sigmas = false;
  for (const auto& p : points) {
    for (const char* k : {"sigma_src_m", "sigma_dst_m", "cov_src_m2", "cov_dst_m2"}) {
      if (p.is_object() && p.contains(k)) set.has_a_priori_sigmas = true;
    }
  }
  const std::set<std::string> known = {"id", "source", "target", "sigma_src_m", "sigma_dst_m", "cov_src_m2", "cov_dst_m2", "epoch", "use",
                                       "solution"};
  std::optional<CrsColumns> crs_columns[2];
  read_crs_columns(doc, points, o, source_name, set, crs_columns);
  detail::apply_caller_frames(set, o);
  // Which frames have values on an ellipsoid (any point's not x_m/y_m/z_m).
  bool uses_ellipsoid[2] = {false, false};
  bool enu[2] = {false, false};
  for (const auto& p : points) {
    for (int k = 0; k < 2; ++k) {
      const char* role = k == 0 ? "source" : "target";
      if (!p.is_object() || !p.contains(role) || !p.at(role).is_object()) continue;
      uses_ellipsoid[k] = uses_ellipsoid[k] || (!crs_columns[k] && !p.at(role).contains("x_m"));
      enu[k] = enu[k] || p.at(role).contains("e_m");
    }
  }
  detail::resolve_ellipsoids(set, o, uses_ellipsoid);
  const detail::RoleConverter converter(o, set);
  set.origin = o.origin;
  if (set.origin) set.origin->ellipsoid = enu[0] || !enu[1] ? set.source_input.ellipsoid : set.target_input.ellipsoid;
  RoleForms forms;
  const PointContext context{source_name, o, crs_columns, converter, set.has_a_priori_sigmas};
  for (std::size_t i = 0; i < points.size(); ++i) {
    const std::string where = source_name + ": points[" + std::to_string(i) + "]";
    const json& jp = points[i];
    if (!jp.is_object()) fail(where, "expected an object");
    if (const auto key = detail::first_unknown_key(jp, known)) {
      fail(where + "." + *key, "unknown key; expected id, source, target, sigma_src_m, sigma_dst_m (isotropic, metres), "
                               "cov_src_m2, cov_dst_m2 (3×3, m²), epoch, use, solution");
    }
    geodesy::ControlPoint p;
    if (!jp.contains("id") || !jp.at("id").is_string() || jp.at("id").get<std::string>().empty()) {
      fail(where + ".id", "missing or empty; expected a string");
    }
    p.id = jp.at("id").get<std::string>();
    p.line = i;
    read_roles(context, jp, where, forms, p);
    read_point_details(jp, where, p);
    if (i > 0 && p.solution.has_value() != set.points.front().solution.has_value()) {
      const std::size_t without = p.solution ? 0 : i;
      fail(source_name + ": points[" + std::to_string(without) + "].solution",
           "missing, but points[" + std::to_string(without == 0 ? i : 0) +
               "] states one; give every point's GNSS solution type or none");
    }
    set.points.push_back(std::move(p));
  }
  set.has_solutions = !set.points.empty() && set.points.front().solution.has_value();
  detail::refuse_duplicate_ids(
      set, [&](const geodesy::ControlPoint& q) { return source_name + ": points[" + std::to_string(q.line) + "]"; },
      [&](const geodesy::ControlPoint& q) { return "points[" + std::to_string(q.line) + "]"; });
  const geodesy::Ellipsoid src_ellipsoid = set.source_input.ellipsoid, dst_ellipsoid = set.target_input.ellipsoid;
  set.source_input = detail::input_form(forms.mixed_src || !forms.src_kind ? CoordinateKind::ecef : *forms.src_kind, std::nullopt,
                                        forms.src_orthometric.value_or(false) ? "H_m" : "", o.src_geoid);
  set.target_input = detail::input_form(forms.mixed_dst || !forms.dst_kind ? CoordinateKind::ecef : *forms.dst_kind, std::nullopt,
                                        forms.dst_orthometric.value_or(false) ? "H_m" : "", o.dst_geoid);
  set.source_input.ellipsoid = src_ellipsoid;
  set.target_input.ellipsoid = dst_ellipsoid;
  for (std::size_t k = 0; k < 2; ++k) {
    if (!crs_columns[k]) continue;
    detail::adopt_crs(set, k == 0, *crs_columns[k], kCrsFlags[k]);
    const std::string cov_key = k == 0 ? "cov_src_m2" : "cov_dst_m2";
    detail::positions_from_crs(
        set, k == 0, *crs_columns[k], kCrsFlags[k], [&](std::size_t i) { return points[set.points[i].line].contains(cov_key); },
        [&](const geodesy::ControlPoint& q) { return source_name + ": points[" + std::to_string(q.line) + "]"; });
  }
  for (auto& p : set.points) {
    if (forms.mixed_src) p.source_as_read = p.source.m;
    if (forms.mixed_dst) p.target_as_read = p.target.m;
  }
  detail::check_physical_positions(
      set, [&](const geodesy::ControlPoint& q) { return source_name + ": points[" + std::to_string(q.line) + "]"; });
  detail::check_frame_epochs(set, o, source_frame_where, target_frame_where);
  return set;
}

geodesy::ControlSet read_control_set(const std::filesystem::path& path, const ControlReadOptions& o) {
  // Read a megabyte at a time, not the stream's 8 KB (10⁶ marks: 96 MB,
  // 12 000 reads on the thread that hands lines to the parsers).
  std::vector<char> buffer(std::size_t{1} << 20);
  std::ifstream in;
  in.rdbuf()->pubsetbuf(buffer.data(), static_cast<std::streamsize>(buffer.size()));
  in.open(path, std::ios::binary);
  if (!in) throw Error(ErrorKind::io, "E_READ", path.string() + ": cannot open control set: " + std::strerror(errno));
  // JSON when the first non-blank character opens an object; CSV otherwise.
  char c = 0;
  while (in.get(c) && std::isspace(static_cast<unsigned char>(c))) {
  }
  in.clear();
  in.seekg(0);
  return c == '{' ? read_control_json(in, path.string(), o) : read_control_csv(in, path.string(), o);
}

}  // namespace geoanchor::io
