#include "crs_command.hpp"

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <cmath>
#include <iostream>

#include "geoanchor/base/number_text.hpp"
#include "geoanchor/io/atomic_file.hpp"
#include "geoanchor/crs/crs.hpp"
#include "geoanchor/io/control/crs_columns.hpp"

namespace geoanchor::cli {

CLI::App* add_crs_command(CLI::App& app, CrsCommandOptions& o) {
  auto* cmd = app.add_subcommand("crs", "Show what geoanchor understands of a CRS (read through PROJ) and the WKT2 it writes");
  cmd->add_option("CRS", o.crs,
                  "EPSG:n, EPSG:h+v, WKT, PROJJSON, a PROJ string, @FILE or a frame name; CRS@EPOCH for a coordinate epoch")
      ->required();
  cmd->add_flag("--json", o.json, "Print JSON (schema geoanchor.crs/1) instead of text");
  return cmd;
}

void run_crs(const CrsCommandOptions& o) {
  const io::Crs crs = io::Crs::parse(o.crs, "crs");
  const std::string json_text = io::crs_json_text(crs);
  if (o.json) {
    std::cout << json_text << '\n';
    io::finish_standard_output("the CRS's description");
    return;
  }
  // The text form says the same as the JSON, one fact per line.
  const auto j = nlohmann::json::parse(json_text);
  auto text = [](const nlohmann::json& v) { return v.is_string() ? v.get<std::string>() : v.dump(); };
  std::cout << "name:           " << text(j["name"]) << '\n';
  if (!j["identifier"].is_null()) std::cout << "identifier:     " << text(j["identifier"]) << '\n';
  std::cout << "type:           " << text(j["type"]);
  if (j.contains("horizontal_type")) std::cout << " (horizontal: " << text(j["horizontal_type"]) << ")";
  std::cout << '\n';
  const auto& datum = j["datum"];
  std::cout << "datum:          " << text(datum["name"]);
  if (datum["ensemble"].get<bool>()) {
    std::cout << " (an ensemble, accuracy " << (datum["accuracy_m"].is_null() ? "not stated" : text(datum["accuracy_m"]) + " m")
              << "; members:";
    for (const auto& m : datum["members"]) std::cout << ' ' << text(m) << ';';
    std::cout << ")";
  }
  std::cout << '\n';
  std::cout << "dynamic:        "
            << (datum["dynamic"].get<bool>()
                    ? "yes: coordinates need their epoch (CRS@YYYY.Y); frame reference epoch " +
                          (datum.contains("frame_reference_epoch") ? text(datum["frame_reference_epoch"]) : "?")
                    : "no: coordinates need no epoch")
            << '\n';
  if (!j["coordinate_epoch"].is_null()) std::cout << "coordinate epoch: " << text(j["coordinate_epoch"]) << '\n';
  std::cout << "catalog frame:  " << (j["catalog_frame"].is_null() ? "none" : text(j["catalog_frame"])) << '\n';
  const auto& e = j["ellipsoid"];
  std::cout << "ellipsoid:      " << text(e["name"]) << " (a = " << format_shortest(e["a_m"].get<double>())
            << " m, 1/f = " << format_shortest(e["rf"].get<double>()) << ")\n";
  const auto& pm = j["prime_meridian"];
  std::cout << "prime meridian: " << text(pm["name"]) << " (" << format_shortest(pm["longitude_deg"].get<double>())
            << "° from Greenwich)\n";
  std::cout << "axes:\n";
  int k = 0;
  for (const auto& a : j["axes"]) {
    std::cout << "  " << ++k << ". " << text(a["name"]) << " (" << text(a["abbreviation"]) << "), " << text(a["direction"]);
    if (a.contains("meridian_deg")) {
      // PROJ's wording: "South along 90°E"; 0° and 180° have no side.
      const double m = a["meridian_deg"].get<double>();
      std::cout << " along " << format_shortest(std::abs(m)) << "°"
                << (m == 0.0 || std::abs(m) == 180.0 ? "" : m > 0.0 ? "E" : "W");
    }
    std::cout << ", " << text(a["unit"]) << '\n';
  }
  if (!j["projection"].is_null()) {
    const auto& p = j["projection"];
    std::cout << "projection:     " << text(p["method"]);
    if (!p["method_id"].is_null()) std::cout << " (" << text(p["method_id"]) << ")";
    std::cout << '\n';
    for (const auto& q : p["parameters"]) {
      std::cout << "  " << text(q["name"]) << " = " << format_shortest(q["value"].get<double>()) << ' ' << text(q["unit"])
                << '\n';
    }
  }
  if (!j["vertical"].is_null()) {
    const auto& v = j["vertical"];
    std::cout << "vertical CRS:   " << text(v["crs"]) << " (datum " << text(v["datum"]) << ")\n";
    std::cout << "geoid:          "
              << (v["geoid_model"].is_null()
                      ? std::string("PROJ names none")
                      : text(v["geoid_model"]) + (v["geoid_on_this_machine"].get<bool>() ? " (on this machine)"
                                                                                          : " (not on this machine)"))
              << '\n';
    if (!v["geoid_operation"].is_null()) {
      std::cout << "geoid model:    " << text(v["geoid_operation"])
                << (v["geoid_operation_id"].is_null() ? std::string() : " (" + text(v["geoid_operation_id"]) + ")")
                << ", written as GEOIDMODEL in the WKT2\n";
    }
  }
  if (!j["area_of_use"].is_null()) {
    const auto& a = j["area_of_use"];
    std::cout << "area of use:    " << text(a["name"]) << " (longitude " << format_shortest(a["west_deg"].get<double>())
              << "° to " << format_shortest(a["east_deg"].get<double>()) << "°, latitude "
              << format_shortest(a["south_deg"].get<double>()) << "° to " << format_shortest(a["north_deg"].get<double>())
              << "°)\n";
  }
  std::cout << "columns:        ";
  if (j["columns"].is_array()) {
    bool first = true;
    for (const auto& c : j["columns"]) {
      std::cout << (first ? "" : ", ") << text(c);
      first = false;
    }
  } else {
    std::cout << text(j["columns"]);
  }
  std::cout << '\n' << "WKT2:2019:\n" << text(j["wkt2"]) << '\n';
  io::finish_standard_output("the CRS's description");
}

}  // namespace geoanchor::cli
