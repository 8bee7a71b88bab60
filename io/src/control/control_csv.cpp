#include "geoanchor/io/control/control_csv.hpp"

#include <Eigen/Cholesky>

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <cstring>
#include <exception>
#include <fstream>
#include <future>
#include <map>
#include <memory>
#include <optional>
#include <thread>
#include <vector>

#include "geoanchor/base/error.hpp"
#include "geoanchor/geodesy/geocentric.hpp"
#include "geoanchor/geodesy/local_frame.hpp"
#include "geoanchor/base/number_text.hpp"
#include "geoanchor/io/control/coordinate_codec.hpp"
#include "geoanchor/io/control/coordinate_columns.hpp"
#include "geoanchor/io/control/crs_columns.hpp"
#include "geoanchor/io/control/crs_csv.hpp"
#include "geoanchor/crs/crs_operation.hpp"
#include "geoanchor/io/csv.hpp"
#include "control/control_common.hpp"

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

[[noreturn]] void refuse_orthometric(const std::string& source, const std::string& column) {
  detail::refuse_orthometric_without_geoid(source + ": column '" + column + "'");
}

// Columns of one role (src or dst): its coordinates and its uncertainty.
struct RoleColumns {
  std::string role;
  CoordinateColumns coords;
  std::optional<CrsColumns> crs;  // a frame in a CRS read through PROJ: its columns, in visualisation order
  std::optional<std::size_t> sigma;
  std::array<std::optional<std::size_t>, 6> cov;
  bool has_cov = false;
};

// The header with only one role's coordinate columns visible, so that the
// other role's columns do not read as a mix of kinds; `index` maps back.
std::vector<std::string> visible_for_role(const std::vector<std::string>& header, const std::string& role,
                                          std::vector<std::size_t>& index) {
  std::vector<std::string> visible;
  index.clear();
  for (std::size_t i = 0; i < header.size(); ++i) {
    const std::string& n = header[i];
    const bool other_role = n.find(role == "src" ? "_dst_" : "_src_") != std::string::npos;
    const bool shared = n == "id" || n == "epoch" || n == "use" || n == "solution" || n.rfind("sigma_", 0) == 0 || n.rfind("cov_", 0) == 0 ||
                        n.rfind("vx_", 0) == 0 || n.rfind("vy_", 0) == 0 || n.rfind("vz_", 0) == 0;
    if (!other_role && !shared) {
      visible.push_back(n);
      index.push_back(i);
    }
  }
  return visible;
}

// The sigma and covariance columns of a role, checked for completeness.
void uncertainty_columns(const std::vector<std::string>& header, const std::string& source, RoleColumns& rc);

// A role whose coordinates are in a CRS read through PROJ: the CRS's
// columns with the role before the unit, and an isotropic sigma.
RoleColumns crs_role_columns(const std::vector<std::string>& header, const std::string& source, const std::string& role,
                             const Crs& crs, const std::string& flag) {
  std::vector<std::size_t> index;
  const std::vector<std::string> visible = visible_for_role(header, role, index);
  RoleColumns rc;
  rc.role = role;
  rc.crs = crs_input_columns(crs, visible, source, flag, role);
  if (!rc.crs->has_height()) {
    throw Error(ErrorKind::input, "E_COLUMN_MISSING",
                source + ": " + rc.crs->names[0] + ", " + rc.crs->names[1] + " but no height: a control point needs its "
                "height (h_" + role + "_<unit> ellipsoidal, or H_" + role + "_<unit> with a compound CRS)");
  }
  const auto at = column_indices(*rc.crs, visible);
  rc.coords.kind = CoordinateKind::ecef;  // read as three numbers; PROJ makes them ECEF after the rows are read
  rc.coords.first = index[at[0]];
  rc.coords.second = index[at[1]];
  rc.coords.third = index[at[2]];
  // Covariance columns are in the CRS's axes, in m² (positions_from_crs).
  uncertainty_columns(header, source, rc);
  return rc;
}

RoleColumns role_columns(const std::vector<std::string>& header, const std::string& source, const std::string& role,
                         bool has_grid, bool has_geoid) {
  std::vector<std::size_t> index;
  const std::vector<std::string> visible = visible_for_role(header, role, index);
  RoleColumns rc;
  rc.role = role;
  CoordinateColumns c = classify_coordinate_header(visible, source, role);
  if (c.kind == CoordinateKind::ned) {
    throw Error(ErrorKind::input, "E_COLUMN",
                source + ": " + role + " coordinates: control sets take ECEF (x_" + role + "_m...), geodetic (lat_" +
                    role + "_deg...), ENU (e_" + role + "_m...) or projected (easting_" + role + "_m...) columns");
  }
  if (c.kind == CoordinateKind::projected && !has_grid) {
    throw Error(ErrorKind::usage, "E_GRID_MISSING",
                source + ": easting_" + role + "_m,northing_" + role + "_m need their grid: a UTM zone or a Transverse "
                    "Mercator (fit and diagnose take --" + role + "-zone ZONE, e.g. 32N, or --" + role +
                    "-tm LAT0,LON0,K0,FE,FN)");
  }
  if (c.utm_zone) {
    throw Error(ErrorKind::input, "E_COLUMN",
                source + ": a utm_zone column in a control set; give the grid of each frame with --" + role + "-zone");
  }
  if ((c.kind == CoordinateKind::geodetic || c.kind == CoordinateKind::projected) && !c.third) {
    throw Error(ErrorKind::input, "E_COLUMN_MISSING",
                source + ": header has " + (c.kind == CoordinateKind::geodetic ? "lat_" + role + "_deg,lon_" + role + "_deg"
                                                                                : "easting_" + role + "_m,northing_" + role + "_m") +
                    " but no h_" + role + "_m; a control point needs its ellipsoidal height");
  }
  if (c.orthometric && !has_geoid) refuse_orthometric(source, visible[*c.third]);
  c.first = index[c.first];
  c.second = index[c.second];
  c.third = index[*c.third];
  c.epoch.reset();
  rc.coords = c;
  uncertainty_columns(header, source, rc);
  return rc;
}

void uncertainty_columns(const std::vector<std::string>& header, const std::string& source, RoleColumns& rc) {
  const std::string& role = rc.role;
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
}

// Every column name a control set reads, for the nearest-name hint.
std::vector<std::string> readable_names() {
  std::vector<std::string> out = {"id", "epoch", "use", "solution"};
  for (const char* role : {"src", "dst"}) {
    for (const auto kind : {CoordinateKind::ecef, CoordinateKind::geodetic, CoordinateKind::enu, CoordinateKind::projected}) {
      for (const auto& n : coordinate_column_names(kind, role)) {
        if (std::find(out.begin(), out.end(), n) == out.end()) out.push_back(n);
      }
    }
    out.push_back(std::string("sigma_") + role + "_m");
    for (const char* c : kCovComponents) out.push_back(std::string("cov_") + role + "_" + c + "_m2");
    for (const char* v : {"vx_", "vy_", "vz_"}) out.push_back(v + std::string(role) + "_m_per_year");
    out.push_back(std::string("sigma_v_") + role + "_m_per_year");
    out.push_back(std::string("H_") + role + "_m");  // orthometric heights: the coordinate reader's to judge
  }
  return out;
}

std::size_t edit_distance(const std::string& a, const std::string& b) {
  std::vector<std::size_t> row(b.size() + 1);
  for (std::size_t j = 0; j <= b.size(); ++j) row[j] = j;
  for (std::size_t i = 1; i <= a.size(); ++i) {
    std::size_t diagonal = row[0];
    row[0] = i;
    for (std::size_t j = 1; j <= b.size(); ++j) {
      const std::size_t up = row[j];
      row[j] = std::min({row[j] + 1, row[j - 1] + 1, diagonal + (a[i - 1] == b[j - 1] ? 0 : 1)});
      diagonal = up;
    }
  }
  return row[b.size()];
}

// Why a column the control set does not read cannot pass through as an
// attribute: it looks like one of geoanchor's own (a sigma, covariance,
// velocity or coordinate of a frame), so a typo or another unit would be
// dropped silently. nullopt for an attribute column (`kind`, `note`).
std::optional<std::string> unread_column_problem(const std::string& name, bool velocities) {
  auto starts = [&](const char* prefix) { return name.rfind(prefix, 0) == 0; };
  const bool roled = name.find("_src") != std::string::npos || name.find("_dst") != std::string::npos;
  std::string what;
  if (starts("sigma_v_")) {
    what = velocities || (name != "sigma_v_src_m_per_year" && name != "sigma_v_dst_m_per_year")
               ? "velocity sigmas are read from sigma_v_src_m_per_year and sigma_v_dst_m_per_year (metres per year)"
               : "a velocity sigma is read only with the velocities vx_src_m_per_year, vy_src_m_per_year, "
                 "vz_src_m_per_year (and the same with dst)";
  } else if (starts("sigma_")) {
    what = "a priori sigmas are read from sigma_src_m and sigma_dst_m (isotropic, in metres) or the cov_ columns";
  } else if (starts("cov_")) {
    what = "covariances are read from cov_src_xx_m2, cov_src_xy_m2, cov_src_xz_m2, cov_src_yy_m2, cov_src_yz_m2, "
           "cov_src_zz_m2 (m², in the axes of the coordinates; and the same with dst)";
  } else if (starts("vx_") || starts("vy_") || starts("vz_")) {
    what = "velocities are read from vx_src_m_per_year, vy_src_m_per_year, vz_src_m_per_year (ECEF, metres per year; "
           "and the same with dst)";
  } else if (roled) {
    what = "a frame's coordinates are read from x_src_m,y_src_m,z_src_m | lat_src_deg,lon_src_deg,h_src_m | "
           "e_src_m,n_src_m,u_src_m | easting_src_m,northing_src_m,h_src_m (and the same with dst; lengths in metres, "
           "angles in degrees); a column naming src or dst that is none of them is not an attribute";
  } else {
    for (const auto kind : {CoordinateKind::ecef, CoordinateKind::geodetic, CoordinateKind::enu, CoordinateKind::ned,
                            CoordinateKind::projected}) {
      const auto names = coordinate_column_names(kind);
      if (std::find(names.begin(), names.end(), name) != names.end() || name == "H_m") {
        const auto under = name.find('_');
        const std::string stem = name.substr(0, under), unit = name.substr(under + 1);
        what = "a control set names each coordinate's frame: " + stem + "_src_" + unit + " or " + stem + "_dst_" + unit;
      }
    }
    // A misspelt or other-cased solution column would pass as an attribute
    // and leave every mark's solution unread (float marks used as fixed).
    std::string lower = name;
    for (char& ch : lower) ch = static_cast<char>(std::tolower(static_cast<unsigned char>(ch)));
    if (what.empty() && name != "solution" &&
        (lower.find("solution") != std::string::npos || edit_distance(lower, "solution") <= 2)) {
      what = "a mark's GNSS solution type is read from the column 'solution' (" + geodesy::gnss_solution_names() + ")";
    }
    if (what.empty()) return std::nullopt;
  }
  // The nearest name geoanchor reads, when the column is likely a typo of it.
  std::string nearest;
  std::size_t best = 3;
  for (const auto& n : readable_names()) {
    const std::size_t d = edit_distance(name, n);
    if (d < best) {
      best = d;
      nearest = n;
    }
  }
  return "not read: " + what + (nearest.empty() ? "" : " (did you mean " + nearest + "?)");
}

class RowReader {
 public:
  RowReader(const std::vector<std::string>& header, std::string source) : header_(header), source_(std::move(source)) {}

  double number(const CsvRecord& r, std::size_t col) const { return number_cell(r, col, header_, source_); }

  [[noreturn]] void fail(const CsvRecord& r, std::size_t col, const std::string& what) const {
    throw Error(ErrorKind::input, "E_VALUE",
                source_ + ":" + std::to_string(r.line) + ": " + header_[col] + "=" + r.values[col] + ": " + what);
  }

 private:
  const std::vector<std::string>& header_;
  std::string source_;
};

// The data rows of `reader` as marks, in file order: lines are read (and
// checked as UTF-8) on this thread, a batch at a time, while the previous
// batch is split, parsed and converted on every core (10⁶ marks: 0.65–0.75 s
// on two cores). The error reported is the one a row-by-row read meets
// first: the earliest line's.
template <class PointOf>
void read_rows_in_parallel(CsvReader& reader, std::vector<ControlPoint>& points, const PointOf& point_of) {
  constexpr std::size_t kBatch = 8192;  // lines
  const std::size_t tasks = std::clamp<std::size_t>(std::thread::hardware_concurrency(), 1, 8);
  struct Batch {
    std::vector<std::string> text;
    std::vector<std::size_t> line;
    std::size_t size = 0;
    std::exception_ptr read_error;  // met after `size` lines were read
  };
  const auto read_batch = [&](Batch& b) {
    b.size = 0;
    b.read_error = nullptr;
    b.text.resize(kBatch);
    b.line.resize(kBatch);
    try {
      while (b.size < kBatch && reader.next_line(b.text[b.size], b.line[b.size])) ++b.size;
    } catch (...) {
      b.read_error = std::current_exception();
    }
  };
  // Parses lines [first, last) of `b` into `out` (comments leave no mark);
  // the first failure is kept, not thrown, so that an earlier range's wins.
  struct Part {
    std::vector<ControlPoint> marks;
    std::exception_ptr error;
  };
  const auto parse_part = [&](const Batch& b, std::size_t first, std::size_t last, Part& out) {
    out.marks.clear();
    out.error = nullptr;
    CsvRecord r;
    try {
      for (std::size_t i = first; i < last; ++i) {
        reader.parse(b.text[i], b.line[i], r, false);  // the values only
        if (r.is_comment) continue;
        point_of(r, out.marks.emplace_back());
      }
    } catch (...) {
      out.error = std::current_exception();
    }
  };
  // Two batches and their parts: one is parsed while the other is read and
  // its marks moved into `points` (a task refers to its batch by address,
  // so neither is ever swapped).
  std::array<Batch, 2> batches;
  std::array<std::vector<Part>, 2> parts{std::vector<Part>(tasks), std::vector<Part>(tasks)};
  const auto launch = [&](std::size_t i) {
    std::vector<std::future<void>> running;
    const Batch& b = batches[i];
    const std::size_t per = (b.size + tasks - 1) / tasks;
    for (std::size_t k = 0; k < tasks; ++k) {
      Part& part = parts[i][k];
      const std::size_t first = std::min(b.size, k * per), last = std::min(b.size, first + per);
      part.marks.clear();
      part.error = nullptr;
      if (first == last) continue;
      if (tasks == 1) {
        parse_part(b, first, last, part);
      } else {
        running.push_back(std::async(std::launch::async, [&, first, last] { parse_part(b, first, last, part); }));
      }
    }
    return running;
  };
  std::size_t cur = 0;
  read_batch(batches[cur]);
  std::vector<std::future<void>> running = launch(cur);
  while (true) {
    const Batch& b = batches[cur];
    // The next lines are read while this batch is parsed (unless this one
    // ended the input).
    const bool more = b.size == kBatch && !b.read_error;
    if (more) read_batch(batches[1 - cur]);
    for (auto& r : running) r.get();
    running.clear();
    for (const auto& part : parts[cur]) {
      if (part.error) std::rethrow_exception(part.error);
    }
    if (b.read_error) std::rethrow_exception(b.read_error);
    // The next batch is parsed while this one's marks are moved.
    if (more) running = launch(1 - cur);
    for (auto& part : parts[cur]) {
      for (auto& m : part.marks) points.push_back(std::move(m));
    }
    if (!more) return;
    cur = 1 - cur;
  }
}

const char* const kCrsFlags[2] = {"--src-crs", "--dst-crs"};

// Each frame's CRS: the option, or the file's "# source_crs = …" comment;
// both must say the same.
void read_crs_comments(const CsvReader& reader, const std::string& source_name, std::optional<Crs> (&crs_of)[2]) {
  const char* crs_keys[2] = {"source_crs", "target_crs"};
  for (std::size_t k = 0; k < 2; ++k) {
    for (const auto& c : reader.leading_comments()) {
      const auto text = comment_value(c, crs_keys[k]);
      if (!text) continue;
      const std::string where = source_name + ": comment '# " + crs_keys[k] + " = …'";
      const Crs stated = Crs::parse(*text, where);
      if (crs_of[k] && !crs_of[k]->same_as(stated)) {
        throw Error(ErrorKind::input, "E_CRS_CONFLICT",
                    std::string(kCrsFlags[k]) + " " + crs_of[k]->display_name() + " contradicts " + where + " (" +
                        stated.display_name() + "); drop the flag or fix the file");
      }
      if (!crs_of[k]) crs_of[k] = stated;
    }
  }
}

void refuse_unreadable_columns(const std::vector<std::string>& header, const std::string& source_name,
                               const std::optional<RoleColumns> (&crs_roles)[2]) {
  auto readable = readable_names();
  for (const auto& rc : crs_roles) {
    if (rc) readable.insert(readable.end(), rc->crs->names.begin(), rc->crs->names.end());
  }
  for (std::size_t i = 0; i < header.size(); ++i) {
    if (std::find(readable.begin(), readable.end(), header[i]) != readable.end()) continue;
    if (const auto problem = unread_column_problem(header[i], false)) {
      throw Error(ErrorKind::input, "E_COLUMN",
                  source_name + ": header column " + std::to_string(i + 1) + " '" + header[i] + "': " + *problem);
    }
  }
}

// Velocities: ECEF components per frame, with a required isotropic sigma.
struct VelocityColumns {
  std::array<std::optional<std::size_t>, 3> v;
  std::optional<std::size_t> sigma;
};

VelocityColumns velocity_columns(const std::vector<std::string>& header, const std::string& source_name, const std::string& role) {
  VelocityColumns vc;
  const char* axes[3] = {"vx_", "vy_", "vz_"};
  int count = 0;
  for (int k = 0; k < 3; ++k) {
    vc.v[static_cast<std::size_t>(k)] = find_column(header, std::string(axes[k]) + role + "_m_per_year");
    count += vc.v[static_cast<std::size_t>(k)] ? 1 : 0;
  }
  vc.sigma = find_column(header, "sigma_v_" + role + "_m_per_year");
  if (count != 0 && count != 3) {
    throw Error(ErrorKind::input, "E_COLUMN_MISSING",
                source_name + ": velocity columns for " + role + " incomplete; expected vx_" + role + "_m_per_year, vy_" +
                    role + "_m_per_year, vz_" + role + "_m_per_year (ECEF)");
  }
  if (count == 3 && !vc.sigma) {
    throw Error(ErrorKind::input, "E_COLUMN_MISSING",
                source_name + ": velocities for " + role + " need their standard deviation: add sigma_v_" + role +
                    "_m_per_year (no default is assumed)");
  }
  return vc;
}

// The columns a control CSV is read from (the caller's, by reference).
struct CsvColumns {
  const std::optional<std::size_t>& id_col;
  const std::optional<std::size_t>& epoch_col;
  const std::optional<std::size_t>& use_col;
  const std::optional<std::size_t>& solution_col;
  const RoleColumns& src;
  const RoleColumns& dst;
  const VelocityColumns& vel_src;
  const VelocityColumns& vel_dst;
};

// Every column is read, or an attribute that passes through: a name we
// read that is not read here (given twice, or a velocity sigma without
// velocities) is refused by name too.
void refuse_unread_columns(const std::vector<std::string>& header, const std::string& source_name, const CsvColumns& columns) {
  const auto& [id_col, epoch_col, use_col, solution_col, src, dst, vel_src, vel_dst] = columns;
  std::vector<bool> read(header.size(), false);
  auto mark = [&](std::optional<std::size_t> c) {
    if (c) read[*c] = true;
  };
  mark(id_col);
  mark(epoch_col);
  mark(use_col);
  mark(solution_col);
  for (const RoleColumns* rc : {&src, &dst}) {
    mark(rc->coords.first);
    mark(rc->coords.second);
    mark(rc->coords.third);
    mark(rc->sigma);
    for (const auto& c : rc->cov) mark(c);
  }
  for (const auto* vc : {&vel_src, &vel_dst}) {
    for (const auto& c : vc->v) mark(c);
    if (vc->v[0]) mark(vc->sigma);
  }
  for (std::size_t i = 0; i < header.size(); ++i) {
    if (read[i]) continue;
    const auto first = std::find(header.begin(), header.end(), header[i]);
    if (first != header.begin() + static_cast<std::ptrdiff_t>(i) && read[static_cast<std::size_t>(first - header.begin())]) {
      throw Error(ErrorKind::input, "E_COLUMN",
                  source_name + ": header column " + std::to_string(i + 1) + " '" + header[i] +
                      "': appears twice in the header (also column " +
                      std::to_string(static_cast<std::size_t>(first - header.begin()) + 1) + "); only one would be read");
    }
    if (const auto problem = unread_column_problem(header[i], vel_src.v[0].has_value())) {
      throw Error(ErrorKind::input, "E_COLUMN",
                  source_name + ": header column " + std::to_string(i + 1) + " '" + header[i] + "': " + *problem);
    }
  }
}

// Frames may be declared in leading comments: "# source_frame = ITRF2014@2024.5".
void read_frame_comments(const CsvReader& reader, const std::string& source_name, ControlSet& set,
                         std::string& source_frame_where, std::string& target_frame_where) {
  // (Blank lines before the header are skipped, so a comment's own line is
  // not known; the header's is.)
  for (std::size_t i = 0; i < reader.leading_comments().size(); ++i) {
    const std::string& c = reader.leading_comments()[i];
    for (const char* key : {"source_frame", "target_frame"}) {
      const auto at = c.find(key);
      if (at == std::string::npos) continue;
      const auto eq = c.find('=', at);
      if (eq == std::string::npos) continue;
      const std::string where =
          source_name + ": comment '" + c + "' (above the header on line " + std::to_string(reader.header_line()) + ")";
      auto frame = geodesy::Frame::parse(c.substr(eq + 1), where);
      const bool source = std::string_view(key) == "source_frame";
      (source ? set.source_frame : set.target_frame) = std::move(frame);
      (source ? source_frame_where : target_frame_where) = where;
    }
  }
}

// Room for the rows up front when the stream can tell its size: a data
// row is about as long as the header, and growing a vector of 10⁶ points
// by doubling would touch twice their memory. (An estimate only: a
// reservation never read is never touched.)
void reserve_rows(std::istream& in, const std::vector<std::string>& header, std::vector<ControlPoint>& points) {
  if (const std::streampos here = in.tellg(); here != std::streampos(-1)) {
    in.seekg(0, std::ios::end);
    const std::streampos end = in.tellg();
    in.seekg(here);
    std::size_t header_bytes = header.size();
    for (const auto& h : header) header_bytes += h.size();
    if (in && end != std::streampos(-1) && end > here) {
      points.reserve(static_cast<std::size_t>(end - here) / std::max<std::size_t>(header_bytes, 32) + 1);
    }
    in.clear();
  }
}

// How one data row becomes a mark: on any thread, for the rows of a batch.
struct MarkOfRow {
  const CsvColumns& columns;
  const RowReader& rows;
  const detail::RoleConverter& converter;
  bool has_a_priori_sigmas;
  const std::string& source_name;

  // ECEF position and covariance of one role in one row.
  void read_role(const CsvRecord& r, const RoleColumns& rc, geodesy::EcefPosition& p, Eigen::Matrix3d& cov,
                 Eigen::Vector3d& as_read) const {
    detail::RoleValues v;
    v.kind = rc.coords.kind;
    v.source = rc.role == "src";
    v.orthometric = rc.coords.orthometric;
    v.a = rows.number(r, rc.coords.first);
    v.b = rows.number(r, rc.coords.second);
    v.c = rows.number(r, *rc.coords.third);
    if (rc.sigma) v.sigma_m = rows.number(r, *rc.sigma);
    if (rc.has_cov) {
      std::array<double, 6> c{};
      for (std::size_t k = 0; k < 6; ++k) c[k] = rows.number(r, *rc.cov[k]);
      v.cov_m2 = c;
    }
    const auto fail = [&](detail::RoleField f, const std::string& message) {
      const std::size_t col = f == detail::RoleField::first    ? rc.coords.first
                              : f == detail::RoleField::second ? rc.coords.second
                              : f == detail::RoleField::third  ? *rc.coords.third
                              : f == detail::RoleField::sigma  ? *rc.sigma
                                                               : *rc.cov[0];
      rows.fail(r, col, f == detail::RoleField::covariance ? "covariance of " + rc.role + ": " + message : message);
    };
    as_read = Eigen::Vector3d(v.a, v.b, v.c);
    as_read.z() += converter.convert(v, has_a_priori_sigmas, fail, p, cov);
  }

  // One data row's mark (the row's line number kept for messages).
  void operator()(const CsvRecord& r, ControlPoint& p) const {
    const auto& [id_col, epoch_col, use_col, solution_col, src, dst, vel_src, vel_dst] = columns;
    p.id = r.values[*id_col];
    p.line = r.line;
    if (p.id.empty()) rows.fail(r, *id_col, "empty id");
    read_role(r, src, p.source, p.source_cov_m2, p.source_as_read);
    read_role(r, dst, p.target, p.target_cov_m2, p.target_as_read);
    if (epoch_col && !r.values[*epoch_col].empty()) {
      p.epoch = geodesy::parse_decimal_year(r.values[*epoch_col], source_name + ":" + std::to_string(r.line) + ": epoch");
    }
    geodesy::MarkVelocities velocities;
    int frames_with_velocity = 0;
    for (const auto* vc : {&vel_src, &vel_dst}) {
      if (!vc->v[0] || r.values[*vc->v[0]].empty()) continue;
      const Eigen::Vector3d v(rows.number(r, *vc->v[0]), rows.number(r, *vc->v[1]), rows.number(r, *vc->v[2]));
      const double sv = rows.number(r, *vc->sigma);
      if (!(sv > 0.0)) rows.fail(r, *vc->sigma, "must be > 0 (a standard deviation in metres per year)");
      (vc == &vel_src ? velocities.source_m_per_year : velocities.target_m_per_year) = v;
      (vc == &vel_src ? velocities.source_cov : velocities.target_cov) = Eigen::Matrix3d::Identity() * sv * sv;
      ++frames_with_velocity;
    }
    if (frames_with_velocity == 1) {
      rows.fail(r, vel_src.v[0] ? *vel_src.v[0] : *vel_dst.v[0], "velocities must be given in both frames or in neither");
    }
    if (frames_with_velocity == 2) p.velocities = std::make_shared<const geodesy::MarkVelocities>(velocities);
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
    if (solution_col) {
      // A column that is there states every mark's solution: an empty cell
      // would be a mark of unknown quality used as if it were fixed.
      const std::string& v = r.values[*solution_col];
      p.solution = geodesy::parse_gnss_solution(v);
      if (!p.solution) {
        rows.fail(r, *solution_col, std::string(v.empty() ? "empty" : "not a GNSS solution type") + "; expected one of " +
                                        geodesy::gnss_solution_names() + " (lower case)");
      }
    }
  }
};

}  // namespace

ControlSet read_control_csv(std::istream& in, const std::string& source_name, const ControlReadOptions& o) {
  CsvReader reader(in, source_name);
  const auto& header = reader.header();
  const auto id_col = find_column(header, "id");
  if (!id_col) {
    throw Error(ErrorKind::input, "E_COLUMN_MISSING", source_name + ": no 'id' column; every control point needs an id");
  }
  std::optional<Crs> crs_of[2] = {o.src_crs, o.dst_crs};
  read_crs_comments(reader, source_name, crs_of);
  // A column that looks like ours but is no name we read is refused before
  // the coordinates are classified, with what is read instead.
  std::optional<RoleColumns> crs_roles[2];
  for (std::size_t k = 0; k < 2; ++k) {
    if (crs_of[k]) crs_roles[k] = crs_role_columns(header, source_name, k == 0 ? "src" : "dst", *crs_of[k], kCrsFlags[k]);
  }
  refuse_unreadable_columns(header, source_name, crs_roles);
  const RoleColumns src = crs_roles[0] ? *crs_roles[0]
                                        : role_columns(header, source_name, "src", o.src_projection.has_value(), o.src_geoid != nullptr);
  const RoleColumns dst = crs_roles[1] ? *crs_roles[1]
                                        : role_columns(header, source_name, "dst", o.dst_projection.has_value(), o.dst_geoid != nullptr);
  const auto epoch_col = find_column(header, "epoch");
  const VelocityColumns vel_src = velocity_columns(header, source_name, "src"),
                        vel_dst = velocity_columns(header, source_name, "dst");
  if (vel_src.v[0].has_value() != vel_dst.v[0].has_value()) {
    throw Error(ErrorKind::input, "E_COLUMN_MISSING",
                source_name + ": velocities are given for one frame only; give vx/vy/vz for both src and dst");
  }
  const auto use_col = find_column(header, "use");
  const auto solution_col = find_column(header, "solution");
  const RowReader rows(header, source_name);

  const CsvColumns columns{id_col, epoch_col, use_col, solution_col, src, dst, vel_src, vel_dst};
  refuse_unread_columns(header, source_name, columns);

  if ((src.coords.kind == CoordinateKind::enu || dst.coords.kind == CoordinateKind::enu) && !o.origin) {
    throw Error(ErrorKind::usage, "E_ORIGIN_MISSING",
                source_name + ": ENU control coordinates need their nominal origin: give --origin LAT,LON,H");
  }
  ControlSet set;
  set.source_name = source_name;
  std::string source_frame_where, target_frame_where;
  read_frame_comments(reader, source_name, set, source_frame_where, target_frame_where);
  set.has_a_priori_sigmas = src.sigma || src.has_cov || dst.sigma || dst.has_cov;
  set.has_solutions = solution_col.has_value();
  set.source_input = detail::input_form(src.coords.kind, o.src_projection,
                                        src.coords.orthometric ? header[*src.coords.third] : std::string(), o.src_geoid);
  set.target_input = detail::input_form(dst.coords.kind, o.dst_projection,
                                        dst.coords.orthometric ? header[*dst.coords.third] : std::string(), o.dst_geoid);
  for (const RoleColumns* rc : {&src, &dst}) {
    if (rc->crs) detail::adopt_crs(set, rc == &src, *rc->crs, kCrsFlags[rc == &src ? 0 : 1]);
  }
  detail::apply_caller_frames(set, o);
  auto uses = [](const RoleColumns& rc) {
    return !rc.crs && (rc.coords.kind == CoordinateKind::geodetic || rc.coords.kind == CoordinateKind::projected ||
                       rc.coords.kind == CoordinateKind::enu);
  };
  const bool uses_ellipsoid[2] = {uses(src), uses(dst)};
  detail::resolve_ellipsoids(set, o, uses_ellipsoid);
  const detail::RoleConverter converter(o, set);
  set.origin = o.origin;
  if (set.origin) {
    set.origin->ellipsoid = src.coords.kind == CoordinateKind::enu || dst.coords.kind != CoordinateKind::enu
                                ? set.source_input.ellipsoid
                                : set.target_input.ellipsoid;
  }

  reserve_rows(in, header, set.points);
  const MarkOfRow point_of{columns, rows, converter, set.has_a_priori_sigmas, source_name};
  read_rows_in_parallel(reader, set.points, point_of);
  // A frame in a CRS: its three numbers as read, to ECEF on its datum
  // through PROJ, a batch at a time (covariances with the conversion's Jacobian).
  for (const RoleColumns* rc : {&src, &dst}) {
    if (!rc->crs) continue;
    detail::positions_from_crs(
        set, rc == &src, *rc->crs, kCrsFlags[rc == &src ? 0 : 1], [&](std::size_t) { return rc->has_cov; },
        [&](const ControlPoint& q) { return source_name + ":" + std::to_string(q.line); });
  }
  detail::refuse_duplicate_ids(
      set, [&](const ControlPoint& q) { return source_name + ":" + std::to_string(q.line); },
      [](const ControlPoint& q) { return "line " + std::to_string(q.line); });
  detail::check_physical_positions(set, [&](const ControlPoint& q) { return source_name + ":" + std::to_string(q.line); });
  detail::check_frame_epochs(set, o, source_frame_where, target_frame_where);
  return set;
}

ControlSet read_control_csv(const std::filesystem::path& path, const ControlReadOptions& o) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error(ErrorKind::io, "E_READ", path.string() + ": cannot open control set: " + std::strerror(errno));
  return read_control_csv(in, path.string(), o);
}

}  // namespace geoanchor::io
