// What geoanchor understood of a CRS, as JSON (schema geoanchor.crs/1).

#include <nlohmann/json.hpp>

#include "geoanchor/geodesy/frame.hpp"
#include "geoanchor/crs/crs.hpp"
#include "geoanchor/io/control/crs_columns.hpp"

namespace geoanchor::io {

using json = nlohmann::ordered_json;

namespace {

json axis_json(const CrsAxis& a) {
  json j{{"name", a.name},           {"abbreviation", a.abbreviation}, {"direction", a.direction},
         {"unit", a.unit_name},       {"unit_to_si", a.unit_to_si},     {"unit_type", a.unit_type}};
  if (a.meridian_deg) j["meridian_deg"] = *a.meridian_deg;  // "south along 90°E"
  return j;
}

json columns_json(const Crs& crs, bool with_height) {
  try {
    return json(written_names(crs_output_columns(crs, with_height, false, "CRS")));
  } catch (const Error& e) {
    return json(std::string("none: ") + e.what());
  }
}

}  // namespace

std::string crs_json_text(const Crs& crs) {
  const CrsDescription& d = crs.description();
  json j;
  j["schema"] = "geoanchor.crs/1";
  j["input"] = crs.text();
  j["name"] = d.name;
  j["identifier"] = d.identifier.empty() ? json(nullptr) : json(d.identifier);
  j["type"] = d.type;
  if (d.type == "compound") j["horizontal_type"] = d.horizontal_type;
  json datum = {{"name", d.datum}, {"ensemble", d.ensemble}, {"dynamic", d.dynamic}};
  if (d.ensemble) {
    datum["members"] = d.ensemble_members;
    datum["accuracy_m"] = d.ensemble_accuracy_m ? json(*d.ensemble_accuracy_m) : json(nullptr);
  }
  if (d.frame_reference_epoch) datum["frame_reference_epoch"] = *d.frame_reference_epoch;
  j["datum"] = datum;
  j["catalog_frame"] = d.catalog_frame.empty() ? json(nullptr) : json(d.catalog_frame);
  j["needs_epoch"] = d.dynamic;
  j["coordinate_epoch"] = crs.epoch() ? json(crs.epoch()->year) : json(nullptr);
  j["ellipsoid"] = {{"name", d.ellipsoid.name}, {"a_m", d.ellipsoid.a_m}, {"rf", d.ellipsoid.rf}};
  j["prime_meridian"] = {{"name", d.prime_meridian}, {"longitude_deg", d.prime_meridian_deg}};
  json axes = json::array();
  for (const auto& a : d.axes) axes.push_back(axis_json(a));
  j["axes"] = axes;
  json vis = json::array();
  for (const auto& a : d.visualization_axes) vis.push_back(axis_json(a).at("name"));
  j["visualization_order"] = vis;
  if (!d.projection_method.empty()) {
    json params = json::array();
    for (const auto& p : d.projection_parameters) {
      params.push_back({{"name", p.name}, {"epsg_code", p.epsg_code.empty() ? json(nullptr) : json(p.epsg_code)},
                        {"value", p.value}, {"unit", p.unit_name}});
    }
    j["projection"] = {{"method", d.projection_method},
                       {"method_id", d.projection_method_code.empty() ? json(nullptr) : json(d.projection_method_code)},
                       {"parameters", params}};
  } else {
    j["projection"] = nullptr;
  }
  if (!d.vertical_crs.empty()) {
    j["vertical"] = {{"crs", d.vertical_crs},
                     {"datum", d.vertical_datum},
                     {"geoid_model", d.geoid_model.empty() ? json(nullptr) : json(d.geoid_model)},
                     {"geoid_on_this_machine", d.geoid_available},
                     {"geoid_operation", d.geoid_operation.empty() ? json(nullptr) : json(d.geoid_operation)},
                     {"geoid_operation_id", d.geoid_operation_id.empty() ? json(nullptr) : json(d.geoid_operation_id)}};
  } else {
    j["vertical"] = nullptr;
  }
  if (d.area) {
    j["area_of_use"] = {{"name", d.area->name},
                        {"west_deg", d.area->west_deg},
                        {"south_deg", d.area->south_deg},
                        {"east_deg", d.area->east_deg},
                        {"north_deg", d.area->north_deg}};
  } else {
    j["area_of_use"] = nullptr;
  }
  j["columns"] = columns_json(crs, d.axes.size() >= 3);
  j["wkt2"] = crs.wkt2();
  return j.dump(2);
}

}  // namespace geoanchor::io
