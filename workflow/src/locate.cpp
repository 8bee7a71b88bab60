#include "geoanchor/workflow/locate.hpp"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <set>
#include <sstream>

#include "geoanchor/base/error.hpp"
#include "geoanchor/geodesy/frame_catalog.hpp"
#include "geoanchor/geodesy/geocentric.hpp"
#include "geoanchor/geodesy/local_frame.hpp"
#include "geoanchor/base/number_text.hpp"
#include "geoanchor/geodesy/physical_range.hpp"
#include "geoanchor/io/csv.hpp"
#include "geoanchor/workflow/uncertainty.hpp"

namespace geoanchor::workflow {

namespace {

using json = nlohmann::ordered_json;

constexpr const char* kColumns[] = {"id", "e_m", "n_m", "u_m"};

struct PointRow {
  std::string id;
  std::size_t line = 0;
  Eigen::Vector3d enu;
};

std::vector<PointRow> read_points(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error(ErrorKind::io, "E_READ", path + ": cannot open");
  io::CsvReader csv(in, path);
  const auto& header = csv.header();
  int at[4] = {-1, -1, -1, -1};
  for (std::size_t c = 0; c < header.size(); ++c) {
    int k = 0;
    while (k < 4 && header[c] != kColumns[k]) ++k;
    if (k == 4) {
      throw Error(ErrorKind::input, "E_COLUMN",
                  path + ":" + std::to_string(csv.header_line()) + ": column '" + header[c] +
                      "' is not one locate reads; expected id,e_m,n_m,u_m (east, north, up in metres at the map's ENU origin)");
    }
    if (at[k] >= 0) {
      throw Error(ErrorKind::input, "E_COLUMN", path + ":" + std::to_string(csv.header_line()) + ": column '" + header[c] + "' given twice");
    }
    at[k] = static_cast<int>(c);
  }
  for (int k = 0; k < 4; ++k) {
    if (at[k] < 0) {
      throw Error(ErrorKind::input, "E_COLUMN",
                  path + ":" + std::to_string(csv.header_line()) + ": no column '" + kColumns[k] + "'; expected id,e_m,n_m,u_m");
    }
  }
  std::vector<PointRow> rows;
  std::set<std::string> ids;
  io::CsvRecord rec;
  while (csv.next(rec)) {
    if (rec.is_comment) continue;
    PointRow p;
    p.line = rec.line;
    p.id = rec.values[static_cast<std::size_t>(at[0])];
    if (p.id.empty()) throw Error(ErrorKind::input, "E_VALUE", path + ":" + std::to_string(rec.line) + ": id: empty");
    if (!ids.insert(p.id).second) {
      throw Error(ErrorKind::input, "E_DUPLICATE_ID", path + ":" + std::to_string(rec.line) + ": id " + p.id + " given twice");
    }
    for (int k = 1; k < 4; ++k) {
      const std::string& text = rec.values[static_cast<std::size_t>(at[k])];
      const auto v = parse_finite_double(text);
      if (!v) {
        throw Error(ErrorKind::input, "E_VALUE",
                    path + ":" + std::to_string(rec.line) + ": " + kColumns[k] + " '" + text + "': expected a finite number of metres");
      }
      p.enu[k - 1] = *v;
    }
    rows.push_back(p);
  }
  if (rows.empty()) throw Error(ErrorKind::input, "E_INPUT", path + ": no points");
  return rows;
}

Eigen::Matrix3d enu_rotation_at(const geodesy::GeodeticPosition& g) { return geodesy::enu_from_ecef_rotation(g.lat, g.lon); }

std::string n(double v, int decimals) { return format_fixed(v, decimals); }

}  // namespace

LocateResult locate_points(const LocateRequest& request) {
  LocateResult r;
  r.map = map_reference(request.map, request.exclude);
  const std::vector<PointRow> rows = read_points(request.points);
  const geodesy::LocalTangentPlane plane(r.map.origin);
  const geodesy::Ellipsoid& ell = r.map.origin.ellipsoid;

  // The second frame.
  std::optional<geodesy::FrameEpochTransform> to_transform;
  std::optional<geodesy::PlateMotionModel> plate;
  if (request.to) {
    r.to = geodesy::Frame::parse(*request.to, "--to");
    geodesy::require_epoch_if_dynamic(*r.to, "--to", ErrorKind::usage);
    r.to_ellipsoid = geodesy::implied_ellipsoid(*r.to);
    if (!r.to_ellipsoid) throw Error(ErrorKind::usage, "E_OPTION", "--to " + *request.to + ": geoanchor knows no ellipsoid of this frame");
    if (request.plate) {
      plate = geodesy::find_plate_motion_model(request.plate_model, *request.plate);
      if (!plate) throw Error(ErrorKind::usage, "E_OPTION", "--plate " + *request.plate + ": no such plate in " + request.plate_model + "-PMM");
    }
    // A static frame named without an epoch takes the other side's; one
    // named with its own epoch keeps it (points move in plate-fixed frames
    // too: issue 40 point 1), and a change of epoch needs --plate.
    const bool from_dynamic = geodesy::is_dynamic(r.map.frame), to_dynamic = geodesy::is_dynamic(*r.to);
    const auto year_of = [](const geodesy::Frame& f) { return f.epoch() ? std::optional<double>(f.epoch()->year) : std::nullopt; };
    std::optional<double> t_from = year_of(r.map.frame), t_to = year_of(*r.to);
    if (!from_dynamic && !t_from && t_to) t_from = t_to;
    if (!to_dynamic && !t_to && t_from) t_to = t_from;
    if (!t_from || !t_to) {
      throw Error(ErrorKind::usage, "E_EPOCH_MISSING", "--to " + *request.to + ": the frames name no epoch to evaluate the path at; give FRAME@YYYY.Y");
    }
    if (*t_from == *t_to) plate.reset();
    if (*t_from != *t_to && !plate) {
      throw Error(ErrorKind::usage, "E_EPOCH_PROPAGATION",
                  "--to " + *request.to + ": the map's points are at " + format_shortest(*t_from) + " and --to asks for " +
                      format_shortest(*t_to) + ": give --plate, the plate the points are on (points move in plate-fixed "
                      "frames too, by intraplate velocities)");
    }
    geodesy::FramePath path = geodesy::find_frame_path(r.map.frame.name(), r.to->name(), "--to");
    r.path_description = path.describe();
    r.path_accuracy_m = path.accuracy_m();
    if (plate) {
      const double m = plate->motion_uncertainty_m(std::abs(*t_to - *t_from));
      r.path_accuracy_m = std::hypot(r.path_accuracy_m, m);
      r.notes.push_back("epoch change " + format_shortest(*t_from) + " -> " + format_shortest(*t_to) + " by plate " + plate->plate +
                        " of " + plate->source + " (±" + n(m * 1000.0, 1) + " mm over it)");
    }
    to_transform.emplace(std::move(path), geodesy::DecimalYear{*t_from}, geodesy::DecimalYear{*t_to}, plate ? &*plate : nullptr, "--to");
  }

  double farthest_outside_m = 0.0;
  std::string farthest_id;
  for (const auto& row : rows) {
    LocatedPoint p;
    p.id = row.id;
    p.line = row.line;
    p.enu_m = row.enu;
    p.ecef = plane.ecef_from_enu(geodesy::EnuPosition{row.enu, r.map.origin});
    p.geodetic = geodesy::geodetic_from_ecef(ell, p.ecef);
    const std::string where = request.points + ":" + std::to_string(row.line);
    geodesy::require_physical_height(p.geodetic.h.m, where + ": " + p.id);
    // How far the point reaches: outside the control network of the map's
    // transform, or from the map's origin when it records none.
    const auto refuse_past_limit = [&](double d, const std::string& from_what) {
      if (!(d <= request.max_extrapolation_m)) {
        throw Error(ErrorKind::rejected, "E_EXTRAPOLATION",
                    where + ": " + p.id + " lies " + n(d / 1000.0, 3) + " km " + from_what + " (limit --max-extrapolation " +
                        format_shortest(request.max_extrapolation_m) + " m); nothing was written");
      }
    };
    const io::ControlExtent* extent =
        r.map.transform && r.map.transform->fit && r.map.transform->fit->extent ? &*r.map.transform->fit->extent : nullptr;
    if (!extent) refuse_past_limit(std::hypot(row.enu.x(), row.enu.y()), "from the map's ENU origin");
    if (r.map.transform) {
      // The map's point came from its source position by the transform;
      // the transform's uncertainty there is the point's.
      const std::optional<geodesy::DecimalYear> epoch =
          r.map.transform_epoch ? std::optional(geodesy::DecimalYear{*r.map.transform_epoch}) : std::nullopt;
      const geodesy::EcefPosition source = r.map.transform->apply(p.ecef, epoch, !r.map.transform_inverse, where);
      if (extent) {
        // The extent is the transform's source frame's, where the map's
        // point was before it moved (with --inverse the map is there).
        const double d = extent->distance_m(r.map.transform_inverse ? p.ecef : source);
        refuse_past_limit(d, "outside the control network of " + r.map.transform_path);
        if (d > farthest_outside_m) farthest_outside_m = d, farthest_id = p.id;
      }
      if (const auto cov = propagated_covariance_m2(*r.map.transform, source, epoch, r.map.transform_inverse)) {
        if (!cov->allFinite()) throw Error(ErrorKind::input, "E_TRANSFORM", r.map.transform_path + ": its sigmas' correlation is incomplete");
        const Eigen::Matrix3d rot = enu_rotation_at(p.geodetic);
        p.covariance_enu_m2 = rot * *cov * rot.transpose();
        for (int k = 0; k < 3; ++k) (*p.covariance_enu_m2)(k, k) = std::max(0.0, (*p.covariance_enu_m2)(k, k));  // rounded below 0
      }
    }
    if (to_transform) {
      const geodesy::StateVector out = to_transform->apply(geodesy::StateVector{p.ecef, std::nullopt}, where);
      p.to_ecef = out.x;
      p.to_geodetic = geodesy::geodetic_from_ecef(*r.to_ellipsoid, out.x);
      if (!out.x.m.allFinite()) throw Error(ErrorKind::input, "E_VALUE", where + ": " + p.id + ": not finite in " + r.to->to_string());
    }
    r.points.push_back(std::move(p));
  }
  if (farthest_outside_m > io::ControlExtent::kOnHull_m) {
    r.notes.push_back("points lie outside the control network of " + r.map.transform_path + " (" + farthest_id + " " +
                      n(farthest_outside_m, 1) + " m): the transform and its uncertainty are extrapolated there");
  }
  if (!r.map.transform) r.notes.push_back("the map was moved by no transform file: no propagated uncertainty");
  else if (r.points.empty() || !r.points.front().covariance_enu_m2) r.notes.push_back("the map's transform file carries no sigmas");
  return r;
}

std::string locate_csv(const LocateResult& r) {
  std::ostringstream out;
  const auto& o = r.map.origin.point;
  out << "# map frame = " << r.map.frame.to_string() << "\n";
  out << "# enu origin = " << n(o.lat.deg(), 10) << "," << n(o.lon.deg(), 10) << "," << n(o.h.m, 4) << " (ellipsoidal, "
      << r.map.origin.ellipsoid.name() << "); source: " << r.map.origin_source << "\n";
  if (r.map.transform) {
    out << "# map transform = " << r.map.transform_path << " (sha256 " << r.map.transform_sha256 << ", "
        << (r.map.transform_inverse ? "inverse" : "forward") << ")\n";
  }
  if (r.to) out << "# to frame = " << r.to->to_string() << " (" << r.to_ellipsoid->name() << "); path accuracy ±" << n(r.path_accuracy_m, 4) << " m\n";
  for (const auto& note : r.notes) out << "# note: " << note << "\n";
  out << "id,e_m,n_m,u_m,x_m,y_m,z_m,lat_deg,lon_deg,h_m,sigma_e_m,sigma_n_m,sigma_u_m";
  if (r.to) out << ",to_x_m,to_y_m,to_z_m,to_lat_deg,to_lon_deg,to_h_m";
  out << "\n";
  for (const auto& p : r.points) {
    out << p.id << "," << n(p.enu_m.x(), 4) << "," << n(p.enu_m.y(), 4) << "," << n(p.enu_m.z(), 4) << "," << n(p.ecef.m.x(), 4)
        << "," << n(p.ecef.m.y(), 4) << "," << n(p.ecef.m.z(), 4) << "," << n(p.geodetic.lat.deg(), 10) << ","
        << n(p.geodetic.lon.deg(), 10) << "," << n(p.geodetic.h.m, 4);
    for (int k = 0; k < 3; ++k) out << "," << (p.covariance_enu_m2 ? n(std::sqrt((*p.covariance_enu_m2)(k, k)), 4) : std::string());
    if (p.to_ecef) {
      out << "," << n(p.to_ecef->m.x(), 4) << "," << n(p.to_ecef->m.y(), 4) << "," << n(p.to_ecef->m.z(), 4) << ","
          << n(p.to_geodetic->lat.deg(), 10) << "," << n(p.to_geodetic->lon.deg(), 10) << "," << n(p.to_geodetic->h.m, 4);
    }
    out << "\n";
  }
  return out.str();
}

std::string locate_json_text(const LocateResult& r) {
  json j;
  j["schema"] = "geoanchor.locate/1";
  const auto& o = r.map.origin.point;
  j["map"] = {{"frame", r.map.frame.to_string()},
              {"enu_origin", {{"lat_deg", o.lat.deg()}, {"lon_deg", o.lon.deg()}, {"h_m", o.h.m}, {"height_type", "ellipsoidal"},
                              {"ellipsoid", r.map.origin.ellipsoid.name()}}},
              {"enu_origin_source", r.map.origin_source},
              {"transform", r.map.transform ? json(r.map.transform_path) : json(nullptr)},
              {"transform_sha256", r.map.transform ? json(r.map.transform_sha256) : json(nullptr)},
              {"artifacts", r.map.artifacts}};
  if (r.to) {
    j["to"] = {{"frame", r.to->to_string()}, {"ellipsoid", r.to_ellipsoid->name()}, {"path", r.path_description},
               {"path_accuracy_m", r.path_accuracy_m}};
  }
  j["notes"] = r.notes;
  json pts = json::array();
  for (const auto& p : r.points) {
    json q = {{"id", p.id},
              {"enu_m", {p.enu_m.x(), p.enu_m.y(), p.enu_m.z()}},
              {"ecef_m", {p.ecef.m.x(), p.ecef.m.y(), p.ecef.m.z()}},
              {"geodetic", {{"lat_deg", p.geodetic.lat.deg()}, {"lon_deg", p.geodetic.lon.deg()}, {"h_m", p.geodetic.h.m}}}};
    if (p.covariance_enu_m2) {
      const auto& c = *p.covariance_enu_m2;
      q["sigma_m"] = {{"east", std::sqrt(c(0, 0))}, {"north", std::sqrt(c(1, 1))}, {"up", std::sqrt(c(2, 2))}};
    } else {
      q["sigma_m"] = nullptr;
    }
    if (p.to_ecef) {
      q["to"] = {{"ecef_m", {p.to_ecef->m.x(), p.to_ecef->m.y(), p.to_ecef->m.z()}},
                 {"geodetic", {{"lat_deg", p.to_geodetic->lat.deg()}, {"lon_deg", p.to_geodetic->lon.deg()}, {"h_m", p.to_geodetic->h.m}}}};
    }
    pts.push_back(q);
  }
  j["points"] = pts;
  return j.dump(2);
}

}  // namespace geoanchor::workflow
