#include "geoanchor/io/control_csv.hpp"

#include <Eigen/Cholesky>

#include <array>
#include <cmath>
#include <cstring>
#include <fstream>
#include <map>

#include "geoanchor/geodesy/error.hpp"
#include "geoanchor/geodesy/geocentric.hpp"
#include "geoanchor/geodesy/local_frame.hpp"
#include "geoanchor/geodesy/number_text.hpp"
#include "geoanchor/io/coordinate_codec.hpp"
#include "geoanchor/io/coordinate_columns.hpp"
#include "geoanchor/io/csv.hpp"

namespace geoanchor::io {
namespace {

using geodesy::ControlPoint;
using geodesy::ControlSet;

constexpr std::array<const char*, 6> kCovComponents = {"xx", "xy", "xz", "yy", "yz", "zz"};

std::optional<std::size_t> find_column(const std::vector<std::string>& header, const std::string& name) {
  for (std::size_t i = 0; i < header.size(); ++i) {
    if (header[i] == name) return i;
  }
  return std::nullopt;
}

// Columns of one role (src or dst): its coordinates and its uncertainty.
struct RoleColumns {
  std::string role;
  CoordinateColumns coords;
  std::optional<std::size_t> sigma;
  std::array<std::optional<std::size_t>, 6> cov;
  bool has_cov = false;
};

RoleColumns role_columns(const std::vector<std::string>& header, const std::string& source, const std::string& role) {
  // Classify with only this role's coordinate columns visible, so that the
  // other role's columns do not read as a mix of kinds.
  std::vector<std::string> visible;
  std::vector<std::size_t> index;
  for (std::size_t i = 0; i < header.size(); ++i) {
    const std::string& n = header[i];
    const bool other_role = n.find(role == "src" ? "_dst_" : "_src_") != std::string::npos;
    const bool shared = n == "id" || n == "epoch" || n == "use" || n.rfind("sigma_", 0) == 0 || n.rfind("cov_", 0) == 0 ||
                        n.rfind("vx_", 0) == 0 || n.rfind("vy_", 0) == 0 || n.rfind("vz_", 0) == 0;
    if (!other_role && !shared) {
      visible.push_back(n);
      index.push_back(i);
    }
  }
  RoleColumns rc;
  rc.role = role;
  CoordinateColumns c = classify_coordinate_header(visible, source, role);
  if (c.kind == CoordinateKind::ned || c.kind == CoordinateKind::projected) {
    throw Error(ErrorKind::input, "E_COLUMN",
                source + ": " + role + " coordinates: control sets take ECEF (x_" + role + "_m...), geodetic (lat_" +
                    role + "_deg...) or ENU (e_" + role + "_m...) columns");
  }
  if (c.kind == CoordinateKind::geodetic && !c.third) {
    throw Error(ErrorKind::input, "E_COLUMN_MISSING",
                source + ": header has lat_" + role + "_deg,lon_" + role + "_deg but no h_" + role +
                    "_m; a control point needs its ellipsoidal height");
  }
  c.first = index[c.first];
  c.second = index[c.second];
  c.third = index[*c.third];
  c.epoch.reset();
  rc.coords = c;
  rc.sigma = find_column(header, "sigma_" + role + "_m");
  for (std::size_t k = 0; k < 6; ++k) {
    rc.cov[k] = find_column(header, std::string("cov_") + role + "_" + kCovComponents[k] + "_m2");
    rc.has_cov = rc.has_cov || rc.cov[k].has_value();
  }
  if (rc.has_cov) {
    for (std::size_t k = 0; k < 6; ++k) {
      if (!rc.cov[k]) {
        throw Error(ErrorKind::input, "E_COLUMN_MISSING",
                    source + ": header has covariance columns for " + role + " but no cov_" + role + "_" +
                        kCovComponents[k] + "_m2; expected all six of xx, xy, xz, yy, yz, zz");
      }
    }
    if (rc.sigma) {
      throw Error(ErrorKind::input, "E_COLUMN",
                  source + ": both sigma_" + role + "_m and cov_" + role + "_.._m2 columns; give one");
    }
  }
  return rc;
}

class RowReader {
 public:
  RowReader(const std::vector<std::string>& header, std::string source) : header_(header), source_(std::move(source)) {}

  double number(const CsvRecord& r, std::size_t col) const {
    const std::string& text = r.values[col];
    const auto v = parse_finite_double(text);
    if (!v) {
      std::string why = text.empty() ? "empty field; expected a number" : "not a finite number";
      if (text.find(',') != std::string::npos) why += " (decimal comma? use '.')";
      throw Error(ErrorKind::input, "E_VALUE",
                  source_ + ":" + std::to_string(r.line) + ": " + header_[col] + "='" + text + "': " + why);
    }
    return *v;
  }

  [[noreturn]] void fail(const CsvRecord& r, std::size_t col, const std::string& what) const {
    throw Error(ErrorKind::input, "E_VALUE",
                source_ + ":" + std::to_string(r.line) + ": " + header_[col] + "=" + r.values[col] + ": " + what);
  }

 private:
  const std::vector<std::string>& header_;
  std::string source_;
};

}  // namespace

ControlSet read_control_csv(std::istream& in, const std::string& source_name, const ControlReadOptions& o) {
  CsvReader reader(in, source_name);
  const auto& header = reader.header();
  const auto id_col = find_column(header, "id");
  if (!id_col) {
    throw Error(ErrorKind::input, "E_COLUMN_MISSING", source_name + ": no 'id' column; every control point needs an id");
  }
  const RoleColumns src = role_columns(header, source_name, "src");
  const RoleColumns dst = role_columns(header, source_name, "dst");
  const auto epoch_col = find_column(header, "epoch");
  const auto use_col = find_column(header, "use");
  const RowReader rows(header, source_name);

  std::optional<geodesy::LocalTangentPlane> plane;
  if (src.coords.kind == CoordinateKind::enu || dst.coords.kind == CoordinateKind::enu) {
    if (!o.origin) {
      throw Error(ErrorKind::usage, "E_ORIGIN_MISSING",
                  source_name + ": ENU control coordinates need their nominal origin: give --origin LAT,LON,H");
    }
    plane.emplace(*o.origin);
  }
  const geodesy::GeocentricConverter geocentric(o.ellipsoid);

  ControlSet set;
  set.source_name = source_name;
  // Frames may be declared in leading comments: "# source_frame = ITRF2014@2024.5".
  for (std::size_t i = 0; i < reader.leading_comments().size(); ++i) {
    const std::string& c = reader.leading_comments()[i];
    for (const char* key : {"source_frame", "target_frame"}) {
      const auto at = c.find(key);
      if (at == std::string::npos) continue;
      const auto eq = c.find('=', at);
      if (eq == std::string::npos) continue;
      auto frame = geodesy::Frame::parse(c.substr(eq + 1), source_name + ": comment '" + c + "'");
      (std::string_view(key) == "source_frame" ? set.source_frame : set.target_frame) = std::move(frame);
    }
  }
  set.has_a_priori_sigmas = src.sigma || src.has_cov || dst.sigma || dst.has_cov;

  // ECEF position and covariance of one role in one row.
  auto read_role = [&](const CsvRecord& r, const RoleColumns& rc, Eigen::Matrix3d& cov) {
    const double a = rows.number(r, rc.coords.first), b = rows.number(r, rc.coords.second),
                 c = rows.number(r, *rc.coords.third);
    Eigen::Matrix3d local_to_ecef = Eigen::Matrix3d::Identity();  // axes of the covariance columns -> ECEF
    geodesy::EcefPosition p;
    switch (rc.coords.kind) {
      case CoordinateKind::ecef: p = geodesy::EcefPosition(a, b, c); break;
      case CoordinateKind::geodetic: {
        if (std::fabs(a) > 90.0) rows.fail(r, rc.coords.first, "latitude not in [-90, 90] degrees");
        if (std::fabs(b) > 180.0) rows.fail(r, rc.coords.second, "longitude not in [-180, 180] degrees");
        const geodesy::GeodeticPosition g{geodesy::Angle::degrees(a), geodesy::Angle::degrees(b), geodesy::EllipsoidalHeight{c}};
        p = geocentric.ecef_from_geodetic(g);
        local_to_ecef = geodesy::LocalTangentPlane(geodesy::LocalOrigin{g, o.ellipsoid}).enu_from_ecef_rotation().transpose();
        break;
      }
      case CoordinateKind::enu:
        p = plane->ecef_from_enu(geodesy::EnuPosition{Eigen::Vector3d(a, b, c), *o.origin});
        local_to_ecef = plane->enu_from_ecef_rotation().transpose();
        break;
      default: break;
    }
    Eigen::Matrix3d local = Eigen::Matrix3d::Identity();  // unit weight when no sigma is given
    if (rc.sigma) {
      const double s = rows.number(r, *rc.sigma);
      if (!(s > 0.0)) rows.fail(r, *rc.sigma, "must be > 0 (a standard deviation in metres)");
      local = Eigen::Matrix3d::Identity() * s * s;
    } else if (rc.has_cov) {
      std::array<double, 6> v{};
      for (std::size_t k = 0; k < 6; ++k) v[k] = rows.number(r, *rc.cov[k]);
      local << v[0], v[1], v[2], v[1], v[3], v[4], v[2], v[4], v[5];
      if (Eigen::LLT<Eigen::Matrix3d>(local).info() != Eigen::Success || !(local.diagonal().minCoeff() > 0.0)) {
        rows.fail(r, *rc.cov[0], "covariance of " + rc.role + " is not positive definite");
      }
    } else if (set.has_a_priori_sigmas) {
      local.setZero();  // the other frame carries the uncertainty
    }
    cov = local_to_ecef * local * local_to_ecef.transpose();
    return p;
  };

  std::map<std::pair<std::string, double>, std::size_t> seen;  // (id, epoch) -> index
  CsvRecord r;
  while (reader.next(r)) {
    if (r.is_comment) continue;
    ControlPoint p;
    p.id = r.values[*id_col];
    p.line = r.line;
    if (p.id.empty()) rows.fail(r, *id_col, "empty id");
    p.source = read_role(r, src, p.source_cov_m2);
    p.target = read_role(r, dst, p.target_cov_m2);
    if (epoch_col && !r.values[*epoch_col].empty()) {
      p.epoch = geodesy::parse_decimal_year(r.values[*epoch_col], source_name + ":" + std::to_string(r.line) + ": epoch");
    }
    if (use_col) {
      const std::string& u = r.values[*use_col];
      if (u == "1" || u == "true" || u == "yes") {
        p.use = true;
      } else if (u == "0" || u == "false" || u == "no") {
        p.use = false;
      } else {
        rows.fail(r, *use_col, "expected 1/0, true/false or yes/no");
      }
    }
    const auto key = std::make_pair(p.id, p.epoch ? p.epoch->year : -1.0);
    if (const auto it = seen.find(key); it != seen.end()) {
      const ControlPoint& first = set.points[it->second];
      const double d = std::max((first.source.m - p.source.m).norm(), (first.target.m - p.target.m).norm());
      throw Error(ErrorKind::input, "E_DUPLICATE_ID",
                  source_name + ":" + std::to_string(r.line) + ": id=" + p.id + ": duplicate of line " +
                      std::to_string(first.line) + (p.epoch ? " at the same epoch" : "") +
                      " (coordinates differ by " + format_shortest(d) + " m); ids must be unique per epoch");
    }
    seen.emplace(key, set.points.size());
    set.points.push_back(std::move(p));
  }
  return set;
}

ControlSet read_control_csv(const std::filesystem::path& path, const ControlReadOptions& o) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error(ErrorKind::io, "E_READ", path.string() + ": cannot open control set: " + std::strerror(errno));
  return read_control_csv(in, path.string(), o);
}

}  // namespace geoanchor::io
