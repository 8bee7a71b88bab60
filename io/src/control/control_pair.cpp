// A control set from two files, one frame each, joined by id
// (read_control_pair, control_csv.hpp): a site's map or legacy coordinates
// in one, and in the other the stations `geoanchor adjust` wrote.

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <cstring>
#include <fstream>
#include <memory>
#include <optional>
#include <string>
#include <unordered_map>
#include <vector>

#include "geoanchor/base/error.hpp"
#include "geoanchor/geodesy/geocentric.hpp"
#include "geoanchor/geodesy/local_frame.hpp"
#include "geoanchor/base/number_text.hpp"
#include "geoanchor/io/control/control_csv.hpp"
#include "geoanchor/io/control/coordinate_columns.hpp"
#include "geoanchor/io/control/crs_columns.hpp"
#include "geoanchor/io/control/crs_csv.hpp"
#include "geoanchor/io/csv.hpp"
#include "control/control_common.hpp"

namespace geoanchor::io {
namespace {

using geodesy::ControlPoint;
using geodesy::ControlSet;

// x_m, y_m, z_m beside lat_deg, lon_deg, h_m (a stations file writes both):
// they must be the same point to within the rounding of the two forms
// (11 decimals of a degree, 5 of a metre: a few micrometres).
constexpr double kEcefBesideGeodeticToleranceM = 1e-4;

constexpr std::array<const char*, 6> kCovComponents = {"xx", "xy", "xz", "yy", "yz", "zz"};
constexpr std::array<const char*, 3> kEnuSigmas = {"sigma_e_m", "sigma_n_m", "sigma_u_m"};
constexpr std::array<const char*, 3> kEnuCorrelations = {"corr_en", "corr_eu", "corr_nu"};
// Columns of a stations file that are derived from the ones read (the
// error ellipses) or describe the adjustment (the constraint, read only to
// allow a held component's zero sigma).
constexpr std::array<const char*, 5> kDerivedColumns = {"ellipse_a_m", "ellipse_b_m", "ellipse_azimuth_deg", "ellipse_conf_a_m",
                                                        "ellipse_conf_b_m"};

std::optional<std::size_t> find_column(const std::vector<std::string>& header, const std::string& name) {
  for (std::size_t i = 0; i < header.size(); ++i) {
    if (header[i] == name) return i;
  }
  return std::nullopt;
}

// One frame's file: its header, what each column is, and what its comments say.
struct RoleFile {
  std::string name;      // the path, for messages
  std::string role;      // "src" | "dst"
  bool source = true;
  std::unique_ptr<std::ifstream> stream;
  std::unique_ptr<CsvReader> reader;
  CoordinateColumns coords;
  std::optional<CrsColumns> crs;
  std::optional<std::size_t> id, use, sigma, constraint, solution;
  std::array<std::optional<std::size_t>, 6> cov;
  std::array<std::optional<std::size_t>, 3> enu_sigma, enu_corr;
  std::array<std::optional<std::size_t>, 3> ecef_beside;  // x_m, y_m, z_m beside geodetic coordinates
  bool has_cov = false, has_enu_sigma = false;
  std::optional<geodesy::Frame> frame;
  std::string frame_where;
  std::optional<std::string> stated_ellipsoid;
  std::string ellipsoid_where;
  bool has_sigmas() const { return sigma || has_cov || has_enu_sigma; }
};

// One row of a role file, converted.
struct RoleRow {
  std::size_t line = 0;
  geodesy::EcefPosition position;
  Eigen::Matrix3d cov_m2 = Eigen::Matrix3d::Zero();
  Eigen::Vector3d as_read = Eigen::Vector3d::Zero();
  bool use = true;
  std::optional<geodesy::GnssSolution> solution;
};

[[noreturn]] void refuse_column(const RoleFile& f, std::size_t i, const std::string& why) {
  throw Error(ErrorKind::input, "E_COLUMN",
              f.name + ": header column " + std::to_string(i + 1) + " '" + f.reader->header()[i] + "': " + why);
}

// The comments above the header: "# frame = NAME@EPOCH", "# ellipsoid = NAME",
// "# crs = CRS"; the two-role keys of a control set are refused here, and so
// is a local network's stations file (its axes are on no frame).
std::optional<Crs> read_role_comments(RoleFile& f, const std::optional<Crs>& flag_crs, const std::string& flag) {
  for (const auto& c : f.reader->leading_comments()) {
    const std::string where =
        f.name + ": comment '" + c + "' (above the header on line " + std::to_string(f.reader->header_line()) + ")";
    for (const char* two_role : {"source_frame", "target_frame", "source_crs", "target_crs"}) {
      if (comment_value(c, two_role)) {
        throw Error(ErrorKind::input, "E_COMMENT",
                    where + ": a file of one frame's coordinates (--src/--dst) names its frame as '# frame = NAME@EPOCH' "
                    "or its CRS as '# crs = CRS'; " + two_role + " belongs to a control set with both frames' columns");
      }
    }
    if (c.rfind("# local network:", 0) == 0) {
      throw Error(ErrorKind::input, "E_FRAME_MISSING",
                  where + ": the stations of a local network are on the network's own axes, not on a frame of the Earth: "
                  "fit needs each frame's coordinates on the Earth");
    }
    if (const auto v = comment_value(c, "frame")) {
      if (f.frame) throw Error(ErrorKind::input, "E_COMMENT", where + ": a second '# frame =' comment; give one");
      f.frame = geodesy::Frame::parse(*v, where);
      f.frame_where = where;
    } else if (const auto e = comment_value(c, "ellipsoid")) {
      if (f.stated_ellipsoid) throw Error(ErrorKind::input, "E_COMMENT", where + ": a second '# ellipsoid =' comment; give one");
      f.stated_ellipsoid = *e;
      f.ellipsoid_where = where;
    }
  }
  // "# crs = …" with its "# coordinate_epoch = …", as convert writes them.
  const std::optional<Crs> stated = crs_from_comments(f.reader->leading_comments(), f.name);
  if (flag_crs && stated && !flag_crs->same_as(*stated)) {
    throw Error(ErrorKind::input, "E_CRS_CONFLICT",
                flag + " " + flag_crs->display_name() + " contradicts " + f.name + "'s '# crs =' (" + stated->display_name() +
                    "); drop the flag or fix the file");
  }
  return flag_crs ? flag_crs : stated;
}

// What each column of a role file is. Every column is read, derived from
// the ones read (a stations file's ellipses), or an attribute that says
// nothing about coordinates; anything else is refused by name.
void classify_role_columns(RoleFile& f, const std::optional<Crs>& crs, const std::string& flag) {
  const auto& header = f.reader->header();
  f.id = find_column(header, "id");
  if (!f.id) throw Error(ErrorKind::input, "E_COLUMN_MISSING", f.name + ": no 'id' column; the two files are joined by id");
  f.use = find_column(header, "use");
  f.constraint = find_column(header, "constraint");
  f.solution = find_column(header, "solution");
  for (std::size_t i = 0; i < header.size(); ++i) {
    const std::string& n = header[i];
    if (n.find("_src") != std::string::npos || n.find("_dst") != std::string::npos) {
      refuse_column(f, i, "a file of one frame's coordinates names no role: its columns are x_m, lat_deg, e_m, easting_m, "
                          "sigma_m, cov_xx_m2 … (--src and --dst say which frame it is)");
    }
    if (n == "epoch") {
      refuse_column(f, i, "a per-point epoch relates both coordinates of a mark and belongs to a control set with both "
                          "frames' columns; here each frame states its epoch ('# frame = NAME@EPOCH')");
    }
    if (n.rfind("vx_", 0) == 0 || n.rfind("vy_", 0) == 0 || n.rfind("vz_", 0) == 0 || n.rfind("sigma_v_", 0) == 0) {
      refuse_column(f, i, "velocities observe a transform's rates and are read from a control set with both frames' "
                          "columns (vx_src_m_per_year …)");
    }
  }
  // Both x,y,z and lat,lon,h (a stations file): the geodetic ones are read,
  // with the covariance in their east, north, up; x,y,z are checked against them.
  std::vector<std::string> visible = header;
  const bool geodetic_too = find_column(header, "lat_deg").has_value();
  for (std::size_t k = 0; k < 3; ++k) {
    const char* axis[3] = {"x_m", "y_m", "z_m"};
    if (const auto at = find_column(header, axis[k]); at && geodetic_too && !crs) {
      f.ecef_beside[k] = at;
      visible[*at] = std::string("beside_") + axis[k];  // hidden from the classification below
    }
  }
  if (f.ecef_beside[0] || f.ecef_beside[1] || f.ecef_beside[2]) {
    if (!(f.ecef_beside[0] && f.ecef_beside[1] && f.ecef_beside[2])) {
      throw Error(ErrorKind::input, "E_COLUMN_MISSING", f.name + ": x_m, y_m, z_m beside lat_deg, lon_deg, h_m must be all three");
    }
  }
  if (crs) {
    f.crs = crs_input_columns(*crs, visible, f.name, flag);
    if (!f.crs->has_height()) {
      throw Error(ErrorKind::input, "E_COLUMN_MISSING",
                  f.name + ": " + f.crs->names[0] + ", " + f.crs->names[1] + " but no height: a control point needs its height");
    }
    const auto at = column_indices(*f.crs, visible);
    f.coords.kind = CoordinateKind::ecef;  // three numbers, to ECEF through PROJ once read
    f.coords.first = at[0];
    f.coords.second = at[1];
    f.coords.third = at[2];
  } else {
    f.coords = classify_coordinate_header(visible, f.name);
    if (f.coords.kind == CoordinateKind::ned) {
      throw Error(ErrorKind::input, "E_COLUMN", f.name + ": control coordinates are ECEF (x_m…), geodetic (lat_deg…), ENU (e_m…) or projected (easting_m…)");
    }
    if (f.coords.utm_zone) refuse_column(f, *f.coords.utm_zone, "give the grid with --" + f.role + "-zone");
    if (!f.coords.third) {
      throw Error(ErrorKind::input, "E_COLUMN_MISSING", f.name + ": no height column (h_m, or H_m with --geoid): a control point needs its height");
    }
  }
  f.sigma = find_column(header, "sigma_m");
  for (std::size_t k = 0; k < 6; ++k) {
    f.cov[k] = find_column(header, std::string("cov_") + kCovComponents[k] + "_m2");
    f.has_cov = f.has_cov || f.cov[k].has_value();
  }
  for (std::size_t k = 0; k < 3; ++k) {
    f.enu_sigma[k] = find_column(header, kEnuSigmas[k]);
    f.enu_corr[k] = find_column(header, kEnuCorrelations[k]);
    f.has_enu_sigma = f.has_enu_sigma || f.enu_sigma[k].has_value();
  }
  if (f.has_cov && !std::all_of(f.cov.begin(), f.cov.end(), [](const auto& c) { return c.has_value(); })) {
    throw Error(ErrorKind::input, "E_COLUMN_MISSING",
                f.name + ": a covariance needs all six of cov_xx_m2, cov_xy_m2, cov_xz_m2, cov_yy_m2, cov_yz_m2, cov_zz_m2");
  }
  if (f.has_enu_sigma && !(f.enu_sigma[0] && f.enu_sigma[1] && f.enu_sigma[2])) {
    throw Error(ErrorKind::input, "E_COLUMN_MISSING", f.name + ": sigma_e_m, sigma_n_m, sigma_u_m must be all three");
  }
  const bool some_corr = f.enu_corr[0] || f.enu_corr[1] || f.enu_corr[2];
  if (some_corr && !(f.enu_corr[0] && f.enu_corr[1] && f.enu_corr[2] && f.has_enu_sigma)) {
    throw Error(ErrorKind::input, "E_COLUMN_MISSING",
                f.name + ": corr_en, corr_eu, corr_nu are read all three, with sigma_e_m, sigma_n_m, sigma_u_m");
  }
  if (int(f.sigma.has_value()) + int(f.has_cov) + int(f.has_enu_sigma) > 1) {
    throw Error(ErrorKind::input, "E_COLUMN", f.name + ": give one of sigma_m, the cov_.._m2 columns, or sigma_e_m/sigma_n_m/sigma_u_m");
  }
  if (f.crs && (f.has_cov || f.has_enu_sigma)) {
    throw Error(ErrorKind::input, "E_COLUMN", f.name + ": coordinates in a CRS take sigma_m (isotropic) only");
  }
  if (f.has_enu_sigma && f.coords.kind != CoordinateKind::geodetic && f.coords.kind != CoordinateKind::enu) {
    throw Error(ErrorKind::input, "E_COLUMN",
                f.name + ": sigma_e_m, sigma_n_m, sigma_u_m are along the local east, north, up: with lat_deg, lon_deg, h_m "
                         "or e_m, n_m, u_m coordinates only (use the cov_.._m2 columns in the coordinates' axes)");
  }
  // Every remaining column: an attribute, unless it speaks of coordinates or their uncertainty.
  std::vector<bool> read(header.size(), false);
  auto mark = [&](std::optional<std::size_t> c) {
    if (c) read[*c] = true;
  };
  for (auto c : {f.id, f.use, f.sigma, f.constraint, f.solution, std::optional<std::size_t>(f.coords.first),
                 std::optional<std::size_t>(f.coords.second), f.coords.third}) {
    mark(c);
  }
  for (const auto& c : f.cov) mark(c);
  for (const auto& c : f.enu_sigma) mark(c);
  for (const auto& c : f.enu_corr) mark(c);
  for (const auto& c : f.ecef_beside) mark(c);
  for (std::size_t i = 0; i < header.size(); ++i) {
    if (read[i]) continue;
    const std::string& n = header[i];
    const auto first = find_column(header, n);
    if (first && *first != i) refuse_column(f, i, "appears twice in the header (also column " + std::to_string(*first + 1) + ")");
    if (std::find(kDerivedColumns.begin(), kDerivedColumns.end(), n) != kDerivedColumns.end()) {
      if (!f.has_enu_sigma) refuse_column(f, i, "an error ellipse is read only beside the sigma_e_m, sigma_n_m, sigma_u_m it is derived from");
      continue;  // derived from sigma_e_m, sigma_n_m, corr_en: nothing more to read
    }
    {
      std::string lower = n;
      for (char& ch : lower) ch = static_cast<char>(std::tolower(static_cast<unsigned char>(ch)));
      if (lower.find("solution") != std::string::npos) {
        refuse_column(f, i, "not read: a mark's GNSS solution type is read from the column 'solution' (" +
                                geodesy::gnss_solution_names() + ")");
      }
    }
    if (n.rfind("sigma", 0) == 0 || n.rfind("cov", 0) == 0 || n.rfind("corr", 0) == 0 || is_coordinate_column_name(n)) {
      refuse_column(f, i, "not read: a frame's uncertainty is read from sigma_m (isotropic, metres), cov_xx_m2 … cov_zz_m2 "
                          "(in the coordinates' axes) or sigma_e_m, sigma_n_m, sigma_u_m with corr_en, corr_eu, corr_nu; "
                          "its coordinates from the columns of convert (x_m…, lat_deg…, e_m…, easting_m…)");
    }
  }
}

RoleFile open_role_file(const std::filesystem::path& path, const std::string& role, const std::optional<Crs>& flag_crs) {
  RoleFile f;
  f.name = path.string();
  f.role = role;
  f.source = role == "src";
  f.stream = std::make_unique<std::ifstream>(path, std::ios::binary);
  if (!*f.stream) throw Error(ErrorKind::io, "E_READ", f.name + ": cannot open control coordinates: " + std::strerror(errno));
  char c = 0;
  while (f.stream->get(c) && std::isspace(static_cast<unsigned char>(c))) {
  }
  if (c == '{') {
    throw Error(ErrorKind::input, "E_FORMAT",
                f.name + ": JSON; one frame's coordinates (--src/--dst) are read from CSV (a JSON control set holds both frames: "
                         "give it as CONTROL)");
  }
  f.stream->clear();
  f.stream->seekg(0);
  f.reader = std::make_unique<CsvReader>(*f.stream, f.name);
  const std::string flag = f.source ? "--src-crs" : "--dst-crs";
  const std::optional<Crs> crs = read_role_comments(f, flag_crs, flag);
  classify_role_columns(f, crs, flag);
  return f;
}

// The rows of `f`, converted, by id (refusing a repeated id).
std::unordered_map<std::string, RoleRow> read_role_rows(RoleFile& f, const detail::RoleConverter& converter,
                                                        const geodesy::ControlInputForm& form, bool set_has_sigmas,
                                                        const std::optional<geodesy::LocalOrigin>& origin,
                                                        std::vector<std::string>& order) {
  std::unordered_map<std::string, RoleRow> rows;
  const auto& header = f.reader->header();
  CsvRecord r;
  while (f.reader->next(r)) {
    if (r.is_comment) continue;
    const auto fail_at = [&](std::size_t col, const std::string& what) -> void {
      throw Error(ErrorKind::input, "E_VALUE",
                  f.name + ":" + std::to_string(r.line) + ": " + header[col] + "='" + r.values[col] + "': " + what);
    };
    const auto number = [&](std::size_t col) { return number_cell(r, col, header, f.name); };
    const std::string& id = r.values[*f.id];
    if (id.empty()) fail_at(*f.id, "empty id");
    RoleRow row;
    row.line = r.line;
    detail::RoleValues v;
    v.kind = f.coords.kind;
    v.source = f.source;
    v.orthometric = f.coords.orthometric;
    v.a = number(f.coords.first);
    v.b = number(f.coords.second);
    v.c = number(*f.coords.third);
    if (f.sigma) v.sigma_m = number(*f.sigma);
    if (f.has_cov) {
      std::array<double, 6> c{};
      for (std::size_t k = 0; k < 6; ++k) c[k] = number(*f.cov[k]);
      v.cov_m2 = c;
    }
    const auto fail = [&](detail::RoleField field, const std::string& message) {
      const std::size_t col = field == detail::RoleField::first    ? f.coords.first
                              : field == detail::RoleField::second ? f.coords.second
                              : field == detail::RoleField::third  ? *f.coords.third
                              : field == detail::RoleField::sigma  ? *f.sigma
                                                                   : *f.cov[0];
      fail_at(col, message);
    };
    row.as_read = Eigen::Vector3d(v.a, v.b, v.c);
    // ENU sigmas are carried below: the converter sees the role as one without sigmas.
    row.as_read.z() += converter.convert(v, set_has_sigmas, fail, row.position, row.cov_m2);
    if (f.has_enu_sigma) {
      std::array<double, 3> s{};
      const std::string held = f.constraint ? r.values[*f.constraint] : std::string();
      if (f.constraint && !(held.size() == 3 && std::all_of(held.begin(), held.end(), [](char ch) { return ch == 'C' || ch == 'F'; }))) {
        fail_at(*f.constraint, "expected three letters C (held) or F (free): latitude, longitude, height");
      }
      // Held components: constraint letters are latitude, longitude, height (north, east, up).
      const std::array<std::size_t, 3> letter_of = {1, 0, 2};
      for (std::size_t k = 0; k < 3; ++k) {
        s[k] = number(*f.enu_sigma[k]);
        const bool is_held = held.size() == 3 && held[letter_of[k]] == 'C';
        if (!(s[k] > 0.0) && !(s[k] == 0.0 && is_held)) {
          fail_at(*f.enu_sigma[k], is_held ? "must be >= 0 (a standard deviation in metres)"
                                           : "must be > 0 (a standard deviation in metres; 0 only for a component the "
                                             "constraint column holds, C)");
        }
      }
      std::array<double, 3> rho{};
      for (std::size_t k = 0; k < 3; ++k) {
        if (!f.enu_corr[k]) continue;
        rho[k] = number(*f.enu_corr[k]);
        if (!(std::fabs(rho[k]) <= 1.0)) fail_at(*f.enu_corr[k], "a correlation must lie in [-1, 1]");
      }
      Eigen::Matrix3d local;
      local << s[0] * s[0], rho[0] * s[0] * s[1], rho[1] * s[0] * s[2],  //
          rho[0] * s[0] * s[1], s[1] * s[1], rho[2] * s[1] * s[2],       //
          rho[1] * s[0] * s[2], rho[2] * s[1] * s[2], s[2] * s[2];
      if (!local.allFinite()) fail_at(*f.enu_sigma[0], "sigma_e_m, sigma_n_m, sigma_u_m give no finite covariance");
      // Positive semi-definite (zeros only where held), to the rounding of six decimals of a correlation.
      const double smallest = Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(local, Eigen::EigenvaluesOnly).eigenvalues()(0);
      if (!(smallest >= -1e-6 * local.diagonal().maxCoeff())) {
        fail_at(f.enu_corr[0] ? *f.enu_corr[0] : *f.enu_sigma[0], "sigmas and correlations make no covariance (smallest eigenvalue " +
                                    format_shortest(smallest) + " m²)");
      }
      Eigen::Matrix3d enu_from_ecef;
      if (f.coords.kind == CoordinateKind::geodetic) {
        enu_from_ecef = geodesy::enu_from_ecef_rotation(geodesy::Angle::degrees(v.a), geodesy::Angle::degrees(v.b));
      } else {  // ENU at the nominal origin: its axes
        enu_from_ecef = geodesy::enu_from_ecef_rotation(origin->point.lat, origin->point.lon);
      }
      row.cov_m2 = enu_from_ecef.transpose() * local * enu_from_ecef;
    }
    if (f.ecef_beside[0]) {
      const Eigen::Vector3d beside(number(*f.ecef_beside[0]), number(*f.ecef_beside[1]), number(*f.ecef_beside[2]));
      const double apart = (beside - row.position.m).norm();
      if (!(apart <= kEcefBesideGeodeticToleranceM)) {
        fail_at(*f.ecef_beside[0], "x_m, y_m, z_m are " + format_shortest(apart) +
                                       " m from lat_deg, lon_deg, h_m on " + form.ellipsoid.name() +
                                       ": the row holds two different points (expected within " +
                                       format_shortest(kEcefBesideGeodeticToleranceM) + " m)");
      }
    }
    if (f.use) {
      const std::string& u = r.values[*f.use];
      if (u == "1" || u == "true" || u == "yes") {
        row.use = true;
      } else if (u == "0" || u == "false" || u == "no") {
        row.use = false;
      } else {
        fail_at(*f.use, "expected 1/0, true/false or yes/no");
      }
    }
    if (f.solution) {
      const std::string& cell = r.values[*f.solution];
      row.solution = geodesy::parse_gnss_solution(cell);
      if (!row.solution) {
        fail_at(*f.solution, std::string(cell.empty() ? "empty" : "not a GNSS solution type") + "; expected one of " +
                                 geodesy::gnss_solution_names() + " (lower case)");
      }
    }
    const auto [at, inserted] = rows.emplace(id, row);
    if (!inserted) {
      throw Error(ErrorKind::input, "E_DUPLICATE_ID",
                  f.name + ":" + std::to_string(r.line) + ": id '" + id + "' is also on line " + std::to_string(at->second.line) +
                      " (the two are " + format_shortest((row.position.m - at->second.position.m).norm()) +
                      " m apart); each mark once");
    }
    order.push_back(id);
  }
  return rows;
}

// Each file's '# ellipsoid =': the ellipsoid its coordinates are read on
// when its frame implies none, and held to the one they are read on.
void read_stated_ellipsoids(const RoleFile (&files)[2], ControlSet& set, const ControlReadOptions& o) {
  // A file on a frame that implies no ellipsoid (outside the catalog) is
  // read on the one its '# ellipsoid =' states, unless --ellipsoid says.
  for (const RoleFile& f : files) {
    const std::optional<geodesy::Frame>& frame = f.source ? set.source_frame : set.target_frame;
    if (!f.stated_ellipsoid || f.crs || o.ellipsoid || (frame && geodesy::implied_ellipsoid(*frame))) continue;
    std::string name = *f.stated_ellipsoid;
    std::transform(name.begin(), name.end(), name.begin(), [](unsigned char ch) { return static_cast<char>(std::toupper(ch)); });
    geodesy::ControlInputForm& form = f.source ? set.source_input : set.target_input;
    // (GRS80 and WGS84 in any case, as before; the other EPSG names as written.)
    const auto named = geodesy::named_ellipsoid(name == "GRS80" || name == "WGS84" ? name : *f.stated_ellipsoid);
    if (!named) {
      throw Error(ErrorKind::input, "E_ELLIPSOID",
                  f.ellipsoid_where + ": '" + *f.stated_ellipsoid + "': expected one of " + geodesy::named_ellipsoid_list());
    }
    form.ellipsoid = *named;
    if (form.projection) form.projection->ellipsoid = form.ellipsoid;
  }
  for (const RoleFile& f : files) {
    const geodesy::ControlInputForm& form = f.source ? set.source_input : set.target_input;
    if (f.stated_ellipsoid && !f.crs) {
      std::string stated = *f.stated_ellipsoid, resolved = form.ellipsoid.name();
      for (auto* s : {&stated, &resolved}) {
        std::transform(s->begin(), s->end(), s->begin(), [](unsigned char ch) { return static_cast<char>(std::toupper(ch)); });
      }
      if (stated != resolved) {
        throw Error(ErrorKind::input, "E_ELLIPSOID",
                    f.ellipsoid_where + ": the file's coordinates are on " + *f.stated_ellipsoid + ", but they would be read on " +
                        form.ellipsoid.name() + (o.ellipsoid ? " (--ellipsoid)" : " (the frame's, or the other file's)") +
                        "; drop --ellipsoid or correct the frame");
      }
    }
  }
}

// The marks in both files, in the source file's order; the others are named
// (`only` receives the ids of each file that the other lacks).
void join_marks(const RoleFile (&files)[2], const std::unordered_map<std::string, RoleRow> (&rows)[2],
                const std::vector<std::string> (&order)[2], ControlSet& set, std::vector<std::string> (&only)[2]) {
  for (const auto& id : order[0]) {
    const auto t = rows[1].find(id);
    if (t == rows[1].end()) {
      only[0].push_back(id);
      continue;
    }
    const RoleRow& s = rows[0].at(id);
    ControlPoint& p = set.points.emplace_back();
    p.id = id;
    p.line = s.line;
    p.source = s.position;
    p.source_cov_m2 = s.cov_m2;
    p.source_as_read = s.as_read;
    p.target = t->second.position;
    p.target_cov_m2 = t->second.cov_m2;
    p.target_as_read = t->second.as_read;
    p.use = s.use && t->second.use;
    // The solution type of either file; both must say the same.
    p.solution = s.solution ? s.solution : t->second.solution;
    if (s.solution && t->second.solution && *s.solution != *t->second.solution) {
      throw Error(ErrorKind::input, "E_VALUE",
                  files[0].name + ":" + std::to_string(s.line) + ": solution=" + std::string(geodesy::to_string(*s.solution)) +
                      " for " + id + " but " + files[1].name + ":" + std::to_string(t->second.line) + " says " +
                      std::string(geodesy::to_string(*t->second.solution)) + "; one mark has one GNSS solution type");
    }
  }
}

void check_joined_sigmas(const RoleFile (&files)[2], const std::unordered_map<std::string, RoleRow> (&rows)[2],
                         const ControlSet& set) {
  // Each joined mark's two covariances together must weigh it: a station
  // held by the adjustment (zero sigma) needs the other file's sigma.
  for (const ControlPoint& p : set.points) {
    const Eigen::Matrix3d both = p.source_cov_m2 + p.target_cov_m2;
    const double smallest = Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(both, Eigen::EigenvaluesOnly).eigenvalues()(0);
    if (!(smallest > 1e-12 * std::max(both.trace(), 1e-300))) {
      throw Error(ErrorKind::input, "E_SIGMA",
                  p.id + " (" + files[0].name + ":" + std::to_string(p.line) + ", " + files[1].name + ":" +
                      std::to_string(rows[1].at(p.id).line) + "): the two files' covariances together leave a direction "
                      "without uncertainty (smallest eigenvalue " + format_shortest(smallest) +
                      " m²): a held station's zero sigma needs a sigma in the other file");
    }
  }
}

}  // namespace

ControlSet read_control_pair(const std::filesystem::path& source, const std::filesystem::path& target,
                             const ControlReadOptions& o, bool unmatched_source_allowed, std::vector<std::string>* notes) {
  RoleFile files[2] = {open_role_file(source, "src", o.src_crs), open_role_file(target, "dst", o.dst_crs)};
  ControlSet set;
  set.source_name = files[0].name + " + " + files[1].name;
  for (RoleFile& f : files) {
    if (f.coords.kind == CoordinateKind::projected && !(f.source ? o.src_projection : o.dst_projection)) {
      throw Error(ErrorKind::usage, "E_GRID_MISSING",
                  f.name + ": easting_m, northing_m need their grid: --" + f.role + "-zone ZONE or --" + f.role + "-tm LAT0,LON0,K0,FE,FN");
    }
    if (f.coords.orthometric && !(f.source ? o.src_geoid : o.dst_geoid)) {
      detail::refuse_orthometric_without_geoid(f.name + ": column '" + f.reader->header()[*f.coords.third] + "'");
    }
    (f.source ? set.source_frame : set.target_frame) = f.frame;
    (f.source ? set.source_input : set.target_input) =
        detail::input_form(f.coords.kind, f.source ? o.src_projection : o.dst_projection,
                           f.coords.orthometric ? f.reader->header()[*f.coords.third] : std::string(),
                           f.source ? o.src_geoid : o.dst_geoid);
  }
  if ((files[0].coords.kind == CoordinateKind::enu || files[1].coords.kind == CoordinateKind::enu) && !o.origin) {
    throw Error(ErrorKind::usage, "E_ORIGIN_MISSING", "ENU control coordinates (e_m, n_m, u_m) need their nominal origin: give --origin LAT,LON,H");
  }
  set.has_a_priori_sigmas = files[0].has_sigmas() || files[1].has_sigmas();
  for (RoleFile& f : files) {
    if (f.crs) detail::adopt_crs(set, f.source, *f.crs, f.source ? "--src-crs" : "--dst-crs");
  }
  detail::apply_caller_frames(set, o);
  const auto uses = [](const RoleFile& f) {
    return !f.crs && (f.coords.kind == CoordinateKind::geodetic || f.coords.kind == CoordinateKind::projected ||
                      f.coords.kind == CoordinateKind::enu);
  };
  const bool uses_ellipsoid[2] = {uses(files[0]), uses(files[1])};
  detail::resolve_ellipsoids(set, o, uses_ellipsoid);
  read_stated_ellipsoids(files, set, o);
  set.origin = o.origin;
  if (set.origin) {
    set.origin->ellipsoid = files[0].coords.kind == CoordinateKind::enu || files[1].coords.kind != CoordinateKind::enu
                                ? set.source_input.ellipsoid
                                : set.target_input.ellipsoid;
  }
  const detail::RoleConverter converter(o, set);
  std::vector<std::string> order[2];
  std::unordered_map<std::string, RoleRow> rows[2];
  for (std::size_t k = 0; k < 2; ++k) {
    rows[k] = read_role_rows(files[k], converter, k == 0 ? set.source_input : set.target_input, set.has_a_priori_sigmas, set.origin, order[k]);
  }
  std::vector<std::string> only[2];
  join_marks(files, rows, order, set, only);
  set.has_solutions = files[0].solution.has_value() || files[1].solution.has_value();
  for (const auto& id : order[1]) {
    if (!rows[0].count(id)) only[1].push_back(id);
  }
  if (set.points.empty()) {
    throw Error(ErrorKind::input, "E_NO_COMMON_MARKS",
                files[0].name + " and " + files[1].name + " have no id in common (" + std::to_string(order[0].size()) +
                    " and " + std::to_string(order[1].size()) + " marks): the two files are joined by id");
  }
  auto listed = [](const std::vector<std::string>& ids) {
    std::string list;
    for (std::size_t i = 0; i < ids.size() && i < 10; ++i) list += (i ? ", " : "") + ids[i];
    if (ids.size() > 10) list += ", … (" + std::to_string(ids.size()) + " in all)";
    return list;
  };
  // Every source mark is control: one the target lacks is a typo or a
  // missing station (RELIABILITY 8), unless the caller allows it. The
  // target may hold more (the other stations of an adjusted network).
  if (!only[0].empty() && !unmatched_source_allowed) {
    throw Error(ErrorKind::input, "E_UNMATCHED_ID",
                files[0].name + ": " + std::to_string(only[0].size()) + " mark(s) have no counterpart in " + files[1].name +
                    ": " + listed(only[0]) + "; correct the ids, or give --allow-unmatched to fit without them");
  }
  if (notes) {
    for (std::size_t k = 0; k < 2; ++k) {
      if (only[k].empty()) continue;
      notes->push_back(std::to_string(only[k].size()) + " mark(s) of " + files[k].name + " are not in " + files[1 - k].name +
                       " and are not part of the control: " + listed(only[k]));
    }
  }
  if (set.has_a_priori_sigmas) check_joined_sigmas(files, rows, set);
  for (const RoleFile& f : files) {
    if (!f.crs) continue;
    const auto& rows_of = rows[f.source ? 0 : 1];
    detail::positions_from_crs(
        set, f.source, *f.crs, f.source ? "--src-crs" : "--dst-crs", [](std::size_t) { return false; },
        [&](const ControlPoint& q) { return f.name + ":" + std::to_string(rows_of.at(q.id).line); });
  }
  detail::check_physical_positions(set, [&](const ControlPoint& q) {
    return files[0].name + ":" + std::to_string(rows[0].at(q.id).line) + " / " + files[1].name + ":" +
           std::to_string(rows[1].at(q.id).line);
  });
  detail::check_frame_epochs(set, o, files[0].frame_where, files[1].frame_where);
  return set;
}

}  // namespace geoanchor::io
