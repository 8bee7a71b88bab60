// Writing a transform file: the model and its parameters, the PROJ, EPSG,
// WKT2 and PROJJSON descriptions, the fit record, and the other
// convention's alternative; the per-point records streamed in one a line
// (transform_write_points.cpp).

#include <cmath>
#include <sstream>
#include <stdexcept>
#include <string>
#include <string_view>
#include <utility>
#include <variant>

#include "geoanchor/geodesy/local_frame.hpp"
#include "geoanchor/io/transform/transform_file.hpp"
#include "transform/transform_common.hpp"

namespace geoanchor::io {
namespace {

using detail::json;
using detail::number;
using detail::parameters_json;
using detail::swapped_convention;
using detail::write_point_records;

json json_number_or_null(double v) { return std::isfinite(v) ? number(v) : json(nullptr); }

// The file's text; its point records those of t.fit, or else `streamed`'s.
void write_json_with(std::ostream& out, const TransformFile& t, const PointRecordSource* streamed) {
  json doc;
  doc["format_version"] = 1;
  doc["model"] = std::string(to_string(t.model));
  if (!t.enu_origin && !t.site_calibration) {
    doc["convention"] = std::string(t.convention_name());
    doc["rotation_model"] = std::string(geodesy::to_string(t.rotation_model));
    if (const std::string m = epsg_method(t); !m.empty()) doc["epsg_method"] = m;
  }
  if (t.source_frame) doc["source_frame"] = t.source_frame->to_string();
  if (t.target_frame) doc["target_frame"] = t.target_frame->to_string();
  if (t.reference_epoch) doc["reference_epoch"] = number(t.reference_epoch->year);
  auto with_pivot = [&](json params) {
    if (t.pivot_m) {
      params["px_m"] = number(t.pivot_m->x());
      params["py_m"] = number(t.pivot_m->y());
      params["pz_m"] = number(t.pivot_m->z());
    }
    return params;
  };
  if (t.site_calibration) {
    const auto& sc = *t.site_calibration;
    const auto& o = sc.local_origin();
    const auto& p = sc.params();
    const auto& g = sc.grid();
    doc["nominal_origin"] = {{"lat_deg", number(o.point.lat.deg())}, {"lon_deg", number(o.point.lon.deg())},
                             {"h_m", number(o.point.h.m)}, {"height_type", "ellipsoidal"}, {"ellipsoid", o.ellipsoid.name()}};
    doc["grid"] = {{"lat0_deg", number(g.tm.lat0.deg())}, {"lon0_deg", number(g.tm.lon0.deg())}, {"k0", number(g.tm.k0)},
                   {"false_easting_m", number(g.tm.false_easting_m)}, {"false_northing_m", number(g.tm.false_northing_m)},
                   {"ellipsoid", g.ellipsoid.name()}};
    doc["parameters"] = {{"shift_e_m", number(p.shift_e_m)},           {"shift_n_m", number(p.shift_n_m)},
                         {"rotation_arcsec", number(p.rotation.arcsec())}, {"scale_ppm", number(p.scale.ppm())},
                         {"vertical_shift_m", number(p.vertical_shift_m)}, {"slope_n_ppm", number(p.slope_n * 1e6)},
                         {"slope_e_ppm", number(p.slope_e * 1e6)},     {"centroid_e_m", number(p.centroid_e_m)},
                         {"centroid_n_m", number(p.centroid_n_m)}};
  } else if (t.enu_origin) {
    const auto& c = *t.enu_origin;
    const geodesy::LocalOrigin corrected = geodesy::corrected_origin(c.nominal, c.shift_enu_m);
    doc["nominal_origin"] = {{"lat_deg", number(c.nominal.point.lat.deg())}, {"lon_deg", number(c.nominal.point.lon.deg())},
                             {"h_m", number(c.nominal.point.h.m)}, {"height_type", "ellipsoidal"},
                             {"ellipsoid", c.nominal.ellipsoid.name()}};
    doc["parameters"] = {{"shift_e_m", number(c.shift_enu_m.x())}, {"shift_n_m", number(c.shift_enu_m.y())},
                         {"shift_u_m", number(c.shift_enu_m.z())}, {"yaw_arcsec", number(c.yaw.arcsec())},
                         {"ds_ppm", number(c.ds.ppm())},           {"origin_lat_deg", number(corrected.point.lat.deg())},
                         {"origin_lon_deg", number(corrected.point.lon.deg())}, {"origin_h_m", number(corrected.point.h.m)}};
  } else {
    doc["parameters"] = with_pivot(std::visit([](const auto& h) { return parameters_json(h); }, t.helmert));
  }
  doc["proj_pipeline"] = proj_pipeline(t);
  if (t.metadata) doc["metadata"] = json::parse(map_metadata_json_text(*t.metadata));
  if (t.fit) {
    if (const auto wkt = to_wkt2(t)) doc["wkt2"] = *wkt;
    if (const auto pj = to_projjson(t)) doc["projjson"] = json::parse(*pj);
  }
  if (t.fit) {
    const FitRecord& f = *t.fit;
    if (!f.generator.empty()) doc["generator"] = f.generator;
    if (!f.control_crs_json.empty()) doc["control_crs"] = json::parse(f.control_crs_json);
    json sig = json::object();
    for (const auto& [name, value] : f.sigmas) sig[name] = number(value);
    doc["sigmas"] = sig;
    if (f.uncorrelated && f.correlation.empty()) {
      doc["correlation"] = "none";  // the parameters are uncorrelated, as the file read said
    } else {
      json corr = json::array();
      for (const auto& row : f.correlation) {
        json r = json::array();
        for (double v : row) r.push_back(number(v));
        corr.push_back(r);
      }
      doc["correlation"] = corr;  // rows and columns in the order of correlation_parameters
      doc["correlation_parameters"] = f.correlation_names;
    }
    if (f.extent) {
      json hull = json::array();
      for (const auto& v : f.extent->hull_en_m) hull.push_back({number(v[0]), number(v[1])});
      doc["control_extent"] = {{"centroid",
                                {{"lat_deg", number(f.extent->centroid.point.lat.deg())},
                                 {"lon_deg", number(f.extent->centroid.point.lon.deg())},
                                 {"h_m", number(f.extent->centroid.point.h.m)},
                                 {"ellipsoid", "WGS84"}}},
                               {"hull_en_m", hull}};
    }
    doc["statistics"] = {
        {"sigma0", f.sigma0 ? number(*f.sigma0) : json(nullptr)},
        {"dof", f.dof},
        {"sigmas_scaled_by_sigma0", f.sigmas_scaled_by_sigma0},
        {"alpha", number(f.alpha)},
        {"alpha_point", number(f.alpha_point)},
        {"global_test",
         {{"statistic", json_number_or_null(f.global_statistic)},
          {"critical", json_number_or_null(f.global_critical_upper)},
          {"critical_lower", json_number_or_null(f.global_critical_lower)},
          {"passed", f.global_applicable ? json(f.global_passed) : json(nullptr)},
          {"applicable", f.global_applicable}}},
        {"warnings", f.warnings}};
    if (f.variance_factors) {
      doc["statistics"]["variance_factors"] = {{"source", number(f.variance_factors->first)},
                                               {"target", number(f.variance_factors->second)}};
    }
    if (f.gnss_solutions) {
      json classes = json::object();
      for (const auto s : geodesy::kGnssSolutions) {
        const SolutionTally& c = f.gnss_solutions->classes[geodesy::solution_index(s)];
        classes[std::string(geodesy::to_string(s))] = {
            {"marks", c.marks}, {"used", c.used}, {"excluded", c.excluded}, {"sigma_factor", number(c.sigma_factor)}};
      }
      doc["gnss_solutions"] = {{"policy", std::string(geodesy::to_string(f.gnss_solutions->policy))}, {"classes", classes}};
    }
    doc["points"] = nullptr;  // placeholder: the records are streamed below, one a line
  }
  if (t.fit && !t.enu_origin && !t.site_calibration) {
    // The exports read the parameters and frames alone: no fit record (a
    // copy of 10⁶ marks' records was 200 MB and a fifth of a second).
    const TransformFile other = swapped_convention(t);
    doc["alternatives"] = json::array({json{{"convention", std::string(other.convention_name())},
                                            {"parameters", with_pivot(std::visit([](const auto& h) { return parameters_json(h); }, other.helmert))},
                                            {"proj_pipeline", proj_pipeline(other)}}});
    if (const std::string m = epsg_method(other); !m.empty()) doc["alternatives"][0]["epsg_method"] = m;
    if (const auto wkt = to_wkt2(other)) doc["alternatives"][0]["wkt2"] = *wkt;
    if (const auto pj = to_projjson(other)) doc["alternatives"][0]["projjson"] = json::parse(*pj);
  }
  std::string text = doc.dump(2);
  if (t.fit) {
    // The per-point records, one JSON object a line: a fit of 10⁶ marks
    // writes them in a second instead of building a DOM of 10⁷ values.
    constexpr std::string_view kPlaceholder = "\n  \"points\": null";
    const auto at = text.find(kPlaceholder);
    if (at == std::string::npos) throw std::logic_error("transform file: the points placeholder is missing");
    out.write(text.data(), static_cast<std::streamsize>(at));
    out << "\n  \"points\": [";
    write_point_records(out, t.fit->points, streamed);
    out << ((streamed ? streamed->count : t.fit->points.size()) == 0 ? "]" : "\n  ]");
    const std::size_t rest = at + kPlaceholder.size();
    out.write(text.data() + rest, static_cast<std::streamsize>(text.size() - rest));
  } else {
    out << text;
  }
  out << '\n';
}

}  // namespace

void write_json(std::ostream& out, const TransformFile& t) { write_json_with(out, t, nullptr); }

void write_json(std::ostream& out, const TransformFile& t, const PointRecordSource& points) {
  if (!t.fit || !t.fit->points.empty()) {
    throw std::logic_error("write_json: streamed point records need a fit record without points of its own");
  }
  write_json_with(out, t, &points);
}

std::string to_json_text(const TransformFile& t) {
  std::ostringstream text;
  write_json(text, t);
  return std::move(text).str();
}

}  // namespace geoanchor::io
