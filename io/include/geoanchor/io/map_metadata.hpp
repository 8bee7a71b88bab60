#pragma once
// The map metadata contract (docs/tile-metadata.md#the-map-metadata-contract):
// the fields a certification reviewer needs, carried by every artifact
// geoanchor writes (tile sidecars, transform files; vector-map sidecars
// alike) as a "metadata" object of schema "geoanchor.map-metadata/1".
// Every field is written, with its value or the string "unknown": never
// absent, never null, so that a reader (a later `audit`) tells a missing
// value from a field it does not know.
//
//   {"schema": "geoanchor.map-metadata/1",
//    "frame": "ITRF2014" | "unknown",                datum and realization
//    "coordinate_epoch": 2024.5 | {"from": 2024.41, "to": 2024.43} | "unknown",
//    "enu_origin": {"lat_deg", "lon_deg", "h_m", "height_type": "ellipsoidal"} | "unknown",
//    "enu_origin_source": "ICAO AIP published; survey confirmed" | "unknown",
//    "horizontal_crs": "..." | "unknown",
//    "vertical_datum": "..." | "unknown",
//    "geoid_model": "EGM96" | "unknown",
//    "gnss_method": "network RTK (VRS)" | "unknown",
//    "gnss_base": "..." | "unknown",
//    "rtk_fixed_percent": 98.7 | "unknown",
//    "rtk_fixed_from": "..." | "unknown",            where the share came from
//    "gnss_solution_counts": {"fixed": n, "ppk": n, "float": n, "dgps": n,
//                             "sbas": n, "standalone": n, "dead_reckoned": n} | "unknown",
//    "coordinate_storage": "float64 ECEF origin + int32 scaled ENU offsets" | "unknown"}
//
// What geoanchor cannot derive comes from a survey-metadata file
// (docs/survey-metadata.md, schema "geoanchor.survey/1"). A value stated by
// two sources (derived, an input's metadata, the survey file, a computed
// share) must agree, else E_METADATA_CONFLICT naming the key, both values
// and both sources: nothing is silently overridden.

#include <array>
#include <cstdint>
#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <utility>

#include "geoanchor/geodesy/frame.hpp"
#include "geoanchor/geodesy/gnss_solution.hpp"

namespace geoanchor::io {

inline constexpr std::string_view kMapMetadataSchema = "geoanchor.map-metadata/1";
inline constexpr std::string_view kSurveyMetadataSchema = "geoanchor.survey/1";
inline constexpr std::string_view kUnknown = "unknown";

// An ENU origin: the map's aerodrome reference point, on the frame's
// ellipsoid, ellipsoidal height.
struct MetadataOrigin {
  double lat_deg = 0.0, lon_deg = 0.0, h_m = 0.0;
};

// Each field: a value, or nullopt, written "unknown".
struct MapMetadata {
  std::optional<std::string> frame;  // datum and realization, the catalog's spelling ("ITRF2014", "WGS84(G2139)")
  std::optional<double> coordinate_epoch;                      // decimal year
  std::optional<std::array<double, 2>> coordinate_epoch_range;  // per-point epochs (LAS GPS times): from, to
  std::optional<MetadataOrigin> enu_origin;
  std::optional<std::string> enu_origin_source;
  std::optional<std::string> horizontal_crs;
  std::optional<std::string> vertical_datum;
  std::optional<std::string> geoid_model;
  std::optional<std::string> gnss_method;
  std::optional<std::string> gnss_base;
  std::optional<double> rtk_fixed_percent;  // [0, 100]: fixed and ppk (geodesy::is_rtk_fixed)
  std::optional<std::string> rtk_fixed_from;
  std::optional<geodesy::SolutionCounts> gnss_solution_counts;
  std::optional<std::string> coordinate_storage;
};

// The "metadata" object as JSON text (every key, "unknown" for nullopt).
std::string map_metadata_json_text(const MapMetadata& m);
// Reads the "metadata" object given as JSON text; `where` names the file
// and the object's path ("t.json: metadata") in messages. Throws
// geoanchor::Error (input, E_METADATA): another schema, an unknown or
// missing key, null, a value of the wrong type or out of range, an empty
// string (write "unknown"), rtk_fixed_from known without the share.
MapMetadata parse_map_metadata(std::string_view object_json, std::string_view where);

// How the coordinates are stored, from a tile's coordinates.kind ("enu",
// "ned", "ecef", "geodetic", "utm", "tm", "crs") and coordinates.storage
// ("float64", "float32", "int32_scaled"): "float64 ECEF origin + int32
// scaled ENU offsets", "float32 ECEF", ...
std::string coordinate_storage_text(std::string_view kind, std::string_view storage);

// Whether `stated` (a share as written, e.g. 98.7 or 98) agrees with
// `computed` to the stated value's rounding: |stated - computed| <= half a
// unit of its last decimal (98 → 0.5, 98.7 → 0.05; at most six decimals).
bool share_agrees(double stated_percent, double computed_percent);

// The survey-metadata file (docs/survey-metadata.md): what geoanchor cannot
// derive, given once per survey. Every key is optional; a string may be
// "unknown" (the same as leaving it out).
struct SurveyMetadata {
  std::string source;                   // the file, for messages
  std::optional<geodesy::Frame> frame;  // checked against the artifact's frame and epoch
  std::optional<MetadataOrigin> enu_origin;
  std::optional<std::string> enu_origin_source, vertical_datum, geoid_model, gnss_method, gnss_base;
  std::optional<double> rtk_fixed_percent;
};

// Throws geoanchor::Error (io when unreadable; input, E_SURVEY_METADATA,
// naming the file and the key: another schema, an unknown key, a key given
// twice, null, a value of the wrong type or out of range).
SurveyMetadata read_survey_metadata(const std::filesystem::path& path);
SurveyMetadata parse_survey_metadata(std::string_view text, std::string_view source);

// Fills a MapMetadata from several sources, checking that they agree.
// Each call states one field's value and who states it ("derived from the
// output's coordinates", "survey metadata s.json", "sidecar in/t.las.geoanchor.json");
// a field stated twice with different values is E_METADATA_CONFLICT
// (input) naming `artifact`, the key, both values and both sources.
class MapMetadataBuilder {
 public:
  explicit MapMetadataBuilder(std::string artifact) : artifact_(std::move(artifact)) {}

  void frame(const std::string& name, const std::string& who);
  void coordinate_epoch(double year, const std::string& who);
  void coordinate_epoch_range(const std::array<double, 2>& range, const std::string& who);
  // Origins agree within 1e-8° (1.1 mm) and 1 mm in height.
  void enu_origin(const MetadataOrigin& o, const std::string& who);
  enum class Text { enu_origin_source, horizontal_crs, vertical_datum, geoid_model, gnss_method, gnss_base, coordinate_storage };
  void text(Text field, const std::string& value, const std::string& who);
  // A stated share agrees with another by share_agrees (the computed one,
  // from counts, is kept); counts must be equal.
  void rtk_fixed_percent(double percent, const std::string& who, bool computed);
  void gnss_solution_counts(const geodesy::SolutionCounts& c, const std::string& who);
  // Every field `s` states; its frame must name the frame (and epoch) the
  // artifact is in when that is known (frame(), coordinate_epoch() first).
  // Without `frame_bound` the fields that hold in the survey's frame only
  // (frame, epoch, ENU origin and its source, vertical datum) are left out:
  // for an artifact moved into another frame, whose input they were
  // checked against.
  void survey(const SurveyMetadata& s, bool frame_bound = true);

  const MapMetadata& metadata() const { return m_; }

 private:
  [[noreturn]] void conflict(const std::string& key, const std::string& had, const std::string& had_who,
                             const std::string& value, const std::string& who) const;
  std::string artifact_;
  MapMetadata m_;
  std::map<std::string, std::string> who_;  // key -> who stated it
};

}  // namespace geoanchor::io
